//! Shared helpers of the integration tests.
#![allow(dead_code)]

use nalgebra::{DMatrix, DVector};
use railmbs_models::Model;
use railmbs_runtime::integrate::{ParkSettings, Rk4Settings, integrate_park, integrate_rk4};
use railmbs_runtime::{Equations, MechanicalSystem, ModelSystem, NumericEquations, Parts};
use rand::{Rng as _, SeedableRng};
use rand_chacha::ChaCha8Rng;
use std::ops::ControlFlow;
use std::path::PathBuf;

/// Path of a file under the repository's `models/` folder.
pub fn model_path(rel: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../models")
        .join(rel)
}

/// Loads `models/mechanisms/<name>.ron`.
pub fn mechanism(name: &str) -> Model {
    let p = model_path(&format!("mechanisms/{name}.ron"));
    railmbs_models::load_model(&p).unwrap_or_else(|e| panic!("{e}"))
}

/// Every bundled mechanism model.
pub fn all_mechanisms() -> Vec<Model> {
    let mut names: Vec<String> = std::fs::read_dir(model_path("mechanisms"))
        .unwrap()
        .filter_map(|e| {
            let p = e.ok()?.path();
            (p.extension()? == "ron").then(|| p.file_stem()?.to_str().map(String::from))?
        })
        .collect();
    names.sort();
    names.iter().map(|n| mechanism(n)).collect()
}

/// Every bundled vehicle model (`models/vehicles/*.ron`; subsystem component
/// files live in subfolders and are covered through the vehicles).
pub fn all_vehicles() -> Vec<Model> {
    let mut paths: Vec<PathBuf> = std::fs::read_dir(model_path("vehicles"))
        .unwrap()
        .filter_map(|e| {
            let p = e.ok()?.path();
            (p.extension()? == "ron").then_some(p)
        })
        .collect();
    paths.sort();
    paths.push(model_path("vehicles/components/wheelset_s1002_irw.ron")); // no vehicle uses it yet
    paths
        .iter()
        .map(|p| railmbs_models::load_model(p).unwrap_or_else(|e| panic!("{e}")))
        .collect()
}

/// A system with the numeric engine and the given parameter overrides.
pub fn numeric_system(
    model: &Model,
    overrides: &[(&str, &str)],
) -> (ModelSystem, Vec<f64>, Vec<f64>) {
    let ov: Vec<(String, String)> = overrides
        .iter()
        .map(|(a, b)| (a.to_string(), b.to_string()))
        .collect();
    let params = model
        .parameter_values(&[], &ov)
        .unwrap_or_else(|e| panic!("{e}"));
    let (q0, v0) = model.initial_state(&params);
    let sys = ModelSystem::new(model, Box::new(NumericEquations::new(model)), params).unwrap();
    (sys, q0, v0)
}

/// Reproducible random numbers for the tests (ChaCha8 seeded with `seed`),
/// uniform in [lo, hi).
pub struct Rng(ChaCha8Rng);
impl Rng {
    pub fn new(seed: u64) -> Self {
        Self(ChaCha8Rng::seed_from_u64(seed))
    }
    pub fn uniform(&mut self, lo: f64, hi: f64) -> f64 {
        self.0.random_range(lo..hi)
    }
    pub fn vec(&mut self, n: usize, lo: f64, hi: f64) -> Vec<f64> {
        (0..n).map(|_| self.uniform(lo, hi)).collect()
    }
}

/// Kinetic energy ½ q̇ᵀ M q̇ plus potential energy −Σ m_j g·r_j (J), at a state
/// of a model whose only forces are gravity (and conservative springs, which
/// are not included here).
pub fn mechanical_energy(
    model: &Model,
    sys: &mut ModelSystem,
    t: f64,
    q: &[f64],
    v: &[f64],
) -> f64 {
    let params = sys.params().to_vec();
    let g: Vec<f64> = model.gravity.iter().map(|e| e.eval(&params, t)).collect();
    let masses: Vec<f64> = model
        .bodies
        .iter()
        .map(|b| b.mass.eval(&params, t))
        .collect();
    let e = sys.evaluate(t, q, v, Parts::ALL).unwrap();
    let vv = DVector::from_column_slice(v);
    let kinetic = 0.5 * vv.dot(&(&e.mass * &vv));
    let potential: f64 = e
        .bodies
        .iter()
        .zip(&masses)
        .map(|(b, m)| -m * (g[0] * b.position.x + g[1] * b.position.y + g[2] * b.position.z))
        .sum();
    kinetic + potential
}

/// (t, q, q̇) at the end of every accepted step.
pub type Trajectory = Vec<(f64, Vec<f64>, Vec<f64>)>;

/// Integrates with RK4 and returns (t, q, v) of every step.
pub fn run_rk4(sys: &mut ModelSystem, q0: &[f64], v0: &[f64], t_end: f64, h: f64) -> Trajectory {
    let mut out = Vec::new();
    integrate_rk4(
        sys,
        &Rk4Settings::new(h),
        0.0,
        q0,
        v0,
        t_end,
        |t, q, v, _| {
            out.push((t, q.to_vec(), v.to_vec()));
            ControlFlow::Continue(())
        },
    )
    .unwrap_or_else(|e| panic!("{e}"));
    out
}

/// Integrates with Park's method and returns (t, q, v) of every step and the stats.
pub fn run_park(
    sys: &mut ModelSystem,
    settings: &ParkSettings,
    q0: &[f64],
    v0: &[f64],
    t_end: f64,
) -> (Trajectory, railmbs_runtime::integrate::IntegrationStats) {
    let mut out = Vec::new();
    let stats = integrate_park(sys, settings, 0.0, q0, v0, t_end, |t, q, v, _| {
        out.push((t, q.to_vec(), v.to_vec()));
        ControlFlow::Continue(())
    })
    .unwrap_or_else(|e| panic!("{e}"));
    (out, stats)
}

/// Mass matrix and f = Q − k at a state, through the `MechanicalSystem` view.
pub fn dynamics(
    sys: &mut ModelSystem,
    t: f64,
    q: &[f64],
    v: &[f64],
) -> (DMatrix<f64>, DVector<f64>) {
    let n = sys.dof();
    let mut m = DMatrix::zeros(n, n);
    let mut f = DVector::zeros(n);
    sys.dynamics(t, q, v, &mut m, &mut f).unwrap();
    (m, f)
}

/// A fresh numeric engine for `model` with default parameters.
pub fn numeric_engine(model: &Model) -> NumericEquations {
    let mut e = NumericEquations::new(model);
    e.set_parameters(&model.default_parameter_values()).unwrap();
    e
}

/// Builds (through the cache under the target directory) and loads the
/// symbolic plugin of `model`; built once per test process and model.
pub fn symbolic_engine(model: &Model) -> railmbs_runtime::PluginEquations {
    use std::collections::HashMap;
    use std::sync::{Mutex, OnceLock};
    static BUILT: OnceLock<Mutex<HashMap<String, PathBuf>>> = OnceLock::new();
    let hash = model.structural_hash();
    let path = {
        let mut map = BUILT
            .get_or_init(|| Mutex::new(HashMap::new()))
            .lock()
            .unwrap();
        map.entry(hash)
            .or_insert_with(|| {
                let cache = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join("railmbs-plugins");
                let opts = railmbs_codegen::GenerateOptions::new();
                railmbs_codegen::build_plugin(model, &opts, Some(cache))
                    .unwrap_or_else(|e| panic!("{}: {e}", model.name))
                    .path
            })
            .clone()
    };
    let plugin = railmbs_runtime::Plugin::load_for(&path, model).unwrap_or_else(|e| panic!("{e}"));
    let mut eq = railmbs_runtime::PluginEquations::new(plugin);
    eq.set_parameters(&model.default_parameter_values())
        .unwrap();
    eq
}

/// Inertia tensor of `body` about its centre of mass in the body frame (kg m²).
pub fn body_inertia(body: &railmbs_models::Body, params: &[f64]) -> nalgebra::Matrix3<f64> {
    let i: Vec<f64> = body.inertia.iter().map(|x| x.eval(params, 0.0)).collect();
    nalgebra::Matrix3::new(i[0], i[3], i[4], i[3], i[1], i[5], i[4], i[5], i[2])
}

/// Columns of a CSV output of `umsim run` by name.
pub struct Table {
    /// Column names, `time` first.
    pub header: Vec<String>,
    /// One row of values per output time.
    pub rows: Vec<Vec<f64>>,
}

impl Table {
    /// Reads a CSV file written by a run (numbers only after the header).
    pub fn read(path: &std::path::Path) -> Table {
        let text = std::fs::read_to_string(path).unwrap();
        let mut lines = text.lines();
        let header = lines
            .next()
            .unwrap()
            .split(',')
            .map(str::to_string)
            .collect();
        let rows = lines
            .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
            .collect();
        Table { header, rows }
    }

    /// The column `name`; panics naming it if absent.
    pub fn col(&self, name: &str) -> Vec<f64> {
        let k = self
            .header
            .iter()
            .position(|h| h == name)
            .unwrap_or_else(|| panic!("no column {name}"));
        self.rows.iter().map(|r| r[k]).collect()
    }
}

/// Runs `scenario` on `model` with `engine`, writing the CSV to a temporary
/// folder; asserts the run reached its end time without error and returns
/// the output.
pub fn run_to_table(
    scenario: &railmbs_models::Scenario,
    model: &Model,
    engine: Box<dyn Equations>,
) -> Table {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.csv");
    let summary =
        railmbs_runtime::run::run_scenario(scenario, model, engine, Some(&out), |_| {}).unwrap();
    assert!(summary.error.is_none(), "{:?}", summary.error);
    assert!((summary.t_end - scenario.end_time).abs() < 1e-9);
    Table::read(&out)
}
