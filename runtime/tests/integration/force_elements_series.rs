//! Stiffness and damping in series (a Maxwell element, Pogorelov 2005, Sect. 3.1):
//! its first-order state integrated by Park's method together with q, against
//! the closed-form solution of the linear third-order system, the energy
//! balance of the damper, and its Jacobian against central differences.

use railmbs_testkit::*;
use std::ops::ControlFlow;

use nalgebra::{DMatrix, DVector, Matrix3, Vector3};
use railmbs_runtime::MechanicalSystem;
use railmbs_runtime::integrate::{JacobianKind, ParkSettings, integrate_park};

/// A mass m on a line, tied to the ground by a spring c in series with a
/// damper d, started with velocity v0 from the relaxed state.
const MAXWELL: &str = r#"
Model(
    name: "maxwell",
    parameters: { "m": 1, "c": 1e4, "d": 200, "v0": 1 },
    gravity: (0, 0, 0),
    bodies: [
        Body(name: "mass", mass: "m", inertia: (ixx: 1, iyy: 1, izz: 1),
             joint: Prismatic(parent: "ground", axis: X, coord: "x", vel: "v0")),
    ],
    forces: [
        SeriesSpring(name: "maxwell", body1: "ground", point1: (-1, 0, 0), body2: "mass",
                     c: "c", d: "d"),
    ],
)
"#;

/// exp(A t) by scaling and squaring with a 30-term Taylor series: for
/// ‖A t / 2^k‖ ≤ 0.5 the truncation is below 1e-40, and 2^k squarings lose
/// about k ε of accuracy.
fn expm(a: &Matrix3<f64>, t: f64) -> Matrix3<f64> {
    let norm = (a * t).abs().row_sum().max();
    let k = (norm / 0.5).log2().ceil().max(0.0) as i32;
    let b = a * t / 2f64.powi(k);
    let (mut term, mut sum) = (Matrix3::identity(), Matrix3::identity());
    for j in 1..30 {
        term = term * b / j as f64;
        sum += term;
    }
    for _ in 0..k {
        sum = sum * sum;
    }
    sum
}

#[test]
fn maxwell_element_follows_the_closed_form_response() {
    let (m, c, d, v0) = (1.0, 1e4, 200.0, 1.0);
    // y = (x, ẋ, s): ẍ = −c s/m, ṡ = ẋ − (c/d) s.
    let a = Matrix3::new(0.0, 1.0, 0.0, 0.0, 0.0, -c / m, 0.0, 1.0, -c / d);
    let y0 = Vector3::new(0.0, v0, 0.0);
    let model = parse(MAXWELL);
    let (mut sys, q0, v0s) = numeric_system(&model, &[]);
    assert_eq!(sys.state_names(), ["maxwell.s"]);
    assert_eq!((q0.len(), v0s.clone()), (2, vec![v0, v0]));
    // Largest deviation of (x, s) from the closed form, and steps, at a tolerance.
    let mut run = |tol: f64| {
        let settings = ParkSettings {
            max_step: 1e-3,
            jacobian: JacobianKind::Analytic,
            ..ParkSettings::with_tolerances(tol, tol)
        };
        let mut worst: f64 = 0.0;
        let st = integrate_park(&mut sys, &settings, 0.0, &q0, &v0s, 0.2, |t, q, _, _| {
            let y = expm(&a, t) * y0;
            worst = worst.max((q[0] - y[0]).abs()).max((q[1] - y[2]).abs());
            ControlFlow::Continue(())
        })
        .unwrap_or_else(|e| panic!("{e}"));
        (worst, st.steps)
    };
    let (coarse, steps_coarse) = run(1e-7);
    let (fine, steps_fine) = run(1e-9);
    eprintln!(
        "maxwell: {coarse} m ({steps_coarse} steps) at 1e-7, {fine} m ({steps_fine} steps) at 1e-9"
    );
    // Amplitude v0/ω ≈ 0.01 m over ten periods. Park is second order: the
    // global error falls like the tolerance and the step count grows by
    // about 100^(1/3) ≈ 4.6 per factor 100 in tolerance (local error ~h³).
    assert!(
        fine < 1e-7,
        "error {fine} m at tolerance 1e-9 ({steps_fine} steps)"
    );
    assert!(
        fine < coarse / 10.0,
        "no convergence: {coarse} m at 1e-7 ({steps_coarse} steps), {fine} m at 1e-9 ({steps_fine} steps)"
    );
}

#[test]
fn maxwell_element_dissipates_its_damper_work() {
    // Energy balance: ½ m v0² = ½ m ẋ² + ½ c s² + ∫ F²/d dt, the damper
    // carrying the spring force F = c s at the rate ẋ − ṡ = F/d.
    let (m, c, d, v0) = (1.0, 1e4, 200.0, 1.0);
    let model = parse(MAXWELL);
    let (mut sys, q0, v0s) = numeric_system(&model, &[]);
    let settings = ParkSettings {
        max_step: 2e-4,
        jacobian: JacobianKind::Analytic,
        ..ParkSettings::with_tolerances(1e-9, 1e-10)
    };
    let mut dissipated = 0.0;
    let mut prev: Option<(f64, f64)> = None;
    let st = integrate_park(&mut sys, &settings, 0.0, &q0, &v0s, 0.1, |t, q, _, _| {
        let power = (c * q[1]).powi(2) / d;
        if let Some((t0, p0)) = prev {
            dissipated += 0.5 * (power + p0) * (t - t0);
        }
        prev = Some((t, power));
        ControlFlow::Continue(())
    })
    .unwrap_or_else(|e| panic!("{e}"));
    let end = 0.5 * m * st.v[0].powi(2) + 0.5 * c * st.q[1].powi(2);
    let start = 0.5 * m * v0 * v0;
    // Trapezoidal rule with h ≤ 2e-4 s on a power varying at ω ≈ 100 rad/s:
    // relative error ~ (ωh)²/12 ≈ 3e-5 of the dissipated energy.
    assert!(dissipated > 0.3 * start, "dissipated {dissipated} J");
    assert!(
        (end + dissipated - start).abs() < 1e-4 * start,
        "start {start} J, end {end} J, dissipated {dissipated} J"
    );
}

/// Two translating bodies joined by a series element on a skew line: the
/// assembled Jacobian (body block, state column, state row) against central
/// differences of `dynamics`.
const SKEW: &str = r#"
Model(
    name: "skew",
    gravity: (0, 0, 0),
    bodies: [
        Body(name: "a", mass: 1, inertia: (ixx: 1, iyy: 1, izz: 1),
             joint: Joint(parent: "ground", transforms: [
                Tx((coord: "ax", init: 0.01, vel: 0.3)), Ty((coord: "ay", init: 0.02, vel: 0.05)),
                Tz((coord: "az", init: -0.003, vel: -0.01))])),
        Body(name: "b", mass: 1, inertia: (ixx: 1, iyy: 1, izz: 1),
             joint: Joint(parent: "ground", transforms: [
                Tx((coord: "bx", vel: 0.02)), Ty((coord: "by", vel: -0.03)), Tz((coord: "bz", init: -0.5, vel: 0.01))])),
    ],
    forces: [
        SeriesSpring(name: "s", body1: "a", point1: (0, 0.1, 0), body2: "b", point2: (0.3, 0, 0),
                     c: 2e4, d: 300, f0: 50),
    ],
)
"#;

#[test]
fn series_element_jacobian_equals_central_differences() {
    let model = parse(SKEW);
    let (mut sys, mut q, mut v) = numeric_system(&model, &[]);
    let n = q.len();
    assert_eq!(n, 7);
    // A loaded spring and a state rate off its equilibrium value.
    q[6] = 0.004;
    v[6] = -0.2;
    let (dq, dv) = analytic_jacobians(&mut sys, &q, &v);
    let mut mass = DMatrix::zeros(n, n);
    let mut f = DVector::zeros(n);
    sys.dynamics(0.0, &q, &v, &mut mass, &mut f).unwrap();
    // No inertia on the state row.
    assert!((0..n).all(|j| mass[(6, j)] == 0.0 && mass[(j, 6)] == 0.0));
    let fq = central_difference(&mut sys, &q, &v, false, 1e-6);
    let fv = central_difference(&mut sys, &q, &v, true, 1e-6);
    // Translating bodies: Γ is constant and the element's local Jacobian is
    // exact, so only difference rounding (ε|f|/h ≈ 1e-7 relative) remains.
    let rel = |a: &DMatrix<f64>, b: &DMatrix<f64>| (a - b).amax() / b.amax();
    assert!(rel(&dq, &fq) < 1e-6, "∂f/∂q\n{dq}\nvs\n{fq}");
    assert!(rel(&dv, &fv) < 1e-6, "∂f/∂q̇\n{dv}\nvs\n{fv}");
}

/// Runs the Maxwell model through a scenario (in a temporary directory) with
/// the given integrator; returns the output or the error text.
fn run_scenario_with(integrator: &str) -> Result<Table, String> {
    let scenario = format!(
        "Scenario(model: \"maxwell.ron\", end_time: 0.05, integrator: {integrator},
                  output: (interval: 0.01, velocities: true, forces: [\"maxwell\"]))"
    );
    run_scenario_files(&[("maxwell.ron", MAXWELL)], &scenario)
}

#[test]
fn scenario_writes_the_state_and_refuses_explicit_integration() {
    let table = run_scenario_with("Park(rtol: 1e-8, atol: 1e-9, max_step: 0.001)")
        .unwrap_or_else(|e| panic!("{e}"));
    let rows = &table.rows;
    assert_eq!(
        table.header,
        [
            "time",
            "x",
            "maxwell.s",
            "x.v",
            "maxwell.s.v",
            "maxwell.F[N]",
            "maxwell.x[m]",
            "maxwell.v[m/s]",
            "maxwell.s[m]",
            "maxwell.E[J]",
            "maxwell.P[W]"
        ]
    );
    assert_eq!(rows.len(), 6);
    for r in rows {
        // The output force is c·s of the state column.
        assert!(
            (r[5] - 1e4 * r[2]).abs() <= 1e-9 * r[5].abs().max(1.0),
            "{r:?}"
        );
        assert_eq!(r[2], r[8]);
    }
    let Err(message) = run_scenario_with("Rk4(step: 1e-4)") else {
        panic!("Rk4 should be refused for a model with element states");
    };
    assert!(
        message.contains("maxwell.s") && message.contains("Park"),
        "{message}"
    );
}

/// Only declared element states may have zero mass-matrix rows: a body
/// without mass is still a singular mass matrix, not a quasi-static
/// coordinate.
#[test]
fn a_massless_body_is_refused_not_taken_for_a_state() {
    let text = MAXWELL.replace(
        r#"SeriesSpring(name: "maxwell", body1: "ground", point1: (-1, 0, 0), body2: "mass",
                     c: "c", d: "d"),"#,
        r#"Spring(name: "k", body1: "ground", point1: (-1, 0, 0), body2: "mass", c: "c", d: "d", x0: 1),"#,
    );
    let model = parse(&text);
    // The model's default mass is checked when it is loaded; a scenario
    // override is not.
    let (mut sys, q0, v0) = numeric_system(&model, &[("m", "0")]);
    assert!(sys.state_names().is_empty());
    let settings = ParkSettings::with_tolerances(1e-8, 1e-9);
    let e = integrate_park(&mut sys, &settings, 0.0, &q0, &v0, 0.1, |_, _, _, _| {
        ControlFlow::Continue(())
    })
    .unwrap_err()
    .to_string();
    assert!(e.contains("singular"), "{e}");
}
