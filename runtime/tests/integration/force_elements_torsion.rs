//! The torsion spring–damper: a disc of inertia J on a revolute joint, tied to
//! the ground by c, d about its axis and relaxed at φ0, is the damped
//! torsional oscillator J φ̈ + d φ̇ + c (φ − φ0) = 0, whose solution from rest
//! at φ(0) = φ0 + A is φ0 + A e^(−σt) (cos ω_d t + (σ/ω_d) sin ω_d t) with
//! σ = d/(2J) and ω_d = √(c/J − σ²).

use railmbs_testkit::*;
use std::ops::ControlFlow;

use railmbs_runtime::Parts;
use railmbs_runtime::integrate::{JacobianKind, ParkSettings, integrate_park};

/// J = 2 kg m², c = 200 N m/rad, d = 0.8 N m s/rad: ω0 = √(c/J) = 10 rad/s,
/// σ = 0.2 1/s (damping ratio 0.02); released at rest 0.2 rad from φ0 = 0.1.
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

/// Length of the oscillator run, s (about five periods).
const T_END: f64 = 3.0;

#[test]
fn torsional_oscillator_matches_the_damped_solution() {
    let (j, c, d, phi0, a): (f64, f64, f64, f64, f64) = (2.0, 200.0, 0.8, 0.1, 0.2);
    let sigma = d / (2.0 * j);
    let wd = (c / j - sigma * sigma).sqrt();
    let exact =
        |t: f64| phi0 + a * (-sigma * t).exp() * ((wd * t).cos() + sigma / wd * (wd * t).sin());
    let (mut sys, q0, v0) = numeric_system(&parse(DISC), &[]);
    let settings = ParkSettings {
        jacobian: JacobianKind::Analytic,
        ..ParkSettings::with_tolerances(1e-8, 1e-10)
    };
    let mut worst: f64 = 0.0;
    // Downward crossings of φ0, to measure the period.
    let mut crossings = Vec::new();
    let mut last = (0.0, q0[0]);
    let stats = integrate_park(&mut sys, &settings, 0.0, &q0, &v0, T_END, |t, q, _, _| {
        worst = worst.max((q[0] - exact(t)).abs());
        if last.1 > phi0 && q[0] <= phi0 {
            // Linear interpolation between the steps.
            let s = (last.1 - phi0) / (last.1 - q[0]);
            crossings.push(last.0 + s * (t - last.0));
        }
        last = (t, q[0]);
        ControlFlow::Continue(())
    })
    .unwrap_or_else(|e| panic!("{e}"));
    println!("{} steps", stats.steps);
    println!("largest |φ − exact| over 3 s: {worst:e} rad");
    // Park's method is second order: with local tolerances 1e-8 (relative)
    // and 1e-10 rad over ~9 400 steps (~5 periods) the global error grows to
    // 7.1e-6 rad here (3.5e-5 of the 0.2 rad amplitude). 3e-5 rad leaves
    // room for other step sequences and still fails on a 1 % error in c
    // (phase shift ≈ 0.005·ω·t = 0.15 rad after 3 s) or in d (amplitude
    // change ≈ 0.01·σt·A = 1.2e-3 · 0.2 rad ≈ 1.2e-4 rad), or a wrong sign.
    assert!(worst < 3e-5, "largest deviation {worst} rad");
    // The period: 2π/ω_d from the crossings, measured within 1.4e-6 s (the
    // integrator's phase error; the linear interpolation of a crossing
    // between steps errs far less). 1e-5 s is 1.6e-5 of the period; a 1 %
    // error in c would change it by 0.5 %, 3e-3 s.
    assert!(crossings.len() >= 4, "crossings {crossings:?}");
    let periods: Vec<f64> = crossings.windows(2).map(|w| w[1] - w[0]).collect();
    let period = 2.0 * std::f64::consts::PI / wd;
    println!("periods {periods:?}, exact {period}");
    for p in &periods {
        assert!((p - period).abs() < 1e-5, "period {p} s, exact {period} s");
    }
}

#[test]
fn outputs_are_moment_angle_rate_energy_and_power() {
    let (mut sys, ..) = numeric_system(&parse(DISC), &[]);
    let (q, v) = ([0.35], [1.5]);
    sys.evaluate(0.0, &q, &v, Parts::KINEMATICS).unwrap();
    let mut out = Vec::new();
    sys.force_outputs(0.0, &mut out);
    let u = 0.35 - 0.1;
    let expected = [
        200.0 * u + 0.8 * 1.5,
        0.35,
        1.5,
        0.5 * 200.0 * u * u,
        0.8 * 1.5 * 1.5,
    ];
    for (k, (o, e)) in out.iter().zip(expected).enumerate() {
        assert!(
            (o - e).abs() < 1e-12 * e.abs().max(1.0),
            "output {k}: {o} vs {e}"
        );
    }
}

/// Two discs on the same axis, both on revolute joints from the ground, the
/// spring between them: the moment depends on the angle difference only, and
/// a rotation of body 1 about e does not turn e, so the assembled Jacobian
/// (−c and −d in the difference coordinates) is exact.
const PAIR: &str = r#"
Model(
    name: "torsion_pair",
    gravity: (0, 0, 0),
    bodies: [
        Body(name: "a", mass: 1, inertia: (ixx: 3, iyy: 2, izz: 2),
             joint: Revolute(parent: "ground", axis: X, coord: "qa", init: 0.2, vel: 0.5)),
        Body(name: "b", mass: 1, inertia: (ixx: 2, iyy: 1, izz: 1),
             joint: Revolute(parent: "ground", axis: X, coord: "qb", init: -0.4, vel: -1.0)),
    ],
    forces: [
        TorsionSpring(name: "t", body1: "a", body2: "b", axis: (1, 0, 0), c: 300, d: 7, phi0: 0.05),
    ],
)
"#;

#[test]
fn assembled_jacobian_equals_central_differences() {
    let (mut sys, q, v) = numeric_system(&parse(PAIR), &[]);
    let (dq, dv) = analytic_jacobians(&mut sys, &q, &v);
    let fq = central_difference(&mut sys, &q, &v, false, 1e-6);
    let fv = central_difference(&mut sys, &q, &v, true, 1e-6);
    // The moment is linear in the angles (φ = qb − qa exactly, |φ| < π) and
    // rates, so central differences are exact up to rounding, ~ε·|M|/h ≈ 1e-8.
    assert!(rel_diff(&dq, &fq) < 1e-6, "∂f/∂q:\n{dq}\nvs\n{fq}");
    assert!(rel_diff(&dv, &fv) < 1e-6, "∂f/∂q̇:\n{dv}\nvs\n{fv}");
    assert!((dq[(0, 0)] + 300.0).abs() < 1e-9 && (dq[(0, 1)] - 300.0).abs() < 1e-9);
    assert!((dv[(1, 1)] + 7.0).abs() < 1e-9 && (dv[(1, 0)] - 7.0).abs() < 1e-9);
}
