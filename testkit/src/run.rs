//! Integrations that record every accepted step, and scenario runs whose CSV
//! output is read back as a [`Table`].

use crate::table::Table;
use railmbs_models::{Model, Scenario};
use railmbs_runtime::integrate::{
    IntegrationStats, ParkSettings, Rk4Settings, integrate_park, integrate_rk4,
};
use railmbs_runtime::run::run_scenario;
use railmbs_runtime::{Equations, ModelSystem, NumericEquations};
use std::ops::ControlFlow;

/// (t, q, q̇) at the end of every accepted step.
pub type Trajectory = Vec<(f64, Vec<f64>, Vec<f64>)>;

/// Integrates from t = 0 to `t_end` with RK4 of step `h` and returns every
/// step.
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

/// Integrates from t = 0 to `t_end` with Park's method and returns every
/// accepted step and the statistics.
pub fn run_park(
    sys: &mut ModelSystem,
    settings: &ParkSettings,
    q0: &[f64],
    v0: &[f64],
    t_end: f64,
) -> (Trajectory, IntegrationStats) {
    let mut out = Vec::new();
    let stats = integrate_park(sys, settings, 0.0, q0, v0, t_end, |t, q, v, _| {
        out.push((t, q.to_vec(), v.to_vec()));
        ControlFlow::Continue(())
    })
    .unwrap_or_else(|e| panic!("{e}"));
    (out, stats)
}

/// Runs `scenario` on `model` with `engine`, writing the CSV to a temporary
/// folder; asserts that the run reached its end time without error and
/// returns the output.
pub fn run_to_table(scenario: &Scenario, model: &Model, engine: Box<dyn Equations>) -> Table {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.csv");
    let summary =
        run_scenario(scenario, model, engine, Some(&out), |_| {}).unwrap_or_else(|e| panic!("{e}"));
    assert!(summary.error.is_none(), "{:?}", summary.error);
    assert!((summary.t_end - scenario.end_time).abs() < 1e-9);
    Table::read(&out)
}

/// Writes `files` (name, text: the model, a track…) and the scenario text
/// `scenario` (as `run.ron`) into a temporary folder, runs the scenario with
/// the numeric engine and returns its output, or the message of what stopped
/// it (loading, setting up, or a failure during the run).
pub fn run_scenario_files(files: &[(&str, &str)], scenario: &str) -> Result<Table, String> {
    let dir = tempfile::tempdir().unwrap();
    for (name, text) in files {
        std::fs::write(dir.path().join(name), text).unwrap();
    }
    let path = dir.path().join("run.ron");
    std::fs::write(&path, scenario).unwrap();
    let sc = railmbs_models::load_scenario(&path).map_err(|e| e.to_string())?;
    let model = railmbs_models::load_model(&sc.model).map_err(|e| e.to_string())?;
    let out = dir.path().join("out.csv");
    let engine = Box::new(NumericEquations::new(&model));
    let summary =
        run_scenario(&sc, &model, engine, Some(&out), |_| {}).map_err(|e| e.to_string())?;
    if let Some(e) = summary.error {
        return Err(e.to_string());
    }
    Ok(Table::read(&out))
}
