//! `umsim bench MODEL.ron [--json] [--engine numeric|symbolic|both] [--scenario FILE] [--states N]`:
//! speed of the equations-of-motion engines on one model.
//!
//! Measured on the same pseudo-random states (fixed seed) for every engine:
//!
//! - **eval**: one evaluation of M and k (`Parts::MASS_AND_BIAS`), ns;
//! - **dynamics**: one `ModelSystem::dynamics` call (M, k, gravity, body
//!   Jacobians and the projection of the force elements' wrenches), ns;
//! - **run**: the whole default scenario (or `--scenario`) by `run_scenario`
//!   with no CSV written (integration and output interpolation; the system
//!   setup is included and small), s;
//! - **whole process**: the CPU time of a whole `umsim run SCENARIO` process
//!   with its CSV ([`process`]), what a user waits for: start-up (plugin and
//!   contact tables found in their caches), run and output, s.
//!
//! Timing method ([`timing`]): a batch repeats the evaluation over the states,
//! its length is doubled until one batch takes at least [`BATCH_SECONDS`];
//! then [`BATCHES`] batches are timed (≥ 0.2 s in all) and the median ns per
//! evaluation is reported. A scenario run is repeated (up to [`MAX_RUNS`]
//! times, while the runs took less than [`RUN_SECONDS`] in all) and the median
//! is reported. Times are the CPU time of the measuring thread where the
//! platform has a per-thread CPU clock (Linux), so other processes on a busy
//! machine do not inflate them; elsewhere wall-clock time.
//!
//! A train file (`Train(...)`) in place of the model benchmarks the train: the
//! evaluation times are summed over its vehicles (the train's M and k are
//! block-diagonal in the vehicles), and the run is the whole train scenario by
//! `run_train` with every vehicle on the same engine.
//!
//! The numeric engine is always measured. The symbolic engine comes from
//! [`build_engine`](crate::engine::build_engine); when it is not available
//! its columns are `null` in JSON and the table says why. `derive_s` is the symbolic derivation time of
//! `railmbs_codegen::generate`, and `compile_s` the rest of the plugin build
//! (build time of the engine minus derivation and emission: the rustc run, or
//! about zero on a plugin-cache hit).
//!
//! Why not criterion here: criterion is a `cargo bench` harness (it owns
//! `main` and the command line) with no public API that hands its estimates
//! back to the caller (they go to its terminal report and `target/criterion`
//! files), so a command with its own table and JSON cannot be built on it. What is measured is written once, in
//! [`workload`] ([`MassAndBias`], [`Dynamics`], [`run_scenario_once`] on
//! [`random_states`]); `umsim bench` times it with the small batch loop of
//! [`timing`] (a quick report on any model, both engines, on the command
//! line), and the criterion benchmark `cargo bench -p railmbs-cli --bench
//! equations` times the same calls on the chain models with criterion's
//! statistics (for tracking the numeric engine's speed across commits).
//!
//! The modules: `model` (a model file and its scenario), `train` (a
//! train file), [`workload`] (what is timed), [`timing`] (how) and
//! [`report`] (the table and the JSON).

mod model;
pub mod process;
pub mod report;
pub mod timing;
mod train;
pub mod workload;

pub use model::default_scenario;
pub use report::{BenchReport, EngineTimes};
pub use timing::{BATCH_SECONDS, BATCHES, MAX_RUNS, RUN_SECONDS, time_per_call};
pub use workload::{Dynamics, MassAndBias, State, random_states, run_scenario_once};

use std::path::PathBuf;

/// Which engines to measure (the numeric engine is always measured).
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum BenchEngine {
    /// The numeric-iterative engine only.
    Numeric,
    /// The numeric engine and the compiled symbolic plugin.
    Symbolic,
    /// Same as `symbolic`: both engines.
    Both,
}

/// Arguments of `umsim bench`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Model file (RON), or a train file (`Train(...)`).
    pub model: PathBuf,
    /// Print one JSON object instead of the table.
    #[arg(long)]
    pub json: bool,
    /// Engines to compare.
    #[arg(long, value_enum, default_value_t = BenchEngine::Both)]
    pub engine: BenchEngine,
    /// Scenario to run (default: `<model dir>/../scenarios/<model stem>*.ron`
    /// whose model is this model).
    #[arg(long)]
    pub scenario: Option<PathBuf>,
    /// Number of random states the evaluations cycle through.
    #[arg(long, default_value_t = 16)]
    pub states: usize,
    /// Creep-force law of every wheel–rail element, overriding the model's,
    /// in the syntax of `umsim creep --method` (see `umsim creep --help`).
    #[arg(long, long_help = crate::creep::LAW_HELP)]
    pub creep: Option<String>,
    /// Build the plugin for any CPU of this architecture instead of this machine's
    /// (`umgen --portable`), to measure what the native CPU features bring.
    #[arg(long)]
    pub portable: bool,
}

/// Parses `--creep`: a creep law in the syntax of
/// [`railmbs_wheelrail::creep::CreepLawSpec`] (as `umsim creep --method`).
pub fn parse_creep(
    text: &str,
) -> Result<railmbs_models::CreepLawSpec<railmbs_models::Expr>, String> {
    let spec: railmbs_models::CreepLawSpec = text.parse().map_err(|e| format!("--creep: {e}"))?;
    Ok(spec.map(|_, &x| railmbs_models::Expr::Num(x)))
}

/// Runs all measurements (no printing).
pub fn measure(args: &Args) -> Result<BenchReport, Box<dyn std::error::Error>> {
    if args.states == 0 {
        return Err("--states must be at least 1".into());
    }
    if train::is_train_file(&args.model) {
        if args.scenario.is_some() {
            return Err(format!(
                "{}: a train file is its own scenario; leave out --scenario",
                args.model.display()
            )
            .into());
        }
        return train::measure_train(args);
    }
    model::measure_model(args)
}

/// Runs `umsim bench`.
pub fn run(args: &Args) -> Result<(), Box<dyn std::error::Error>> {
    let report = measure(args)?;
    if args.json {
        println!("{}", serde_json::to_string_pretty(&report.to_json())?);
    } else {
        print!("{}", report.table());
    }
    Ok(())
}
