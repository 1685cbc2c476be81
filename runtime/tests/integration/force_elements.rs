//! Force elements: local Jacobians against central differences of the forces,
//! and Park's method with the analytic approximate Jacobian (Pogorelov 2005, Sect. 6)
//! against finite differences.
//!
//! Expected values come from central differences of the forces themselves
//! (an independent computation), from closed-form solutions, or from runs with
//! the finite-difference Jacobian, never from the analytic Jacobian under test.

use railmbs_testkit::*;
use std::ops::ControlFlow;

use nalgebra::DMatrix;
use railmbs_runtime::MechanicalSystem;
use railmbs_runtime::integrate::{JacobianKind, ParkSettings, integrate_park};

/// Two bodies moving by translations only (Γ constant, no rotation), joined by
/// springs at points off their centres and a 6×6 element with coupling terms:
/// there the approximation of Sect. 6 neglects nothing, so the assembled
/// Jacobian must equal the derivative of f.
const TRANSLATING: &str = r#"
Model(
    name: "translating",
    gravity: (0, 0, -9.81),
    bodies: [
        Body(name: "a", mass: 2, inertia: (ixx: 1, iyy: 1, izz: 1),
             joint: Joint(parent: "ground", transforms: [
                Tx((coord: "ax", init: 0.1, vel: 0.3)), Ty((coord: "ay", init: -0.2, vel: -0.1)),
                Tz((coord: "az", init: 0.05, vel: 0.7))])),
        Body(name: "b", mass: 3, inertia: (ixx: 1, iyy: 1, izz: 1),
             joint: Joint(parent: "a", transforms: [Tx(0.5),
                Tx((coord: "bx", init: 0.2, vel: -0.4)), Ty((coord: "by", init: 0.1, vel: 0.2)),
                Tz((coord: "bz", init: -0.3, vel: 0.1))])),
    ],
    forces: [
        Spring(name: "s1", body1: "ground", point1: (0, 0.1, 1), body2: "a", point2: (0.1, 0.2, -0.1),
               c: 1000, d: 20, f0: 15, x0: 0.7),
        Spring(name: "s2", body1: "a", point1: (0.3, 0, 0.1), body2: "b", point2: (-0.1, 0.05, 0.2),
               c: 3000, d: 50, f0: -5, x0: 0.4),
        Linear6(name: "l6", body1: "a", point1: (0.2, 0.1, 0), rotation1: (0.1, -0.2, 0.3),
                body2: "b", point2: (0, 0.1, 0.1), rotation2: (0.1, -0.2, 0.3),
                stiffness: Full([1e4, 200, 0, 0, 30, 0,   200, 2e4, 0, 0, 0, 0,   0, 0, 3e4, 0, 0, 0,
                                 0, 0, 0, 100, 0, 0,   30, 0, 0, 0, 100, 0,   0, 0, 0, 0, 0, 100]),
                damping: Diag((100, 200, 300, 1, 1, 1)), preload: (10, 0, -20, 0, 0, 0)),
        Applied(name: "push", body: "b", point: (0, 0, 0), force: ("10*sin(t)", 0, 0)),
    ],
)
"#;

#[test]
fn assembled_jacobian_equals_central_differences_for_translating_bodies() {
    let model = parse(TRANSLATING);
    let (mut sys, q, v) = numeric_system(&model, &[]);
    let (dq, dv) = analytic_jacobians(&mut sys, &q, &v);
    let fq = central_difference(&mut sys, &q, &v, false, 1e-6);
    let fv = central_difference(&mut sys, &q, &v, true, 1e-6);
    // Central differences with h = 1e-6 of forces ~1e3 N: truncation
    // ~h²·f''' ≈ 1e-9 relative, rounding ~ε·|f|/h ≈ 1e-10·|f|: 1e-6 is ample.
    assert!(rel_diff(&dq, &fq) < 1e-6, "∂f/∂q:\n{dq}\nvs\n{fq}");
    assert!(rel_diff(&dv, &fv) < 1e-6, "∂f/∂q̇:\n{dv}\nvs\n{fv}");
    assert!(dq.amax() > 1e3, "the test exercises the stiffness terms");
}

/// Two free bodies (six coordinates each, rotating) joined by a 6×6 element and
/// a bipolar spring at its free length, evaluated at rest: all forces are
/// zero, so the neglected ∂Γ/∂q terms (proportional to the forces) vanish and
/// the approximate Jacobian is exact.
const ROTATING: &str = r#"
Model(
    name: "rotating",
    gravity: (0, 0, 0),
    bodies: [
        Body(name: "a", mass: 2, inertia: (ixx: 1, iyy: 2, izz: 1.5),
             joint: SixDof(parent: "ground", at: (0, 0, 0), init: (0.1, 0.2, 0.3, 0.2, -0.3, 0.4))),
        Body(name: "b", mass: 3, inertia: (ixx: 1, iyy: 1, izz: 2),
             joint: SixDof(parent: "a", at: (1, 0, 0), init: (0, 0, 0, 0, 0, 0))),
    ],
    forces: [
        Linear6(name: "l6", body1: "a", point1: (0.5, 0.1, 0), rotation1: (0.1, 0.2, 0),
                body2: "b", point2: (-0.5, 0.1, 0), rotation2: (0.1, 0.2, 0),
                stiffness: Full([1e4, 200, 0, 0, 30, 0,   200, 2e4, 0, 0, 0, 0,   0, 0, 3e4, 0, 0, 0,
                                 0, 0, 0, 100, 0, 0,   30, 0, 0, 0, 100, 0,   0, 0, 0, 0, 0, 100]),
                damping: Diag((100, 200, 300, 1, 2, 3))),
        Spring(name: "s", body1: "a", point1: (0, 0.3, 0), body2: "b", point2: (0, 0.2, 0.4),
               c: 5000, d: 40, x0: "sqrt(1 + 0.01 + 0.16)"),
    ],
)
"#;

#[test]
fn assembled_jacobian_is_exact_for_rotating_bodies_at_zero_force() {
    let model = parse(ROTATING);
    let (mut sys, q, v) = numeric_system(&model, &[]);
    assert!(v.iter().all(|x| *x == 0.0));
    let (dq, dv) = analytic_jacobians(&mut sys, &q, &v);
    let fq = central_difference(&mut sys, &q, &v, false, 1e-6);
    let fv = central_difference(&mut sys, &q, &v, true, 1e-6);
    // Same difference accuracy as above; rotations enter through sin/cos of
    // O(1) angles, which the O(h²) truncation does not change.
    assert!(rel_diff(&dq, &fq) < 1e-6, "∂f/∂q:\n{dq}\nvs\n{fq}");
    assert!(rel_diff(&dv, &fv) < 1e-6, "∂f/∂q̇:\n{dv}\nvs\n{fv}");
}

#[test]
fn systems_without_force_elements_fall_back_to_differences() {
    let model = parse(
        r#"Model(name: "p", bodies: [Body(name: "a", mass: 1, inertia: (ixx: 1, iyy: 1, izz: 1),
            joint: Revolute(parent: "ground", axis: X, to_com: (0, 0, -1)))])"#,
    );
    let (mut sys, q, v) = numeric_system(&model, &[]);
    let mut dq = DMatrix::zeros(1, 1);
    let mut dv = DMatrix::zeros(1, 1);
    assert!(!sys.force_jacobian(0.0, &q, &v, &mut dq, &mut dv).unwrap());
}

#[test]
fn park_with_the_analytic_jacobian_matches_differences_with_fewer_evaluations() {
    let model = mechanism("spring_mass");
    let run = |kind: JacobianKind| {
        let (mut sys, q0, v0) = numeric_system(&model, &[]);
        let settings = ParkSettings {
            jacobian: kind,
            ..ParkSettings::with_tolerances(1e-8, 1e-10)
        };
        let mut samples = Vec::new();
        let st = integrate_park(&mut sys, &settings, 0.0, &q0, &v0, 3.0, |t, q, _, _| {
            samples.push((t, q[0]));
            ControlFlow::Continue(())
        })
        .unwrap();
        (st, samples)
    };
    let (fd, _) = run(JacobianKind::ForwardDifference);
    let (an, samples) = run(JacobianKind::Analytic);
    // Exact solution: the damped oscillator m z̈ = −k (z + L0) − c ż − m g about
    // z_eq = −L0 − m g/k, starting at rest at z = −L0: z = z_eq + A e^{−ζωt}(cos ω_d t
    // + ζω/ω_d sin ω_d t) with A = m g/k.
    let (m, k, zeta, l0, g) = (1.0f64, 100.0f64, 0.1f64, 1.0f64, 9.81f64);
    let w = (k / m).sqrt();
    let wd = w * (1.0 - zeta * zeta).sqrt();
    let exact = |t: f64| {
        -l0 - m * g / k
            + m * g / k * (-zeta * w * t).exp() * ((wd * t).cos() + zeta * w / wd * (wd * t).sin())
    };
    let err = samples
        .iter()
        .map(|(t, z)| (z - exact(*t)).abs())
        .fold(0.0, f64::max);
    // Amplitude 0.098 m; rtol 1e-8 per step over ~300 steps: 1e-5 m is loose.
    assert!(
        err < 1e-5,
        "analytic-Jacobian run deviates {err} m from the exact solution"
    );
    // Same tolerance, same answer: both runs agree within the tolerance scale.
    assert!(
        (an.q[0] - fd.q[0]).abs() < 1e-6,
        "{} vs {}",
        an.q[0],
        fd.q[0]
    );
    // The analytic Jacobian costs no extra `dynamics` calls (forward
    // differences cost 2n = 2 per Jacobian evaluation).
    assert!(
        an.dynamics_evaluations < fd.dynamics_evaluations,
        "analytic {} vs differences {} dynamics evaluations",
        an.dynamics_evaluations,
        fd.dynamics_evaluations
    );
}
