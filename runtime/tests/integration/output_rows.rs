//! Output rows agree with the step they belong to: the runner evaluates the
//! rows of a step before the step is accepted, with the element states
//! (friction modes) that the step was integrated with. Newton's second law
//! then holds in every written row: for a 1 kg mass held only by the
//! load-dependent friction element (Pogorelov 2005, Sect. 3.1, Fig. 3), the
//! written acceleration equals the written element force on the mass, also
//! in the rows where the element changes between sticking and sliding.

use railmbs_runtime::NumericEquations;
use railmbs_runtime::run::{Table, run_scenario_into};

/// The free vibration of `force_elements_decay`, which sticks and slides
/// twice per cycle (ω ≈ 30 rad/s, so 0.5 s holds several mode changes).
const MODEL: &str = r#"
Model(
    name: "decay",
    parameters: { "a0": 0.01 },
    gravity: (0, 0, 0),
    bodies: [
        Body(name: "mass", mass: 1, inertia: (ixx: 1, iyy: 1, izz: 1),
             joint: Prismatic(parent: "ground", axis: X, coord: "u", init: "a0")),
    ],
    forces: [
        LoadFriction(name: "lf", body1: "ground", point1: (-0.5, 0, 0), body2: "mass",
                     c1: 3000, c2: 1000, mu0: 0.25, mu: 0.25, x0: 0.5),
    ],
)
"#;

#[test]
fn every_row_satisfies_newtons_law_across_friction_mode_changes() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("decay.ron"), MODEL).unwrap();
    // RK4 with the output interval equal to its step: every row is the end
    // of a step, where the written acceleration is the integrator's own.
    let text = r#"Scenario(model: "decay.ron", end_time: 0.5, integrator: Rk4(step: 1e-4),
        output: (interval: 1e-4, forces: ["lf"], accelerometers: { "acc": ("mass", (0, 0, 0)) }))"#;
    let path = dir.path().join("run.ron");
    std::fs::write(&path, text).unwrap();
    let scenario = railmbs_models::parse_scenario(text, &path).unwrap();
    let model = railmbs_models::load_model(&scenario.model).unwrap();
    let mut table = Table::new();
    let summary = run_scenario_into(
        &scenario,
        &model,
        Box::new(NumericEquations::new(&model)),
        &mut table,
        |_| {},
    )
    .unwrap();
    assert!(summary.error.is_none(), "{:?}", summary.error);
    let col = |name: &str| {
        table
            .column(name)
            .unwrap_or_else(|| panic!("no column {name} in {:?}", table.names()))
    };
    let (force, sliding, accel) = (col("lf.F[N]"), col("lf.sliding[-]"), col("acc.ax[m/s2]"));
    assert_eq!(table.rows(), 5001);
    // The element pulls the mass towards the ground point (tension F > 0
    // along the line from the mass to (−0.5, 0, 0)): m ü = −F, m = 1 kg.
    let scale = force.iter().fold(0.0_f64, |m, f| m.max(f.abs()));
    let changes = sliding.windows(2).filter(|w| w[0] != w[1]).count();
    assert!(changes >= 4, "only {changes} friction mode changes");
    for (k, (f, a)) in force.iter().zip(accel).enumerate() {
        // Both are one evaluation of the same state: only rounding of the
        // mass-matrix solve and the accelerometer's kinematics remains.
        assert!(
            (a + f).abs() <= 1e-12 * scale,
            "row {k} (t = {} s, sliding {}): ü = {a} m/s², F = {f} N",
            col("time")[k],
            sliding[k]
        );
    }
}

/// A torsional oscillator: J = 2 kg m², c = 200 N m/rad, d = 0.8 N m s/rad,
/// released at rest 0.2 rad from φ0 = 0.1 rad.
const DISC: &str = r#"
Model(
    name: "torsion",
    parameters: { "J": 2, "c": 200, "d": 0.8, "phi0": 0.1 },
    gravity: (0, 0, 0),
    bodies: [
        Body(name: "disc", mass: 5, inertia: (ixx: 1, iyy: 1, izz: "J"),
             joint: Revolute(parent: "ground", axis: Z, coord: "phi", init: 0.3)),
    ],
    forces: [
        TorsionSpring(name: "t", body1: "ground", body2: "disc", axis: (0, 0, 2),
                      c: "c", d: "d", phi0: "phi0"),
    ],
)
"#;

/// A run whose steps collapse stops with a message instead of running for
/// hours: tolerances below what double precision resolves (atol 1e-11 rad on
/// a 0.3 rad coordinate) make Park's steps shrink to about 1e-9 s, 1e-6 of
/// the output interval (51 million steps for 0.05 s without the limit). The
/// rows before are kept.
#[test]
fn a_run_without_progress_stops_and_says_why() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("disc.ron"), DISC).unwrap();
    let text = r#"Scenario(model: "disc.ron", end_time: 0.05,
        integrator: Park(rtol: 1e-9, atol: 1e-11, max_step: 1e-3, jacobian: Analytic),
        output: (interval: 1e-3))"#;
    let path = dir.path().join("run.ron");
    std::fs::write(&path, text).unwrap();
    let scenario = railmbs_models::parse_scenario(text, &path).unwrap();
    let model = railmbs_models::load_model(&scenario.model).unwrap();
    let mut table = Table::new();
    let summary = run_scenario_into(
        &scenario,
        &model,
        Box::new(NumericEquations::new(&model)),
        &mut table,
        |_| {},
    )
    .unwrap();
    let err = summary.error.expect("the run should stop").to_string();
    assert!(err.contains("no progress"), "{err}");
    assert!(err.contains("next output row at t = "), "{err}");
    // The step that reaches the limit is refused, not accepted.
    assert_eq!(
        summary.steps + 1,
        railmbs_runtime::run::MAX_STEPS_PER_ROW,
        "{err}"
    );
    assert!(
        table.rows() >= 1 && summary.t_end < 0.05,
        "{} rows",
        table.rows()
    );
}
