//! Hertz contact against published numbers (reference data README, "Numbers worth knowing").

use railmbs_wheelrail::hertz::{HertzShape, wheel_rail_curvatures};

/// Worked example: wheel radius 0.46 m on a rail crown radius 0.3 m (cylindrical
/// tread), Fn = 100 kN, E = 210 GPa, ν = 0.3 → a = 7.162 mm, b = 5.387 mm,
/// approach 0.1041 mm, p_max ≈ 1237 MPa. The reference is given to 4 significant
/// digits, so the tolerance is 1e-3 relative (half a unit of the last digit is
/// ≤ 0.7e-4 for a, b, δ; p_max is "≈", given to 4 digits: 1e-3).
#[test]
fn worked_example_wheel_on_rail() {
    let (ca, cb) = wheel_rail_curvatures(0.46, 0.0, 1.0 / 0.3);
    let shape = HertzShape::new(ca, cb, 210e9, 0.3).unwrap();
    let c = shape.contact(100e3).unwrap();
    let rel = |x: f64, r: f64| (x / r - 1.0).abs();
    assert!(rel(c.a, 7.162e-3) < 2e-4, "a = {}", c.a);
    assert!(rel(c.b, 5.387e-3) < 2e-4, "b = {}", c.b);
    assert!(
        rel(c.approach, 0.1041e-3) < 5e-4,
        "approach = {}",
        c.approach
    );
    assert!(rel(c.p_max, 1237e6) < 1e-3, "p_max = {}", c.p_max);
    // Inverse: the force from the approach.
    let n = shape.normal_force(c.approach).unwrap();
    assert!(rel(n, 100e3) < 1e-12);
    assert_eq!(shape.normal_force(-1e-6).unwrap(), 0.0);
    // Stiffness dN/dδ = 1.5 N/δ (N ∝ δ^1.5).
    assert!(rel(shape.stiffness(c.approach), 1.5 * 100e3 / c.approach) < 1e-12);
}

/// Classic Hertz coefficients m, n against θ (cos θ = |B − A|/(A + B)), from the
/// reference README: 30° 2.7306/0.4931, 50° 1.7541/0.6407, 70° 1.2851/0.7999,
/// 90° 1/1. Tabulated to 4–5 digits: tolerance 2e-4 relative.
#[test]
fn hertz_m_n_coefficients() {
    for (theta, m_ref, n_ref) in [
        (30.0_f64, 2.7306, 0.4931),
        (50.0, 1.7541, 0.6407),
        (70.0, 1.2851, 0.7999),
        (90.0, 1.0, 1.0),
    ] {
        let c = theta.to_radians().cos();
        // A = 1, B = (1 + c)/(1 − c) gives (B − A)/(A + B) = c; also swapped.
        for (ca, cb) in [(1.0, (1.0 + c) / (1.0 - c)), ((1.0 + c) / (1.0 - c), 1.0)] {
            let shape = HertzShape::with_modulus(ca, cb, 1.15e11).unwrap();
            let (m, n) = shape.m_n();
            assert!((m / m_ref - 1.0).abs() < 2e-4, "θ = {theta}: m = {m}");
            assert!((n / n_ref - 1.0).abs() < 2e-4, "θ = {theta}: n = {n}");
        }
    }
}

/// Circle and extreme ratios: no NaN, monotone and continuous through A = B,
/// and the axis ratio follows the large-ratio asymptote b/a → 0.
#[test]
fn robust_near_circle_and_extreme_ratios() {
    let mut last = 0.0;
    for k in -6..=6 {
        let eps = f64::from(k) * 1e-9;
        let s = HertzShape::with_modulus(1.0, 1.0 + eps, 1e11).unwrap();
        let c = s.contact(1e4).unwrap();
        assert!(c.a.is_finite() && c.b.is_finite() && c.approach.is_finite());
        if k > -6 {
            assert!((c.a / last - 1.0).abs() < 1e-8);
        }
        last = c.a;
    }
    for ratio in [1e-6, 1e-3, 1e3, 1e6] {
        let s = HertzShape::with_modulus(1.0, ratio, 1e11).unwrap();
        let c = s.contact(1e4).unwrap();
        assert!(
            c.a > 0.0 && c.b > 0.0 && c.p_max.is_finite(),
            "{ratio}: {c:?}"
        );
        // Longer axis along the smaller curvature.
        assert_eq!(c.a > c.b, ratio > 1.0);
    }
    assert!(HertzShape::with_modulus(0.0, 1.0, 1e11).is_err());
    assert!(HertzShape::with_modulus(1.0, -1.0, 1e11).is_err());
    assert!(HertzShape::new(1.0, 1.0, 210e9, 0.7).is_err());
    assert!(
        HertzShape::new(1.0, 1.0, 210e9, 0.3)
            .unwrap()
            .contact(f64::NAN)
            .is_err()
    );
}
