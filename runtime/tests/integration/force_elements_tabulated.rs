//! Tabulated characteristics with monotone cubic interpolation
//! (`interpolation: Spline`, Fritsch & Carlson 1980): through every row, a
//! continuous slope, no overshoot in a bump stop's clearance, quadratics
//! reproduced exactly inside the table (the three-point slope is exact for
//! them), and the element's Jacobian against central differences.

use railmbs_runtime::ModelSystem;
use railmbs_testkit::*;

/// One translating body on a tabulated element along x (x0 = 0.5: the
/// deflection is the coordinate).
fn model(table: &str, interpolation: &str) -> String {
    format!(
        r#"
Model(
    name: "tab",
    gravity: (0, 0, 0),
    bodies: [
        Body(name: "b", mass: 1, inertia: (ixx: 1, iyy: 1, izz: 1),
             joint: Joint(parent: "ground", transforms: [
                Tx((coord: "u", init: 0.5, vel: 0.1)), Ty((coord: "v", init: 0.05))])),
    ],
    forces: [
        Tabulated(name: "tab", body1: "ground", body2: "b", table: {table},
                  interpolation: {interpolation}, d: 20, x0: 0.5),
    ],
)
"#
    )
}

/// The system of a model text (see [`model`]) and its initial state.
fn system_of(text: &str) -> (ModelSystem, Vec<f64>, Vec<f64>) {
    numeric_system(&parse(text), &[])
}

/// The element's characteristic f(u) (N) at deflection u, read from its
/// output at rest (no damping force) on the x axis.
fn characteristic(sys: &mut ModelSystem, u: f64) -> f64 {
    let (q, v) = ([0.5 + u, 0.0], [0.0, 0.0]);
    sys.evaluate(0.0, &q, &v, railmbs_runtime::Parts::KINEMATICS)
        .unwrap();
    let mut out = Vec::new();
    sys.force_outputs(0.0, &mut out);
    out[0]
}

#[test]
fn spline_reproduces_a_quadratic_inside_the_table() {
    // f = 1e4·u² on rows u = 0, 0.01, …, 0.05: interior segments exact.
    let rows: Vec<String> = (0..6)
        .map(|k| {
            let u = 0.01 * k as f64;
            format!("({u}, {})", 1e4 * u * u)
        })
        .collect();
    let (mut sys, ..) = system_of(&model(&format!("[{}]", rows.join(", ")), "Spline"));
    for k in 0..=40 {
        let u = 0.01 + 0.03 * k as f64 / 40.0;
        let f = characteristic(&mut sys, u);
        assert!(
            (f - 1e4 * u * u).abs() < 1e-9,
            "f({u}) = {f}, exact {}",
            1e4 * u * u
        );
    }
}

/// A bump stop: clearance ±10 mm, then a progressive stop (m, N), as table
/// text and as rows.
const STOP_TABLE: &str =
    "[(-0.03, -6e4), (-0.02, -1.5e4), (-0.01, 0), (0.01, 0), (0.02, 1.5e4), (0.03, 6e4)]";
const STOP_ROWS: [(f64, f64); 6] = [
    (-0.03, -6e4),
    (-0.02, -1.5e4),
    (-0.01, 0.0),
    (0.01, 0.0),
    (0.02, 1.5e4),
    (0.03, 6e4),
];

#[test]
fn spline_bump_stop_passes_the_rows_without_overshoot() {
    // Clearance ±10 mm, then a progressive stop.
    let table = STOP_TABLE;
    let rows = STOP_ROWS;
    let (mut sys, ..) = system_of(&model(table, "Spline"));
    for (u, f) in rows {
        assert!((characteristic(&mut sys, u) - f).abs() < 1e-9, "row {u}");
    }
    // Monotone non-decreasing everywhere, exactly zero in the clearance.
    let mut prev = f64::NEG_INFINITY;
    for k in 0..=800 {
        let u = -0.04 + 0.08 * k as f64 / 800.0;
        let f = characteristic(&mut sys, u);
        assert!(f >= prev - 1e-9, "not monotone at u = {u}: {prev} then {f}");
        if u.abs() <= 0.01 {
            assert_eq!(f, 0.0, "overshoot in the clearance at u = {u}");
        }
        prev = f;
    }
    // Continuous slope at an interior row (left and right difference
    // quotients agree to O(h)); the linear table has a kink there.
    let slope_jump = |sys: &mut ModelSystem| {
        let (u, h) = (0.02, 1e-7);
        let left = (characteristic(sys, u) - characteristic(sys, u - h)) / h;
        let right = (characteristic(sys, u + h) - characteristic(sys, u)) / h;
        (right - left).abs()
    };
    assert!(
        slope_jump(&mut sys) < 1e-2 * 4.5e6,
        "{}",
        slope_jump(&mut sys)
    );
    let (mut linear, ..) = system_of(&model(table, "Linear"));
    assert!(slope_jump(&mut linear) > 1e6);
}

#[test]
fn spline_element_jacobian_equals_central_differences() {
    let (mut sys, mut q, v) = system_of(&model(STOP_TABLE, "Spline"));
    q[0] = 0.5 + 0.0237; // inside a cubic segment
    let (dq, _) = analytic_jacobians(&mut sys, &q, &v);
    let fq = central_difference(&mut sys, &q, &v, false, 1e-7);
    // Forces ~3e4 N, h = 1e-7 m: rounding ε·3e4/h ≈ 7e-5 N/m, truncation
    // f'''h²/6 ≈ negligible: 1e-7 of the largest entry (~4e6 N/m).
    assert!(
        (&fq - &dq).amax() < 1e-7 * dq.amax(),
        "∂f/∂q\n{dq}\nvs central differences\n{fq}"
    );
}

/// The characteristic's energy ∫₀ᵘ f is exact: for a straight-line table the
/// areas of its trapezoids (and of the linear extensions), for the cubic the
/// integral of the reproduced quadratic inside the table.
#[test]
fn characteristic_energy_is_the_integral_of_the_force() {
    use railmbs_models::Interpolation;
    use railmbs_runtime::forces::Characteristic;
    let c = Characteristic::new(&STOP_ROWS, Interpolation::Linear).unwrap();
    // Clearance: no energy; then the triangle and trapezoid areas.
    assert_eq!(c.energy(0.005), 0.0);
    let e = |u: f64| c.energy(u);
    assert!((e(0.02) - 0.5 * 1.5e4 * 0.01).abs() < 1e-9);
    assert!((e(0.03) - (75.0 + 0.5 * (1.5e4 + 6e4) * 0.01)).abs() < 1e-9);
    // Beyond the table the end slope 4.5e6 N/m continues: f(0.04) = 1.05e5.
    assert!((e(0.04) - (e(0.03) + 0.5 * (6e4 + 1.05e5) * 0.01)).abs() < 1e-9);
    assert!((e(-0.02) - 0.5 * 1.5e4 * 0.01).abs() < 1e-9);
    // Quadratic rows f = 1e4 u² (u = 0 … 0.05): interior segments are exact,
    // so ∫ from 0.01 to 0.04 = 1e4 (0.04³ − 0.01³)/3.
    let rows: Vec<(f64, f64)> = (0..6)
        .map(|k| {
            let u = 0.01 * k as f64;
            (u, 1e4 * u * u)
        })
        .collect();
    let q = Characteristic::new(&rows, Interpolation::Spline).unwrap();
    let exact = 1e4 * (0.04f64.powi(3) - 0.01f64.powi(3)) / 3.0;
    assert!(
        (q.energy(0.04) - q.energy(0.01) - exact).abs() < 1e-12,
        "{}",
        q.energy(0.04) - q.energy(0.01)
    );
    // And the derivative of the energy is the force, at a point inside a segment.
    let (u, h) = (0.0237, 1e-7);
    let slope = (q.energy(u + h) - q.energy(u - h)) / (2.0 * h);
    assert!((slope - q.eval(u).0).abs() < 1e-6 * q.eval(u).0);
}
