//! Track-following frames (runtime inputs): a free body described relative to
//! a frame that drives a curve with varying cant moves in a straight line at
//! constant velocity in SC0, with either engine; and the engines agree with
//! inputs set.

use railmbs_runtime::integrate::ParkSettings;
use railmbs_runtime::{
    DrivenEquations, Equations, Evaluation, InputProvider, ModelSystem, NumericEquations, Parts,
    SimError,
};
use railmbs_testkit::*;

/// A frame running at speed V on a circle of radius R (left-hand curve),
/// with roll φ(t) = a sin(w t) and pitch θ(t) = b sin(w t): analytic pose,
/// rates and accelerations.
struct CircleFrame {
    radius: f64,
    speed: f64,
    roll: f64,
    pitch: f64,
    w: f64,
}

impl InputProvider for CircleFrame {
    fn input_count(&self) -> usize {
        6
    }
    fn inputs(&mut self, t: f64, out: &mut [f64]) -> Result<(), SimError> {
        let (r, v, w) = (self.radius, self.speed, self.w);
        let psi = v * t / r;
        let wz = v / r;
        let (s, c) = psi.sin_cos();
        let (sw, cw) = (w * t).sin_cos();
        // x, y, z, yaw, pitch, roll: (value, rate, acceleration) each.
        let vals = [
            [r * s, v * c, -v * wz * s],
            [r * (1.0 - c), v * s, v * wz * c],
            [0.0, 0.0, 0.0],
            [psi, wz, 0.0],
            [
                self.pitch * sw,
                self.pitch * w * cw,
                -self.pitch * w * w * sw,
            ],
            [self.roll * sw, self.roll * w * cw, -self.roll * w * w * sw],
        ];
        for (k, x) in vals.iter().enumerate() {
            out[3 * k..3 * k + 3].copy_from_slice(x);
        }
        Ok(())
    }
}

fn frame() -> Box<CircleFrame> {
    Box::new(CircleFrame {
        radius: 150.0,
        speed: 20.0,
        roll: 0.1,
        pitch: 0.02,
        w: 1.5,
    })
}

#[test]
fn a_free_body_moves_in_a_straight_line_whatever_the_track_frame_does() {
    let model = mechanism("track_free_body");
    let params = model.default_parameter_values();
    // At rest relative to the frame at t = 0: the body starts at the frame's
    // origin with the frame's velocity (20, 0, 0) m/s and its angular velocity.
    let (q0, v0) = model.initial_state(&params);
    for engine in ["numeric", "symbolic"] {
        let inner: Box<dyn Equations> = match engine {
            "numeric" => Box::new(NumericEquations::new(&model)),
            _ => Box::new(symbolic_engine(&model)),
        };
        assert_eq!(inner.input_count(), 6);
        let driven = DrivenEquations::new(inner, frame()).unwrap();
        let mut sys = ModelSystem::new(&model, Box::new(driven), params.clone()).unwrap();
        let (steps, _) = run_park(
            &mut sys,
            &ParkSettings {
                max_step: 2e-3,
                ..ParkSettings::with_tolerances(1e-9, 1e-9)
            },
            &q0,
            &v0,
            4.0,
        );
        for (t, q, v) in steps.iter().step_by(100) {
            let e = sys.evaluate(*t, q, v, Parts::KINEMATICS).unwrap();
            let b = e.bodies[0];
            // Straight line at 20 m/s along x while the frame has turned by
            // 80 m / 150 m ≈ 0.53 rad and drifted ~21 m sideways.
            let expect = nalgebra::Vector3::new(20.0 * t, 0.0, 0.0);
            assert!(
                (b.position - expect).norm() < 1e-5,
                "{engine}, t = {t}: body at {:?}, expected {:?}",
                b.position,
                expect
            );
            assert!((b.velocity - nalgebra::Vector3::new(20.0, 0.0, 0.0)).norm() < 1e-5);
        }
    }
}

#[test]
fn a_model_with_track_frames_needs_an_input_provider() {
    let model = mechanism("track_free_body");
    let err = ModelSystem::new(
        &model,
        Box::new(NumericEquations::new(&model)),
        model.default_parameter_values(),
    )
    .unwrap_err()
    .to_string();
    assert!(err.contains("track-following"), "{err}");
}

#[test]
fn symbolic_equals_numeric_with_inputs() {
    let model = mechanism("track_free_body");
    let mut num = numeric_engine(&model);
    let mut sym = symbolic_engine(&model);
    let mut en = Evaluation::for_equations(&num);
    let mut es = Evaluation::for_equations(&sym);
    let mut rng = seeded_rng(17);
    for _ in 0..100 {
        let u = uniform_vec(&mut rng, 18, -2.0, 2.0);
        num.set_inputs(&u).unwrap();
        sym.set_inputs(&u).unwrap();
        let q = uniform_vec(&mut rng, 6, -1.0, 1.0);
        let v = uniform_vec(&mut rng, 6, -2.0, 2.0);
        num.evaluate(0.3, &q, &v, Parts::ALL, &mut en).unwrap();
        sym.evaluate(0.3, &q, &v, Parts::ALL, &mut es).unwrap();
        let scale = en.mass.abs().max();
        assert!((&es.mass - &en.mass).abs().max() < 1e-12 * scale);
        let kscale = scale * (1.0 + 4.0 * 4.0);
        assert!(
            (&es.bias - &en.bias).abs().max() < 1e-12 * kscale,
            "k differs"
        );
        assert!((&es.jacobians - &en.jacobians).abs().max() < 1e-12 * en.jacobians.abs().max());
    }
}

/// Largest deviation (m) of the free body from x = 11 + 4.4 t, y = z = 0 on
/// track case 1 with Park at the given tolerance, and the number of rows.
fn tc1_free_body_error(tol: f64) -> (f64, usize) {
    let scenario_path = model_path("scenarios/track_free_body_tc1.ron");
    let mut scenario =
        railmbs_models::load_scenario(&scenario_path).unwrap_or_else(|e| panic!("{e}"));
    scenario.integrator = railmbs_models::IntegratorSpec::Park {
        rtol: tol,
        atol: tol,
        max_step: 0.05,
        initial_step: None,
        jacobian: railmbs_models::JacobianKind::FiniteDifference,
        solver: Default::default(),
    };
    let model = railmbs_models::load_model(&scenario.model).unwrap_or_else(|e| panic!("{e}"));
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("tc1.csv");
    let summary = railmbs_runtime::run::run_scenario(
        &scenario,
        &model,
        Box::new(NumericEquations::new(&model)),
        Some(&out),
        |_| {},
    )
    .unwrap();
    assert!(summary.error.is_none(), "{:?}", summary.error);
    assert_eq!(
        summary.rejected_steps, 0,
        "steps rejected at the track's kinks"
    );
    let table = Table::read(&out);
    let (time, x, y, z) = (
        table.col("time"),
        table.col("body.x[m]"),
        table.col("body.y[m]"),
        table.col("body.z[m]"),
    );
    let mut worst: f64 = 0.0;
    for (k, &t) in time.iter().enumerate() {
        worst = worst
            .max((x[k] - (11.0 + 4.4 * t)).abs())
            .max(y[k].abs())
            .max(z[k].abs());
    }
    (worst, table.rows.len())
}

#[test]
fn a_free_body_on_manchester_track_case_1_goes_straight_in_sc0() {
    // At rest relative to its frame at t = 0 (s = 11 m on the straight lead-in,
    // 4.4 m/s), the body keeps x = 11 + 4.4 t, y = z = 0 while the frame runs
    // through the transitions, the cant ramps (whose ends are velocity kinks:
    // the run restarts there with continuous absolute velocities) and the
    // R = 150 m curve. The deviation is the global integration error: it falls
    // with the tolerance (second order: about tol^(2/3)).
    let (coarse, rows) = tc1_free_body_error(1e-8);
    let (fine, _) = tc1_free_body_error(1e-10);
    assert_eq!(rows, 81);
    assert!(fine < 1e-5, "deviation {fine} m at tolerance 1e-10");
    assert!(
        coarse / fine > 8.0,
        "deviation {coarse} → {fine} m does not fall with the tolerance"
    );

    // Missing track in the scenario: a clear error naming the scenario.
    let scenario_path = model_path("scenarios/track_free_body_tc1.ron");
    let mut scenario =
        railmbs_models::load_scenario(&scenario_path).unwrap_or_else(|e| panic!("{e}"));
    let model = railmbs_models::load_model(&scenario.model).unwrap_or_else(|e| panic!("{e}"));
    scenario.track = None;
    let err = railmbs_runtime::run::run_scenario(
        &scenario,
        &model,
        Box::new(NumericEquations::new(&model)),
        None,
        |_| {},
    )
    .unwrap_err()
    .to_string();
    assert!(
        err.contains("track_free_body_tc1.ron") && err.contains("track"),
        "{err}"
    );
}

#[test]
fn a_run_into_a_table_holds_the_csv_columns_exactly() {
    // The same run written to a CSV file and kept in memory: the table has
    // the file's header and, column by column, its values (the CSV's
    // shortest round-trip text parses back to the same f64).
    let scenario_path = model_path("scenarios/track_free_body_tc1.ron");
    let scenario = railmbs_models::load_scenario(&scenario_path).unwrap_or_else(|e| panic!("{e}"));
    let model = railmbs_models::load_model(&scenario.model).unwrap_or_else(|e| panic!("{e}"));
    let engine = || Box::new(NumericEquations::new(&model));
    let csv = run_to_table(&scenario, &model, engine());
    let mut table = railmbs_runtime::run::Table::new();
    let summary =
        railmbs_runtime::run::run_scenario_into(&scenario, &model, engine(), &mut table, |_| {})
            .unwrap();
    assert!(summary.error.is_none(), "{:?}", summary.error);
    assert_eq!(summary.rows, csv.rows.len());
    assert_eq!(table.names(), &csv.header[..]);
    assert_eq!(table.rows(), csv.rows.len());
    for name in &csv.header {
        assert_eq!(table.column(name).unwrap(), &csv.col(name)[..], "{name}");
    }
    assert!(table.column("no such column").is_none());
}
