//! Trains: several vehicles on one track coupled by couplers
//! (`railmbs_runtime::train`).

use railmbs_models::{Model, TrainScenario, load_model, load_scenario, parse_train};
use railmbs_runtime::train::run_train;
use railmbs_runtime::{Equations, MechanicalSystem, NumericEquations};
use railmbs_testkit::*;
use std::path::Path;

/// A train file written to `dir` (paths in it are absolute).
fn train_from_text(dir: &Path, text: &str) -> TrainScenario {
    let path = dir.join("train.ron");
    std::fs::write(&path, text).unwrap();
    parse_train(text, &path).unwrap_or_else(|e| panic!("{e}"))
}

fn path_text(rel: &str) -> String {
    model_path(rel).display().to_string()
}

/// Runs a train with one engine per vehicle made by `engine`; returns the
/// output table and the summary.
fn run(
    train: &TrainScenario,
    engine: impl Fn(&Model) -> Box<dyn Equations>,
    out: &Path,
) -> (Table, railmbs_runtime::run::RunSummary) {
    let models = vehicle_models(train);
    let refs: Vec<&Model> = models.iter().collect();
    let engines = models.iter().map(&engine).collect();
    let summary = run_train(train, &refs, engines, Some(out), |_| {}).unwrap();
    assert!(summary.error.is_none(), "{:?}", summary.error);
    (Table::read(out), summary)
}

/// The models of a train's vehicles, in vehicle order.
fn vehicle_models(train: &TrainScenario) -> Vec<Model> {
    train
        .vehicles
        .iter()
        .map(|v| load_model(&v.model).unwrap())
        .collect()
}

fn numeric(model: &Model) -> Box<dyn Equations> {
    Box::new(NumericEquations::new(model))
}

/// A train of one vehicle without couplers runs exactly the plain scenario of
/// that vehicle (same engine): Vehicle 1 at 55 m/s entering lateral
/// irregularities.
#[test]
fn a_train_of_one_vehicle_runs_the_plain_scenario() {
    let dir = tempfile::tempdir().unwrap();
    let mut scenario = load_scenario(&model_path("scenarios/vehicle1_straight_55.ron")).unwrap();
    // From the model's given state, as a train starts (trains do not
    // start from equilibrium yet).
    scenario.initial_kind = railmbs_models::InitialStateKind::Given;
    scenario.end_time = 0.8;
    scenario.output.coordinates = true;
    scenario.output.velocities = true;
    let model = load_model(&scenario.model).unwrap();
    let plain_out = dir.path().join("plain.csv");
    let plain = railmbs_runtime::run::run_scenario(
        &scenario,
        &model,
        numeric(&model),
        Some(&plain_out),
        |_| {},
    )
    .unwrap();
    assert!(plain.error.is_none());
    let p = Table::read(&plain_out);
    // The vehicle at the train's reference point, and 26 m behind it with the
    // reference point 26 m further on: the same track under the same wheels.
    for (offset, start) in [(0.0, 20.0), (-26.0, 46.0)] {
        let train = train_from_text(
            dir.path(),
            &format!(
                r#"Train(
                vehicles: [Vehicle(name: "V", model: "{}", offset: {offset:?},
                                   parameters: {{ "v0": 55.0 }})],
                track: (file: "{}", start: {start:?}, speed: 55.0),
                end_time: 0.8,
                integrator: Park(rtol: 1e-4, atol: 1e-6, max_step: 0.005),
                output: (interval: 0.005, velocities: true),
            )"#,
                path_text("vehicles/vehicle1.ron"),
                path_text("tracks/straight_lateral_irregularity.ron"),
            ),
        );
        let (t, summary) = run(&train, numeric, &dir.path().join("train.csv"));
        assert_eq!(summary.steps, plain.steps);
        assert_eq!(t.rows.len(), p.rows.len());
        let mut worst: f64 = 0.0;
        let mut moved: f64 = 0.0;
        for c in &model.coordinates {
            for name in [c.name.clone(), format!("{}.v", c.name)] {
                let a = p.col(&name);
                let b = t.col(&format!("V.{name}"));
                for (x, y) in a.iter().zip(&b) {
                    worst = worst.max((x - y).abs() / x.abs().max(1e-3));
                }
                if name == "body.y" {
                    moved = a.iter().fold(0.0, |m, x| m.max(x.abs()));
                }
            }
        }
        assert!(moved > 1e-5, "the irregularity should move the car body");
        assert!(
            worst < 1e-9,
            "offset {offset}: largest relative difference {worst:e}"
        );
        // The column s[m] is the train's reference point.
        assert_eq!(t.col("s[m]")[0], start);
    }
}

#[test]
fn couplers_conserve_the_total_linear_momentum() {
    let dir = tempfile::tempdir().unwrap();
    for integrator in [
        "Rk4(step: 0.001)",
        "Park(rtol: 1e-8, atol: 1e-10, max_step: 0.01)",
    ] {
        let train = train_from_text(
            dir.path(),
            &format!(
                r#"Train(
                vehicles: [
                    Vehicle(name: "A", model: "{car}", offset: 0.0,
                            initial: [(coord: "body.x", velocity: 0.5), (coord: "body.rz", velocity: 0.1)]),
                    Vehicle(name: "B", model: "{car}", offset: -10.0, parameters: {{ "m": 3000.0 }},
                            initial: [(coord: "body.y", velocity: -0.2), (coord: "body.z", velocity: 0.1)]),
                ],
                couplers: [
                    Coupler(name: "AB", body1: "A.body", point1: (-5.0, 0.0, 0.3),
                            body2: "B.body", point2: (5.0, 0.0, 0.3),
                            stiffness: (1e5, 2e4, 3e4), damping: (1e3, 500.0, 500.0),
                            angular_stiffness: (1e4, 1e4, 1e4), preload: (200.0, 0.0, 0.0)),
                ],
                track: (file: "{track}", start: 100.0, speed: 10.0),
                end_time: 2.0,
                integrator: {integrator},
                output: (interval: 0.05, bodies: ["*"]),
            )"#,
                car = path_text("vehicles/train/track_car.ron"),
                track = path_text("tracks/straight.ron"),
            ),
        );
        let (t, _) = run(&train, numeric, &dir.path().join("out.csv"));
        let (ma, mb) = (1000.0, 3000.0);
        let fx = t.col("AB.Fx[N]");
        assert!(fx.iter().fold(0.0_f64, |m, f| m.max(f.abs())) > 1e3);
        let tol = if integrator.starts_with("Rk4") {
            1e-11
        } else {
            1e-7
        };
        for axis in ["x", "y", "z"] {
            let a = t.col(&format!("A.body.v{axis}[m/s]"));
            let b = t.col(&format!("B.body.v{axis}[m/s]"));
            let p: Vec<f64> = a.iter().zip(&b).map(|(x, y)| ma * x + mb * y).collect();
            let scale = ma * 10.0;
            for pi in &p {
                assert!(
                    (pi - p[0]).abs() < tol * scale,
                    "{integrator}: momentum along {axis} {pi} vs {} at start",
                    p[0]
                );
            }
        }
    }
}

/// A vehicle with a first-order element state (a spring in series with a
/// damper between its body and an inner mass) in a train: the state sits after
/// the vehicle's coordinates and takes no coupler force; total momentum of the
/// three bodies is conserved.
#[test]
fn a_vehicle_with_element_states_couples_and_conserves_momentum() {
    let dir = tempfile::tempdir().unwrap();
    let car = dir.path().join("damped_car.ron");
    std::fs::write(
        &car,
        r#"Model(
    name: "damped_car",
    gravity: (0, 0, 0),
    bodies: [
        Body(name: "body", mass: 1000, inertia: (ixx: 800, iyy: 2500, izz: 2600),
             joint: SixDof(parent: "ground", order: "zxy", track: Some(0))),
        Body(name: "inner", mass: 200, inertia: (ixx: 10, iyy: 10, izz: 10),
             joint: Prismatic(parent: "body", axis: Y, coord: "u", vel: 0.3)),
    ],
    forces: [
        SeriesSpring(name: "maxwell", body1: "body", point1: (0, -1, 0), body2: "inner",
                     c: 2e5, d: 4e3),
    ],
)"#,
    )
    .unwrap();
    let train = train_from_text(
        dir.path(),
        &format!(
            r#"Train(
            vehicles: [
                Vehicle(name: "A", model: "{car}", offset: 0.0,
                        initial: [(coord: "body.x", velocity: 0.5)]),
                Vehicle(name: "B", model: "{plain}", offset: -10.0,
                        initial: [(coord: "body.y", velocity: -0.2)]),
            ],
            couplers: [
                Coupler(name: "AB", body1: "A.body", point1: (-5.0, 0.0, 0.3),
                        body2: "B.body", point2: (5.0, 0.0, 0.3),
                        stiffness: (1e5, 2e4, 3e4), damping: (1e3, 500.0, 500.0)),
            ],
            track: (file: "{track}", start: 100.0, speed: 10.0),
            end_time: 2.0,
            integrator: Park(rtol: 1e-8, atol: 1e-10, max_step: 0.01),
            output: (interval: 0.05, bodies: ["*"], forces: ["A.maxwell"]),
        )"#,
            car = car.display(),
            plain = path_text("vehicles/train/track_car.ron"),
            track = path_text("tracks/straight.ron"),
        ),
    );
    let (t, _) = run(&train, numeric, &dir.path().join("out.csv"));
    // The Maxwell element carries load (its spring extension is the state).
    let s = t.col("A.maxwell.s[m]");
    assert!(s.iter().fold(0.0_f64, |m, x| m.max(x.abs())) > 1e-4);
    for axis in ["x", "y", "z"] {
        let p: Vec<f64> = (0..t.col("time").len())
            .map(|i| {
                1000.0 * t.col(&format!("A.body.v{axis}[m/s]"))[i]
                    + 200.0 * t.col(&format!("A.inner.v{axis}[m/s]"))[i]
                    + 1000.0 * t.col(&format!("B.body.v{axis}[m/s]"))[i]
            })
            .collect();
        for pi in &p {
            // Park at rtol 1e-8 over 2 s: as for the plain coupler test.
            assert!(
                (pi - p[0]).abs() < 1e-7 * 1e4,
                "momentum along {axis}: {pi} vs {}",
                p[0]
            );
        }
    }
}

/// A coupler with slack and buffers (`longitudinal` characteristic): the
/// trailing car closing on the leading one at 1 m/s meets no force for the
/// 0.05 m of slack, then the 1e6 N/m buffers act for half a period of the
/// two-mass oscillator, π√(μ/k) with μ = m/2, and the equal cars exchange
/// their velocities (no damping: an elastic impact). They then drift apart
/// through the slack; the draw gear would engage 0.1 s later, after the run.
#[test]
fn coupler_slack_and_buffers_give_an_elastic_impact() {
    let dir = tempfile::tempdir().unwrap();
    let train = train_from_text(
        dir.path(),
        &format!(
            r#"Train(
            vehicles: [
                Vehicle(name: "A", model: "{car}", offset: 0.0),
                Vehicle(name: "B", model: "{car}", offset: -10.0,
                        initial: [(coord: "body.x", velocity: 1.0)]),
            ],
            couplers: [
                Coupler(name: "AB", body1: "A.body", point1: (-5.0, 0.0, 0.0),
                        body2: "B.body", point2: (5.0, 0.0, 0.0),
                        stiffness: (0.0, 2e4, 3e4),
                        longitudinal: [(-0.15, -1e5), (-0.05, 0.0), (0.05, 0.0), (0.15, 1e5)]),
            ],
            track: (file: "{track}", start: 100.0, speed: 10.0),
            end_time: 0.2,
            integrator: Park(rtol: 1e-9, atol: 1e-10, max_step: 0.001),
            output: (interval: 0.001, bodies: ["*"], forces: []),
        )"#,
            car = path_text("vehicles/train/track_car.ron"),
            track = path_text("tracks/straight.ron"),
        ),
    );
    let (t, _) = run(&train, numeric, &dir.path().join("out.csv"));
    let (time, fx) = (t.col("time"), t.col("AB.Fx[N]"));
    let (va, vb) = (t.col("A.body.vx[m/s]"), t.col("B.body.vx[m/s]"));
    let omega = (1e6f64 / 500.0).sqrt();
    let (t_touch, t_leave) = (0.05, 0.05 + std::f64::consts::PI / omega);
    for i in 0..time.len() {
        if time[i] < t_touch - 1e-3 || time[i] > t_leave + 1e-3 {
            assert!(fx[i].abs() < 1e-6, "force {} N at t = {}", fx[i], time[i]);
        }
    }
    // Peak buffer force k·v/ω = 1e6·1/44.7 N, on body 2 pushing it back.
    let peak = fx.iter().fold(0.0_f64, |m, f| m.max(f.abs()));
    assert!(
        (peak - 1e6 / omega).abs() < 2e-3 * 1e6 / omega,
        "peak {peak} N"
    );
    // Velocities exchanged (absolute, the frames move at 10 m/s); Park at
    // rtol 1e-9 with the kinks at touch-down and lift-off falling inside
    // steps of ≤ 1 ms: 1e-3 m/s.
    let last = time.len() - 1;
    assert!(
        (va[last] - 11.0).abs() < 1e-3 && (vb[last] - 10.0).abs() < 1e-3,
        "{} {}",
        va[last],
        vb[last]
    );
}

/// Three coaches from the bundled train file, numeric engine.
fn train3(end_time: f64) -> TrainScenario {
    let mut train =
        railmbs_models::load_train(&model_path("scenarios/train3_straight.ron")).unwrap();
    train.end_time = end_time;
    train.output.coordinates = true;
    train
}

/// The symmetric three-coach train on perfect straight track stays centred:
/// every lateral displacement and yaw angle of the 126 coordinates and the
/// couplers' lateral forces stay at rounding level.
#[test]
fn a_symmetric_train_on_straight_track_stays_centred() {
    let dir = tempfile::tempdir().unwrap();
    let train = train3(3.0);
    let (t, summary) = run(&train, numeric, &dir.path().join("out.csv"));
    let models = vehicle_models(&train);
    assert_eq!(
        models.iter().map(|m| m.coordinates.len()).sum::<usize>(),
        126
    );
    assert_eq!(summary.assessment.len(), 3 * 4 * 10);
    let mut worst: f64 = 0.0;
    for (v, m) in train.vehicles.iter().zip(&models) {
        for c in m
            .coordinates
            .iter()
            .filter(|c| c.name.ends_with(".y") || c.name.ends_with(".rz"))
        {
            let col = t.col(&format!("{}.{}", v.name, c.name));
            worst = col.iter().fold(worst, |w, x| w.max(x.abs()));
        }
    }
    assert!(
        worst < 1e-9,
        "largest lateral displacement or yaw {worst:e}"
    );
    for c in ["C12", "C23"] {
        let fy = t.col(&format!("{c}.Fy[N]"));
        assert!(fy.iter().all(|f| f.abs() < 1e-3), "{c}: lateral force");
    }
    // The coaches keep their places along the track (26 m apart).
    let x1 = t.col("Coach1.body.x[m]");
    let x3 = t.col("Coach3.body.x[m]");
    for (a, b) in x1.iter().zip(&x3) {
        assert!((a - b - 52.0).abs() < 1e-3);
    }
}

/// At the initial state of the three-coach train the blocks of the analytic
/// Jacobian between vehicles (couplers only) match finite differences of
/// the generalized forces.
#[test]
fn the_coupler_jacobian_matches_finite_differences() {
    let train = train3(1.0);
    let models = vehicle_models(&train);
    let refs: Vec<&Model> = models.iter().collect();
    let engines = models.iter().map(numeric).collect();
    let mut setup = railmbs_runtime::train::build_train(&train, &refs, engines).unwrap();
    let n = setup.system.dof();
    // Perturb the state a little so that couplers deflect.
    let mut rng = seeded_rng(7);
    let mut q = setup.q0.clone();
    let mut v = setup.v0.clone();
    for (qi, vi) in q.iter_mut().zip(v.iter_mut()) {
        *qi += rng.random_range(-1e-5..1e-5);
        *vi += rng.random_range(-1e-4..1e-4);
    }
    let sys = &mut setup.system;
    let (mut dq, mut dv) = (
        nalgebra::DMatrix::zeros(n, n),
        nalgebra::DMatrix::zeros(n, n),
    );
    assert!(sys.force_jacobian(0.1, &q, &v, &mut dq, &mut dv).unwrap());
    let mut mass = nalgebra::DMatrix::zeros(n, n);
    let mut f0 = nalgebra::DVector::zeros(n);
    let mut f1 = nalgebra::DVector::zeros(n);
    let r1 = sys.range(0);
    let r2 = sys.range(1);
    let (mut worst, mut scale): (f64, f64) = (0.0, 0.0);
    for j in r2.clone() {
        for (which, h) in [(0, 1e-8), (1, 1e-7)] {
            let (mut qp, mut vp) = (q.clone(), v.clone());
            let (mut qm, mut vm) = (q.clone(), v.clone());
            if which == 0 {
                qp[j] += h;
                qm[j] -= h;
            } else {
                vp[j] += h;
                vm[j] -= h;
            }
            sys.dynamics(0.1, &qp, &vp, &mut mass, &mut f1).unwrap();
            sys.dynamics(0.1, &qm, &vm, &mut mass, &mut f0).unwrap();
            let analytic = if which == 0 { &dq } else { &dv };
            for i in r1.clone() {
                let fd = (f1[i] - f0[i]) / (2.0 * h);
                worst = worst.max((fd - analytic[(i, j)]).abs());
                scale = scale.max(fd.abs());
            }
        }
    }
    assert!(scale > 1e4, "couplers should couple the vehicles: {scale}");
    assert!(
        worst < 1e-3 * scale,
        "largest difference {worst} (largest entry {scale})"
    );
    // Vehicles 1 and 3 are not coupled directly.
    let r3 = sys.range(2);
    for i in r1 {
        for j in r3.clone() {
            assert_eq!(dq[(i, j)], 0.0);
        }
    }
}

/// The symbolic plugin (one per model file, shared by the three coaches) and
/// the numeric engine run the same three-coach train into a lateral
/// irregularity to the integration tolerance.
#[test]
fn symbolic_and_numeric_engines_agree_on_a_train() {
    let dir = tempfile::tempdir().unwrap();
    // Straight track with a lateral sinusoid (20 m, 3 mm) from s = 115 m,
    // which the leading coach enters after 0.14 s.
    let track = dir.path().join("track.ron");
    std::fs::write(
        &track,
        "Custom((sections: [Straight(length: 1000.0)], irregularities: [\
         Sinusoid(component: Lateral, wavelength: 20.0, amplitude: 0.003, start: 115.0, end: 900.0)]))",
    )
    .unwrap();
    let mut train = train3(1.0);
    train.track.load_file(&track).unwrap();
    let (a, _) = run(&train, numeric, &dir.path().join("numeric.csv"));
    let (b, summary) = run(
        &train,
        |m| Box::new(symbolic_engine(m)),
        &dir.path().join("symbolic.csv"),
    );
    assert_eq!(summary.engine, "symbolic");
    assert_eq!(a.header, b.header);
    for (coach, least) in [("Coach1", 1e-4), ("Coach2", 1e-7)] {
        let y = a.col(&format!("{coach}.body.y[m]"));
        let most = y.iter().fold(0.0_f64, |m, x| m.max(x.abs()));
        assert!(most > least, "{coach} moves laterally by {most:e} m only");
    }
    // Coordinates (m, rad) against the integrator's tolerances (rtol 1e-4,
    // atol 1e-6): the error of each engine's run is estimated to those; the
    // engines agree to rounding on the equations.
    let d = a.coordinate_difference(&b, 1e-4, 1e-6);
    assert!(
        d.tolerances < 1.0,
        "{}: difference {} tolerances",
        d.column,
        d.tolerances
    );
}

/// Mistakes in a train file are reported with the file, the element and the
/// line and column: an unknown vehicle in a coupler (when read), an unknown
/// body of a known vehicle and an unknown train-wide parameter (when built).
#[test]
fn train_file_errors_name_the_element_and_position() {
    let dir = tempfile::tempdir().unwrap();
    let text = |body1: &str, parameter: &str| {
        format!(
            r#"Train(
    vehicles: [
        Vehicle(name: "A", model: "{car}"),
        Vehicle(name: "B", model: "{car}", offset: -10.0),
    ],
    couplers: [
        Coupler(name: "AB", body1: "{body1}", point1: (-5.0, 0.0, 0.0),
                body2: "B.body", point2: (5.0, 0.0, 0.0), stiffness: (1e5, 1e4, 1e4)),
    ],
    parameters: {{ "{parameter}": 900.0 }},
    track: (file: "{track}", start: 100.0, speed: 10.0),
    end_time: 1.0,
    integrator: Rk4(step: 0.001),
    output: (interval: 0.1),
)"#,
            car = path_text("vehicles/train/track_car.ron"),
            track = path_text("tracks/straight.ron"),
        )
    };
    let path = dir.path().join("bad.ron");
    let e = parse_train(&text("C.body", "m"), &path)
        .unwrap_err()
        .to_string();
    assert!(e.contains("bad.ron:7:"), "{e}");
    assert!(e.contains("coupler \"AB\""), "{e}");
    assert!(e.contains("\"C.body\""), "{e}");
    let build = |text: String| {
        std::fs::write(&path, &text).unwrap();
        let train = parse_train(&text, &path).unwrap();
        let model = load_model(&train.vehicles[0].model).unwrap();
        let engines = vec![numeric(&model), numeric(&model)];
        railmbs_runtime::train::build_train(&train, &[&model, &model], engines)
            .err()
            .expect("an error")
            .to_string()
    };
    let e = build(text("A.bdy", "m"));
    assert!(e.contains("bad.ron:7:"), "{e}");
    assert!(e.contains("coupler \"AB\""), "{e}");
    assert!(e.contains("no body \"bdy\""), "{e}");
    let e = build(text("A.body", "mass"));
    assert!(e.contains("bad.ron:10:"), "{e}");
    assert!(e.contains("parameter \"mass\""), "{e}");
    // A negative stiffness would feed energy into the train.
    let negative =
        text("A.body", "m").replace("stiffness: (1e5, 1e4, 1e4)", "stiffness: (-1e5, 1e4, 1e4)");
    let e = parse_train(&negative, &path).unwrap_err().to_string();
    assert!(e.contains("bad.ron:7:"), "{e}");
    assert!(
        e.contains("coupler stiffness must not be negative, got (-100000, 10000, 10000)"),
        "{e}"
    );
}

/// The train's matrices in block form (each vehicle a diagonal block, the
/// coaches' car bodies the border) hold exactly the entries of the dense
/// ones, and the bordered block-diagonal LU solves Park's iteration matrix
/// M − β ∂f/∂q̇ − β² ∂f/∂q (β = 0.6 ms) and M itself like the dense LU, to
/// 1e-10 relative; the residual of both solutions is at rounding level.
#[test]
fn the_block_solve_of_a_train_matches_the_dense_solve() {
    let train = train3(1.0);
    let models = vehicle_models(&train);
    let refs: Vec<&Model> = models.iter().collect();
    let engines = models.iter().map(numeric).collect();
    let mut setup = railmbs_runtime::train::build_train(&train, &refs, engines).unwrap();
    let mut rng = seeded_rng(11);
    let mut q = setup.q0.clone();
    let mut v = setup.v0.clone();
    for (qi, vi) in q.iter_mut().zip(v.iter_mut()) {
        *qi += rng.random_range(-1e-5..1e-5);
        *vi += rng.random_range(-1e-4..1e-4);
    }
    let sys = &mut setup.system;
    let pattern = sys
        .block_pattern()
        .expect("a train of three has a block pattern");
    assert_eq!(pattern.blocks().len(), 3);
    // The border is the three car bodies' coordinates (each has six,
    // relative to its track frame): couplers join the car bodies only.
    let body = models[0]
        .bodies
        .iter()
        .position(|b| b.name == "body")
        .unwrap();
    let own: Vec<usize> = (0..models[0].coordinates.len())
        .filter(|&i| models[0].coordinates[i].body == body)
        .collect();
    assert_eq!(own.len(), 6);
    let starts: Vec<usize> = (0..3).map(|k| sys.range(k).start).collect();
    let expect: Vec<usize> = starts
        .iter()
        .flat_map(|&s| own.iter().map(move |&i| s + i))
        .collect();
    assert_eq!(pattern.border(), &expect[..]);
    crate::block_solve::assert_block_solve_matches_dense(sys, &pattern, &q, &v);
}

/// The dense and the block-bordered linear solver run the three-coach train
/// into a lateral irregularity to the integration tolerance (their
/// solutions differ by rounding, the steps follow the same error control),
/// and the block run really uses the block solver.
#[test]
fn block_and_dense_solvers_run_the_same_train() {
    let dir = tempfile::tempdir().unwrap();
    let track = dir.path().join("track.ron");
    std::fs::write(
        &track,
        "Custom((sections: [Straight(length: 1000.0)], irregularities: [\
         Sinusoid(component: Lateral, wavelength: 20.0, amplitude: 0.003, start: 115.0, end: 900.0)]))",
    )
    .unwrap();
    let mut runs = Vec::new();
    for solver in [
        railmbs_models::LinearSolverKind::Dense,
        railmbs_models::LinearSolverKind::Block,
    ] {
        let mut train = train3(1.0);
        train.track.load_file(&track).unwrap();
        if let railmbs_models::IntegratorSpec::Park { solver: s, .. } = &mut train.integrator {
            *s = solver;
        }
        runs.push(run(&train, numeric, &dir.path().join(format!("{solver:?}.csv"))).0);
    }
    let (a, b) = (&runs[0], &runs[1]);
    assert_eq!(a.header, b.header);
    let y = a.col("Coach1.body.y[m]");
    assert!(y.iter().fold(0.0_f64, |m, x| m.max(x.abs())) > 1e-4);
    let d = a.coordinate_difference(b, 1e-4, 1e-6);
    assert!(
        d.differs,
        "the block run should round differently from the dense one"
    );
    assert!(
        d.tolerances < 1.0,
        "{}: difference {} tolerances",
        d.column,
        d.tolerances
    );
}
