//! `TorsionSpring`: its defaults, and its value errors located at their fields.

use railmbs_models::{ForceKind, parse_model};
use std::path::Path;

fn model(spring: &str) -> Result<railmbs_models::Model, railmbs_models::ModelErrors> {
    let text = format!(
        r#"Model(name: "t", bodies: [
            Body(name: "disc", mass: 1, inertia: (ixx: 1, iyy: 1, izz: 1),
                 joint: Revolute(parent: "ground", axis: Z)),
        ], forces: [
            {spring},
        ])"#
    );
    parse_model(&text, Path::new("t.ron"))
}

#[test]
fn resolves_with_defaults() {
    let m = model(r#"TorsionSpring(name: "t", body1: "ground", body2: "disc", c: 10)"#)
        .unwrap_or_else(|e| panic!("{e}"));
    let ForceKind::TorsionSpring(t) = &m.forces[0].kind else {
        panic!("{:?}", m.forces[0].kind)
    };
    let p = [];
    let axis: Vec<f64> = t.axis.iter().map(|e| e.eval(&p, 0.0)).collect();
    assert_eq!(axis, [0.0, 0.0, 1.0]);
    assert_eq!(t.damping.eval(&p, 0.0), 0.0);
    assert_eq!(t.preload_angle.eval(&p, 0.0), 0.0);
}

#[test]
fn errors_are_located_at_their_field() {
    let errors = model(
        r#"TorsionSpring(name: "t", body1: "disc", body2: "disc", axis: (0, 0, 0), c: -1, d: -2)"#,
    )
    .unwrap_err();
    for needle in [
        "connects body \"disc\" to itself",
        "axis must not be zero",
        "c must not be negative, got -1",
        "d must not be negative, got -2",
    ] {
        let e = errors
            .iter()
            .find(|e| e.message.contains(needle))
            .unwrap_or_else(|| panic!("no {needle:?} in {errors}"));
        assert_eq!(e.element, "force \"t\"");
        assert!(e.position.is_some(), "{e}");
    }
}
