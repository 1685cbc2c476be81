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
//!   setup is included and small), s.
//!
//! Timing method: a batch repeats the evaluation over the states, its length is
//! doubled until one batch takes at least [`BATCH_SECONDS`]; then
//! [`BATCHES`] batches are timed (≥ 0.2 s in all) and the median ns per
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
//! [`build_engine`]; when it is not available its columns are `null` in JSON
//! and the table says why. `derive_s` is the symbolic derivation time of
//! `railmbs_codegen::generate`, and `compile_s` the rest of the plugin build
//! (build time of the engine minus derivation and emission: the rustc run, or
//! about zero on a plugin-cache hit).

use crate::engine::{Engine, build_engine, build_engine_with};
use nalgebra::{DMatrix, DVector};
use railmbs_models::{Model, Scenario};
use railmbs_runtime::run::run_scenario;
use railmbs_runtime::{Equations, Evaluation, MechanicalSystem, ModelSystem, Parts};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// A stopwatch on the thread's CPU clock (the `cpu-time` crate), or on the wall
/// clock where the platform has none.
struct Stopwatch {
    cpu: Option<cpu_time::ThreadTime>,
    wall: Instant,
}

impl Stopwatch {
    fn start() -> Self {
        Self {
            cpu: cpu_time::ThreadTime::try_now().ok(),
            wall: Instant::now(),
        }
    }
    /// Seconds since `start`.
    fn seconds(&self) -> f64 {
        match &self.cpu {
            Some(t) => t.elapsed().as_secs_f64(),
            None => self.wall.elapsed().as_secs_f64(),
        }
    }
}

/// Minimum duration of one timed batch, s.
pub const BATCH_SECONDS: f64 = 0.04;
/// Number of timed batches (the median is reported).
pub const BATCHES: usize = 5;
/// Scenario runs stop repeating once they took this long in all, s.
pub const RUN_SECONDS: f64 = 1.0;
/// Most scenario runs per engine.
pub const MAX_RUNS: usize = 5;

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

/// The measurements of one engine.
#[derive(Debug, Clone, Default)]
pub struct EngineTimes {
    /// M and k, ns per evaluation.
    pub eval_ns: Option<f64>,
    /// `ModelSystem::dynamics`, ns per call.
    pub dynamics_ns: Option<f64>,
    /// Scenario run (`run_scenario` without CSV output), s.
    pub run_s: Option<f64>,
    /// Integration steps of the scenario run.
    pub run_steps: Option<usize>,
    /// Why something is missing.
    pub note: Option<String>,
}

/// Everything `umsim bench` measures.
#[derive(Debug, Clone)]
pub struct BenchReport {
    /// Name of the model (for a train file, the train's name and its number
    /// of vehicles).
    pub model: String,
    /// The model (or train) file given on the command line.
    pub model_file: PathBuf,
    /// Number of degrees of freedom (for a train, summed over its vehicles).
    pub dof: usize,
    /// Number of bodies (for a train, summed over its vehicles).
    pub bodies: usize,
    /// Number of random states evaluated at (`--states`).
    pub states: usize,
    /// The scenario file that was run, if any (a train file is its own
    /// scenario).
    pub scenario: Option<PathBuf>,
    /// Why no scenario was run.
    pub scenario_note: Option<String>,
    /// Measurements of the numeric-iterative engine.
    pub numeric: EngineTimes,
    /// Measurements of the compiled symbolic plugin; what was not measured
    /// is `None` and its `note` says why.
    pub symbolic: EngineTimes,
    /// Symbolic derivation, s.
    pub derive_s: Option<f64>,
    /// Plugin build beyond derivation and emission (compilation or cache), s.
    pub compile_s: Option<f64>,
    /// The `--creep` override, if any.
    pub creep: Option<String>,
}

fn ratio(a: Option<f64>, b: Option<f64>) -> Option<f64> {
    match (a, b) {
        (Some(a), Some(b)) if b > 0.0 => Some(a / b),
        _ => None,
    }
}

impl BenchReport {
    /// numeric / symbolic time of one (M, k) evaluation.
    pub fn eval_ratio(&self) -> Option<f64> {
        ratio(self.numeric.eval_ns, self.symbolic.eval_ns)
    }
    /// numeric / symbolic time of one `dynamics` call.
    pub fn dynamics_ratio(&self) -> Option<f64> {
        ratio(self.numeric.dynamics_ns, self.symbolic.dynamics_ns)
    }
    /// numeric / symbolic time of the scenario run.
    pub fn run_ratio(&self) -> Option<f64> {
        ratio(self.numeric.run_s, self.symbolic.run_s)
    }

    /// The JSON object printed by `--json`.
    pub fn to_json(&self) -> serde_json::Value {
        serde_json::json!({
            "model": self.model,
            "model_file": self.model_file.display().to_string(),
            "dof": self.dof,
            "bodies": self.bodies,
            "states": self.states,
            "scenario": self.scenario.as_ref().map(|p| p.display().to_string()),
            "scenario_note": self.scenario_note,
            "numeric_eval_ns": self.numeric.eval_ns,
            "symbolic_eval_ns": self.symbolic.eval_ns,
            "eval_ratio": self.eval_ratio(),
            "numeric_dynamics_ns": self.numeric.dynamics_ns,
            "symbolic_dynamics_ns": self.symbolic.dynamics_ns,
            "dynamics_ratio": self.dynamics_ratio(),
            "numeric_run_s": self.numeric.run_s,
            "symbolic_run_s": self.symbolic.run_s,
            "run_ratio": self.run_ratio(),
            "numeric_run_steps": self.numeric.run_steps,
            "symbolic_run_steps": self.symbolic.run_steps,
            "creep": self.creep,
            "derive_s": self.derive_s,
            "compile_s": self.compile_s,
            "numeric_note": self.numeric.note,
            "symbolic_note": self.symbolic.note,
        })
    }

    /// The human-readable table.
    pub fn table(&self) -> String {
        use std::fmt::Write as _;
        let mut s = String::new();
        let _ = writeln!(
            s,
            "model {} ({}): {} coordinates, {} bodies, {} random states",
            self.model,
            self.model_file.display(),
            self.dof,
            self.bodies,
            self.states
        );
        match (&self.scenario, &self.scenario_note) {
            (Some(p), _) => {
                let _ = writeln!(s, "scenario {}", p.display());
                if let Some(c) = &self.creep {
                    let _ = writeln!(s, "creep law of every wheel–rail element: {c}");
                }
            }
            (None, Some(n)) => {
                let _ = writeln!(s, "scenario: none ({n})");
            }
            (None, None) => {}
        }
        let ns = |x: Option<f64>| x.map_or("-".to_string(), |v| format!("{v:.1} ns"));
        let sec = |x: Option<f64>| x.map_or("-".to_string(), |v| format!("{v:.4} s"));
        let r = |x: Option<f64>| x.map_or("-".to_string(), |v| format!("{v:.2}"));
        let per_step = |t: Option<f64>, n: Option<usize>| match (t, n) {
            (Some(t), Some(n)) if n > 0 => format!("{:.1} µs", 1e6 * t / n as f64),
            _ => "-".to_string(),
        };
        let _ = writeln!(
            s,
            "{:<28} {:>14} {:>14} {:>18}",
            "", "numeric", "symbolic", "numeric/symbolic"
        );
        let rows = [
            (
                "M, k per evaluation",
                ns(self.numeric.eval_ns),
                ns(self.symbolic.eval_ns),
                r(self.eval_ratio()),
            ),
            (
                "dynamics per evaluation",
                ns(self.numeric.dynamics_ns),
                ns(self.symbolic.dynamics_ns),
                r(self.dynamics_ratio()),
            ),
            (
                "scenario run",
                sec(self.numeric.run_s),
                sec(self.symbolic.run_s),
                r(self.run_ratio()),
            ),
            (
                "steps of the run",
                self.numeric.run_steps.map_or("-".into(), |n| n.to_string()),
                self.symbolic
                    .run_steps
                    .map_or("-".into(), |n| n.to_string()),
                String::new(),
            ),
            (
                "CPU time per step",
                per_step(self.numeric.run_s, self.numeric.run_steps),
                per_step(self.symbolic.run_s, self.symbolic.run_steps),
                String::new(),
            ),
        ];
        for (label, a, b, c) in rows {
            let _ = writeln!(s, "{label:<28} {a:>14} {b:>14} {c:>18}");
        }
        if self.numeric.dynamics_ns.is_none() && self.numeric.eval_ns.is_some() {
            let _ = writeln!(
                s,
                "dynamics: not timed alone for a model on the track (its wheel–rail forces \
                 need the scenario's track); the scenario run includes it"
            );
        }
        let _ = writeln!(
            s,
            "symbolic derivation {}, plugin compilation {}",
            sec(self.derive_s),
            sec(self.compile_s)
        );
        for (name, t) in [("numeric", &self.numeric), ("symbolic", &self.symbolic)] {
            if let Some(n) = &t.note {
                let _ = writeln!(s, "{name}: {n}");
            }
        }
        s
    }
}

/// Deterministic pseudo-random numbers (xorshift64*), uniform in [lo, hi).
struct Rng(u64);

impl Rng {
    fn new(seed: u64) -> Self {
        Self(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1)
    }
    fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        let x = (self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 / (1u64 << 53) as f64;
        lo + (hi - lo) * x
    }
}

/// A state (t, q, q̇) to evaluate at.
#[derive(Debug, Clone)]
pub struct State {
    /// Time, s.
    pub t: f64,
    /// Generalized coordinates q (m or rad), model order.
    pub q: Vec<f64>,
    /// Generalized velocities q̇ (m/s or rad/s), model order.
    pub v: Vec<f64>,
}

/// `count` states near the model's initial state: q = q₀ + U(−0.5, 0.5)
/// (m or rad), q̇ = U(−1, 1) (m/s or rad/s), t = U(0, 1) s.
pub fn random_states(model: &Model, params: &[f64], count: usize) -> Vec<State> {
    let (q0, _) = model.initial_state(params);
    let mut rng = Rng::new(20_260_422);
    (0..count)
        .map(|_| State {
            t: rng.uniform(0.0, 1.0),
            q: q0.iter().map(|x| x + rng.uniform(-0.5, 0.5)).collect(),
            v: q0.iter().map(|_| rng.uniform(-1.0, 1.0)).collect(),
        })
        .collect()
}

/// Median ns per call of `f(k)` (k the running call index), by the batch
/// method of the module documentation. The first error stops the timing.
pub fn time_per_call<E>(mut f: impl FnMut(usize) -> Result<(), E>) -> Result<f64, E> {
    let mut calls = 1usize;
    let mut k = 0usize;
    let mut batch = |calls: usize, f: &mut dyn FnMut(usize) -> Result<(), E>| {
        let watch = Stopwatch::start();
        for _ in 0..calls {
            f(k)?;
            k += 1;
        }
        Ok(watch.seconds())
    };
    // Calibration: double the batch until it lasts BATCH_SECONDS.
    loop {
        let t = batch(calls, &mut f)?;
        if t >= BATCH_SECONDS || calls >= 1 << 40 {
            break;
        }
        calls *= 2;
    }
    let mut per_call = Vec::with_capacity(BATCHES);
    for _ in 0..BATCHES {
        let t = batch(calls, &mut f)?;
        per_call.push(1e9 * t / calls as f64);
    }
    per_call.sort_by(f64::total_cmp);
    Ok(per_call[BATCHES / 2])
}

/// Times (M, k) and `dynamics` of `equations` (and of a second, identical
/// engine for the system) on `states`. Models on track-following frames get
/// random frame inputs for (M, k); their `dynamics` needs the scenario's track
/// (wheel–rail elements) and is measured by the scenario run instead (`None`).
fn time_engine(
    model: &Model,
    params: &[f64],
    states: &[State],
    make: &dyn Fn() -> Result<Box<dyn Equations>, String>,
) -> Result<(f64, Option<f64>), String> {
    let mut eng = make()?;
    eng.set_parameters(params).map_err(|e| e.to_string())?;
    if eng.input_count() > 0 {
        let mut rng = Rng::new(7);
        let u: Vec<f64> = (0..3 * eng.input_count())
            .map(|_| rng.uniform(-1.0, 1.0))
            .collect();
        eng.set_inputs(&u).map_err(|e| e.to_string())?;
    }
    let mut out = Evaluation::for_equations(eng.as_ref());
    let n = states.len();
    let eval_ns = time_per_call(|k| {
        let s = &states[k % n];
        eng.evaluate(s.t, &s.q, &s.v, Parts::MASS_AND_BIAS, &mut out)
            .map_err(|e| format!("evaluation of M and k failed: {e}"))?;
        std::hint::black_box(&out.mass);
        Ok::<(), String>(())
    })?;
    if !model.track_frames.is_empty() {
        return Ok((eval_ns, None));
    }
    let mut system =
        ModelSystem::new(model, make()?, params.to_vec()).map_err(|e| e.to_string())?;
    let dof = system.dof();
    let mut mass = DMatrix::zeros(dof, dof);
    let mut force = DVector::zeros(dof);
    let dynamics_ns = time_per_call(|k| {
        let s = &states[k % n];
        system
            .dynamics(s.t, &s.q, &s.v, &mut mass, &mut force)
            .map_err(|e| format!("dynamics failed: {e}"))?;
        std::hint::black_box(&force);
        Ok::<(), String>(())
    })?;
    Ok((eval_ns, Some(dynamics_ns)))
}

/// Median wall time of `run` (one simulation: its seconds and steps), repeated until
/// [`MAX_RUNS`] runs or [`RUN_SECONDS`] in all, and the steps of a run.
fn median_run(
    mut run: impl FnMut() -> Result<(f64, usize), String>,
) -> Result<(f64, usize), String> {
    let mut steps = 0;
    let mut times = Vec::new();
    let mut total = 0.0;
    while times.len() < MAX_RUNS && (times.is_empty() || total < RUN_SECONDS) {
        let (seconds, n) = run()?;
        steps = n;
        total += seconds;
        times.push(seconds);
    }
    times.sort_by(f64::total_cmp);
    Ok((times[times.len() / 2], steps))
}

/// Median time of `run_scenario` (no CSV output) with engines from `make`, s,
/// and the number of steps of a run.
fn time_run(
    scenario: &Scenario,
    model: &Model,
    make: &dyn Fn() -> Result<Box<dyn Equations>, String>,
) -> Result<(f64, usize), String> {
    median_run(|| {
        let equations = make()?;
        let watch = Stopwatch::start();
        let summary =
            run_scenario(scenario, model, equations, None, |_| {}).map_err(|e| e.to_string())?;
        // The runner's own timer is wall-clock; the stopwatch also counts
        // the setup (state, system) of the run, which is small.
        let seconds = watch.seconds();
        match summary.error {
            Some(e) => Err(format!("the scenario run failed: {e}")),
            None => Ok((seconds, summary.steps)),
        }
    })
}

fn same_file(a: &Path, b: &Path) -> bool {
    match (a.canonicalize(), b.canonicalize()) {
        (Ok(a), Ok(b)) => a == b,
        _ => a == b,
    }
}

/// The default scenario of the model file `model_file`: a file
/// `<stem>*.ron` in `<model dir>/../scenarios` (then `<model dir>/scenarios`,
/// then the model's own folder) whose `model` is this model file; `<stem>.ron`
/// first, then in name order. `Err` says where it looked.
pub fn default_scenario(model_file: &Path) -> Result<Scenario, String> {
    let stem = model_file
        .file_stem()
        .and_then(|s| s.to_str())
        .ok_or_else(|| format!("{}: not a file name", model_file.display()))?;
    let dir = model_file
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let folders = [
        dir.join("../scenarios"),
        dir.join("scenarios"),
        dir.to_path_buf(),
    ];
    for folder in &folders {
        let Ok(entries) = std::fs::read_dir(folder) else {
            continue;
        };
        let mut candidates: Vec<PathBuf> = entries
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| {
                p.extension().is_some_and(|x| x == "ron")
                    && p.file_name()
                        .and_then(|n| n.to_str())
                        .is_some_and(|n| n.starts_with(stem))
                    && !same_file(p, model_file)
            })
            .collect();
        candidates.sort_by_key(|p| (p.file_stem().is_none_or(|s| s != stem), p.clone()));
        for p in candidates {
            if let Ok(s) = railmbs_models::load_scenario(&p)
                && same_file(&s.model, model_file)
            {
                return Ok(s);
            }
        }
    }
    Err(format!(
        "no scenario file {stem}*.ron for this model in {}",
        folders
            .iter()
            .map(|f| f.display().to_string())
            .collect::<Vec<_>>()
            .join(", ")
    ))
}

/// Replaces the creep law of every wheel–rail element; `false` when the
/// model has none.
fn override_creep(
    model: &mut Model,
    law: &railmbs_models::CreepLawSpec<railmbs_models::Expr>,
) -> bool {
    let mut found = false;
    for f in &mut model.forces {
        if let railmbs_models::ForceKind::WheelRail(w) = &mut f.kind {
            w.creep = law.clone();
            found = true;
        }
    }
    found
}

/// True if the file is a train (`Train(...)`, read as a scenario of either
/// kind).
fn is_train_file(path: &Path) -> bool {
    matches!(
        railmbs_models::load_any_scenario(path),
        Ok(railmbs_models::AnyScenario::Train(_))
    )
}

/// Builds the engine of one vehicle's model.
type VehicleEngines = dyn Fn(&Model) -> Result<Box<dyn Equations>, String>;

/// Median time of `run_train` (no CSV) with every vehicle's engine from
/// `make`, s, and the steps of a run.
fn time_train_run(
    train: &railmbs_models::TrainScenario,
    models: &[Model],
    make: &VehicleEngines,
) -> Result<(f64, usize), String> {
    let refs: Vec<&Model> = models.iter().collect();
    median_run(|| {
        let engines = models.iter().map(make).collect::<Result<Vec<_>, _>>()?;
        let watch = Stopwatch::start();
        let summary = railmbs_runtime::train::run_train(train, &refs, engines, None, |_| {})
            .map_err(|e| e.to_string())?;
        let seconds = watch.seconds();
        match summary.error {
            Some(e) => Err(format!("the train run failed: {e}")),
            None => Ok((seconds, summary.steps)),
        }
    })
}

/// `measure` for a train file: evaluations summed over the vehicles, the
/// train run with each engine.
fn measure_train(args: &Args) -> Result<BenchReport, Box<dyn std::error::Error>> {
    let train = railmbs_models::load_train(&args.model)?;
    let law = args.creep.as_deref().map(parse_creep).transpose()?;
    let mut models = Vec::new();
    for v in &train.vehicles {
        let mut m = railmbs_models::load_model(&v.model)?;
        if let Some(law) = &law {
            override_creep(&mut m, law);
        }
        models.push(m);
    }
    if law.is_some()
        && !models.iter().any(|m| {
            m.forces
                .iter()
                .any(|f| matches!(f.kind, railmbs_models::ForceKind::WheelRail(_)))
        })
    {
        return Err(format!(
            "--creep: no vehicle of the train {} has a wheel–rail element",
            args.model.display()
        )
        .into());
    }
    let mut numeric = EngineTimes::default();
    let mut symbolic = EngineTimes::default();
    let (mut derive_s, mut compile_s) = (Some(0.0), Some(0.0));
    let add = |acc: &mut Option<f64>, x: Option<f64>| {
        *acc = match (*acc, x) {
            (Some(a), Some(b)) => Some(a + b),
            _ => None,
        }
    };
    let (mut numeric_sum, mut symbolic_sum) = (Some(0.0), Some(0.0));
    for model in &models {
        let params = model.default_parameter_values();
        let states = random_states(model, &params, args.states);
        let numeric_make = || build_engine(model, Engine::Numeric, None).map_err(|e| e.to_string());
        let e = time_engine(model, &params, &states, &numeric_make)?.0;
        add(&mut numeric_sum, Some(e));
        if args.engine != BenchEngine::Numeric {
            let start = Instant::now();
            match build_engine_with(model, Engine::Symbolic, None, args.portable) {
                Err(e) => {
                    symbolic.note = Some(format!("unavailable: {e}"));
                    symbolic_sum = None;
                }
                Ok(_) => {
                    let build_s = start.elapsed().as_secs_f64();
                    let g =
                        railmbs_codegen::generate(model, &railmbs_codegen::GenerateOptions::new())?;
                    let d = g.derive_time.as_secs_f64();
                    add(&mut derive_s, Some(d));
                    add(
                        &mut compile_s,
                        Some((build_s - d - g.emit_time.as_secs_f64()).max(0.0)),
                    );
                    let make = || {
                        build_engine_with(model, Engine::Symbolic, None, args.portable)
                            .map_err(|e| e.to_string())
                    };
                    add(
                        &mut symbolic_sum,
                        Some(time_engine(model, &params, &states, &make)?.0),
                    );
                }
            }
        }
    }
    numeric.eval_ns = numeric_sum;
    let (t, n) = time_train_run(&train, &models, &|m| {
        build_engine(m, Engine::Numeric, None).map_err(|e| e.to_string())
    })?;
    numeric.run_s = Some(t);
    numeric.run_steps = Some(n);
    if args.engine == BenchEngine::Numeric {
        symbolic.note = Some("not requested (--engine numeric)".into());
        (derive_s, compile_s) = (None, None);
    } else if symbolic.note.is_none() {
        symbolic.eval_ns = symbolic_sum;
        let portable = args.portable;
        let (t, n) = time_train_run(&train, &models, &move |m| {
            build_engine_with(m, Engine::Symbolic, None, portable).map_err(|e| e.to_string())
        })?;
        symbolic.run_s = Some(t);
        symbolic.run_steps = Some(n);
    } else {
        (derive_s, compile_s) = (None, None);
    }
    let name = args
        .model
        .file_stem()
        .map_or("train".into(), |s| s.to_string_lossy().into_owned());
    Ok(BenchReport {
        model: format!("{name} (train of {})", train.vehicles.len()),
        model_file: args.model.clone(),
        dof: models.iter().map(|m| m.coordinates.len()).sum(),
        bodies: models.iter().map(|m| m.bodies.len()).sum(),
        states: args.states,
        scenario: Some(train.source.clone()),
        scenario_note: None,
        numeric,
        symbolic,
        derive_s,
        compile_s,
        creep: args.creep.clone(),
    })
}

/// Runs all measurements (no printing).
pub fn measure(args: &Args) -> Result<BenchReport, Box<dyn std::error::Error>> {
    if args.states == 0 {
        return Err("--states must be at least 1".into());
    }
    if is_train_file(&args.model) {
        if args.scenario.is_some() {
            return Err(format!(
                "{}: a train file is its own scenario; leave out --scenario",
                args.model.display()
            )
            .into());
        }
        return measure_train(args);
    }
    let mut model = railmbs_models::load_model(&args.model)?;
    if let Some(text) = &args.creep {
        let law = parse_creep(text)?;
        if !override_creep(&mut model, &law) {
            return Err(format!(
                "--creep: model {} has no wheel–rail element",
                args.model.display()
            )
            .into());
        }
    }
    let (scenario, scenario_note) = match &args.scenario {
        Some(p) => {
            let s = railmbs_models::load_scenario(p)?;
            if !same_file(&s.model, &args.model) {
                return Err(format!(
                    "{}: the scenario runs the model {}, not {}",
                    p.display(),
                    s.model.display(),
                    args.model.display()
                )
                .into());
            }
            (Some(s), None)
        }
        None => match default_scenario(&args.model) {
            Ok(s) => (Some(s), None),
            Err(e) => (None, Some(e)),
        },
    };
    let params = model.default_parameter_values();
    if let Some(i) = params.iter().position(|p| !p.is_finite()) {
        return Err(format!(
            "{}: the default value of parameter \"{}\" is not finite",
            args.model.display(),
            model.parameters[i].name
        )
        .into());
    }
    let states = random_states(&model, &params, args.states);

    let numeric_make = || build_engine(&model, Engine::Numeric, None).map_err(|e| e.to_string());
    let mut numeric = EngineTimes::default();
    match time_engine(&model, &params, &states, &numeric_make) {
        Ok((e, d)) => {
            numeric.eval_ns = Some(e);
            numeric.dynamics_ns = d;
        }
        Err(e) => numeric.note = Some(e),
    }
    if let Some(s) = &scenario {
        match time_run(s, &model, &numeric_make) {
            Ok((t, n)) => {
                numeric.run_s = Some(t);
                numeric.run_steps = Some(n);
            }
            Err(e) => numeric.note = Some(e),
        }
    }

    let mut symbolic = EngineTimes::default();
    let (mut derive_s, mut compile_s) = (None, None);
    if args.engine == BenchEngine::Numeric {
        symbolic.note = Some("not requested (--engine numeric)".into());
    } else {
        let start = Instant::now();
        let first = build_engine_with(&model, Engine::Symbolic, None, args.portable);
        let build_s = start.elapsed().as_secs_f64();
        match first {
            Err(e) => symbolic.note = Some(format!("unavailable: {e}")),
            Ok(first) => {
                drop(first);
                let generated =
                    railmbs_codegen::generate(&model, &railmbs_codegen::GenerateOptions::new())?;
                let d = generated.derive_time.as_secs_f64();
                let emit = generated.emit_time.as_secs_f64();
                derive_s = Some(d);
                compile_s = Some((build_s - d - emit).max(0.0));
                // Later engines come from the plugin cache.
                let make = || {
                    build_engine_with(&model, Engine::Symbolic, None, args.portable)
                        .map_err(|e| e.to_string())
                };
                match time_engine(&model, &params, &states, &make) {
                    Ok((e, dy)) => {
                        symbolic.eval_ns = Some(e);
                        symbolic.dynamics_ns = dy;
                    }
                    Err(e) => symbolic.note = Some(e),
                }
                if let Some(s) = &scenario {
                    match time_run(s, &model, &make) {
                        Ok((t, n)) => {
                            symbolic.run_s = Some(t);
                            symbolic.run_steps = Some(n);
                        }
                        Err(e) => symbolic.note = Some(e),
                    }
                }
            }
        }
    }

    Ok(BenchReport {
        model: model.name.clone(),
        model_file: args.model.clone(),
        dof: model.coordinates.len(),
        bodies: model.bodies.len(),
        states: args.states,
        scenario: scenario.map(|s| s.source),
        scenario_note,
        numeric,
        symbolic,
        derive_s,
        compile_s,
        creep: args.creep.clone(),
    })
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
