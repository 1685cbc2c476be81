//! The critical-speed criterion on a signal whose answer is known by hand.

use railmbs_runtime::run::{OutputSink, Table};
use railmbs_study::{Cell, Reduction, ReductionKind, reduce_table};

#[test]
fn the_critical_speed_is_the_speed_of_the_limit_cycles_last_extreme() {
    // A run decelerating from 60 m/s at 2 m/s²; the lateral column
    // alternates ±1 mm every row (0.01 s) up to t = 4.99 s, then is 0.
    let mut table = Table::new();
    let header = ["time", "s[m]", "v[m/s]", "y"].map(String::from);
    table.begin(&header).unwrap();
    for k in 0..=1000 {
        let t = k as f64 * 0.01;
        let v = 60.0 - 2.0 * t;
        let y = if t < 4.995 {
            1e-3 * if k % 2 == 0 { 1.0 } else { -1.0 }
        } else {
            0.0
        };
        table.row(&[t, 60.0 * t - t * t, v, y]).unwrap();
    }
    let reduction = |window: f64| {
        Reduction::new(
            ReductionKind::CriticalSpeed {
                column: "y".into(),
                amplitude: 2e-4,
                window,
            },
            None,
        )
    };
    // The limit cycle's last extreme is the row at t = 4.99 s: with a
    // 1.005 s window the amplitude (half the range over the window) falls
    // below the threshold at t = 6.00 s, as that row leaves the window;
    // with a 0.505 s window at t = 5.50 s. Either way the answer is the
    // speed at the row that left, v = 60 − 2·4.99.
    for window in [1.005, 0.505] {
        let cells = reduce_table(&[reduction(window)], &table, &[]).unwrap();
        let Cell::Num(v) = cells[0] else {
            panic!("{cells:?}")
        };
        assert!(
            (v - (60.0 - 2.0 * 4.99)).abs() < 1e-9,
            "window {window}: {v}"
        );
    }
    // A threshold above half the amplitude: no limit cycle is established
    // (it needs twice the threshold), no critical speed.
    let high = Reduction::new(
        ReductionKind::CriticalSpeed {
            column: "y".into(),
            amplitude: 6e-4,
            window: 1.0,
        },
        None,
    );
    assert_eq!(reduce_table(&[high], &table, &[]).unwrap(), [Cell::Empty]);
}

/// A real decelerating run: the wheelset on soft springs
/// (`wheelset_on_springs_critical.ron`, released 6 mm off centre at 46 m/s,
/// slowed at 1 m/s² to 32 m/s) hunts on its flanges (±6.3 mm) and the
/// limit cycle dies out near 34 m/s. The study's reduction and
/// `umsim critical-speed`'s detection (different thresholds, one detector)
/// place the collapse within 0.3 m/s of each other, and within the fold
/// of the stable branch that the continuation brackets (`umsim
/// critical-speed wheelset_on_springs_critical.ron --bifurcation 30:60:3
/// --hold 5`: hunting at 36 m/s, not at 33 m/s). The collapse is where the
/// linear model is still stable (hunting mode's damping ratio > 0): a
/// subcritical Hopf bifurcation, the nonlinear critical speed below the
/// linear one (51.4 m/s, `wickens.rs`).
#[test]
fn the_critical_speed_of_a_real_decelerating_run() {
    use railmbs_runtime::NumericEquations;
    use railmbs_runtime::analysis::critical::{Detection, DetectionSettings, decelerating_run};
    use railmbs_runtime::analysis::speed::{at_speed, scenario_modes};
    use railmbs_runtime::forces::ContactTableCache;
    let mut s = railmbs_models::load_scenario(&railmbs_testkit::model_path(
        "scenarios/wheelset_on_springs_critical.ron",
    ))
    .unwrap();
    let track = s.track.as_mut().unwrap();
    track.speed_profile = vec![(0.0, 46.0), (14.0, 32.0)];
    s.set_parameter("v0", "46.0");
    s.set_parameter("y0", "0.006");
    s.set_end_time(14.0).unwrap();
    let model = railmbs_models::load_model(&s.model).unwrap();
    // The command's default settings.
    let settings = DetectionSettings {
        on: 4e-3,
        relative: 0.5,
        ..DetectionSettings::new(1.0, 1e-3)
    };
    let mut table = Table::new();
    let (summary, detection) = decelerating_run(
        &s,
        &model,
        Box::new(NumericEquations::new(&model)),
        &["ws.y".to_string()],
        settings,
        &mut table,
        |_| {},
    )
    .unwrap();
    assert!(summary.error.is_none(), "{:?}", summary.error);
    let Detection::Collapsed(c) = detection else {
        panic!("{detection:?}")
    };
    println!("collapse: {c:?}");
    assert!(c.speed > 33.0 && c.speed < 36.0, "{c:?}");
    assert!(c.amplitude > 6e-3, "flange hunting: {c:?}");
    // The study's reduction over the same rows.
    let cells = reduce_table(
        &[Reduction::new(
            ReductionKind::CriticalSpeed {
                column: "ws.y".into(),
                amplitude: 2.5e-3,
                window: 1.0,
            },
            None,
        )],
        &table,
        &[],
    )
    .unwrap();
    let Cell::Num(v) = cells[0] else {
        panic!("{cells:?}")
    };
    println!("study reduction: {v} m/s");
    assert!((v - c.speed).abs() < 0.3, "{v} against {}", c.speed);
    // Linearly stable there.
    let one = scenario_modes(
        &at_speed(&s, &model, c.speed),
        &model,
        Box::new(NumericEquations::new(&model)),
        &ContactTableCache::new(),
    )
    .unwrap();
    let hunting = one.modes.least_damped_lateral().unwrap();
    println!("at {} m/s: {hunting:?}", c.speed);
    assert!(hunting.damping_ratio > 0.0, "{hunting:?}");
}
