//! Vehicle 2 (the two-axle freight wagon with load-dependent friction
//! suspension, `models/vehicles/vehicle2.ron`) on track case 3: quick
//! physics checks on the first half second, before the lateral sinusoid.

use railmbs_models::{Model, Scenario};
use railmbs_runtime::NumericEquations;
use railmbs_testkit::*;

/// The bundled scenario shortened to `end_time`, and its model.
fn scenario(end_time: f64) -> (Scenario, Model) {
    let mut scenario =
        railmbs_models::load_scenario(&model_path("scenarios/vehicle2_tc3.ron")).unwrap();
    scenario.end_time = end_time;
    let model = railmbs_models::load_model(&scenario.model).unwrap();
    (scenario, model)
}

fn param(model: &Model, name: &str) -> f64 {
    model.default_parameter_values()[model.parameter_index(name).unwrap()]
}

/// The wagon starts in static equilibrium: every wheel carries a quarter of
/// the weight and every leaf spring a quarter of the car body's, within 1 %,
/// over the first 0.5 s (straight track before the sinusoid at s = 50 m).
fn assert_static(model: &Model, t: &Table) {
    let g = param(model, "g");
    let (mc, mw) = (param(model, "mc"), param(model, "mw"));
    let wheel = (mc + 2.0 * mw) * g / 4.0;
    let spring = mc * g / 4.0;
    for ws in ["WS1", "WS2"] {
        for side in ["L", "R"] {
            for q in t.col(&format!("{ws}.contact.{side}.Q [N]")) {
                assert!(
                    (q - wheel).abs() < 0.01 * wheel,
                    "{ws} {side}: Q {q} N vs {wheel} N"
                );
            }
        }
    }
    for s in ["Spring1Left", "Spring1Right", "Spring2Left", "Spring2Right"] {
        for f in t.col(&format!("{s}.F[N]")) {
            assert!(
                (f - spring).abs() < 0.01 * spring,
                "{s}: {f} N vs {spring} N"
            );
        }
    }
}

#[test]
fn vehicle2_starts_with_a_quarter_of_its_weight_on_every_wheel() {
    let (scenario, model) = scenario(0.5);
    let t = run_to_table(&scenario, &model, Box::new(NumericEquations::new(&model)));
    assert_static(&model, &t);
}

#[test]
fn vehicle2_runs_with_the_symbolic_engine_as_with_the_numeric() {
    let (scenario, model) = scenario(0.5);
    let a = run_to_table(&scenario, &model, Box::new(NumericEquations::new(&model)));
    let b = run_to_table(&scenario, &model, Box::new(symbolic_engine(&model)));
    assert_static(&model, &b);
    // Same start, same equations: the car body's height agrees to far below
    // the 4e-4 m static sinking of the wheels.
    let (za, zb) = (a.col("body.z[m]"), b.col("body.z[m]"));
    assert_eq!(za.len(), zb.len());
    for (x, y) in za.iter().zip(&zb) {
        assert!((x - y).abs() < 1e-7, "body.z {x} vs {y}");
    }
}
