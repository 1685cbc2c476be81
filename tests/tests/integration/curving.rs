//! Quasi-static curving (`umsim curving`) against the steady part of a
//! time-domain run through the same curve: Manchester Vehicle 1 in the
//! 150 m right curve with 100 mm cant of track case 1 at 4.4 m/s.

use railmbs_models::InitialStateKind;
use railmbs_models::{Model, Scenario, load_model, load_scenario};
use railmbs_runtime::analysis::curving::{
    Curve, Curving, curve_scenario, curving, curving_by_continuation, direct_settings, first_guess,
};
use railmbs_runtime::forces::ContactTableCache;
use railmbs_runtime::run::RunError;
use railmbs_runtime::run::scenario::scenario_system_with;
use railmbs_runtime::{Equations, NumericEquations};
use railmbs_testkit::*;

fn vehicle1_tc1() -> (Scenario, Model) {
    let s = load_scenario(&model_path("scenarios/vehicle1_tc1.ron")).unwrap();
    let model = load_model(&s.model).unwrap();
    (s, model)
}

fn solve(s: &Scenario, model: &Model, curve: &Curve) -> Curving {
    let mut engine =
        || -> Result<Box<dyn Equations>, RunError> { Ok(Box::new(NumericEquations::new(model))) };
    curving(s, model, &mut engine, &ContactTableCache::new(), curve)
        .unwrap_or_else(|e| panic!("{e}"))
}

/// The time-domain run of track case 1 (`vehicle1_tc1.ron`, from its
/// equilibrium on the straight lead-in, through the 50 m clothoid into the
/// 50 m circular curve) is steady while the whole vehicle is in the
/// circular curve (body centre at s = 86–114 m; its wheelsets span
/// ±10.75 m): its means over body positions 92–108 m (the small
/// oscillation left from the curve entry averaged out) equal the
/// quasi-static solution of the same vehicle in the same curve solved
/// directly — every wheelset's lateral position and angle of attack, and
/// every wheel's Q and Y — within 1 % (the figure; found: 0.03 % at
/// most; the run's integrator tolerance rtol = 1e-4 and the
/// remaining transient are its scale).
#[test]
fn vehicle1_curves_quasi_statically_as_it_runs_through_track_case_1() {
    let (mut s, model) = vehicle1_tc1();
    let curve = Curve {
        radius: -150.0,
        cant: 0.1,
        speed: 4.4,
    };
    let solved = solve(&s, &model, &curve);
    s.end_time = (108.0 - 11.0) / 4.4 + 0.1;
    s.output.interval = 0.05;
    let run = run_to_table(&s, &model, Box::new(NumericEquations::new(&model)));
    let arc = run.col("s[m]");
    let window: Vec<usize> = (0..arc.len())
        .filter(|&i| (92.0..=108.0).contains(&arc[i]))
        .collect();
    assert!(window.len() > 50, "{} samples", window.len());
    let mean = |col: &str| {
        let c = run.col(col);
        window.iter().map(|&i| c[i]).sum::<f64>() / window.len() as f64
    };
    assert_eq!(solved.wheelsets.len(), 4);
    for w in &solved.wheelsets {
        let ws = w.wheelset.as_str();
        let mut checks = vec![
            (format!("{ws}.y"), w.lateral.unwrap()),
            (format!("{ws}.rz"), w.yaw.unwrap()),
        ];
        for name in ["L.Q [N]", "R.Q [N]", "L.Y [N]", "R.Y [N]"] {
            checks.push((format!("{}.{name}", w.element), w.output(name).unwrap()));
        }
        for (col, quasi_static) in checks {
            let run = mean(&col);
            println!("{col}: run {run:.6e}, quasi-static {quasi_static:.6e}");
            assert!(
                (run - quasi_static).abs() < 0.01 * quasi_static.abs(),
                "{col}: run {run}, quasi-static {quasi_static}"
            );
        }
    }
    // The leading wheelsets run on the outer (left) rail's flange in this
    // right curve, the trailing ones towards the inner rail: the solution is
    // the flanging one, not a centred guess.
    let leading = &solved.wheelsets[0];
    assert!(leading.lateral.unwrap() > 5e-3, "{leading:?}");
}

/// At high cant deficiency (the 600 m left curve with 100 mm cant at
/// 40 m/s: 2.0 m/s² uncompensated) the steady state has every wheelset
/// towards the outer (right) rail, the leading ones on the flange; Newton's
/// method with the default 0.1 m steps went from the centred guess to a
/// state with the rear wheelset at the inner flange and stalled (no steady
/// state found). The run in time through a 100 m transition into the same
/// curve (from its equilibrium on the straight lead-in) settles to it:
/// its means over t = 6–14 s (arc 260–580 m, the whole vehicle in the
/// circular curve from t ≈ 3 s) equal the quasi-static solution — every
/// wheelset's lateral position and angle of attack, every wheel's Q and
/// Y — within 1 %, as in track case 1.
#[test]
fn vehicle1_at_high_cant_deficiency_curves_quasi_statically_as_it_runs() {
    let (mut s, model) = vehicle1_tc1();
    let curve = Curve {
        radius: 600.0,
        cant: 0.1,
        speed: 40.0,
    };
    let solved = solve(&s, &model, &curve);
    let dir = tempfile::tempdir().unwrap();
    let file = dir.path().join("curve600.ron");
    std::fs::write(
        &file,
        "Custom((sections: [
            Straight(length: 30.0),
            Transition(length: 100.0, direction: Left, radius_end: Some(600.0), cant_end: 0.1),
            Curve(length: 1500.0, radius: 600.0, direction: Left, cant: 0.1),
        ]))",
    )
    .unwrap();
    let spec = s.track.as_mut().unwrap();
    spec.load_file(&file).unwrap_or_else(|e| panic!("{e}"));
    spec.start = 20.0;
    spec.speed = 40.0;
    s.set_parameter("v0", "40.0");
    s.end_time = 14.0;
    s.output.interval = 0.05;
    let run = run_to_table(&s, &model, Box::new(NumericEquations::new(&model)));
    let time = run.col("time");
    let window: Vec<usize> = (0..time.len())
        .filter(|&i| (6.0..=14.0).contains(&time[i]))
        .collect();
    assert!(window.len() > 100, "{} samples", window.len());
    let mean = |col: &str| {
        let c = run.col(col);
        window.iter().map(|&i| c[i]).sum::<f64>() / window.len() as f64
    };
    for w in &solved.wheelsets {
        let ws = w.wheelset.as_str();
        // Towards the outer (right) rail, all four.
        assert!(w.lateral.unwrap() < -4e-3, "{w:?}");
        let mut checks = vec![
            (format!("{ws}.y"), w.lateral.unwrap()),
            (format!("{ws}.rz"), w.yaw.unwrap()),
        ];
        for name in ["L.Q [N]", "R.Q [N]", "L.Y [N]", "R.Y [N]"] {
            checks.push((format!("{}.{name}", w.element), w.output(name).unwrap()));
        }
        for (col, quasi_static) in checks {
            let run = mean(&col);
            println!("{col}: run {run:.6e}, quasi-static {quasi_static:.6e}");
            assert!(
                (run - quasi_static).abs() < 0.01 * quasi_static.abs(),
                "{col}: run {run}, quasi-static {quasi_static}"
            );
        }
    }
}

/// In a wide curve (3000 m, no cant, 30 m/s) the solve converges from the
/// centred guess directly and its wheel loads carry the vehicle's weight:
/// ΣQ = M g (Vehicle 1's 32 000 + 2 × 2615 + 4 × 1813 kg, g = 9.81 m/s²)
/// to 0.1 % (the centripetal load transfer only moves load between the
/// wheels: on a level track without cant the contact normals' vertical
/// components are the loads; their lateral components and the creep
/// forces' small vertical ones are what the 0.1 % allows).
#[test]
fn vehicle1_in_a_wide_curve_carries_its_weight_on_its_wheels() {
    let (s, model) = vehicle1_tc1();
    let solved = solve(
        &s,
        &model,
        &Curve {
            radius: 3000.0,
            cant: 0.0,
            speed: 30.0,
        },
    );
    let total: f64 = solved
        .wheelsets
        .iter()
        .map(|w| w.output("L.Q [N]").unwrap() + w.output("R.Q [N]").unwrap())
        .sum();
    let weight = (32000.0 + 2.0 * 2615.0 + 4.0 * 1813.0) * 9.81;
    assert!(
        (total - weight).abs() < 1e-3 * weight,
        "ΣQ = {total} N, M g = {weight} N"
    );
    // A left curve: the outer rail is the right one, and it carries more.
    for w in &solved.wheelsets {
        assert!(
            w.output("R.Q [N]").unwrap() > w.output("L.Q [N]").unwrap(),
            "{w:?}"
        );
    }
}

#[test]
fn a_bad_curve_is_refused_with_a_message_naming_it() {
    let (s, model) = vehicle1_tc1();
    let mut engine =
        || -> Result<Box<dyn Equations>, RunError> { Ok(Box::new(NumericEquations::new(&model))) };
    for (curve, words) in [
        ((0.0, 0.1, 10.0), "radius 0 m"),
        ((500.0, -0.1, 10.0), "cant -0.1 m"),
        ((500.0, 0.1, f64::NAN), "speed NaN m/s"),
    ] {
        let curve = Curve {
            radius: curve.0,
            cant: curve.1,
            speed: curve.2,
        };
        let err = curving(&s, &model, &mut engine, &ContactTableCache::new(), &curve)
            .err()
            .unwrap_or_else(|| panic!("{curve:?} accepted"))
            .to_string();
        assert!(err.contains(words), "{err}");
        assert!(err.contains("vehicle1_tc1.ron"), "{err}");
    }
}

/// The direct solve from the rigid vehicle's position in the curve
/// (`first_guess`, the default cold path) reaches the same steady state as
/// the continuation in curvature from the centred state, in the 150 m
/// curve of track case 1 and in a tighter 120 m one, both with 100 mm cant
/// at 4.4 m/s. Both solutions leave residual forces below the Newton
/// tolerance τ (1.9e-2 N for Vehicle 1); the softest restraint of a solved
/// position is the car body's lateral one on its four secondary springs,
/// k = 4 × 160 kN/m, so two such states differ by at most 2τ/k = 6.0e-8 m
/// (or rad) in every coordinate. The final solve starts at `first_guess`'s
/// values (the fast path, not the continuation, gave the solution).
#[test]
fn the_direct_cold_solve_equals_the_continuation_in_curvature() {
    let (s, model) = vehicle1_tc1();
    let tables = ContactTableCache::new();
    let mut engine =
        || -> Result<Box<dyn Equations>, RunError> { Ok(Box::new(NumericEquations::new(&model))) };
    for radius in [-150.0, -120.0] {
        let curve = Curve {
            radius,
            cant: 0.1,
            speed: 4.4,
        };
        let direct = curving(&s, &model, &mut engine, &tables, &curve).unwrap();
        let reference = curving_by_continuation(&s, &model, &mut engine, &tables, &curve).unwrap();
        let tolerance = direct.equilibrium.tolerance;
        assert!(
            direct.equilibrium.residual <= tolerance,
            "{}",
            direct.equilibrium.residual
        );
        assert!(reference.equilibrium.residual <= tolerance);
        let bound = 2.0 * tolerance / (4.0 * 160e3);
        for (i, c) in direct
            .coordinates
            .iter()
            .enumerate()
            .take(model.coordinates.len())
        {
            if direct.equilibrium.roles[i] != railmbs_runtime::analysis::equilibrium::Role::Position
            {
                continue;
            }
            let (a, b) = (direct.equilibrium.q[i], reference.equilibrium.q[i]);
            assert!(
                (a - b).abs() <= bound,
                "R = {radius} m, {}: {a} against {b}",
                c.name
            );
        }
        // The fast path: the final solve started from the guess.
        let mut given = curve_scenario(&s, &model, &curve).unwrap();
        given.initial_kind = InitialStateKind::Given;
        let built = scenario_system_with(
            &given,
            &model,
            engine().unwrap(),
            &tables,
            &direct_settings(),
        )
        .unwrap();
        let guess = first_guess(&model, &built, &curve);
        assert!(guess.len() >= 4 * 4 + 2 * 3, "{guess:?}");
        for g in &guess {
            let i = direct
                .coordinates
                .iter()
                .position(|c| c.name == g.coordinate)
                .unwrap();
            assert_eq!(
                direct.equilibrium.q_start[i],
                g.value.unwrap(),
                "{}",
                g.coordinate
            );
        }
        // The leading wheelsets at the outer (left) flange, the trailing
        // ones towards the inner rail, as the guess put them.
        assert!(direct.wheelsets[0].lateral.unwrap() > 5e-3);
        assert!(direct.wheelsets[1].lateral.unwrap() < -5e-3);
    }
}
