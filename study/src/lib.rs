//! # railmbs-study
//!
//! Parameter studies: many runs of one scenario with different parameters,
//! each reduced to a row of scalars. The model's symbolic plugin is built
//! **once** per study (parameters are runtime inputs of the plugin) and every
//! case runs in process on it, streaming its rows into reducers (no output
//! table is kept in memory unless the time series are asked for).
//!
//! The pieces are separate so that another front end (the Python package's
//! Dask backend, a Slurm job array) can drive them:
//!
//! - [`Study::load`] reads a study file (located errors, like model files);
//!   [`Study::cases`] lists its cases, each with a stable [`Case::id`];
//! - [`StudyEngine::prepare`] builds (through the plugin cache) and loads the
//!   model's plugin once (a train: one per distinct model file);
//!   [`StudyEngine::from_plugins`] loads plugins built elsewhere (shipped to
//!   a worker);
//! - [`StudyEngine::run_case`] runs one case to a [`CaseResult`] (a failed
//!   run is a result with its error, not an error);
//! - [`ResultStore`] is the append-only result table (one CSV row per case,
//!   flushed per row) that resumes: [`ResultStore::finished`] are the ids
//!   to skip; a partly written last line (a killed process) is dropped;
//! - [`run_local`] runs the pending cases on a local pool of threads and
//!   appends each result as it finishes.
//!
//! ## The study file
//!
//! ```ron
//! // Vehicle 1 on track case 1: primary longitudinal stiffness (which sets
//! // the primary yaw stiffness) of both bogies × running speed.
//! Study(
//!     // The scenario (or train) every case starts from, relative to this file.
//!     scenario: "../scenarios/vehicle1_tc1.ron",
//!     // Symbolic (default: one compiled plugin for all cases) or Numeric.
//!     engine: Symbolic,
//!     // Optional: end time of every case, s (replaces the scenario's).
//!     end_time: Some(3.0),
//!     // Optional: parameters set in every case; `{name}` is replaced by the
//!     // case's value of variable `name` (in parentheses).
//!     set: { "Bogie1.kx": "{kx}", "Bogie2.kx": "{kx}", "v0": "{@speed}" },
//!     // The cases: Grid (full factorial, the last variable fastest), List,
//!     // Table (a CSV file) or LatinHypercube.
//!     cases: Grid({ "kx": [15e6, 31.391e6], "@speed": [4.4, 6.0] }),
//!     // What each case is reduced to.
//!     reductions: [
//!         Assessment,
//!         Max(column: "Bogie1.WS1.contact.L.Y [N]", window: Some(Distance(20.0, 30.0))),
//!         Rms(column: "*.contact.*.Y [N]"),
//!     ],
//!     // Optional: write each case's output as series/<case id>.csv.
//!     time_series: false,
//!     // Optional: the format of those files, Csv (default) or Parquet
//!     // (series/<case id>.parquet: one DOUBLE column per output column,
//!     // the values bit for bit).
//!     series_format: Csv,
//! )
//! ```
//!
//! ### Variables
//!
//! A case sets **variables**. A variable named like a model parameter sets
//! that parameter (through [`Scenario::set_parameter`](railmbs_models::Scenario::set_parameter));
//! its value is a number or an expression over the model's parameters.
//! Three names are reserved, written with `@` (never a parameter name):
//!
//! - `@speed`: the running speed, m/s (a scenario on a track at constant speed);
//! - `@end_time`: the end time, s (replaces the study's `end_time`);
//! - `@macro`: the name of a model macro applied after the scenario's own
//!   (`""` for none).
//!
//! In a train file (`Train(...)`), parameters are train-wide (every vehicle
//! whose model has them, as `umsim run --set` on a train) and `@macro` is
//! not available (each vehicle has its own macros).
//!
//! Any other name is a free variable: it must be used in `set`, where
//! `"{name}"` stands for its value. A model's macros are named sets of
//! parameter values, so every case runs the same model structure and shares
//! one plugin.
//!
//! ### Cases
//!
//! - `Grid({ "a": [1, 2], "b": [10, 20, 30] })`: every combination, in the
//!   order of an odometer whose last variable turns fastest
//!   (a=1 b=10, a=1 b=20, …, a=2 b=30);
//! - `List([{ "a": 1, "b": 10 }, { "a": 2, "b": 30 }])`: the cases as
//!   written, each with the same variables;
//! - `Table("cases.csv")`: a CSV file (relative to the study file), a header
//!   of variable names and one case per line; a cell that reads as a number
//!   is a number, any other is an expression (or a macro name);
//! - `LatinHypercube(samples: 16, seed: 7, ranges: { "a": (1.0, 2.0) })`: a
//!   seeded Latin hypercube: each range is cut into `samples` strata of equal
//!   width and every stratum of every variable holds exactly one sample, at a
//!   uniformly random place within it; the strata are paired across variables
//!   by independent random permutations (ChaCha8 seeded with `seed`, so the
//!   cases are the same on every machine).
//!
//! ### Case ids
//!
//! A case's id is the first 16 hexadecimal digits of the BLAKE3 hash of its
//! [canonical text](Case::canonical): what the run depends on beyond the
//! scenario file's contents, one item per line,
//!
//! ```text
//! railmbs-study-case/1
//! scenario=../scenarios/vehicle1_tc1.ron
//! engine=symbolic
//! end_time=3
//! speed=4.4
//! macros=
//! parameter Bogie1.kx=(15000000)
//! parameter Bogie2.kx=(15000000)
//! parameter v0=(4.4)
//! ```
//!
//! with the scenario path as written in the study file, numbers in Rust's
//! shortest round-trip form (`{}`), an empty value for what the case leaves
//! as the scenario has it, the macros the case adds joined by `,`, and the
//! parameters it sets sorted by name, each with the expression text it sets.
//! The id is the same on every machine and in every run; it does not cover
//! the contents of the scenario, model and track files (change those and
//! start a new result folder).
//!
//! ### Reductions
//!
//! Columns are named as in the output CSV (`umsim info` lists them);
//! `column` may be a glob (`*.contact.*.Y [N]`), reduced over all the columns
//! it matches (the result names the one that gave the value). A `window` is
//! `Some(Time(t0, t1))` (s) or `Some(Distance(s0, s1))` (m, the `s[m]`
//! column of a run on a track); without one, the whole run. Values are taken
//! at the output rows (every `interval` of the scenario's `output`).
//!
//! - `Assessment`: the run's EN 14363 table (the runtime's
//!   [`AssessmentReducer`](railmbs_runtime::run::AssessmentReducer), over the
//!   accepted steps) reduced over all wheelsets: the largest judged Y/Q (the
//!   2 m sliding mean, or the peak on a run shorter than 2 m, as the run's
//!   own table judges) and |ΣY| with the element and side, time, distance
//!   and limit; the largest and smallest Q;
//! - `Max`, `Min`, `MaxAbs` (largest |x|) with the time of the extreme, and
//!   `Rms` (root mean square over the rows in the window), each with an
//!   optional `name` for its result column;
//! - `CriticalSpeed(column: "B.WS1.ws.y", amplitude: 1e-4, window: 1.0)`:
//!   for a decelerating run (`speed_profile`), the running speed where the
//!   lateral limit cycle dies out, by the runtime's limit-cycle detection
//!   (`railmbs_runtime::analysis::critical::LimitCycleDetector`, the one
//!   `umsim critical-speed` uses). The amplitude at time t is half the range
//!   (max − min) of `column` over the `window` seconds before t (choose it
//!   longer than a hunting period); a limit cycle is established once the
//!   amplitude reaches twice `amplitude` (same unit as the column) and has
//!   died out once it falls below `amplitude` (hysteresis). The critical
//!   speed is the running speed `v[m/s]` at the last extreme of the last
//!   limit cycle that died out (the row that left the window as the
//!   amplitude fell below `amplitude`); it is empty when no limit cycle was
//!   established or one still goes on at the end of the run (it survives to
//!   the lowest speed).
//!
//! ### Analyses
//!
//! Instead of (or besides) a time run, a case can be reduced by one of the
//! runtime's analyses at the case's parameters and speed
//! ([`railmbs_runtime::analysis`], the functions of `umsim modes` and `umsim
//! curving`), written in `reductions` like the run's reductions:
//!
//! - `LeastDamping(name: Some("hunting"))` (or `LeastDamping()`): the least
//!   damped lateral mode at the case's steady state and speed, as `umsim
//!   modes` reports it; columns NAME (the damping ratio, 1), `NAME.f[Hz]`
//!   (its damped frequency) and `NAME.mode` (its name). Default name
//!   `least_damping`;
//! - `LinearCriticalSpeed(speeds: (20.0, 80.0, 2.0))`: the root locus at the
//!   speeds FROM, FROM + STEP, … TO (m/s; `umsim modes --speed
//!   FROM:TO:STEP`) and the linear critical speed, where the least damped
//!   lateral mode's damping ratio first crosses zero (m/s, empty when it does
//!   not cross in the range). Default name `linear_critical_speed[m/s]`;
//! - `Curving(radius: 300.0, cant: 0.1, speed: Some(20.0))`: the
//!   quasi-static curving solution (`umsim curving`) on a circular curve of
//!   radius m (positive left, negative right) and cant m (default 0), at
//!   `speed` m/s (default: the case's speed); columns `NAME.YQ.max` and
//!   `NAME.YQ.wheel` (the largest Y/Q of all wheels and which, `ELEMENT
//!   left|right`), `NAME.sumY.max[N]` and `NAME.sumY.element` (largest
//!   |ΣY|), `NAME.Q.max[N]`, `NAME.Q.min[N]`, `NAME.y.max[m]` and
//!   `NAME.yaw.max[rad]` (the largest |lateral position| and |angle of
//!   attack| of the wheelsets). Default name `curving`.
//!
//! Their columns follow those of the run's reductions, in the file's order.
//! A study whose `reductions` are all analyses (and without `time_series`)
//! runs no time simulation: `steps` and `t_end[s]` are 0. Analyses apply
//! to a single vehicle (`Scenario(...)`), not to a train. An analysis that
//! fails (no equilibrium, say) fails its case, with the message.
//!
//! ## The result table
//!
//! `results.csv`, one row per case: `index`, `case_id`, the variables,
//! `status` (`ok` or `failed`), `error`, `steps`, `rejected_steps`,
//! `t_end[s]` (time reached), `integration_time[s]` (the integration's
//! time by the runner's clock: CPU time of the case's thread, wall-clock
//! time where the platform has no thread clock), `cpu_time[s]` (CPU time of
//! the case's thread: set-up, run, reductions), `wall_time[s]` (wall-clock time of the case), then the
//! reductions. A failed case has empty reductions
//! (values of a run cut short are not written as if fine) and its error.

mod analysis;
mod cases;
mod engine;
mod format;
mod pool;
mod reduce;
mod series;
mod store;

pub use analysis::{Analysis, AnalysisKind};
pub use cases::{Case, Overrides};
pub use engine::{CaseOptions, CaseResult, CaseStatus, PluginBuilds, StudyEngine};
pub use format::{CaseSource, EngineKind, Study, StudyScenario};
pub use pool::{PoolOptions, PoolSummary, run_local, threads};
pub use reduce::{Cell, Reduction, ReductionKind, Stat, Window, reduce_table};
pub use series::{ParquetFile, SeriesFormat};
pub use store::{ResultStore, case_file, collect_case_files, read_case_file, write_case_file};

/// Errors of a study as a whole (a case's own failure is a [`CaseResult`]).
#[derive(Debug, thiserror::Error)]
pub enum StudyError {
    /// The study file, or a file it names, is wrong (located).
    #[error(transparent)]
    File(#[from] railmbs_models::ModelErrors),
    /// The model's plugin could not be built or loaded.
    #[error("plugin of model \"{model}\": {message}")]
    Plugin {
        /// The model's name.
        model: String,
        /// What went wrong.
        message: String,
    },
    /// A result file is unusable.
    #[error("{}: {message}", path.display())]
    Results {
        /// The file.
        path: std::path::PathBuf,
        /// What is wrong.
        message: String,
    },
    /// A file could not be read or written.
    #[error("{}: {source}", path.display())]
    Io {
        /// The file.
        path: std::path::PathBuf,
        /// The operating system's error.
        source: std::io::Error,
    },
    /// The study was interrupted (Ctrl-C): the cases finished before are
    /// recorded.
    #[error("interrupted")]
    Interrupted,
}
