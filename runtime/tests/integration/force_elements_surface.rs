//! Point–Z-surface contact (Pogorelov 2005, Sect. 3.3, the surface z = f(x, y)
//! given as an expression): a bead sliding without friction in a bowl swings
//! with the pendulum period of the bowl's radius of curvature; a planar
//! surface gives the same forces and Jacobians as the equivalent point–plane
//! contact; bad surfaces give clear errors.

use railmbs_testkit::*;
use std::f64::consts::PI;
use std::ops::ControlFlow;

use nalgebra::{DMatrix, DVector};
use railmbs_runtime::MechanicalSystem;
use railmbs_runtime::integrate::{JacobianKind, ParkSettings, integrate_park};

/// A 1 kg bead (translations only) released at rest at x = A in the bowl
/// z = (x² + y²)/(2R), frictionless, on a stiff contact (503 Hz, ζ = 0.5).
const BOWL: &str = r#"
Model(
    name: "bowl",
    parameters: { "R": 1, "A": 0.01, "c": 1e7, "d": 3162 },
    gravity: (0, 0, -9.81),
    bodies: [
        Body(name: "bead", mass: 1, inertia: (ixx: 1e-4, iyy: 1e-4, izz: 1e-4),
             joint: Joint(parent: "ground", transforms: [
                Tx((coord: "x", init: "A")), Ty((coord: "y")),
                Tz((coord: "z", init: "A^2/(2*R) - 9.81/c"))])),
    ],
    forces: [
        PointPlane(name: "bowl", body: "bead", points: [(0, 0, 0)], surface: "(x^2 + y^2)/(2*R)",
                   c: "c", d: "d", mu0: 0, mu: 0),
    ],
)
"#;

#[test]
fn bead_in_a_bowl_swings_with_the_pendulum_period() {
    let model = parse(BOWL);
    let (mut sys, q0, v0) = numeric_system(&model, &[]);
    let settings = ParkSettings {
        max_step: 1e-3,
        jacobian: JacobianKind::Analytic,
        ..ParkSettings::with_tolerances(1e-8, 1e-9)
    };
    // Times where x crosses zero downwards, linearly interpolated.
    let mut crossings = Vec::new();
    let mut prev: Option<(f64, f64)> = None;
    let mut max_y: f64 = 0.0;
    integrate_park(&mut sys, &settings, 0.0, &q0, &v0, 7.0, |t, q, _, _| {
        if let Some((t0, x0)) = prev
            && x0 > 0.0
            && q[0] <= 0.0
        {
            crossings.push(t0 + (t - t0) * x0 / (x0 - q[0]));
        }
        prev = Some((t, q[0]));
        max_y = max_y.max(q[1].abs());
        ControlFlow::Continue(())
    })
    .unwrap_or_else(|e| panic!("{e}"));
    assert!(crossings.len() >= 3, "{crossings:?}");
    let periods: Vec<f64> = crossings.windows(2).map(|w| w[1] - w[0]).collect();
    // Small oscillation of a bead in a bowl of radius of curvature R: the
    // pendulum period 2π√(R/g). Corrections: the parabola's amplitude
    // dependence, of order (A/R)² = 1e-4 (measured: +2.7e-5), the contact's
    // compliance (ω/ω_c)² ≈ 1e-6, the interpolated crossing with h ≤ 1e-3 s
    // ~1e-6 s.
    let expected = 2.0 * PI * (1.0f64 / 9.81).sqrt();
    println!("periods {periods:?} s, pendulum {expected} s");
    for p in &periods {
        assert!(
            (p - expected).abs() < 1e-4 * expected,
            "period {p} s, pendulum {expected} s"
        );
    }
    // Released in the x–z plane, it stays there.
    assert!(max_y < 1e-12, "lateral drift {max_y} m");
}

/// A point on body `a` against a sloped plane on the moving body `b`, as a
/// Z-surface and as the equivalent point–plane contact.
fn sloped(surface: bool) -> String {
    let contact = if surface {
        r#"surface: "0.1*x - 0.2*y + 0.3""#
    } else {
        "origin: (0, 0, 0.3), normal: (-0.1, 0.2, 1)"
    };
    format!(
        r#"
Model(
    name: "sloped",
    gravity: (0, 0, 0),
    bodies: [
        Body(name: "a", mass: 1, inertia: (ixx: 1, iyy: 1, izz: 1),
             joint: Joint(parent: "ground", transforms: [
                Tx((coord: "ax", init: 0.1, vel: 0.3)), Ty((coord: "ay", init: 0.2, vel: 0.05)),
                Tz((coord: "az", init: 0.28, vel: -0.01))])),
        Body(name: "b", mass: 1, inertia: (ixx: 1, iyy: 1, izz: 1),
             joint: Joint(parent: "ground", transforms: [
                Tx((coord: "bx", vel: 0.02)), Ty((coord: "by", vel: -0.03)),
                Rz((coord: "bpsi", init: 0.3, vel: 0.2))])),
    ],
    forces: [
        PointPlane(name: "pp", body: "a", points: [(0.01, 0.02, 0)], plane_body: "b", {contact},
                   c: 1e5, d: 300, ct: 5e4, dt: 100, mu0: 0.5, mu: 0.4),
    ],
)
"#
    )
}

#[test]
fn planar_surface_equals_the_point_plane_contact() {
    let (surface, plane) = (parse(&sloped(true)), parse(&sloped(false)));
    let (mut s1, q, v) = numeric_system(&surface, &[]);
    let (mut s2, ..) = numeric_system(&plane, &[]);
    let n = q.len();
    for (va, stick) in [(0.3, false), (0.0, true)] {
        let mut v = v.clone();
        v[0] = va;
        if stick {
            v.iter_mut().for_each(|x| *x *= 1e-3);
        }
        // Modes and anchors from the same accepted state, then moved.
        s1.accept_step(0.0, &q, &v).unwrap();
        s2.accept_step(0.0, &q, &v).unwrap();
        let q: Vec<f64> = q.iter().map(|x| x + 2e-4).collect();
        let mut m = DMatrix::zeros(n, n);
        let (mut f1, mut f2) = (DVector::zeros(n), DVector::zeros(n));
        s1.dynamics(0.0, &q, &v, &mut m, &mut f1).unwrap();
        s2.dynamics(0.0, &q, &v, &mut m, &mut f2).unwrap();
        assert!(f1.amax() > 1.0, "no contact force: {f1}");
        assert!((&f1 - &f2).amax() <= 1e-12 * f2.amax(), "{f1} vs {f2}");
        let (mut q1, mut v1, mut q2, mut v2) = (m.clone(), m.clone(), m.clone(), m.clone());
        s1.force_jacobian(0.0, &q, &v, &mut q1, &mut v1).unwrap();
        s2.force_jacobian(0.0, &q, &v, &mut q2, &mut v2).unwrap();
        assert!((&q1 - &q2).amax() <= 1e-12 * q2.amax());
        assert!((&v1 - &v2).amax() <= 1e-12 * v2.amax());
    }
}

#[test]
fn bad_surfaces_are_refused_with_the_element_named() {
    let unknown = BOWL.replace("(x^2 + y^2)/(2*R)", "z^2");
    let e = try_parse(&unknown).unwrap_err().to_string();
    assert!(
        e.contains("bowl") && e.contains("surface") && e.contains("\"z\""),
        "{e}"
    );
    let with_normal = BOWL.replace("surface:", "normal: (0, 1, 1), surface:");
    let e = try_parse(&with_normal).unwrap_err().to_string();
    assert!(e.contains("normal"), "{e}");
    // A surface undefined under the point stops the evaluation with the place.
    let domain = BOWL.replace("(x^2 + y^2)/(2*R)", "sqrt(1e-4 - x^2)");
    let model = parse(&domain);
    let (mut sys, mut q, v) = numeric_system(&model, &[]);
    q[0] = 0.02;
    let n = q.len();
    let e = sys
        .dynamics(
            0.0,
            &q,
            &v,
            &mut DMatrix::zeros(n, n),
            &mut DVector::zeros(n),
        )
        .unwrap_err()
        .to_string();
    assert!(e.contains("bowl") && e.contains("x = 0.02"), "{e}");
    // A kink (the slope of abs is 0/0 at 0) is not an error: the point on
    // the ridge of the V-shaped surface z = 0.1|x| is pushed straight up.
    let kink = BOWL.replace("(x^2 + y^2)/(2*R)", "0.1*abs(x)");
    let model = parse(&kink);
    let (mut sys, mut q, v) = numeric_system(&model, &[]);
    q[0] = 0.0;
    q[2] = -1e-4;
    let mut f = DVector::zeros(n);
    sys.dynamics(0.0, &q, &v, &mut DMatrix::zeros(n, n), &mut f)
        .unwrap();
    assert!(f[2] > 0.0 && f[0] == 0.0 && f[1] == 0.0, "{f}");
}
