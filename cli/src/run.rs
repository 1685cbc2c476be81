//! `umsim run SCENARIO.ron [--engine numeric|symbolic] [--plugin FILE] [-o out.csv]
//! [--set NAME=VALUE]… [--end-time SECONDS]`.

use crate::engine::{Engine, build_engine, build_run_engine};
use railmbs_runtime::run::{Interruptible, RunSummary, output_sink, run_scenario_into};
use std::io::IsTerminal;
use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

/// Arguments of `umsim run`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Scenario file (RON).
    pub scenario: PathBuf,
    /// Which equations of motion to use.
    #[arg(long, value_enum, default_value_t = Engine::Numeric)]
    pub engine: Engine,
    /// A compiled plugin of the scenario's model (implies `--engine symbolic`).
    #[arg(long)]
    pub plugin: Option<PathBuf>,
    /// Output CSV (overrides the scenario's `output_file`).
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// No progress bar and no summary table.
    #[arg(short, long)]
    pub quiet: bool,
    /// Sets a model parameter for this run, `NAME=VALUE` (VALUE an expression
    /// over the parameters, in the parameter's own unit, SI); repeatable, and
    /// it replaces the scenario's own assignment of NAME. In a train file it
    /// is a train-wide parameter (every vehicle whose model has it).
    #[arg(long = "set", value_name = "NAME=VALUE", value_parser = parse_assignment)]
    pub set: Vec<(String, String)>,
    /// Runs to this end time instead of the scenario's, s.
    #[arg(long, value_name = "SECONDS")]
    pub end_time: Option<f64>,
    /// A train's vehicles are evaluated in N threads (overrides the train
    /// file's `threads`; 1: sequentially). The output does not depend on it.
    #[arg(long, value_name = "N")]
    pub threads: Option<usize>,
    /// Linear solver of Park's method (overrides the integrator's `solver`):
    /// `dense` LU of the whole iteration matrix, or `block`, the bordered
    /// block-diagonal LU of a train (vehicles as blocks, the coupled bodies'
    /// coordinates as the border) or of a vehicle (bogies as blocks, the car
    /// body and what joins it as the border); dense for models without that
    /// structure.
    #[arg(long, value_enum)]
    pub solver: Option<Solver>,
}

/// `--solver`: [`railmbs_models::LinearSolverKind`] on the command line.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Solver {
    /// Dense LU of the whole matrix.
    Dense,
    /// Bordered block-diagonal LU where the system has a block pattern.
    Block,
}

/// Sets Park's linear solver of `spec` to `solver` (`--solver`).
fn set_solver(
    spec: &mut railmbs_models::IntegratorSpec,
    solver: Option<Solver>,
) -> Result<(), Box<dyn std::error::Error>> {
    let Some(solver) = solver else {
        return Ok(());
    };
    match spec {
        railmbs_models::IntegratorSpec::Park { solver: s, .. } => {
            *s = match solver {
                Solver::Dense => railmbs_models::LinearSolverKind::Dense,
                Solver::Block => railmbs_models::LinearSolverKind::Block,
            };
            Ok(())
        }
        railmbs_models::IntegratorSpec::Rk4 { .. } => {
            Err("--solver: the scenario's integrator is RK4, which has no Newton solve".into())
        }
    }
}

/// `NAME=VALUE` of `--set`.
pub(crate) fn parse_assignment(text: &str) -> Result<(String, String), String> {
    match text.split_once('=') {
        Some((name, value)) if !name.trim().is_empty() && !value.trim().is_empty() => {
            Ok((name.trim().to_string(), value.trim().to_string()))
        }
        _ => Err(format!("expected NAME=VALUE, got {text:?}")),
    }
}

/// Runs `umsim run`.
pub fn run(args: &Args) -> Result<(), Box<dyn std::error::Error>> {
    let mut scenario = match railmbs_models::load_any_scenario(&args.scenario)? {
        railmbs_models::AnyScenario::Single(s) => s,
        railmbs_models::AnyScenario::Train(mut t) => {
            for (name, value) in &args.set {
                t.set_parameter(name, value);
            }
            if let Some(end) = args.end_time {
                t.set_end_time(end)
                    .map_err(|e| format!("--end-time: {e}"))?;
            }
            if let Some(n) = args.threads {
                if n == 0 {
                    return Err("--threads: at least 1".into());
                }
                t.threads = n;
            }
            set_solver(&mut t.integrator, args.solver)?;
            return run_train(args, &t);
        }
    };
    for (name, value) in &args.set {
        scenario.set_parameter(name, value);
    }
    set_solver(&mut scenario.integrator, args.solver)?;
    if let Some(t) = args.end_time {
        scenario
            .set_end_time(t)
            .map_err(|e| format!("--end-time: {e}"))?;
    }
    let model = railmbs_models::load_model(&scenario.model)?;
    let engine = if args.plugin.is_some() {
        Engine::Symbolic
    } else {
        args.engine
    };
    if matches!(
        scenario.integrator,
        railmbs_models::IntegratorSpec::Park { .. }
    ) {
        engine.require_mass_matrix("Park's implicit method (the scenario's integrator)")?;
    }
    let equations = build_run_engine(&model, engine, args.plugin.as_deref(), &scenario.integrator)?;
    let output = args.output.clone().or_else(|| scenario.output_file.clone());

    let bar = progress_bar(args);
    let t_end = scenario.end_time;
    let mut file = output_sink(output.as_deref(), &scenario.input_files())?;
    let mut sink = Interruptible::new(&mut *file, interrupt_flag());
    let summary = run_scenario_into(&scenario, &model, equations, &mut sink, |t| {
        if let Some(b) = &bar {
            b.set_position((1000.0 * t / t_end) as u64);
            b.set_message(format!("{t:.3}"));
        }
    });
    finish(
        args,
        bar,
        interrupted_note(summary, output.as_deref())?,
        output,
    )
}

/// A flag set by Ctrl-C (SIGINT): the run stops at its next output row and
/// keeps what it wrote. A second Ctrl-C ends the process at once.
pub(crate) fn interrupt_flag() -> Arc<AtomicBool> {
    // One handler per process (the system allows only one), installed by
    // the first run; later runs share its flag.
    static FLAG: std::sync::OnceLock<Arc<AtomicBool>> = std::sync::OnceLock::new();
    FLAG.get_or_init(|| {
        let flag = Arc::new(AtomicBool::new(false));
        let set = flag.clone();
        // Without a handler (another one is installed) Ctrl-C keeps its
        // default: the process ends, the rows written are kept.
        let _ = ctrlc::set_handler(move || {
            if set.swap(true, Ordering::SeqCst) {
                std::process::exit(130);
            }
        });
        flag
    })
    .clone()
}

/// An interrupted run's error, with where its rows are.
fn interrupted_note(
    summary: Result<RunSummary, railmbs_runtime::run::RunError>,
    output: Option<&std::path::Path>,
) -> Result<RunSummary, Box<dyn std::error::Error>> {
    match summary {
        Err(e @ railmbs_runtime::run::RunError::Interrupted { .. }) => Err(match output {
            Some(path) => format!("{e}; {} keeps them", path.display()),
            None => format!("{e} (no output file)"),
        }
        .into()),
        other => Ok(other?),
    }
}

/// A progress bar on a terminal unless `--quiet`.
fn progress_bar(args: &Args) -> Option<indicatif::ProgressBar> {
    if args.quiet || !std::io::stderr().is_terminal() {
        return None;
    }
    let bar = indicatif::ProgressBar::new(1000);
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{spinner} [{elapsed_precise}] {wide_bar} t = {msg} s, {eta} left",
        )
        .expect("valid progress template"),
    );
    bar.set_message("0.000");
    Some(bar)
}

/// A train's models and engines: each distinct model file loaded once
/// (with `creep` as the law of its wheel–rail elements, if given) and, for
/// the symbolic engine, its plugin built (or found in the cache) once and
/// shared by identical vehicles; `plugin` serves trains whose vehicles all
/// use one model.
pub struct TrainEngines {
    /// The distinct models, in order of first use.
    pub models: Vec<railmbs_models::Model>,
    /// Index into `models` of each vehicle's model, in vehicle order.
    pub vehicle_models: Vec<usize>,
    /// One engine per vehicle, in vehicle order.
    pub engines: Vec<Box<dyn railmbs_runtime::Equations>>,
}

impl TrainEngines {
    /// Loads the models of `train` and builds one `engine` per vehicle.
    ///
    /// # Errors
    /// A model file's problems, a plugin that cannot be built or loaded,
    /// `plugin` given for a train of several model files.
    pub fn build(
        train: &railmbs_models::TrainScenario,
        engine: Engine,
        plugin: Option<&std::path::Path>,
        creep: Option<&railmbs_models::CreepLawSpec<railmbs_models::Expr>>,
    ) -> Result<Self, Box<dyn std::error::Error>> {
        // Distinct model files, loaded (and compiled) once each.
        let mut files: Vec<(PathBuf, railmbs_models::Model, Option<PathBuf>)> = Vec::new();
        let mut which = Vec::new();
        for v in &train.vehicles {
            let k = match files.iter().position(|(p, _, _)| p == &v.model) {
                Some(k) => k,
                None => {
                    let mut model = railmbs_models::load_model(&v.model)?;
                    if let Some(law) = creep {
                        model.set_creep_law(law);
                    }
                    let plugin = match (engine, plugin) {
                        (Engine::Numeric | Engine::NumericAba, _) => None,
                        (Engine::Symbolic, Some(p)) => Some(p.to_path_buf()),
                        (Engine::Symbolic, None) => {
                            Some(crate::engine::build_symbolic(&model, false)?.path)
                        }
                    };
                    files.push((v.model.clone(), model, plugin));
                    files.len() - 1
                }
            };
            which.push(k);
        }
        if plugin.is_some() && files.len() > 1 {
            return Err(format!(
                "--plugin serves one model, but the train {} uses {} model files; \
                 leave it out to build each model's plugin",
                train.source.display(),
                files.len()
            )
            .into());
        }
        let engines = which
            .iter()
            .map(|&k| build_engine(&files[k].1, engine, files[k].2.as_deref()))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Self {
            models: files.into_iter().map(|(_, m, _)| m).collect(),
            vehicle_models: which,
            engines,
        })
    }
}

/// `umsim run` of a train file: one engine per vehicle ([`TrainEngines`]).
fn run_train(
    args: &Args,
    train: &railmbs_models::TrainScenario,
) -> Result<(), Box<dyn std::error::Error>> {
    let engine = if args.plugin.is_some() {
        Engine::Symbolic
    } else {
        args.engine
    };
    engine.require_mass_matrix("a train (its system solves the coupled vehicles' M)")?;
    let TrainEngines {
        models,
        vehicle_models,
        engines,
    } = TrainEngines::build(train, engine, args.plugin.as_deref(), None)?;
    let models: Vec<&railmbs_models::Model> = vehicle_models.iter().map(|&k| &models[k]).collect();
    let output = args.output.clone().or_else(|| train.output_file.clone());
    let bar = progress_bar(args);
    let t_end = train.end_time;
    let mut file = output_sink(output.as_deref(), &train.input_files())?;
    let mut sink = Interruptible::new(&mut *file, interrupt_flag());
    let summary = railmbs_runtime::train::run_train_into(train, &models, engines, &mut sink, |t| {
        if let Some(b) = &bar {
            b.set_position((1000.0 * t / t_end) as u64);
            b.set_message(format!("{t:.3}"));
        }
    });
    finish(
        args,
        bar,
        interrupted_note(summary, output.as_deref())?,
        output,
    )
}

/// Clears the progress bar, prints the summary, turns a simulation error
/// into the command's error.
fn finish(
    args: &Args,
    bar: Option<indicatif::ProgressBar>,
    summary: RunSummary,
    output: Option<PathBuf>,
) -> Result<(), Box<dyn std::error::Error>> {
    if let Some(b) = bar {
        b.finish_and_clear();
    }
    if !args.quiet {
        print_summary(&summary, output.as_deref());
    }
    match summary.error {
        Some(e) => Err(format!(
            "{e} (scenario {}; {} output rows up to t = {} s were written{})",
            args.scenario.display(),
            summary.rows,
            summary.t_end,
            output
                .as_ref()
                .map(|p| format!(" to {}", p.display()))
                .unwrap_or_default()
        )
        .into()),
        None => Ok(()),
    }
}

/// The summary line with the CPU time of the whole `umsim` process (what
/// the user waits for; `umsim bench` reads it).
pub const PROCESS_CPU_LABEL: &str = "process CPU time       ";

/// Prints the run summary; a closed stdout (`umsim run … | head`) is not an error.
fn print_summary(s: &RunSummary, output: Option<&std::path::Path>) {
    use std::io::Write;
    let text = summary_text(s, output);
    let _ = std::io::stdout().lock().write_all(text.as_bytes());
}

fn summary_text(s: &RunSummary, output: Option<&std::path::Path>) -> String {
    use std::fmt::Write;
    let mut out = String::new();
    macro_rules! say {
        ($($arg:tt)*) => {{
            let _ = writeln!(out, $($arg)*);
        }};
    }
    say!("engine                 {}", s.engine);
    say!("simulated time         {} s", s.t_end);
    say!("steps                  {}", s.steps);
    say!("rejected steps         {}", s.rejected_steps);
    say!("Newton iterations      {}", s.newton_iterations);
    say!("Jacobian evaluations   {}", s.jacobian_evaluations);
    say!("equation evaluations   {}", s.dynamics_evaluations);
    say!("CPU time               {:.4} s", s.cpu_time);
    if let Ok(process) = cpu_time::ProcessTime::try_now() {
        say!(
            "{PROCESS_CPU_LABEL}{:.4} s (start-up, run and output so far)",
            process.as_duration().as_secs_f64()
        );
    }
    say!("real-time factor       {:.2}", s.realtime_factor());
    if s.steps > 0 {
        say!(
            "CPU time per step      {:.3} µs",
            1e6 * s.cpu_time / s.steps as f64
        );
    }
    if !s.assessment.is_empty() {
        say!("");
        say!(
            "{:<28} {:<12} {:>12} {:>9} {:>12} {:<11} {:>6}",
            "element",
            "quantity",
            "max",
            "at t [s]",
            "limit",
            "",
            "ratio"
        );
        for a in &s.assessment {
            let (limit, ratio) = match a.limit {
                Some(l) => (format!("{l:.4}"), format!("{:.2}", a.max / l)),
                None => (String::new(), String::new()),
            };
            say!(
                "{:<28} {:<12} {:>12.4} {:>9.3} {:>12} {:<11} {:>6}",
                a.element,
                format!("{} [{}]", a.quantity, a.unit),
                a.max,
                a.time,
                limit,
                a.limit_name,
                ratio
            );
        }
        say!("");
    }
    match output {
        Some(p) => say!("output                 {} ({} rows)", p.display(), s.rows),
        None => {
            say!("output                 none (give -o FILE or output_file in the scenario)")
        }
    }
    out
}
