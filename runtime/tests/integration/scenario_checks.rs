//! A scenario's parameter overrides are checked like the model's defaults:
//! an override that makes a body's mass or inertia impossible is refused
//! before the run, naming the scenario file and the body (it used to fail
//! later as "Cholesky failed").

use railmbs_runtime::NumericEquations;
use railmbs_runtime::run::{Discard, run_scenario_into};

const MODEL: &str = r#"
Model(
    name: "box",
    parameters: { "m": 2, "j": 1 },
    gravity: (0, 0, -9.81),
    bodies: [
        Body(name: "box", mass: "m", inertia: (ixx: "j", iyy: "j", izz: "j"),
             joint: Prismatic(parent: "ground", axis: Z, coord: "z")),
    ],
)
"#;

fn run(parameters: &str) -> Result<(), String> {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("box.ron"), MODEL).unwrap();
    let text = format!(
        r#"Scenario(model: "box.ron", parameters: {{ {parameters} }}, end_time: 0.1,
            integrator: Rk4(step: 1e-3), output: (interval: 0.01))"#
    );
    let path = dir.path().join("run.ron");
    std::fs::write(&path, &text).unwrap();
    let scenario = railmbs_models::parse_scenario(&text, &path).unwrap();
    let model = railmbs_models::load_model(&scenario.model).unwrap();
    let equations = Box::new(NumericEquations::new(&model));
    run_scenario_into(&scenario, &model, equations, &mut Discard, |_| {})
        .map(|_| ())
        .map_err(|e| e.to_string())
}

#[test]
fn overrides_that_make_a_body_impossible_are_refused() {
    run(r#""m": 3"#).unwrap();
    let e = run(r#""m": -3"#).unwrap_err();
    assert!(e.contains("run.ron"), "{e}");
    assert!(
        e.contains("body \"box\": mass must be positive, got -3"),
        "{e}"
    );
    let e = run(r#""j": 0"#).unwrap_err();
    assert!(
        e.contains("body \"box\": inertia tensor is not positive definite"),
        "{e}"
    );
}
