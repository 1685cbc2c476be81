//! Wheelsets on the track with wheel–rail contact: physics oracles.

mod common;

use common::*;
use railmbs_runtime::NumericEquations;
use railmbs_wheelrail::conicity::{RollTreatment, conicity_curve};
use railmbs_wheelrail::geometry::{ContactGeometry, SearchSettings, Track, Wheelset};
use railmbs_wheelrail::profile::{Profile, ProfileKind, ProfileSettings};

/// Columns of a CSV output by name.
struct Table {
    header: Vec<String>,
    rows: Vec<Vec<f64>>,
}

impl Table {
    fn read(path: &std::path::Path) -> Table {
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
    fn col(&self, name: &str) -> Vec<f64> {
        let k = self
            .header
            .iter()
            .position(|h| h == name)
            .unwrap_or_else(|| panic!("no column {name}"));
        self.rows.iter().map(|r| r[k]).collect()
    }
}

/// Runs a bundled scenario with the numeric engine; returns the output table.
fn run(scenario: &str) -> Table {
    let scenario = railmbs_models::load_scenario(&model_path(scenario)).unwrap();
    let model = railmbs_models::load_model(&scenario.model).unwrap();
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.csv");
    let summary = railmbs_runtime::simulate::run_scenario(
        &scenario,
        &model,
        Box::new(NumericEquations::new(&model)),
        Some(&out),
        |_| {},
    )
    .unwrap();
    assert!(summary.error.is_none(), "{:?}", summary.error);
    Table::read(&out)
}

/// Times where `y` crosses zero upwards (linear interpolation).
fn up_crossings(t: &[f64], y: &[f64]) -> Vec<f64> {
    (1..y.len())
        .filter(|&i| y[i - 1] < 0.0 && y[i] >= 0.0)
        .map(|i| t[i - 1] + (t[i] - t[i - 1]) * (-y[i - 1]) / (y[i] - y[i - 1]))
        .collect()
}

/// A free wheelset (S1002 on UIC60 1:40, no suspension) released 2 mm off
/// centre runs Klingel's kinematic oscillation: wavelength
/// λ = 2π √(r0 e0 / tan γe), with tan γe the EN 15302 equivalent conicity at
/// the oscillation's amplitude (profile pair strongly nonlinear: the
/// amplitude is measured over the same cycles as the wavelength). Tolerance
/// 3 % (the issue's): Klingel's formula is the kinematic limit (no creep
/// compliance, no gravitational stiffness), which at 10 m/s and this
/// conicity shifts the wavelength by about 1 %.
#[test]
fn free_wheelset_runs_klingels_kinematic_oscillation() {
    let speed = 10.0;
    let out = run("scenarios/free_wheelset_klingel.ron");
    let (t, y) = (out.col("time"), out.col("ws.y"));
    let ups = up_crossings(&t, &y);
    assert!(ups.len() >= 5, "too few cycles: {ups:?}");
    // The last three full cycles.
    let (t0, t1) = (ups[ups.len() - 4], ups[ups.len() - 1]);
    let period = (t1 - t0) / 3.0;
    let wavelength = speed * period;
    let amplitude = t
        .iter()
        .zip(&y)
        .filter(|(tt, _)| **tt >= t0 && **tt <= t1)
        .fold(0.0_f64, |m, (_, yy)| m.max(yy.abs()));

    let profiles = model_path("profiles");
    let s = ProfileSettings::default();
    let wheel = Profile::read(
        &profiles.join("MBench_S1002_v3.prw"),
        ProfileKind::Wheel,
        &s,
    )
    .unwrap();
    let rail = Profile::read(&profiles.join("MBench_UIC60_v3.ban"), ProfileKind::Rail, &s).unwrap();
    let geo = ContactGeometry::new(
        &Wheelset::new(wheel.clone(), wheel, 0.46, 1.360),
        &Track::new(rail.clone(), rail, 1.435),
        SearchSettings::default(),
    )
    .unwrap();
    let centre = geo.rigid(0.0).unwrap();
    let e0 = 0.5 * (centre.sides[0].deepest().rail_y - centre.sides[1].deepest().rail_y);
    let conicity = conicity_curve(&geo, &[amplitude], RollTreatment::Neglected).unwrap()[0].1;
    let klingel = 2.0 * std::f64::consts::PI * (0.46 * e0 / conicity).sqrt();
    let err = (wavelength - klingel).abs() / klingel;
    println!(
        "amplitude {:.3} mm, tan γe {conicity:.4}, e0 {e0:.4} m: simulated {wavelength:.3} m, \
         Klingel {klingel:.3} m, error {:.2} %",
        amplitude * 1e3,
        100.0 * err
    );
    assert!(err < 0.03, "wavelength error {:.2} %", 100.0 * err);
}
