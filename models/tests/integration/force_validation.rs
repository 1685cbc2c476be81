//! Validation of the friction, contact and tabulated force elements: each
//! check names the element and the field, at its position in the file.

use crate::common;

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
        ForceKind::PointPlane(railmbs_models::forces::PointPlane {
            points,
            tangential_stiffness,
            stiffness,
            ..
        }) => {
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
            ForceKind::Coulomb(railmbs_models::forces::Coulomb {
                static_limit,
                sliding_force,
                ..
            }),
            ForceKind::LoadFriction(railmbs_models::forces::LoadFriction { mu_static, mu, .. }),
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

/// The vertical-spring helper of `Linear6` (a coil spring with vertical,
/// shear, bending and torsion stiffness and height H, frames at its lower
/// plate) against the mechanics of the spring: a pure shear of the upper
/// plate (translation u_x) is resisted by the shear force c_s u_x acting at
/// mid-height, i.e. with the moment c_s u_x H/2 about the lower plate; a tilt
/// of the upper body about the spring's mid-height point (translation
/// −θ H/2 at the lower plate, no shear) only bends it: moment c_b θ, no force.
#[test]
fn vertical_spring_helper_gives_the_coil_spring_stiffness() {
    let (cz, cs, cb, ct, h) = (1.2e6, 3.0e5, 4.0e4, 2.0e4, 0.4);
    let element = format!(
        "Linear6(name: \"coil\", body1: \"a\", body2: \"b\", \
         stiffness: VerticalSpring(vertical: {cz}, shear: {cs}, bending: {cb}, torsion: {ct}, height: {h}))"
    );
    let text = BASE.replacen("c: \"k\"),", &format!("c: \"k\"),\n        {element},"), 1);
    let m = load(&text).unwrap_or_else(|e| panic!("{e}"));
    let ForceKind::Linear6(railmbs_models::forces::Linear6 { stiffness, .. }) = &m.forces[1].kind
    else {
        panic!("{:?}", m.forces[1].kind)
    };
    let c: Vec<f64> = stiffness.iter().map(|e| e.eval(&[], 0.0)).collect();
    let times = |d: [f64; 6]| -> Vec<f64> {
        (0..6)
            .map(|r| (0..6).map(|k| c[6 * r + k] * d[k]).sum())
            .collect()
    };
    let close = |a: f64, b: f64| (a - b).abs() <= 1e-12 * b.abs().max(1.0);
    // Symmetric (it is a Hessian).
    for r in 0..6 {
        for k in 0..6 {
            assert_eq!(c[6 * r + k], c[6 * k + r]);
        }
    }
    let u = 1e-3;
    let w = times([u, 0.0, 0.0, 0.0, 0.0, 0.0]);
    assert!(
        close(w[0], cs * u) && close(w[4], cs * u * h / 2.0),
        "{w:?}"
    );
    let w = times([0.0, u, 0.0, 0.0, 0.0, 0.0]);
    assert!(
        close(w[1], cs * u) && close(w[3], -cs * u * h / 2.0),
        "{w:?}"
    );
    let th = 2e-3;
    let w = times([-th * h / 2.0, 0.0, 0.0, 0.0, th, 0.0]);
    assert!(close(w[0], 0.0) && close(w[4], cb * th), "{w:?}");
    let w = times([0.0, th * h / 2.0, 0.0, th, 0.0, 0.0]);
    assert!(close(w[1], 0.0) && close(w[3], cb * th), "{w:?}");
    let w = times([0.0, 0.0, u, 0.0, 0.0, th]);
    assert!(close(w[2], cz * u) && close(w[5], ct * th), "{w:?}");
}

/// `SeriesSpring` was missing from the locator's list of force constructors,
/// so its errors had no line and column; the list now comes from the force
/// registry, and its errors point at the field.
#[test]
fn series_spring_errors_are_located() {
    let ss = "SeriesSpring(name: \"ss\", body1: \"a\", body2: \"b\", c: 0, d: 10)";
    let errors = errors_with(ss);
    let e = find(&errors, "force \"ss\"", "c must be positive, got 0");
    let text = BASE.replacen("c: \"k\"),", &format!("c: \"k\"),\n        {ss},"), 1);
    let at = text.find("c: 0").unwrap();
    let line = text[..at].matches('\n').count() + 1;
    let col = at - text[..at].rfind('\n').map_or(0, |k| k + 1) + 1;
    assert_eq!(e.position, Some((line, col)));
    // `find` also checks that the error has a position.
    find(
        &errors_with(&ss.replace("d: 10", "d: -1")),
        "force \"ss\"",
        "d must be positive",
    );
}
