//! Kalker's creepage coefficients `C11, C22, C23, C33` of the linear theory of
//! rolling contact, by table interpolation.
//!
//! Source: J.J. Kalker, *Three-dimensional elastic bodies in rolling contact*,
//! Kluwer 1990, Table E.3 (`C11, C22, C23`), as tabulated in CONTACT's
//! `m_hertz.f90` (E.A.H. Vollebregt, Apache-2.0); `C33` as commonly reproduced
//! from Kalker 1967/1990 (see `../shared/reference/kalker/kalker_creep_coefficients.csv`
//! for provenance and its caveat). Only the numbers are used here.
//!
//! Linear theory (forces on the wheel, CONTACT's convention, `c = √(ab)`):
//!
//! ```text
//! Fx = −G c² C11 ξ
//! Fy = −G c² C22 η − G c³ C23 φ
//! Mz =  G c³ C23 η − G c⁴ C33 φ
//! ```
//!
//! Interpolation: piecewise linear in the table's own abscissa (`a/b` from 0.1 to
//! 1 in steps of 0.1, then `b/a` from 0.9 down to 0.1) and piecewise linear in
//! `ν` between 0, 0.25 and 0.5. Outside `0.1 ≤ a/b ≤ 10` the end rows are used
//! (clamped); `ν` must lie in `[0, 0.5]`.

/// Kalker's coefficients for one ellipse shape and Poisson ratio (dimensionless).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct KalkerCoefficients {
    /// Longitudinal creepage coefficient.
    pub c11: f64,
    /// Lateral creepage coefficient.
    pub c22: f64,
    /// Lateral–spin coupling coefficient (`C32 = −C23`).
    pub c23: f64,
    /// Spin coefficient.
    pub c33: f64,
}

/// Table rows: columns C11(ν=0, 0.25, 0.5), C22(…), C23(…), C33(…). Rows 0–9:
/// a/b = 0.1 … 1.0; rows 10–18: b/a = 0.9 … 0.1. Kalker 1990, Table E.3.
#[rustfmt::skip]
#[allow(clippy::approx_constant)] // 3.14 is a table value, not π
const TABLE: [[f64; 12]; 19] = [
    [2.51, 3.31, 4.85, 2.51, 2.52, 2.53, 0.334, 0.473, 0.731, 6.42, 8.28, 11.7], // a/b = 0.1
    [2.59, 3.37, 4.81, 2.59, 2.63, 2.66, 0.483, 0.603, 0.809, 3.46, 4.27, 5.66], // a/b = 0.2
    [2.68, 3.44, 4.8, 2.68, 2.75, 2.81, 0.607, 0.715, 0.889, 2.49, 2.96, 3.72], // a/b = 0.3
    [2.78, 3.53, 4.82, 2.78, 2.88, 2.98, 0.72, 0.823, 0.977, 2.02, 2.32, 2.77], // a/b = 0.4
    [2.88, 3.62, 4.83, 2.88, 3.01, 3.14, 0.827, 0.929, 1.07, 1.74, 1.93, 2.22], // a/b = 0.5
    [2.98, 3.72, 4.91, 2.98, 3.14, 3.31, 0.93, 1.03, 1.18, 1.56, 1.68, 1.86], // a/b = 0.6
    [3.09, 3.81, 4.97, 3.09, 3.28, 3.48, 1.03, 1.14, 1.29, 1.43, 1.5, 1.6], // a/b = 0.7
    [3.19, 3.91, 5.05, 3.19, 3.41, 3.65, 1.13, 1.25, 1.4, 1.34, 1.37, 1.42], // a/b = 0.8
    [3.29, 4.01, 5.12, 3.29, 3.54, 3.82, 1.23, 1.36, 1.51, 1.27, 1.27, 1.27], // a/b = 0.9
    [3.4, 4.12, 5.2, 3.4, 3.67, 3.98, 1.33, 1.47, 1.63, 1.21, 1.19, 1.16], // a/b = 1.0
    [3.51, 4.22, 5.3, 3.51, 3.81, 4.16, 1.44, 1.59, 1.77, 1.16, 1.11, 1.06], // b/a = 0.9
    [3.65, 4.36, 5.42, 3.65, 3.99, 4.39, 1.58, 1.75, 1.94, 1.1, 1.04, 0.954], // b/a = 0.8
    [3.82, 4.54, 5.58, 3.82, 4.21, 4.67, 1.76, 1.95, 2.18, 1.05, 0.965, 0.852], // b/a = 0.7
    [4.06, 4.78, 5.8, 4.06, 4.5, 5.04, 2.01, 2.23, 2.5, 1.01, 0.892, 0.751], // b/a = 0.6
    [4.37, 5.1, 6.11, 4.37, 4.9, 5.56, 2.35, 2.62, 2.96, 0.958, 0.819, 0.65], // b/a = 0.5
    [4.84, 5.57, 6.57, 4.84, 5.48, 6.31, 2.88, 3.24, 3.7, 0.912, 0.747, 0.549], // b/a = 0.4
    [5.57, 6.34, 7.34, 5.57, 6.4, 7.51, 3.79, 4.32, 5.01, 0.868, 0.674, 0.446], // b/a = 0.3
    [6.96, 7.78, 8.82, 6.96, 8.14, 9.79, 5.72, 6.63, 7.89, 0.828, 0.601, 0.341], // b/a = 0.2
    [10.7, 11.7, 12.9, 10.7, 12.8, 16.0, 12.2, 14.6, 18.0, 0.795, 0.526, 0.228], // b/a = 0.1
];

impl KalkerCoefficients {
    /// Coefficients for semi-axes ratio `a_over_b` (`a` in the rolling direction)
    /// and Poisson ratio `nu` in `[0, 0.5]`. Returns `None` for a non-positive or
    /// non-finite ratio or `nu` outside `[0, 0.5]`.
    #[inline]
    pub fn interpolate(a_over_b: f64, nu: f64) -> Option<Self> {
        if !(a_over_b.is_finite() && a_over_b > 0.0) {
            return None;
        }
        Self::interpolate_ab(a_over_b, 1.0, nu)
    }

    /// The slopes of a saturating creep law for an approximate Jacobian:
    /// Kalker's linear creep coefficients f11 = G a b C11 and f22 = G a b C22
    /// (N), both scaled by the saturation ratio |F| / |F_linear| (≤ 1) of the
    /// actual longitudinal and lateral forces `fx`, `fy` (N) at the creepages
    /// `xi`, `eta`. `None` where [`KalkerCoefficients::interpolate_ab`] is.
    #[allow(clippy::too_many_arguments)]
    pub fn saturated_slopes(
        a: f64,
        b: f64,
        shear_modulus: f64,
        nu: f64,
        xi: f64,
        eta: f64,
        fx: f64,
        fy: f64,
    ) -> Option<(f64, f64)> {
        let k = Self::interpolate_ab(a, b, nu)?;
        let gab = shear_modulus * a * b;
        let (f11, f22) = (gab * k.c11, gab * k.c22);
        let linear = (f11 * xi).hypot(f22 * eta);
        let ratio = if linear > 0.0 {
            (fx.hypot(fy) / linear).min(1.0)
        } else {
            1.0
        };
        Some((f11 * ratio, f22 * ratio))
    }

    /// As [`KalkerCoefficients::interpolate`] from the semi-axes `a`
    /// (rolling direction) and `b` (positive, finite; one division).
    #[inline]
    pub fn interpolate_ab(a: f64, b: f64, nu: f64) -> Option<Self> {
        if !(a.is_finite() && b.is_finite() && a > 0.0 && b > 0.0 && (0.0..=0.5).contains(&nu)) {
            return None;
        }
        // Continuous table abscissa s in [0, 18].
        let s = if a <= b {
            10.0 * a / b - 1.0
        } else {
            19.0 - 10.0 * b / a
        };
        let s = s.clamp(0.0, 18.0);
        let i = (s as usize).min(17);
        let ts = s - i as f64;
        // ν between 0, 0.25, 0.5.
        let (j, tn) = if nu <= 0.25 {
            (0, nu * 4.0)
        } else {
            (1, (nu - 0.25) * 4.0)
        };
        let r0 = &TABLE[i];
        let r1 = &TABLE[i + 1];
        let v = |col: usize| {
            let a0 = r0[col + j] + tn * (r0[col + j + 1] - r0[col + j]);
            let a1 = r1[col + j] + tn * (r1[col + j + 1] - r1[col + j]);
            a0 + ts * (a1 - a0)
        };
        Some(Self {
            c11: v(0),
            c22: v(3),
            c23: v(6),
            c33: v(9),
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn table_nodes_are_reproduced() {
        let c = KalkerCoefficients::interpolate(1.0, 0.25).unwrap();
        assert!((c.c11 - 4.12).abs() < 1e-12 && (c.c22 - 3.67).abs() < 1e-12);
        assert!((c.c23 - 1.47).abs() < 1e-12 && (c.c33 - 1.19).abs() < 1e-12);
        let c = KalkerCoefficients::interpolate(2.0, 0.5).unwrap();
        assert!((c.c11 - 6.11).abs() < 1e-12 && (c.c33 - 0.65).abs() < 1e-12);
        let c = KalkerCoefficients::interpolate(0.1, 0.0).unwrap();
        assert!((c.c11 - 2.51).abs() < 1e-12);
        let c = KalkerCoefficients::interpolate(10.0, 0.0).unwrap();
        assert!((c.c23 - 12.2).abs() < 1e-12);
        assert!(KalkerCoefficients::interpolate(-1.0, 0.3).is_none());
        assert!(KalkerCoefficients::interpolate(1.0, 0.6).is_none());
    }

    /// Below saturation (forces equal to the linear theory's) the slopes are
    /// Kalker's G a b C11, G a b C22; forces at half the linear magnitude halve
    /// both; a law never reports slopes above the linear ones.
    #[test]
    fn saturated_slopes_scale_with_the_saturation() {
        let (a, b, g, nu) = (0.006, 0.004, 8.1e10, 0.28);
        let k = KalkerCoefficients::interpolate_ab(a, b, nu).unwrap();
        let (f11, f22) = (g * a * b * k.c11, g * a * b * k.c22);
        let (xi, eta) = (1e-4, -2e-4);
        let lin = (-f11 * xi, -f22 * eta);
        let (s11, s22) =
            KalkerCoefficients::saturated_slopes(a, b, g, nu, xi, eta, lin.0, lin.1).unwrap();
        assert!((s11 - f11).abs() < 1e-9 * f11 && (s22 - f22).abs() < 1e-9 * f22);
        let (h11, h22) =
            KalkerCoefficients::saturated_slopes(a, b, g, nu, xi, eta, 0.5 * lin.0, 0.5 * lin.1)
                .unwrap();
        assert!((h11 - 0.5 * f11).abs() < 1e-9 * f11 && (h22 - 0.5 * f22).abs() < 1e-9 * f22);
        let (m11, _) =
            KalkerCoefficients::saturated_slopes(a, b, g, nu, xi, eta, 3.0 * lin.0, 3.0 * lin.1)
                .unwrap();
        assert!((m11 - f11).abs() < 1e-9 * f11);
        assert!(KalkerCoefficients::saturated_slopes(a, b, g, 0.7, xi, eta, 0.0, 0.0).is_none());
    }
}
