//! Validation of the friction, contact and tabulated force elements: each
//! check names the element and the field, at its position in the file.

mod common;

use common::*;
use railmbs_models::ForceKind;

/// BASE with `element` added to its forces; the resulting errors.
fn errors_with(element: &str) -> railmbs_models::ModelErrors {
    base_errors("c: \"k\"),", &format!("c: \"k\"),\n        {element},"))
}

const PP: &str = "PointPlane(name: \"pp\", body: \"a\", points: [(0, 0, -1), (1, 0, -1)], c: 1e5, d: 10, mu0: 0.3, mu: 0.2)";
const CF: &str =
    "Coulomb(name: \"cf\", body1: \"a\", body2: \"b\", c: 1e5, d: 10, limit: 100, sliding: 80)";
const LF: &str =
    "LoadFriction(name: \"lf\", body1: \"a\", body2: \"b\", c1: 1e5, c2: 1e5, mu0: 0.3, mu: 0.2)";
const TB: &str = "Tabulated(name: \"tb\", body1: \"a\", body2: \"b\", table: [(-1, -10), (0, 0), (1, 10)], d: 1)";

#[test]
fn valid_elements_load_with_defaults() {
    let text = BASE.replacen(
        "c: \"k\"),",
        &format!("c: \"k\"),\n        {PP},\n        {CF},\n        {LF},\n        {TB},"),
        1,
    );
    let m = load(&text).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(m.forces.len(), 5);
    match &m.forces[1].kind {
        ForceKind::PointPlane {
            points,
            tangential_stiffness,
            stiffness,
            ..
        } => {
            assert_eq!(points.len(), 2);
            // ct defaults to c.
            assert_eq!(tangential_stiffness, stiffness);
        }
        k => panic!("{k:?}"),
    }
    // sliding defaults to the static limit, mu0 to mu.
    let text = BASE.replacen(
        "c: \"k\"),",
        "c: \"k\"),\n        Coulomb(name: \"cf\", body1: \"a\", body2: \"b\", c: 1, limit: 5),\n        LoadFriction(name: \"lf\", body1: \"a\", body2: \"b\", c1: 1, c2: 1, mu: 0.2),",
        1,
    );
    let m = load(&text).unwrap_or_else(|e| panic!("{e}"));
    match (&m.forces[1].kind, &m.forces[2].kind) {
        (
            ForceKind::Coulomb {
                static_limit,
                sliding_force,
                ..
            },
            ForceKind::LoadFriction { mu_static, mu, .. },
        ) => {
            assert_eq!(static_limit, sliding_force);
            assert_eq!(mu_static, mu);
        }
        k => panic!("{k:?}"),
    }
}

#[test]
fn stiffness_must_be_positive() {
    find(
        &errors_with(&PP.replace("c: 1e5", "c: 0")),
        "force \"pp\"",
        "c must be positive, got 0",
    );
    find(
        &errors_with(&PP.replace("c: 1e5", "c: 1e5, ct: -1")),
        "force \"pp\"",
        "ct must be positive",
    );
    find(
        &errors_with(&CF.replace("c: 1e5", "c: -3")),
        "force \"cf\"",
        "c must be positive",
    );
    find(
        &errors_with(&LF.replace("c1: 1e5", "c1: 0")),
        "force \"lf\"",
        "c1 must be positive",
    );
    find(
        &errors_with(&LF.replace("c2: 1e5", "c2: \"-k\"")),
        "force \"lf\"",
        "c2 must be positive",
    );
}

#[test]
fn damping_must_not_be_negative() {
    find(
        &errors_with(&PP.replace("d: 10", "d: -1")),
        "force \"pp\"",
        "d must not be negative",
    );
    find(
        &errors_with(&PP.replace("d: 10", "d: 10, dt: -2")),
        "force \"pp\"",
        "dt must not be negative",
    );
    find(
        &errors_with(&CF.replace("d: 10", "d: -1")),
        "force \"cf\"",
        "d must not be negative",
    );
    find(
        &errors_with(&TB.replace("d: 1", "d: -1")),
        "force \"tb\"",
        "d must not be negative",
    );
}

#[test]
fn friction_coefficients_are_ordered() {
    find(
        &errors_with(&PP.replace("mu: 0.2", "mu: -0.1")),
        "force \"pp\"",
        "mu must not be negative",
    );
    find(
        &errors_with(&PP.replace("mu: 0.2", "mu: 0.4")),
        "force \"pp\"",
        "mu = 0.4 must not exceed mu0 = 0.3",
    );
    find(
        &errors_with(&LF.replace("mu: 0.2", "mu: 0.5")),
        "force \"lf\"",
        "mu = 0.5 must not exceed mu0",
    );
    find(
        &errors_with(&LF.replace("mu0: 0.3, mu: 0.2", "mu0: 1.2, mu: 0.2")),
        "force \"lf\"",
        "mu0 must be below 1",
    );
    find(
        &errors_with(&CF.replace("sliding: 80", "sliding: 120")),
        "force \"cf\"",
        "sliding = 120 must not exceed limit = 100",
    );
    find(
        &errors_with(&CF.replace("sliding: 80", "sliding: -1")),
        "force \"cf\"",
        "sliding must not be negative",
    );
}

#[test]
fn contact_geometry_is_checked() {
    find(
        &errors_with(&PP.replace("mu: 0.2", "mu: 0.2, normal: (0, 0, 0)")),
        "force \"pp\"",
        "normal must not be zero",
    );
    find(
        &errors_with(&PP.replace("points: [(0, 0, -1), (1, 0, -1)]", "points: []")),
        "force \"pp\"",
        "at least one point",
    );
    find(
        &errors_with(&PP.replace("mu: 0.2", "mu: 0.2, plane_body: \"a\"")),
        "force \"pp\"",
        "another body",
    );
    find(
        &errors_with(&PP.replace("mu: 0.2", "mu: 0.2, plane_body: \"nope\"")),
        "force \"pp\"",
        "unknown body \"nope\" in plane_body",
    );
}

#[test]
fn table_is_checked() {
    find(
        &errors_with(&TB.replace("[(-1, -10), (0, 0), (1, 10)]", "[(0, 0)]")),
        "force \"tb\"",
        "at least 2 rows, got 1",
    );
    find(
        &errors_with(&TB.replace(
            "[(-1, -10), (0, 0), (1, 10)]",
            "[(-1, -10), (0.5, 0), (0.5, 10)]",
        )),
        "force \"tb\"",
        "table deflections must increase: row 2 has 0.5 after 0.5",
    );
}
