//! The analyses of `railmbs_runtime::analysis` in process, behind the
//! `Scenario` methods `equilibrium`, `modes`, `critical_speed` and
//! `curving` ([`crate::sim`]): the same functions `umsim equilibrium`,
//! `umsim modes`, `umsim critical-speed` and `umsim curving` call, run with
//! the GIL released, their results handed to Python as dicts of plain
//! values and numpy arrays that `railmbs.analysis` wraps (DataFrames,
//! complex mode shapes).
//!
//! The engine is built once per call (the symbolic plugin found or
//! compiled through the content-hash cache and loaded once); a root locus,
//! a parameter locus or a curving sweep gets a fresh engine state on it for
//! each solve, and shares the wheel–rail contact tables.

use crate::errors;
use numpy::PyArray1;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use railmbs_cli::engine::{Engine, build_symbolic};
use railmbs_models::{InitialStateKind, Model, Scenario};
use railmbs_runtime::analysis::critical::{
    BranchPoint, Detection, DetectionSettings, Staircase, bifurcation, decelerating_run,
    wheelset_lateral_coordinates,
};
use railmbs_runtime::analysis::curving::{Curve, Curving, curving_from};
use railmbs_runtime::analysis::equilibrium::{Equilibrium, Role};
use railmbs_runtime::analysis::modes::zero_crossing;
use railmbs_runtime::analysis::speed::{
    SpeedModes, at_speed, critical_speed, parameter_locus, root_locus, scenario_modes,
};
use railmbs_runtime::analysis::{CoordinateInfo, wheel_loads};
use railmbs_runtime::forces::ContactTableCache;
use railmbs_runtime::run::scenario::scenario_system;
use railmbs_runtime::run::{Interruptible, RunError, RunSummary, Table};
use railmbs_runtime::{Equations, NumericEquations, Plugin, PluginEquations};
use std::path::Path;

/// The equations of an analysis: built once, a fresh engine state per solve.
pub(crate) enum Engines<'a> {
    /// The numeric-iterative engine of the model.
    Numeric(&'a Model),
    /// The model's compiled plugin, loaded once.
    Symbolic(Box<Plugin>),
}

impl<'a> Engines<'a> {
    /// The engine `engine` of `model` (`plugin`: a compiled plugin to load
    /// instead of the cache's).
    ///
    /// # Errors
    /// The plugin cannot be built or loaded, as its message.
    pub(crate) fn new(
        model: &'a Model,
        engine: Engine,
        plugin: Option<&Path>,
    ) -> Result<Self, String> {
        match engine {
            Engine::Numeric => Ok(Self::Numeric(model)),
            Engine::NumericAba => Err(Engine::NumericAba
                .require_mass_matrix("this analysis")
                .expect_err("numeric-aba needs no M")),
            Engine::Symbolic => {
                let path = match plugin {
                    Some(p) => p.to_path_buf(),
                    None => {
                        build_symbolic(model, false)
                            .map_err(|e| e.to_string())?
                            .path
                    }
                };
                Plugin::load_for(&path, model)
                    .map(|p| Self::Symbolic(Box::new(p)))
                    .map_err(|e| e.to_string())
            }
        }
    }

    /// A fresh engine state.
    pub(crate) fn make(&self) -> Box<dyn Equations> {
        match self {
            Self::Numeric(m) => Box::new(NumericEquations::new(m)),
            Self::Symbolic(p) => Box::new(PluginEquations::new((**p).clone())),
        }
    }
}

/// Why an analysis gave no result.
pub(crate) enum Failure {
    /// The engine could not be built.
    Engine(String),
    /// The analysis failed.
    Run(RunError),
}

impl From<RunError> for Failure {
    fn from(e: RunError) -> Self {
        Self::Run(e)
    }
}

/// An analysis failure as a Python exception: a scenario that does not fit
/// its model is `ModelError`, an engine `PluginError`, an interruption
/// `KeyboardInterrupt`, every other failure of the analysis (no
/// equilibrium, a failed eigendecomposition, no steady curving state, a
/// scenario the analysis cannot use) `AnalysisError` with the Rust message.
pub(crate) fn failure(py: Python<'_>, f: Failure) -> PyErr {
    match f {
        Failure::Engine(message) => errors::plain(py, "PluginError", message),
        Failure::Run(RunError::Model(m)) => errors::model_errors(py, &m),
        Failure::Run(RunError::Interrupted { .. }) => {
            pyo3::exceptions::PyKeyboardInterrupt::new_err("the analysis was interrupted")
        }
        Failure::Run(e @ RunError::Setup { .. }) => {
            let file = match &e {
                RunError::Setup { file, .. } => Some(file.display().to_string()),
                _ => None,
            };
            errors::analysis_error(py, &e.to_string(), file)
        }
        Failure::Run(e) => errors::analysis_error(py, &e.to_string(), None),
    }
}

/// The unit of a coordinate's value (`m`, `rad`, or empty for an element
/// state) and of its rate.
fn units(c: &CoordinateInfo) -> (&'static str, &'static str) {
    (c.kind.unit(), c.kind.rate_unit())
}

/// A dict of an equilibrium: time, coordinate names, units, roles, q, v,
/// the starting guess, the solve's figures.
fn equilibrium_dict<'py>(
    py: Python<'py>,
    coordinates: &[CoordinateInfo],
    eq: &Equilibrium,
) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("t", eq.t)?;
    d.set_item(
        "coordinates",
        coordinates
            .iter()
            .map(|c| c.name.clone())
            .collect::<Vec<_>>(),
    )?;
    d.set_item(
        "units",
        coordinates.iter().map(|c| units(c).0).collect::<Vec<_>>(),
    )?;
    d.set_item(
        "rate_units",
        coordinates.iter().map(|c| units(c).1).collect::<Vec<_>>(),
    )?;
    d.set_item(
        "roles",
        eq.roles
            .iter()
            .map(|r| match r {
                Role::Position => "solved",
                Role::Rate => "rate solved",
                Role::Held => "held",
            })
            .collect::<Vec<_>>(),
    )?;
    d.set_item("q", PyArray1::from_slice(py, &eq.q))?;
    d.set_item("v", PyArray1::from_slice(py, &eq.v))?;
    d.set_item("q_start", PyArray1::from_slice(py, &eq.q_start))?;
    d.set_item("v_start", PyArray1::from_slice(py, &eq.v_start))?;
    d.set_item("iterations", eq.iterations)?;
    d.set_item("residual", eq.residual)?;
    d.set_item("tolerance", eq.tolerance)?;
    d.set_item("seconds", eq.seconds)?;
    Ok(d)
}

/// `scenario` set to start from its equilibrium.
fn at_equilibrium(scenario: &Scenario) -> Scenario {
    let mut s = scenario.clone();
    s.initial_kind = InitialStateKind::Equilibrium;
    s
}

/// The static (steady) equilibrium at the scenario's start and the wheel
/// loads there, as `umsim equilibrium`.
pub(crate) fn equilibrium(
    py: Python<'_>,
    scenario: &Scenario,
    model: &Model,
    engine: Engine,
    plugin: Option<&Path>,
) -> PyResult<Py<PyAny>> {
    let s = at_equilibrium(scenario);
    let solved = py.detach(|| -> Result<_, Failure> {
        let engines = Engines::new(model, engine, plugin).map_err(Failure::Engine)?;
        let mut solved = scenario_system(&s, model, engines.make())?;
        let eq = solved
            .equilibrium
            .clone()
            .expect("an equilibrium was asked for");
        let loads = wheel_loads(&mut solved.system, eq.t, &eq.q, &eq.v)
            .map_err(|e| Failure::Run(RunError::Sim(e)))?;
        Ok((solved.coordinates, eq, loads))
    });
    let (coordinates, eq, loads) = solved.map_err(|f| failure(py, f))?;
    let d = equilibrium_dict(py, &coordinates, &eq)?;
    let rows = PyList::empty(py);
    for (element, w) in &loads {
        for (side, (q, y)) in ["left", "right"].iter().zip(w.loads) {
            let r = PyDict::new(py);
            r.set_item("element", element)?;
            r.set_item("side", side)?;
            r.set_item("Q[N]", q)?;
            r.set_item("Y[N]", y)?;
            rows.append(r)?;
        }
    }
    d.set_item("wheel_loads", rows)?;
    wrap(py, "Equilibrium", d)
}

/// An instance of the class `name` of `railmbs.analysis` made from `d`.
fn wrap(py: Python<'_>, name: &str, d: Bound<'_, PyDict>) -> PyResult<Py<PyAny>> {
    Ok(py
        .import("railmbs.analysis")?
        .getattr(name)?
        .call1((d,))?
        .unbind())
}

/// A dict of the modes at one speed (see `railmbs.analysis.Modes`).
fn modes_dict<'py>(py: Python<'py>, one: &SpeedModes) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("speed", one.speed)?;
    d.set_item(
        "coordinates",
        one.coordinates
            .iter()
            .map(|c| c.name.clone())
            .collect::<Vec<_>>(),
    )?;
    let rows = PyList::empty(py);
    let (mut re, mut im) = (Vec::new(), Vec::new());
    for m in &one.modes.modes {
        let r = PyDict::new(py);
        r.set_item("frequency[Hz]", m.frequency)?;
        r.set_item("natural_frequency[Hz]", m.natural_frequency)?;
        r.set_item("damping_ratio", m.damping_ratio)?;
        r.set_item("re[1/s]", m.re)?;
        r.set_item("im[rad/s]", m.im)?;
        r.set_item("lateral_share", m.lateral_share)?;
        r.set_item("lateral", m.is_lateral())?;
        r.set_item("name", &m.name)?;
        rows.append(r)?;
        for &(a, b) in &m.shape {
            re.push(a);
            im.push(b);
        }
    }
    d.set_item("modes", rows)?;
    d.set_item("shape_re", PyArray1::from_vec(py, re))?;
    d.set_item("shape_im", PyArray1::from_vec(py, im))?;
    d.set_item("zero_modes", one.modes.zero_modes.clone())?;
    d.set_item(
        "equilibrium",
        equilibrium_dict(py, &one.coordinates, &one.equilibrium)?,
    )?;
    let a = &one.linearization.a;
    // Row-major, as numpy's default.
    let flat: Vec<f64> = (0..a.nrows())
        .flat_map(|i| (0..a.ncols()).map(move |j| a[(i, j)]))
        .collect();
    d.set_item("a", PyArray1::from_vec(py, flat))?;
    d.set_item("states", one.linearization.names.clone())?;
    d.set_item("seconds", one.seconds.to_vec())?;
    Ok(d)
}

/// What `Scenario.modes` computes.
pub(crate) enum ModesOf {
    /// At the scenario's own speed, or at this one (m/s).
    One(Option<f64>),
    /// A root locus over these speeds (m/s).
    Speeds(Vec<f64>),
    /// A locus over model parameter `.0` at these values, at the scenario's
    /// own speed or at `.2` (m/s).
    Parameter(String, Vec<f64>, Option<f64>),
}

/// The modes (`umsim modes`), a root locus (`--speed`) or a parameter
/// locus (`--sweep`).
pub(crate) fn modes(
    py: Python<'_>,
    scenario: &Scenario,
    model: &Model,
    engine: Engine,
    plugin: Option<&Path>,
    what: ModesOf,
) -> PyResult<Py<PyAny>> {
    let computed = py.detach(|| -> Result<Vec<SpeedModes>, Failure> {
        let engines = Engines::new(model, engine, plugin).map_err(Failure::Engine)?;
        let mut make = || Ok(engines.make());
        let own = |v: Option<f64>| match v {
            Some(v) => at_speed(scenario, model, v),
            None => scenario.clone(),
        };
        Ok(match &what {
            ModesOf::One(v) => vec![scenario_modes(
                &own(*v),
                model,
                engines.make(),
                &ContactTableCache::new(),
            )?],
            ModesOf::Speeds(speeds) => root_locus(scenario, model, speeds, &mut make)?,
            ModesOf::Parameter(name, values, v) => {
                parameter_locus(&own(*v), model, name, values, &mut make)?
            }
        })
    });
    let locus = computed.map_err(|f| failure(py, f))?;
    let (axis, values, critical) = match what {
        ModesOf::One(_) => return wrap(py, "Modes", modes_dict(py, &locus[0])?),
        ModesOf::Speeds(speeds) => ("speed[m/s]".to_string(), speeds, critical_speed(&locus)),
        ModesOf::Parameter(name, values, _) => {
            let samples: Vec<(f64, f64)> = locus
                .iter()
                .zip(&values)
                .filter_map(|(one, &x)| {
                    one.modes
                        .least_damped_lateral()
                        .map(|m| (x, m.damping_ratio))
                })
                .collect();
            (name, values, zero_crossing(&samples))
        }
    };
    let d = PyDict::new(py);
    d.set_item("axis", axis)?;
    d.set_item("values", PyArray1::from_vec(py, values))?;
    d.set_item("critical", critical)?;
    let points = PyList::empty(py);
    for one in &locus {
        points.append(wrap(py, "Modes", modes_dict(py, one)?)?)?;
    }
    d.set_item("modes", points)?;
    wrap(py, "Locus", d)
}

/// Settings of `Scenario.critical_speed`.
pub(crate) struct CriticalOptions {
    /// Limit-cycle signals (coordinate names); empty: the wheelsets' lateral
    /// coordinates.
    pub signals: Vec<String>,
    /// The detection's thresholds and window.
    pub detection: DetectionSettings,
    /// A bifurcation diagram over these speeds (m/s) instead of the
    /// decelerating run, with its plateau plan (`speeds` filled in here).
    pub bifurcation: Option<Staircase>,
}

/// The nonlinear critical speed (`umsim critical-speed`): a decelerating
/// run, or a bifurcation diagram; the run's rows are kept.
pub(crate) fn critical(
    py: Python<'_>,
    scenario: &Scenario,
    model: &Model,
    engine: Engine,
    plugin: Option<&Path>,
    options: CriticalOptions,
    watch: &crate::sim::Watch<'_>,
) -> PyResult<Py<PyAny>> {
    enum Found {
        Run(Detection),
        Branch(Vec<BranchPoint>),
    }
    let mut table = Table::new();
    let outcome = {
        let table = &mut table;
        let options = &options;
        py.detach(
            move || -> Result<(Vec<String>, RunSummary, Found), Failure> {
                let engines = Engines::new(model, engine, plugin).map_err(Failure::Engine)?;
                let signals = if options.signals.is_empty() {
                    let system = scenario_system(scenario, model, engines.make())?;
                    wheelset_lateral_coordinates(model, &system.coordinates)
                } else {
                    options.signals.clone()
                };
                let mut sink = Interruptible::new(table, watch.stop.clone());
                match &options.bifurcation {
                    None => {
                        let (summary, detection) = decelerating_run(
                            scenario,
                            model,
                            engines.make(),
                            &signals,
                            options.detection,
                            &mut sink,
                            |t| watch.tick(t),
                        )?;
                        Ok((signals, summary, Found::Run(detection)))
                    }
                    Some(plan) => {
                        let (summary, points) = bifurcation(
                            scenario,
                            model,
                            engines.make(),
                            &signals,
                            plan,
                            &mut sink,
                            |t| watch.tick(t),
                        )?;
                        Ok((signals, summary, Found::Branch(points)))
                    }
                }
            },
        )
    };
    if let Some(e) = watch.raised() {
        return Err(e);
    }
    let (signals, summary, found) = outcome.map_err(|f| failure(py, f))?;
    let d = PyDict::new(py);
    d.set_item("signals", signals)?;
    d.set_item("error", summary.error.as_ref().map(|e| e.to_string()))?;
    d.set_item("result", crate::sim::run_result(py, table, &summary)?)?;
    let s = options.detection;
    d.set_item("window", s.window)?;
    d.set_item("threshold", s.off)?;
    d.set_item("on", s.on)?;
    d.set_item("relative", s.relative)?;
    match found {
        Found::Run(detection) => {
            let (kind, speed, t, position, amplitude) = match detection {
                Detection::Collapsed(c) => (
                    "collapsed",
                    Some(c.speed),
                    Some(c.t),
                    c.position,
                    c.amplitude,
                ),
                Detection::StillHunting { amplitude, .. } => {
                    ("still_hunting", None, None, None, amplitude)
                }
                Detection::NoLimitCycle { max_amplitude } => {
                    ("no_limit_cycle", None, None, None, max_amplitude)
                }
            };
            d.set_item("detection", kind)?;
            d.set_item("speed", speed)?;
            d.set_item("t", t)?;
            d.set_item("position", position)?;
            d.set_item("amplitude", amplitude)?;
            if let Detection::StillHunting { speed, .. } = detection {
                d.set_item("end_speed", speed)?;
            }
            wrap(py, "CriticalSpeed", d)
        }
        Found::Branch(points) => {
            let rows = PyList::empty(py);
            for p in &points {
                let r = PyDict::new(py);
                r.set_item("speed[m/s]", p.speed)?;
                r.set_item("amplitude", p.amplitude)?;
                r.set_item("early", p.early)?;
                r.set_item("late", p.late)?;
                r.set_item("settled", p.settled(s.off))?;
                rows.append(r)?;
            }
            d.set_item("points", rows)?;
            wrap(py, "Bifurcation", d)
        }
    }
}

/// A dict of one curving solution (see `railmbs.analysis.Curving`).
fn curving_dict<'py>(py: Python<'py>, c: &Curving) -> PyResult<Bound<'py, PyDict>> {
    let d = PyDict::new(py);
    d.set_item("radius", c.curve.radius)?;
    d.set_item("cant", c.curve.cant)?;
    d.set_item("speed", c.curve.speed)?;
    d.set_item(
        "cant_deficiency_acceleration",
        c.curve.cant_deficiency_acceleration(),
    )?;
    d.set_item(
        "equilibrium",
        equilibrium_dict(py, &c.coordinates, &c.equilibrium)?,
    )?;
    let rows = PyList::empty(py);
    for w in &c.wheelsets {
        let r = PyDict::new(py);
        r.set_item("element", &w.element)?;
        r.set_item("wheelset", &w.wheelset)?;
        r.set_item("lateral", w.lateral)?;
        r.set_item("yaw", w.yaw)?;
        let outputs = PyDict::new(py);
        for (n, x) in &w.outputs {
            outputs.set_item(n, x)?;
        }
        r.set_item("outputs", outputs)?;
        rows.append(r)?;
    }
    d.set_item("wheelsets", rows)?;
    d.set_item("seconds", c.seconds.to_vec())?;
    Ok(d)
}

/// The quasi-static curving solution at each of `speeds` (m/s), each from
/// the one before (`umsim curving --speed`).
#[allow(clippy::too_many_arguments)]
pub(crate) fn curving(
    py: Python<'_>,
    scenario: &Scenario,
    model: &Model,
    engine: Engine,
    plugin: Option<&Path>,
    radius: f64,
    cant: f64,
    speeds: &[f64],
) -> PyResult<Py<PyAny>> {
    for &speed in speeds {
        Curve {
            radius,
            cant,
            speed,
        }
        .track()
        .map_err(pyo3::exceptions::PyValueError::new_err)?;
    }
    let solved = py.detach(|| -> Result<Vec<Curving>, Failure> {
        let engines = Engines::new(model, engine, plugin).map_err(Failure::Engine)?;
        let mut make = || Ok(engines.make());
        let tables = ContactTableCache::new();
        let mut out: Vec<Curving> = Vec::new();
        for &speed in speeds {
            let curve = Curve {
                radius,
                cant,
                speed,
            };
            let one = curving_from(scenario, model, &mut make, &tables, &curve, out.last())?;
            out.push(one);
        }
        Ok(out)
    });
    let solutions = solved.map_err(|f| failure(py, f))?;
    let list = PyList::empty(py);
    for c in &solutions {
        list.append(curving_dict(py, c)?)?;
    }
    let d = PyDict::new(py);
    d.set_item("solutions", list)?;
    wrap(py, "Curving", d)
}
