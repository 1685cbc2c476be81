//! Models and scenarios in process: `railmbs.Model` and `railmbs.Scenario`.
//!
//! A scenario is loaded from a file or a string (a `Scenario(...)` or a
//! `Train(...)`), changed as `umsim run --set/--end-time` change it (through
//! [`railmbs_models::Scenario::set_parameter`] and `set_end_time`), plus
//! macros, initial conditions and the creep law, and run by either engine
//! ([`railmbs_cli::engine::build_run_engine`]: the symbolic plugin comes from the
//! same content-hash cache as the CLI's) into an in-memory [`Table`], with
//! the GIL released. The progress callback and Ctrl-C are served every
//! ≥ 100 ms of the run (the runner's progress calls); either stops the run
//! at its next output row through [`Interruptible`].

use crate::errors;
use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use railmbs_cli::engine::{Engine, build_run_engine};
use railmbs_cli::run::TrainEngines;
use railmbs_models::{AnyScenario, CreepLawSpec, Expr, InitialOverride, TrainScenario};
use railmbs_runtime::run::{Interruptible, RunError, RunSummary, Table, run_scenario_into};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};

/// A model (`Model(...)` file): its names and defaults, for inspection and
/// for `Scenario.for_model`.
#[pyclass(module = "railmbs._railmbs", frozen)]
#[derive(Clone)]
pub struct Model {
    pub(crate) inner: Arc<railmbs_models::Model>,
}

#[pymethods]
impl Model {
    /// Reads a model file (RON). Errors: `railmbs.ModelError` with file,
    /// element, line and column.
    #[staticmethod]
    fn load(py: Python<'_>, path: PathBuf) -> PyResult<Self> {
        let model = railmbs_models::load_model(&path).map_err(|e| errors::model_errors(py, &e))?;
        Ok(Self {
            inner: Arc::new(model),
        })
    }

    /// Resolves model text; `path` names it in errors and resolves the
    /// files it refers to (subsystems, profiles) relative to its folder.
    #[staticmethod]
    #[pyo3(signature = (text, path = PathBuf::from("model.ron")))]
    fn from_string(py: Python<'_>, text: &str, path: PathBuf) -> PyResult<Self> {
        let model =
            railmbs_models::parse_model(text, &path).map_err(|e| errors::model_errors(py, &e))?;
        Ok(Self {
            inner: Arc::new(model),
        })
    }

    /// The model's `name`.
    #[getter]
    fn name(&self) -> &str {
        &self.inner.name
    }

    /// The file it was read from (`None` for a string without a path).
    #[getter]
    fn path(&self) -> Option<PathBuf> {
        self.inner.source.clone()
    }

    /// Parameter long names and default values (SI units, as in the file).
    #[getter]
    fn parameters<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        let d = PyDict::new(py);
        let values = self.inner.default_parameter_values();
        for (p, v) in self.inner.parameters.iter().zip(values) {
            d.set_item(&p.name, v)?;
        }
        Ok(d)
    }

    /// Macro long names.
    #[getter]
    fn macros(&self) -> Vec<String> {
        self.inner.macros.iter().map(|m| m.name.clone()).collect()
    }

    /// Generalized coordinate names (the first CSV columns after `time`).
    #[getter]
    fn coordinates(&self) -> Vec<String> {
        self.inner.coordinate_names()
    }

    /// Body long names.
    #[getter]
    fn bodies(&self) -> Vec<String> {
        self.inner.bodies.iter().map(|b| b.name.clone()).collect()
    }

    /// Force element long names.
    #[getter]
    fn forces(&self) -> Vec<String> {
        self.inner.forces.iter().map(|f| f.name.clone()).collect()
    }

    fn __repr__(&self) -> String {
        format!(
            "Model({:?}: {} bodies, {} coordinates, {} force elements)",
            self.inner.name,
            self.inner.bodies.len(),
            self.inner.coordinates.len(),
            self.inner.forces.len()
        )
    }
}

/// What a scenario holds: one model or a train.
#[derive(Clone)]
enum Kind {
    /// `Scenario(...)`, with its model once loaded (or given).
    Single(
        Box<railmbs_models::Scenario>,
        Option<Arc<railmbs_models::Model>>,
    ),
    /// `Train(...)`.
    Train(Box<TrainScenario>),
}

/// A scenario (`Scenario(...)`) or a train (`Train(...)`), to change and run.
#[pyclass(module = "railmbs._railmbs")]
#[derive(Clone)]
pub struct Scenario {
    kind: Kind,
    /// The creep law of every wheel–rail element, replacing the model's.
    creep: Option<(String, CreepLawSpec<Expr>)>,
}

impl Scenario {
    fn from_any(any: AnyScenario) -> Self {
        Self {
            kind: match any {
                AnyScenario::Single(s) => Kind::Single(Box::new(s), None),
                AnyScenario::Train(t) => Kind::Train(Box::new(t)),
            },
            creep: None,
        }
    }

    /// The scenario file (or the path given with its text).
    fn source(&self) -> &Path {
        match &self.kind {
            Kind::Single(s, _) => &s.source,
            Kind::Train(t) => &t.source,
        }
    }

    /// The single scenario, or a `ValueError` naming `what` for a train.
    fn single(&mut self, what: &str) -> PyResult<&mut railmbs_models::Scenario> {
        match &mut self.kind {
            Kind::Single(s, _) => Ok(s),
            Kind::Train(t) => Err(pyo3::exceptions::PyValueError::new_err(format!(
                "{}: {what} applies to a single-model scenario, not to a train \
                 (set it in the train file's vehicles)",
                t.source.display()
            ))),
        }
    }

    /// The scenario's model (read from its file on first use).
    fn model_arc(&mut self, py: Python<'_>) -> PyResult<Arc<railmbs_models::Model>> {
        let Kind::Single(s, model) = &mut self.kind else {
            return Err(pyo3::exceptions::PyValueError::new_err(format!(
                "{}: a train has one model per vehicle, not one model",
                self.source().display()
            )));
        };
        if model.is_none() {
            let m =
                railmbs_models::load_model(&s.model).map_err(|e| errors::model_errors(py, &e))?;
            *model = Some(Arc::new(m));
        }
        Ok(model.clone().expect("loaded above"))
    }
}

impl Scenario {
    /// The single scenario and its model (with the creep law of
    /// `set_creep_law`) for the analysis `what`; a train is a `ValueError`.
    fn analysis_inputs(
        &mut self,
        py: Python<'_>,
        what: &str,
    ) -> PyResult<(railmbs_models::Scenario, Arc<railmbs_models::Model>)> {
        let scenario = self.single(what)?.clone();
        let mut model = self.model_arc(py)?;
        if let Some((_, law)) = &self.creep {
            let m = Arc::make_mut(&mut model);
            if m.set_creep_law(law) == 0 {
                return Err(pyo3::exceptions::PyValueError::new_err(format!(
                    "set_creep_law: model \"{}\" has no wheel–rail element",
                    m.name
                )));
            }
        }
        Ok((scenario, model))
    }
}

/// Speeds (m/s) from Python: one number or a sequence of numbers.
enum SpeedArg {
    One(f64),
    Many(Vec<f64>),
}

fn speed_arg(value: &Bound<'_, PyAny>, what: &str) -> PyResult<SpeedArg> {
    if let Ok(x) = value.extract::<f64>() {
        return Ok(SpeedArg::One(x));
    }
    value
        .extract::<Vec<f64>>()
        .map(SpeedArg::Many)
        .map_err(|_| {
            pyo3::exceptions::PyTypeError::new_err(format!(
                "{what} is a speed in m/s or a sequence of speeds, got {}",
                value
                    .repr()
                    .map_or_else(|_| "?".to_string(), |r| r.to_string())
            ))
        })
}

/// A parameter value from Python: a number (written in Rust's shortest
/// round-trip form, so it reads back as the same double) or expression text.
fn value_text(value: &Bound<'_, PyAny>) -> PyResult<String> {
    if let Ok(s) = value.extract::<String>() {
        return Ok(s);
    }
    let x: f64 = value.extract().map_err(|_| {
        pyo3::exceptions::PyTypeError::new_err(format!(
            "a parameter value is a number or an expression string, got {}",
            value
                .repr()
                .map_or_else(|_| "?".to_string(), |r| r.to_string())
        ))
    })?;
    Ok(format!("{x}"))
}

/// The engine named `name`.
fn engine_of(name: &str, plugin: &Option<PathBuf>) -> PyResult<Engine> {
    match (name, plugin) {
        (_, Some(_)) | ("symbolic", _) => Ok(Engine::Symbolic),
        ("numeric", None) => Ok(Engine::Numeric),
        (other, None) => Err(pyo3::exceptions::PyValueError::new_err(format!(
            "engine must be \"numeric\" or \"symbolic\", got {other:?}"
        ))),
    }
}

/// Why a run did not produce a result.
enum Failure {
    /// Building the engine (or loading a train's models) failed.
    Engine(String),
    /// A train's model file has problems.
    Model(railmbs_models::ModelErrors),
}

/// The progress callback and the stop flag of a run, shared with the run's
/// thread.
pub(crate) struct Watch<'a> {
    pub(crate) progress: Option<&'a Py<PyAny>>,
    pub(crate) t_end: f64,
    pub(crate) stop: Arc<AtomicBool>,
    /// The exception that stopped the run (KeyboardInterrupt, or the
    /// callback's own).
    pub(crate) raised: Mutex<Option<PyErr>>,
}

impl Watch<'_> {
    /// Called by the runner now and then (at most every 100 ms): Python's
    /// signal handlers (Ctrl-C raises KeyboardInterrupt), then the callback.
    pub(crate) fn tick(&self, t: f64) {
        if self.stop.load(Ordering::Relaxed) {
            return;
        }
        Python::attach(|py| {
            let outcome = py.check_signals().and_then(|()| match self.progress {
                Some(cb) => cb.call1(py, (t, self.t_end)).map(drop),
                None => Ok(()),
            });
            if let Err(e) = outcome {
                *self.raised.lock().expect("not poisoned") = Some(e);
                self.stop.store(true, Ordering::Relaxed);
            }
        });
    }

    pub(crate) fn raised(&self) -> Option<PyErr> {
        self.raised.lock().expect("not poisoned").take()
    }
}

#[pymethods]
impl Scenario {
    /// Reads a scenario or train file (RON). Errors: `railmbs.ModelError`
    /// with file, element, line and column.
    #[staticmethod]
    fn load(py: Python<'_>, path: PathBuf) -> PyResult<Self> {
        railmbs_models::load_any_scenario(&path)
            .map(Self::from_any)
            .map_err(|e| errors::model_errors(py, &e))
    }

    /// Resolves scenario (or train) text; `path` names it in errors and
    /// resolves its model, track and output files relative to its folder.
    /// `model`, if given, is run instead of the model file the text names.
    #[staticmethod]
    #[pyo3(signature = (text, path = PathBuf::from("scenario.ron"), model = None))]
    fn from_string(
        py: Python<'_>,
        text: &str,
        path: PathBuf,
        model: Option<PyRef<'_, Model>>,
    ) -> PyResult<Self> {
        let any = if railmbs_models::top_constructor(text) == Some("Train") {
            railmbs_models::parse_train(text, &path).map(AnyScenario::Train)
        } else {
            railmbs_models::parse_scenario(text, &path).map(AnyScenario::Single)
        }
        .map_err(|e| errors::model_errors(py, &e))?;
        let mut s = Self::from_any(any);
        if let Some(m) = model {
            s.set_model(m)?;
        }
        Ok(s)
    }

    /// The scenario file (or the path given with its text).
    #[getter]
    fn path(&self) -> PathBuf {
        self.source().to_path_buf()
    }

    /// True for a train (`Train(...)`).
    #[getter]
    fn is_train(&self) -> bool {
        matches!(self.kind, Kind::Train(_))
    }

    /// The model (read from the file the scenario names, on first use).
    #[getter]
    fn model(&mut self, py: Python<'_>) -> PyResult<Model> {
        Ok(Model {
            inner: self.model_arc(py)?,
        })
    }

    /// Runs `model` instead of the scenario's model file.
    #[setter]
    fn set_model(&mut self, model: PyRef<'_, Model>) -> PyResult<()> {
        let path = model.inner.source.clone();
        let s = self.single("a model")?;
        if let Some(p) = path {
            s.model = p;
        }
        if let Kind::Single(_, m) = &mut self.kind {
            *m = Some(model.inner.clone());
        }
        Ok(())
    }

    /// Simulated time from t = 0, s.
    #[getter]
    fn end_time(&self) -> f64 {
        match &self.kind {
            Kind::Single(s, _) => s.end_time,
            Kind::Train(t) => t.end_time,
        }
    }

    /// Replaces the end time (s), checked as `umsim run --end-time` checks
    /// it. Errors: `railmbs.ModelError` naming the scenario file.
    #[setter]
    fn set_end_time(&mut self, py: Python<'_>, end_time: f64) -> PyResult<()> {
        let checked = match &mut self.kind {
            Kind::Single(s, _) => s.set_end_time(end_time),
            Kind::Train(t) => t.set_end_time(end_time),
        };
        checked.map_err(|e| errors::file_error(py, self.source(), "end_time", &e))
    }

    /// The parameter assignments (long name → expression text), the file's
    /// and those of `set`, in order.
    #[getter]
    fn parameters(&self) -> Vec<(String, String)> {
        match &self.kind {
            Kind::Single(s, _) => s.parameters.clone(),
            Kind::Train(t) => t.parameters.clone(),
        }
    }

    /// Sets parameter `name` to `value` for this scenario (`umsim run --set
    /// NAME=VALUE`): a number in the parameter's own SI unit, or an
    /// expression string over the parameters. It replaces the file's
    /// assignment of `name`; in a train it is train-wide. Checked against
    /// the model when the run starts.
    fn set(&mut self, name: &str, value: &Bound<'_, PyAny>) -> PyResult<()> {
        let text = value_text(value)?;
        match &mut self.kind {
            Kind::Single(s, _) => s.set_parameter(name, &text),
            Kind::Train(t) => t.set_parameter(name, &text),
        }
        Ok(())
    }

    /// The macros applied, in order, before the parameter assignments.
    #[getter]
    fn macros(&self) -> Vec<String> {
        match &self.kind {
            Kind::Single(s, _) => s.macros.clone(),
            Kind::Train(_) => Vec::new(),
        }
    }

    /// Replaces the macros (long names of the model's macros, applied in
    /// order before the parameter assignments).
    #[setter]
    fn set_macros(&mut self, macros: Vec<String>) -> PyResult<()> {
        self.single("macros")?.macros = macros;
        Ok(())
    }

    /// Sets the initial value (m or rad) and/or velocity (m/s or rad/s) of
    /// coordinate `coordinate`, replacing the model's `init`/`vel` (and the
    /// file's `initial` entry); checked against the model when the run
    /// starts.
    #[pyo3(signature = (coordinate, value = None, velocity = None))]
    fn set_initial(
        &mut self,
        coordinate: &str,
        value: Option<f64>,
        velocity: Option<f64>,
    ) -> PyResult<()> {
        let s = self.single("set_initial")?;
        match s.initial.iter_mut().find(|i| i.coordinate == coordinate) {
            Some(i) => {
                i.value = value.or(i.value);
                i.velocity = velocity.or(i.velocity);
            }
            None => s.initial.push(InitialOverride {
                coordinate: coordinate.to_string(),
                value,
                velocity,
            }),
        }
        Ok(())
    }

    /// Initial-condition overrides: (coordinate, value or None, velocity or None).
    #[getter]
    fn initial(&self) -> Vec<(String, Option<f64>, Option<f64>)> {
        match &self.kind {
            Kind::Single(s, _) => s
                .initial
                .iter()
                .map(|i| (i.coordinate.clone(), i.value, i.velocity))
                .collect(),
            Kind::Train(_) => Vec::new(),
        }
    }

    /// Uses `law` for every wheel–rail element instead of the model's, in
    /// the syntax of `umsim creep --method` and `umsim bench --creep`
    /// (`kalker`, `mueller:3`, `fastsim:10`, `fastsim-a:20,sliding=integrated`,
    /// `polach:ka=0.5,ks=0.3`, …). Errors: `ValueError` with the syntax.
    fn set_creep_law(&mut self, law: &str) -> PyResult<()> {
        let spec: CreepLawSpec = law
            .parse()
            .map_err(|e| pyo3::exceptions::PyValueError::new_err(format!("{e}")))?;
        self.creep = Some((law.to_string(), spec.map(|_, &x| Expr::Num(x))));
        Ok(())
    }

    /// The creep law set by `set_creep_law` (`None`: the model's own).
    #[getter]
    fn creep_law(&self) -> Option<String> {
        self.creep.as_ref().map(|(text, _)| text.clone())
    }

    /// A copy to change independently.
    fn copy(&self) -> Self {
        self.clone()
    }

    /// Runs the scenario and returns a `railmbs.RunResult`.
    ///
    /// `engine` is `"numeric"` or `"symbolic"` (the plugin is generated and
    /// compiled through the same content-hash cache as `umsim run`'s, or
    /// `plugin` is loaded). `progress(t, t_end)` (s) is called at most
    /// every 100 ms of the run and once at its end; an exception it raises,
    /// or Ctrl-C (KeyboardInterrupt), stops the run at its next output row
    /// and is re-raised. The GIL is released while the run goes on.
    ///
    /// Errors: `ModelError` (the scenario does not fit its model),
    /// `PluginError`, `SimulationError` (the simulation failed; its `result`
    /// holds the rows up to the failure, `time` when).
    #[pyo3(signature = (engine = "numeric", plugin = None, progress = None))]
    fn run(
        &mut self,
        py: Python<'_>,
        engine: &str,
        plugin: Option<PathBuf>,
        progress: Option<Py<PyAny>>,
    ) -> PyResult<Py<PyAny>> {
        let engine = engine_of(engine, &plugin)?;
        let creep = self.creep.as_ref().map(|(_, law)| law.clone());
        let watch = Watch {
            progress: progress.as_ref(),
            t_end: self.end_time(),
            stop: Arc::new(AtomicBool::new(false)),
            raised: Mutex::new(None),
        };
        let mut table = Table::new();
        let outcome = match &self.kind {
            Kind::Single(..) => {
                let mut model = self.model_arc(py)?;
                if let Some(law) = &creep {
                    let m = Arc::make_mut(&mut model);
                    if m.set_creep_law(law) == 0 {
                        return Err(pyo3::exceptions::PyValueError::new_err(format!(
                            "set_creep_law: model \"{}\" has no wheel–rail element",
                            m.name
                        )));
                    }
                }
                let Kind::Single(scenario, _) = &self.kind else {
                    unreachable!("matched above")
                };
                let (scenario, model, table) = (&**scenario, &*model, &mut table);
                py.detach(|| {
                    let equations =
                        build_run_engine(model, engine, plugin.as_deref(), &scenario.integrator)
                            .map_err(|e| Failure::Engine(e.to_string()))?;
                    let mut sink = Interruptible::new(table, watch.stop.clone());
                    Ok(run_scenario_into(
                        scenario,
                        model,
                        equations,
                        &mut sink,
                        |t| watch.tick(t),
                    ))
                })
            }
            Kind::Train(train) => {
                let (train, table) = (&**train, &mut table);
                py.detach(|| {
                    let built =
                        TrainEngines::build(train, engine, plugin.as_deref(), creep.as_ref())
                            .map_err(|e| match e.downcast::<railmbs_models::ModelErrors>() {
                                Ok(m) => Failure::Model(*m),
                                Err(e) => Failure::Engine(e.to_string()),
                            })?;
                    let TrainEngines {
                        models,
                        vehicle_models,
                        engines,
                    } = built;
                    let models: Vec<_> = vehicle_models.iter().map(|&k| &models[k]).collect();
                    let mut sink = Interruptible::new(table, watch.stop.clone());
                    Ok(railmbs_runtime::train::run_train_into(
                        train,
                        &models,
                        engines,
                        &mut sink,
                        |t| watch.tick(t),
                    ))
                })
            }
        };
        if let Some(e) = watch.raised() {
            return Err(e);
        }
        let summary = match outcome {
            Ok(Ok(summary)) => summary,
            Ok(Err(e)) => return Err(run_error(py, e)),
            Err(Failure::Engine(message)) => return Err(errors::plain(py, "PluginError", message)),
            Err(Failure::Model(e)) => return Err(errors::model_errors(py, &e)),
        };
        let result = run_result(py, table, &summary)?;
        if let Some(e) = &summary.error {
            return Err(errors::simulation_error(
                py,
                &format!(
                    "{e} (scenario {}; {} output rows up to t = {} s are in the error's result)",
                    self.source().display(),
                    summary.rows,
                    summary.t_end
                ),
                summary.t_end,
                Some(result.into_bound(py)),
            ));
        }
        if let Some(cb) = &progress {
            cb.call1(py, (summary.t_end, watch.t_end))?;
        }
        Ok(result)
    }

    /// The static (steady) equilibrium at the scenario's start, as `umsim
    /// equilibrium` (and `initial_state: Equilibrium`): a Newton solve with
    /// every force element and the wheel–rail contact, the wheels' rolling
    /// rates solved, coordinates without stiffness held. Returns a
    /// `railmbs.analysis.Equilibrium`: the state `q` (m, rad), `v` (m/s,
    /// rad/s), the role of each coordinate and the wheel loads Q and lateral
    /// forces Y (N) of every wheel. The GIL is released during the solve.
    ///
    /// Errors: `AnalysisError` (no equilibrium: the residual and the
    /// coordinates carrying it), `ModelError`, `PluginError`; `ValueError`
    /// for a train.
    #[pyo3(signature = (engine = "numeric", plugin = None))]
    fn equilibrium(
        &mut self,
        py: Python<'_>,
        engine: &str,
        plugin: Option<PathBuf>,
    ) -> PyResult<Py<PyAny>> {
        let engine = engine_of(engine, &plugin)?;
        let (scenario, model) = self.analysis_inputs(py, "equilibrium")?;
        crate::analysis::equilibrium(py, &scenario, &model, engine, plugin.as_deref())
    }

    /// The linear modes at the steady state, as `umsim modes`: the full
    /// model (contact linearized at its actual geometry) linearized at its
    /// equilibrium, the eigenvalues with damped and natural frequency (Hz),
    /// damping ratio, mode name and normalized shape.
    ///
    /// `speed`: `None`, the scenario's own speed (`railmbs.analysis.Modes`);
    /// a number (m/s), the modes at that constant speed; a sequence of
    /// speeds (m/s), the root locus (`railmbs.analysis.Locus`, with
    /// `critical_speed`: the linear critical speed, where the least damped
    /// lateral mode's damping ratio first crosses zero, interpolated).
    /// `parameter` with `values`: a locus over a model parameter (its own
    /// unit) at the scenario's speed (or at `speed`, a number), as `umsim
    /// modes --sweep`. The GIL is released during the computation.
    ///
    /// Errors: `AnalysisError` (no equilibrium, a failed
    /// eigendecomposition), `ModelError`, `PluginError`, `ValueError`.
    #[pyo3(signature = (speed = None, parameter = None, values = None, engine = "numeric", plugin = None))]
    fn modes(
        &mut self,
        py: Python<'_>,
        speed: Option<&Bound<'_, PyAny>>,
        parameter: Option<String>,
        values: Option<Vec<f64>>,
        engine: &str,
        plugin: Option<PathBuf>,
    ) -> PyResult<Py<PyAny>> {
        let engine = engine_of(engine, &plugin)?;
        let speed = speed.map(|v| speed_arg(v, "speed")).transpose()?;
        let bad = |m: String| Err(pyo3::exceptions::PyValueError::new_err(m));
        let what = match (speed, parameter, values) {
            (None, None, None) => crate::analysis::ModesOf::One(None),
            (Some(SpeedArg::One(v)), None, None) => crate::analysis::ModesOf::One(Some(v)),
            (Some(SpeedArg::Many(v)), None, None) => {
                if v.is_empty() {
                    return bad("modes: speed is an empty sequence".into());
                }
                crate::analysis::ModesOf::Speeds(v)
            }
            (s @ (None | Some(SpeedArg::One(_))), Some(p), Some(values)) => {
                if values.is_empty() {
                    return bad("modes: values is an empty sequence".into());
                }
                let v = match s {
                    Some(SpeedArg::One(v)) => Some(v),
                    _ => None,
                };
                crate::analysis::ModesOf::Parameter(p, values, v)
            }
            (Some(SpeedArg::Many(_)), Some(_), _) => {
                return bad("modes: a parameter locus is at one speed, not at a sequence".into());
            }
            _ => return bad("modes: parameter and values go together".into()),
        };
        if let crate::analysis::ModesOf::One(Some(v))
        | crate::analysis::ModesOf::Parameter(_, _, Some(v)) = &what
            && !(v.is_finite() && *v >= 0.0)
        {
            return bad(format!("modes: speed {v} m/s must be finite and ≥ 0"));
        }
        if let crate::analysis::ModesOf::Speeds(v) = &what
            && let Some(x) = v.iter().find(|x| !(x.is_finite() && **x >= 0.0))
        {
            return bad(format!("modes: speed {x} m/s must be finite and ≥ 0"));
        }
        let (scenario, model) = self.analysis_inputs(py, "modes")?;
        crate::analysis::modes(py, &scenario, &model, engine, plugin.as_deref(), what)
    }

    /// The nonlinear critical speed, as `umsim critical-speed`.
    ///
    /// Without `bifurcation`: the scenario is a decelerating run (its
    /// `speed_profile`) from a large disturbance; the lateral limit cycle
    /// of `signals` (coordinate names; default the wheelsets' lateral
    /// coordinates) is detected, its amplitude half the range over `window`
    /// s, established from `on` m, died out below `threshold` m or below
    /// `relative` times its largest amplitude. Returns a
    /// `railmbs.analysis.CriticalSpeed` (`speed`, m/s, where the cycle died
    /// out, or `None`; the run's `result`).
    ///
    /// With `bifurcation` (a sequence of speeds, m/s): one run at
    /// constant-speed plateaus from the highest down, each `hold` s long
    /// (the first twice), joined by ramps of `ramp` s, each starting from
    /// the state the one before ended in; the amplitude over the last
    /// `measure` s (default half a plateau) of each: a
    /// `railmbs.analysis.Bifurcation`. `progress(t, t_end)` (s) as for
    /// `run`; the GIL is released during the run.
    ///
    /// Errors: `AnalysisError` (bad settings, no track, no signal),
    /// `ModelError`, `PluginError`.
    #[pyo3(signature = (bifurcation = None, signals = None, window = 1.0, threshold = 1e-3, on = 4e-3, relative = 0.5, hold = 6.0, ramp = 0.5, measure = None, engine = "numeric", plugin = None, progress = None))]
    #[allow(clippy::too_many_arguments)]
    fn critical_speed(
        &mut self,
        py: Python<'_>,
        bifurcation: Option<Vec<f64>>,
        signals: Option<Vec<String>>,
        window: f64,
        threshold: f64,
        on: f64,
        relative: f64,
        hold: f64,
        ramp: f64,
        measure: Option<f64>,
        engine: &str,
        plugin: Option<PathBuf>,
        progress: Option<Py<PyAny>>,
    ) -> PyResult<Py<PyAny>> {
        use railmbs_runtime::analysis::critical::{DetectionSettings, Staircase};
        let engine = engine_of(engine, &plugin)?;
        let (scenario, model) = self.analysis_inputs(py, "critical_speed")?;
        let detection = DetectionSettings {
            relative,
            on,
            ..DetectionSettings::new(window, threshold)
        };
        detection
            .check()
            .map_err(pyo3::exceptions::PyValueError::new_err)?;
        let plan = bifurcation.map(|speeds| {
            let mut speeds = speeds;
            // Run from the highest speed down.
            speeds.sort_by(|a, b| b.total_cmp(a));
            Staircase {
                speeds,
                first_hold: 2.0 * hold,
                hold,
                ramp,
                measure: measure.unwrap_or(0.5 * hold),
            }
        });
        if let Some(p) = &plan {
            p.check().map_err(pyo3::exceptions::PyValueError::new_err)?;
        }
        let watch = Watch {
            progress: progress.as_ref(),
            t_end: plan.as_ref().map_or(scenario.end_time, Staircase::end_time),
            stop: Arc::new(AtomicBool::new(false)),
            raised: Mutex::new(None),
        };
        let options = crate::analysis::CriticalOptions {
            signals: signals.unwrap_or_default(),
            detection,
            bifurcation: plan,
        };
        let out = crate::analysis::critical(
            py,
            &scenario,
            &model,
            engine,
            plugin.as_deref(),
            options,
            &watch,
        )?;
        if let Some(cb) = &progress {
            cb.call1(py, (watch.t_end, watch.t_end))?;
        }
        Ok(out)
    }

    /// The quasi-static curving solution, as `umsim curving`: the steady
    /// state of the scenario's vehicle on a circular curve of `radius` m
    /// (positive left, negative right) with `cant` m, at constant `speed`
    /// (m/s, or a sequence of speeds: a sweep, each from the one before),
    /// solved directly in the track-following frames with every force
    /// element and the wheel–rail contact. Returns a
    /// `railmbs.analysis.Curving`: per speed and wheelset the lateral
    /// position (m), angle of attack (rad) and every contact output (Q, Y,
    /// Y/Q, ΣY, creep forces, wear number…), per wheel Q, Y and Y/Q. The
    /// GIL is released during the solve.
    ///
    /// Errors: `ValueError` (a bad curve), `AnalysisError` (no steady
    /// state, no track), `ModelError`, `PluginError`.
    #[pyo3(signature = (radius, speed, cant = 0.0, engine = "numeric", plugin = None))]
    fn curving(
        &mut self,
        py: Python<'_>,
        radius: f64,
        speed: &Bound<'_, PyAny>,
        cant: f64,
        engine: &str,
        plugin: Option<PathBuf>,
    ) -> PyResult<Py<PyAny>> {
        let engine = engine_of(engine, &plugin)?;
        let speeds = match speed_arg(speed, "speed")? {
            SpeedArg::One(v) => vec![v],
            SpeedArg::Many(v) if !v.is_empty() => v,
            SpeedArg::Many(_) => {
                return Err(pyo3::exceptions::PyValueError::new_err(
                    "curving: speed is an empty sequence",
                ));
            }
        };
        let (scenario, model) = self.analysis_inputs(py, "curving")?;
        crate::analysis::curving(
            py,
            &scenario,
            &model,
            engine,
            plugin.as_deref(),
            radius,
            cant,
            &speeds,
        )
    }

    fn __repr__(&self) -> String {
        format!(
            "Scenario({:?}{}, end_time={})",
            self.source().display().to_string(),
            if self.is_train() { ", train" } else { "" },
            self.end_time()
        )
    }
}

/// A run's error (not the simulation's own) as a Python exception.
fn run_error(py: Python<'_>, e: RunError) -> PyErr {
    match e {
        RunError::Model(m) => errors::model_errors(py, &m),
        RunError::Setup { file, message } => errors::file_error(py, &file, "", &message),
        RunError::Sim(s) => errors::simulation_error(py, &s.to_string(), 0.0, None),
        other => errors::plain(py, "RailmbsError", other),
    }
}

/// The `railmbs.RunResult` of a run: the table's columns as numpy arrays
/// (moved, not copied), the summary and the assessment table.
pub(crate) fn run_result(py: Python<'_>, table: Table, s: &RunSummary) -> PyResult<Py<PyAny>> {
    let names = table.names().to_vec();
    let columns = PyList::empty(py);
    for c in table.into_columns() {
        columns.append(PyArray1::from_vec(py, c))?;
    }
    let summary = PyDict::new(py);
    summary.set_item("engine", &s.engine)?;
    summary.set_item("t_end", s.t_end)?;
    summary.set_item("steps", s.steps)?;
    summary.set_item("rejected_steps", s.rejected_steps)?;
    summary.set_item("newton_iterations", s.newton_iterations)?;
    summary.set_item("jacobian_evaluations", s.jacobian_evaluations)?;
    summary.set_item("dynamics_evaluations", s.dynamics_evaluations)?;
    summary.set_item("cpu_time", s.cpu_time)?;
    summary.set_item("realtime_factor", s.realtime_factor())?;
    summary.set_item("rows", s.rows)?;
    summary.set_item("error", s.error.as_ref().map(|e| e.to_string()))?;
    let assessment = PyList::empty(py);
    for a in &s.assessment {
        let row = PyDict::new(py);
        row.set_item("element", &a.element)?;
        row.set_item("quantity", &a.quantity)?;
        row.set_item("unit", a.unit)?;
        row.set_item("max", a.max)?;
        row.set_item("time", a.time)?;
        row.set_item("limit", a.limit)?;
        row.set_item("limit_name", a.limit_name)?;
        row.set_item("ratio", a.limit.map(|l| a.max / l))?;
        assessment.append(row)?;
    }
    let class = py.import("railmbs.result")?.getattr("RunResult")?;
    Ok(class.call1((names, columns, summary, assessment))?.unbind())
}
