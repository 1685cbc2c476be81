//! Scenario files: syntax, defaults, validation, resolution against a model.

use crate::common;

use common::FULL;
use railmbs_models::*;
use std::path::{Path, PathBuf};

/// A scratch folder with `mechanisms/everything.ron` and the given scenario
/// files under `scenarios/`.
struct Scratch(PathBuf);

impl Scratch {
    fn new(tag: &str) -> Self {
        let dir = std::env::temp_dir().join(format!(
            "railmbs-models-scenario-{tag}-{}",
            std::process::id()
        ));
        std::fs::create_dir_all(dir.join("mechanisms")).unwrap();
        std::fs::create_dir_all(dir.join("scenarios")).unwrap();
        std::fs::write(dir.join("mechanisms/everything.ron"), FULL).unwrap();
        Scratch(dir)
    }

    fn scenario(&self, name: &str, text: &str) -> PathBuf {
        let p = self.0.join("scenarios").join(name);
        std::fs::write(&p, text).unwrap();
        p
    }
}

impl Drop for Scratch {
    fn drop(&mut self) {
        std::fs::remove_dir_all(&self.0).ok();
    }
}

const FULL_SCENARIO: &str = r#"// Every field.
Scenario(
    model: "../mechanisms/everything.ron",
    macros: ["heavy"],
    parameters: { "l1": 2.0, "k": "2*g" },
    initial: [(coord: "q0", value: 0.3), (coord: "q1", velocity: 1.0)],
    end_time: 10.0,
    integrator: Park(rtol: 1e-6, atol: 1e-8, max_step: 0.01, initial_step: 1e-4, jacobian: Analytic),
    output: (interval: 0.01, coordinates: true, velocities: true, bodies: ["*"], forces: ["k1"]),
    output_file: "everything.csv",
)
"#;

#[test]
fn loads_every_field_and_resolves_paths() {
    let s = Scratch::new("full");
    let path = s.scenario("full.ron", FULL_SCENARIO);
    let sc = load_scenario(&path).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(sc.source, path);
    let dir = path.parent().unwrap();
    assert_eq!(sc.model, dir.join("../mechanisms/everything.ron"));
    assert_eq!(sc.output_file, Some(dir.join("everything.csv")));
    assert_eq!(sc.macros, ["heavy"]);
    assert_eq!(
        sc.parameters,
        vec![
            ("l1".to_string(), "2.0".to_string()),
            ("k".to_string(), "2*g".to_string())
        ]
    );
    assert_eq!(sc.end_time, 10.0);
    assert_eq!(
        sc.integrator,
        IntegratorSpec::Park {
            rtol: 1e-6,
            atol: 1e-8,
            max_step: 0.01,
            initial_step: Some(1e-4),
            jacobian: JacobianKind::Analytic,
            solver: Default::default(),
        }
    );
    assert_eq!(
        sc.output,
        OutputSpec {
            interval: 0.01,
            coordinates: true,
            velocities: true,
            bodies: vec!["*".into()],
            forces: vec!["k1".into()],
            accelerometers: vec![],
        }
    );
    assert_eq!(sc.initial.len(), 2);
    assert_eq!(sc.initial[0].value, Some(0.3));
    assert_eq!(sc.initial[0].velocity, None);
    assert_eq!(sc.initial[1].velocity, Some(1.0));

    // Resolution against the model.
    let model = load_model(&sc.model).unwrap();
    let p = sc.parameter_values(&model).unwrap();
    let i = |n: &str| model.parameter_index(n).unwrap();
    assert_eq!(p[i("l1")], 2.0);
    assert_eq!(p[i("l2")], 2.0, "l2 = l1 follows the override");
    assert_eq!(p[i("k")], 2.0 * 9.81);
    assert_eq!(p[i("m2")], 4.0, "macro heavy");
    let (q, v) = sc.initial_state(&model, &p).unwrap();
    assert_eq!(q[0], 0.3);
    // q1 keeps its model initial value 0.1*l1 (with l1 = 2), velocity overridden.
    assert_eq!(q[1], 0.2);
    assert_eq!(v[1], 1.0);
}

#[test]
fn optional_fields_have_defaults() {
    let s = Scratch::new("min");
    let path = s.scenario(
        "min.ron",
        r#"Scenario(model: "../mechanisms/everything.ron", end_time: 1,
            integrator: Rk4(step: 0.001), output: (interval: 0.1))"#,
    );
    let sc = load_scenario(&path).unwrap_or_else(|e| panic!("{e}"));
    assert!(sc.macros.is_empty() && sc.parameters.is_empty() && sc.initial.is_empty());
    assert_eq!(sc.integrator, IntegratorSpec::Rk4 { step: 0.001 });
    assert!(sc.output.coordinates);
    assert!(!sc.output.velocities);
    assert!(sc.output.bodies.is_empty() && sc.output.forces.is_empty());
    assert_eq!(sc.output_file, None);
    let path = s.scenario(
        "park.ron",
        r#"Scenario(model: "m.ron", end_time: 1,
            integrator: Park(rtol: 1e-6, atol: 1e-8, max_step: 0.01), output: (interval: 0.1))"#,
    );
    let sc = load_scenario(&path).unwrap();
    assert_eq!(
        sc.integrator,
        IntegratorSpec::Park {
            rtol: 1e-6,
            atol: 1e-8,
            max_step: 0.01,
            initial_step: None,
            jacobian: JacobianKind::FiniteDifference,
            solver: Default::default(),
        }
    );
}

fn errors_of(s: &Scratch, text: &str) -> (PathBuf, ModelErrors) {
    let path = s.scenario("bad.ron", text);
    let e = load_scenario(&path).expect_err("should fail");
    (path, e)
}

fn assert_names(errs: &ModelErrors, path: &Path, needle: &str, line: usize) {
    let e = errs
        .iter()
        .find(|e| e.message.contains(needle))
        .unwrap_or_else(|| panic!("no {needle:?} in {errs}"));
    assert_eq!(e.file, path);
    assert_eq!(e.line(), Some(line), "{e}");
    assert!(
        e.to_string()
            .starts_with(&format!("{}:{line}:", path.display())),
        "{e}"
    );
}

#[test]
fn validation_errors_name_the_scenario_file() {
    let s = Scratch::new("bad");
    let (p, errs) = errors_of(
        &s,
        "Scenario(model: \"m.ron\",\n end_time: -1,\n integrator: Rk4(step: 0),\n output: (interval: 0))",
    );
    assert_eq!(errs.len(), 3, "{errs}");
    assert_names(&errs, &p, "end_time must be positive", 2);
    assert_names(&errs, &p, "step must be positive", 3);
    assert_names(&errs, &p, "interval must be positive", 4);

    let (p, errs) = errors_of(
        &s,
        "Scenario(model: \"m.ron\", end_time: 1,\n integrator: Park(rtol: 0, atol: -1e-8,\n max_step: 0, initial_step: -1),\n output: (interval: 0.1))",
    );
    assert_eq!(errs.len(), 4, "{errs}");
    assert_names(&errs, &p, "rtol must be positive", 2);
    assert_names(&errs, &p, "atol must be positive", 2);
    assert_names(&errs, &p, "max_step must be positive", 3);
    assert_names(&errs, &p, "initial_step must be positive", 3);

    let (p, errs) = errors_of(
        &s,
        "Scenario(model: \"m.ron\", end_time: inf,\n integrator: Rk4(step: 0.1), output: (interval: 0.1))",
    );
    assert_names(
        &errs,
        &p,
        "end_time must be positive and finite, got inf",
        1,
    );

    // Syntax: a missing required field.
    let (p, errs) = errors_of(
        &s,
        "Scenario(model: \"m.ron\",\n integrator: Rk4(step: 0.1), output: (interval: 0.1))",
    );
    assert!(errs.0[0].message.contains("end_time"), "{errs}");
    assert_eq!(errs.0[0].file, p);
    assert!(errs.0[0].position.is_some());

    let (p, errs) = errors_of(
        &s,
        "Scenario(model: \"m.ron\", end_time: 1,\n integrator: Euler(step: 0.1), output: (interval: 0.1))",
    );
    assert_names(&errs, &p, "Euler", 2);
}

/// Runs that could not finish (or would fill the disk) are refused when the
/// file is read, at the field that makes them so.
#[test]
fn runs_beyond_the_limits_are_refused_up_front() {
    let s = Scratch::new("limits");
    let (p, errs) = errors_of(
        &s,
        "Scenario(model: \"m.ron\", end_time: 1e20,\n integrator: Park(rtol: 1e-6, atol: 1e-8, max_step: 1e-3),\n output: (interval: 0.01))",
    );
    assert_names(&errs, &p, "would write 1.000e22 rows", 3);
    assert_names(&errs, &p, "would take at least 1.000e23 steps", 2);
    let (p, errs) = errors_of(
        &s,
        "Scenario(model: \"m.ron\", end_time: 1,\n integrator: Rk4(step: 1e-308),\n output: (interval: 1e-300))",
    );
    assert_names(
        &errs,
        &p,
        "RK4 step 1e-308 s over end_time 1 s would take 1.000e308 steps",
        2,
    );
    assert_names(&errs, &p, "would write 1.000e300 rows", 3);
    let (p, errs) = errors_of(
        &s,
        "Scenario(model: \"m.ron\", end_time: 10,\n integrator: Park(rtol: 1e-6, atol: 1e-8, max_step: 1e-9),\n output: (interval: 0.01))",
    );
    assert_eq!(errs.len(), 1, "{errs}");
    assert_names(&errs, &p, "max_step 1e-9 s over end_time 10 s", 2);
    let (p, errs) = errors_of(
        &s,
        "Scenario(model: \"m.ron\", end_time: 0.05,\n integrator: Rk4(step: 0.1),\n output: (interval: 0.01))",
    );
    assert_eq!(errs.len(), 1, "{errs}");
    assert_names(
        &errs,
        &p,
        "RK4 step 0.1 s is longer than the run (end_time 0.05 s)",
        2,
    );
    // At the limits themselves a run is accepted.
    let path = s.scenario(
        "ok.ron",
        "Scenario(model: \"m.ron\", end_time: 1, integrator: Rk4(step: 1e-9), output: (interval: 1e-8))",
    );
    let e = load_scenario(&path).err();
    assert!(
        e.as_ref()
            .is_none_or(|e| !e.to_string().contains("at most")),
        "{e:?}"
    );
}

#[test]
fn unknown_macro_parameter_or_coordinate_in_scenario() {
    let s = Scratch::new("names");
    let path = s.scenario(
        "names.ron",
        "Scenario(\n model: \"../mechanisms/everything.ron\",\n macros: [\"heavy\",\n \"empty\"],\n end_time: 1,\n integrator: Rk4(step: 0.1), output: (interval: 0.1))",
    );
    let sc = load_scenario(&path).unwrap();
    let model = load_model(&sc.model).unwrap();
    let errs = sc.parameter_values(&model).unwrap_err();
    let e = &errs.0[0];
    assert_eq!(e.element, "macro \"empty\"");
    assert_eq!(e.file, path);
    assert_eq!(e.line(), Some(4), "{e}");
    assert!(e.message.contains("unknown macro"), "{e}");

    let path = s.scenario(
        "params.ron",
        "Scenario(\n model: \"../mechanisms/everything.ron\",\n parameters: { \"l1\": 2,\n \"mass\": 3 },\n end_time: 1,\n integrator: Rk4(step: 0.1), output: (interval: 0.1))",
    );
    let sc = load_scenario(&path).unwrap();
    let errs = sc.parameter_values(&model).unwrap_err();
    let e = &errs.0[0];
    assert_eq!(e.element, "parameter \"mass\"");
    assert_eq!(e.line(), Some(4), "{e}");
    assert!(
        e.to_string().starts_with(&format!("{}:4:", path.display())),
        "{e}"
    );

    let path = s.scenario(
        "init.ron",
        "Scenario(\n model: \"../mechanisms/everything.ron\",\n initial: [(coord: \"q0\", value: 1),\n (coord: \"q9\", value: 1), (coord: \"x\", velocity: 2)],\n end_time: 1,\n integrator: Rk4(step: 0.1), output: (interval: 0.1))",
    );
    let sc = load_scenario(&path).unwrap();
    let p = sc.parameter_values(&model).unwrap();
    let errs = sc.initial_state(&model, &p).unwrap_err();
    assert_eq!(errs.len(), 2, "{errs}");
    assert_eq!(errs.0[0].element, "initial \"q9\"");
    assert_eq!(errs.0[0].line(), Some(4));
    assert!(errs.0[0].message.contains("unknown coordinate"));
    assert_eq!(errs.0[1].element, "initial \"x\"");
}

/// A scenario on the track file `track` (written beside the scenario as
/// `track.ron` when given).
fn track_scenario(s: &Scratch, track: Option<&str>) -> PathBuf {
    if let Some(text) = track {
        std::fs::write(s.0.join("scenarios/track.ron"), text).unwrap();
    }
    s.scenario(
        "on_track.ron",
        r#"Scenario(
    model: "../mechanisms/everything.ron",
    end_time: 1.0,
    integrator: Rk4(step: 0.001),
    output: (interval: 0.01),
    track: (file: "track.ron", start: 10.0, speed: 20.0),
)"#,
    )
}

#[test]
fn the_track_file_is_read_and_built_when_the_scenario_loads() {
    let s = Scratch::new("track-ok");
    let path = track_scenario(
        &s,
        Some("Custom((sections: [Straight(length: 120.0), Straight(length: 30.0)]))"),
    );
    let sc = load_scenario(&path).unwrap_or_else(|e| panic!("{e}"));
    let track = sc.track.expect("a track");
    assert_eq!(track.file, s.0.join("scenarios/track.ron"));
    // the built track is the file's: 120 m + 30 m
    assert!(
        (track.track.length() - 150.0).abs() < 1e-12,
        "{}",
        track.track.length()
    );
}

#[test]
fn a_bad_track_file_is_a_load_error_with_its_file_line_and_column() {
    let s = Scratch::new("track-bad");
    // RON syntax: the error names the track file and the position of `Straigt`
    let path = track_scenario(
        &s,
        Some("Custom((\n    sections: [Straigt(length: 5.0)],\n))"),
    );
    let e = load_scenario(&path).unwrap_err();
    let err = &e.0[0];
    assert_eq!(err.file, s.0.join("scenarios/track.ron"));
    assert_eq!(err.position.map(|p| p.0), Some(2), "{e}");
    // invalid geometry: named file and element
    let path = track_scenario(&s, Some("Custom((sections: [Straight(length: -5.0)]))"));
    let e = load_scenario(&path).unwrap_err();
    assert_eq!(e.0[0].file, s.0.join("scenarios/track.ron"));
    assert_eq!(e.0[0].element, "track");
    // a missing file
    std::fs::remove_file(s.0.join("scenarios/track.ron")).unwrap();
    let e = load_scenario(&path).unwrap_err();
    assert!(e.to_string().contains("cannot read the track file"), "{e}");
}
