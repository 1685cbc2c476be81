//! `umgen MODEL.ron [-o PLUGIN] [--emit-source DIR] [--fixed IDENT ...]`: derive
//! the equations of motion symbolically, emit Rust and compile a plugin.

use railmbs_codegen::GenerateOptions;
use std::path::PathBuf;

/// Arguments of `umgen`.
#[derive(Debug, clap::Parser)]
#[command(
    name = "umgen",
    version,
    about = "railmbs plugin generator: model file -> symbolic equations -> compiled plugin"
)]
pub struct Args {
    /// Model file (RON).
    pub model: PathBuf,
    /// Where to put the compiled plugin (a copy of the cached library).
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Also write the generated Rust source into this directory.
    #[arg(long)]
    pub emit_source: Option<PathBuf>,
    /// Identifiers to fix at their default values (constant-folded; a run
    /// with another value is then refused).
    #[arg(long, num_args = 1..)]
    pub fixed: Vec<String>,
    /// Largest number of instructions per generated function.
    #[arg(long, default_value_t = 600)]
    pub max_function_size: usize,
    /// Compile for any CPU of this architecture, not only this machine's (on x86-64 the
    /// default is `-C target-cpu=native`; such a plugin is refused on a CPU lacking one of
    /// its features).
    #[arg(long)]
    pub portable: bool,
}

/// Runs `umgen`.
pub fn run(args: &Args) -> Result<(), Box<dyn std::error::Error>> {
    let model = railmbs_models::load_model(&args.model)?;
    let mut opts = GenerateOptions::new();
    opts.fixed = args.fixed.clone();
    opts.max_instructions_per_function = args.max_function_size.max(1);
    opts.portable = args.portable;
    let built = railmbs_codegen::build_plugin(&model, &opts, None)?;
    let g = &built.generated;
    if let Some(dir) = &args.emit_source {
        let name = format!("{}.rs", model.name);
        railmbs_build_support::write_source(dir, &name, &g.source)?;
        println!("source                 {}", dir.join(&name).display());
    }
    let target = match &args.output {
        Some(out) => {
            if let Some(dir) = out.parent().filter(|d| !d.as_os_str().is_empty()) {
                std::fs::create_dir_all(dir)?;
            }
            // Copy through a temporary file in the same directory, then rename.
            let tmp = out.with_extension("tmp-umgen");
            std::fs::copy(&built.path, &tmp)
                .map_err(|e| format!("cannot write {}: {e}", tmp.display()))?;
            std::fs::rename(&tmp, out)
                .map_err(|e| format!("cannot write {}: {e}", out.display()))?;
            out.clone()
        }
        None => built.path.clone(),
    };
    let s = &g.stats;
    println!(
        "model                  {} ({})",
        model.name,
        args.model.display()
    );
    println!(
        "size                   {} coordinates, {} bodies, {} constraints, {} parameters ({} fixed)",
        model.coordinates.len(),
        model.bodies.len(),
        model
            .cut_joints
            .iter()
            .map(|c| c.constrained.len())
            .sum::<usize>(),
        model.parameters.len(),
        args.fixed.len()
    );
    println!(
        "operations             {} as trees, {} after CSE (adds {}, muls {}, divs {}, calls {})",
        s.ops_tree.total(),
        s.ops_cse.total(),
        s.ops_cse.adds,
        s.ops_cse.muls,
        s.ops_cse.divs,
        s.ops_cse.calls
    );
    println!("M, k, Q_g program      {} instructions", s.dyn_instructions);
    println!(
        "generated source       {} lines in {} functions",
        s.source_lines, s.functions
    );
    println!(
        "derivation time        {:.4} s",
        g.derive_time.as_secs_f64()
    );
    println!("CSE time               {:.4} s", s.cse_time.as_secs_f64());
    println!(
        "derive + CSE           {:.4} s",
        (g.derive_time + s.cse_time).as_secs_f64()
    );
    println!(
        "source formatting      {:.4} s",
        s.format_time.as_secs_f64()
    );
    match built.compile_time {
        Some(t) => println!(
            "compile time           {:.3} s (cache miss)",
            t.as_secs_f64()
        ),
        None => println!("compile time           0 s (cache hit)"),
    }
    println!("plugin                 {}", target.display());
    Ok(())
}
