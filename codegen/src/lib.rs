//! # railmbs-codegen
//!
//! The symbolic path: from a validated [`Model`] to the equations of motion as
//! expressions ([`derive`](mod@derive), with the `cas` crate), to optimized straight-line
//! Rust ([`emit`]: common-subexpression elimination over all outputs, split into
//! functions of bounded size), to a compiled, cached `cdylib` plugin
//! ([`build_plugin`], with `build-support`). The `umgen` binary (crate `cli`)
//! drives it; `railmbs_runtime::plugin` loads the result.
//!
//! Identifiers stay symbols (runtime inputs of the plugin) unless fixed with
//! [`GenerateOptions::fixed`].

pub mod derive;
pub mod emit;
pub mod lanes;
pub mod sin_cos;

pub use derive::{DeriveOptions, Derived, derive};
pub use emit::{EmitStats, PluginHeader};

use railmbs_build_support::{BuildError, BuildOptions};
use railmbs_models::Model;
use std::path::PathBuf;
use std::time::{Duration, Instant};

/// Options of code generation.
#[derive(Debug, Clone)]
pub struct GenerateOptions {
    /// Names of identifiers to fix at their default values (constant-folded).
    pub fixed: Vec<String>,
    /// Largest number of instructions per generated function (rustc's time is
    /// superlinear in function size; ~500–1000 lines keep it near-linear).
    pub max_instructions_per_function: usize,
    /// Compile for any CPU of the target architecture instead of this machine's
    /// (`-C target-cpu=native`, the default on x86-64). A native plugin is refused, with a
    /// message, on a machine lacking one of its CPU features; a portable one runs anywhere,
    /// slower (see [`native_cpu_flags`]).
    pub portable: bool,
}

impl GenerateOptions {
    /// The defaults: nothing fixed, 600 instructions per function, built for this machine.
    /// (The plugin's ABI version is the interface's, [`railmbs_plugin_abi::ABI_VERSION`].)
    pub fn new() -> Self {
        Self {
            fixed: Vec::new(),
            max_instructions_per_function: 600,
            portable: false,
        }
    }
}

impl Default for GenerateOptions {
    fn default() -> Self {
        Self::new()
    }
}

/// The rustc flags of a plugin built for this machine's CPU: `-C target-cpu=native` on x86-64,
/// where plugins report their CPU features to the loader (`railmbs_target_features`); none
/// elsewhere.
///
/// Measured with `umsim bench [--portable]` (M, k and Q_g per evaluation, AMD EPYC with
/// AVX-512, rustc 1.95, portable → native in one run each): Vehicle 1 (42 dof) 518 → 319 ns,
/// chain30 1407 → 977 ns, chain10 181 → 147 ns. The numeric engine, built by cargo, gains
/// nothing from the same flag (chain30 2430 vs 2438 ns, Vehicle 1 1512 vs 1515 ns with
/// `RUSTFLAGS="-C target-cpu=native"`): the straight-line code uses the 32 vector registers,
/// the three-operand instructions and the 8-wide batch of sin and cos; the numeric engine's
/// recursion over joints does not.
pub fn native_cpu_flags() -> Vec<String> {
    if cfg!(target_arch = "x86_64") {
        vec!["-C".to_owned(), "target-cpu=native".to_owned()]
    } else {
        Vec::new()
    }
}

/// Errors of code generation and compilation.
#[derive(Debug, thiserror::Error)]
pub enum CodegenError {
    /// `--fixed` names an identifier the model does not have.
    #[error("model \"{model}\": --fixed names no identifier \"{name}\"")]
    UnknownFixed {
        /// The model.
        model: String,
        /// The name.
        name: String,
    },
    /// Compiling the plugin failed.
    #[error(transparent)]
    Build(#[from] BuildError),
}

/// Generated source and what it took.
#[derive(Debug, Clone)]
pub struct Generated {
    /// The plugin's Rust source (one file).
    pub source: String,
    /// Sizes and times of the emission.
    pub stats: EmitStats,
    /// Symbolic derivation time (expressions of all outputs).
    pub derive_time: Duration,
    /// CSE, splitting and source emission time (see `stats` for the parts).
    pub emit_time: Duration,
    /// Structural hash of the model, written into the plugin.
    pub model_hash: String,
}

/// Derives the equations of `model` and emits the plugin source.
pub fn generate(model: &Model, opts: &GenerateOptions) -> Result<Generated, CodegenError> {
    let defaults = model.default_parameter_values();
    let mut fixed_idx = Vec::new();
    for name in &opts.fixed {
        let i = model
            .parameter_index(name)
            .ok_or_else(|| CodegenError::UnknownFixed {
                model: model.name.clone(),
                name: name.clone(),
            })?;
        fixed_idx.push(i);
    }
    let start = Instant::now();
    let derived = derive(
        model,
        &DeriveOptions {
            fixed: fixed_idx.clone(),
            defaults: defaults.clone(),
        },
    );
    let derive_time = start.elapsed();
    let start = Instant::now();
    let model_hash = model.structural_hash();
    let header = PluginHeader {
        model_name: &model.name,
        model_hash: &model_hash,
        coordinate_names: model.coordinates.iter().map(|c| c.name.clone()).collect(),
        parameter_names: model.parameters.iter().map(|p| p.name.clone()).collect(),
        input_names: model
            .track_frames
            .iter()
            .flat_map(|f| {
                let body = &model.bodies[f.body].name;
                railmbs_models::TRACK_FRAME_COMPONENTS
                    .iter()
                    .map(move |c| format!("{body}.{c}"))
            })
            .collect(),
        fixed: fixed_idx.iter().map(|&i| (i, defaults[i])).collect(),
    };
    let (source, stats) = emit::emit(
        &derived,
        &header,
        opts.max_instructions_per_function,
        lanes::lanes_for(opts.portable),
    );
    Ok(Generated {
        source,
        stats,
        derive_time,
        emit_time: start.elapsed(),
        model_hash,
    })
}

/// A compiled plugin.
#[derive(Debug, Clone)]
pub struct BuiltPlugin {
    /// The library in the cache.
    pub path: PathBuf,
    /// Its source and the statistics of generating it.
    pub generated: Generated,
    /// `None` on a cache hit.
    pub compile_time: Option<Duration>,
    /// Whether the library came from the cache.
    pub cache_hit: bool,
    /// What was wrong with a damaged cache entry that was rebuilt (see
    /// `railmbs_build_support::BuildOutput::rebuilt_damaged`).
    pub rebuilt_damaged: Option<String>,
}

/// Digest of the generator's own code and compiler (see `build.rs`): part of
/// [`input_digest`], so a plugin indexed by an older generator is not found.
pub const GENERATOR_DIGEST: &str = env!("RAILMBS_GENERATOR_DIGEST");

/// A hash of everything the plugin source of `model` with `opts` is
/// generated from: the whole model (every field but the path it was read
/// from, so parameter defaults and initial values count even where the
/// source does not depend on them), the options, the plugin ABI and
/// [`GENERATOR_DIGEST`]. The key of the plugin index
/// ([`railmbs_build_support::index`]).
pub fn input_digest(model: &Model, opts: &GenerateOptions) -> String {
    let mut located = model.clone();
    located.source = None;
    let mut h = blake3::Hasher::new();
    h.update(b"railmbs plugin input v1\0");
    h.update(GENERATOR_DIGEST.as_bytes());
    h.update(&railmbs_plugin_abi::ABI_VERSION.to_le_bytes());
    h.update(format!("\0{opts:?}\0{located:?}").as_bytes());
    h.finalize().to_hex().to_string()
}

/// The plugin library of a model in the cache: what [`find_or_build_plugin`]
/// returns.
#[derive(Debug, Clone)]
pub struct PluginFile {
    /// The library in the cache.
    pub path: PathBuf,
    /// `None` unless it was compiled now.
    pub compile_time: Option<Duration>,
    /// Whether the library came from the cache.
    pub cache_hit: bool,
    /// Whether it was found through the plugin index, without generating its
    /// source or running rustc.
    pub indexed: bool,
    /// What was wrong with a damaged cache entry that was rebuilt.
    pub rebuilt_damaged: Option<String>,
}

/// The compiled plugin of `model`: found through the plugin index when an
/// earlier build recorded it (no derivation, no source, no rustc process:
/// what a run of a cached model waits for), else [`build_plugin`], which
/// records it for next time.
pub fn find_or_build_plugin(
    model: &Model,
    opts: &GenerateOptions,
    cache_dir: Option<PathBuf>,
) -> Result<PluginFile, CodegenError> {
    let input = input_digest(model, opts);
    if let Some(out) =
        railmbs_build_support::index::lookup(&input, &build_options(opts, cache_dir.clone()))
    {
        return Ok(PluginFile {
            path: out.path,
            compile_time: None,
            cache_hit: true,
            indexed: true,
            rebuilt_damaged: None,
        });
    }
    let built = build_plugin(model, opts, cache_dir)?;
    Ok(PluginFile {
        path: built.path,
        compile_time: built.compile_time,
        cache_hit: built.cache_hit,
        indexed: false,
        rebuilt_damaged: built.rebuilt_damaged,
    })
}

/// The build options of a plugin generated with `opts`.
fn build_options(opts: &GenerateOptions, cache_dir: Option<PathBuf>) -> BuildOptions {
    let mut build = BuildOptions::new(railmbs_plugin_abi::ABI_VERSION);
    if !opts.portable {
        build.extra_flags = native_cpu_flags();
    }
    if let Some(dir) = cache_dir {
        build = build.with_cache_dir(dir);
    }
    build
}

/// Generates and compiles the plugin of `model` through the cache, and
/// records it in the plugin index
/// (`cache_dir`, else `RAILMBS_CACHE_DIR`, else the platform cache directory).
pub fn build_plugin(
    model: &Model,
    opts: &GenerateOptions,
    cache_dir: Option<PathBuf>,
) -> Result<BuiltPlugin, CodegenError> {
    let generated = generate(model, opts)?;
    let build = build_options(opts, cache_dir);
    let out = railmbs_build_support::build_plugin(&generated.source, &build)?;
    railmbs_build_support::index::record(&input_digest(model, opts), &build, &out);
    Ok(BuiltPlugin {
        path: out.path,
        compile_time: out.compile_time,
        cache_hit: out.cache_hit,
        rebuilt_damaged: out.rebuilt_damaged,
        generated,
    })
}
