//! Equivalent conicity by EN 15302 (Annex B: integration of the nonlinear differential
//! equation of the wheelset's kinematic oscillation).
//!
//! A wheelset rolling without slip on straight track, with rolling radius difference
//! `Δr(y) = r_left − r_right` (y to the left), obeys Klingel's kinematic equations
//! `dy/dx = ψ`, `dψ/dx = −Δr(y)/(2 e0 r0)`, i.e. `y'' = −Δr(y)/(2 e0 r0)` with `x` the
//! distance travelled, `e0` half the lateral distance between the contact points and `r0` the
//! nominal rolling radius. Its first integral is
//! `ψ² = (2/(2 e0 r0))·S(y)`, `S(y) = −∫_{y₁}^{y} Δr(η) dη`, between turning points `y₁ < y₂`
//! with `S(y₂) = 0` (the Annex B steps: the integral of `Δr`, the yaw angle from it, the
//! longitudinal abscissa `x = ∫ dy/ψ`). For an amplitude `ŷ` the turning points satisfy
//! `y₂ − y₁ = 2ŷ`; the wavelength is `λ = 2 ∫_{y₁}^{y₂} dy/ψ` and the equivalent conicity the
//! cone angle with the same wavelength by Klingel's formula `λ = 2π √(e0 r0 / tan γe)`:
//! `tan γe = (2π)² e0 r0 / λ²`. A cone (`Δr = 2γy`) gives `tan γe = γ` exactly.
//!
//! Numerically `Δr` is interpolated linearly between its samples, so `S` is integrated exactly;
//! the turning-point singularity `1/√S` is removed by the substitution
//! `y = c − ŷ cos θ` and the `θ`-integral taken by the midpoint rule.

use crate::geometry::{ContactGeometry, GeometryError};

/// Errors of the conicity evaluation.
#[derive(Debug, thiserror::Error)]
pub enum ConicityError {
    /// Invalid input.
    #[error("invalid {what}: {message}")]
    Invalid {
        /// Which input.
        what: &'static str,
        /// What is wrong.
        message: String,
    },
    /// The amplitude does not fit the Δr function's lateral range.
    #[error(
        "amplitude {amplitude} m needs Δr over a range of {needed} m, the function covers [{min}, {max}] m"
    )]
    OutOfRange {
        /// Requested amplitude (m).
        amplitude: f64,
        /// Lateral range needed (m).
        needed: f64,
        /// Lower end of the Δr function (m).
        min: f64,
        /// Upper end (m).
        max: f64,
    },
    /// No kinematic oscillation with this amplitude (Δr does not restore the wheelset).
    #[error("no kinematic oscillation of amplitude {amplitude} m: Δr is not restoring over it")]
    NoOscillation {
        /// Amplitude (m).
        amplitude: f64,
    },
    /// Contact geometry failed.
    #[error(transparent)]
    Geometry(#[from] GeometryError),
}

/// Rolling radius difference function `Δr(y)` on increasing lateral shifts.
#[derive(Debug, Clone)]
pub struct RollingRadiusDifference {
    y: Vec<f64>,
    dr: Vec<f64>,
    /// Cumulative integral `∫_{y_0}^{y_i} Δr` at the samples.
    cum: Vec<f64>,
}

impl RollingRadiusDifference {
    /// From samples `y` (m, strictly increasing) and `Δr = r_left − r_right` (m).
    pub fn new(y: Vec<f64>, dr: Vec<f64>) -> Result<Self, ConicityError> {
        if y.len() != dr.len() || y.len() < 2 {
            return Err(ConicityError::Invalid {
                what: "Δr function",
                message: format!(
                    "needs at least two samples and equal lengths, got {} y and {} Δr",
                    y.len(),
                    dr.len()
                ),
            });
        }
        if let Some(i) = (0..y.len()).find(|&i| !y[i].is_finite() || !dr[i].is_finite()) {
            return Err(ConicityError::Invalid {
                what: "Δr function",
                message: format!("sample {i} is not finite (y = {}, Δr = {})", y[i], dr[i]),
            });
        }
        if let Some(i) = (1..y.len()).find(|&i| y[i] <= y[i - 1]) {
            return Err(ConicityError::Invalid {
                what: "Δr function",
                message: format!(
                    "lateral shifts not increasing at sample {i} ({} after {})",
                    y[i],
                    y[i - 1]
                ),
            });
        }
        let mut cum = vec![0.0; y.len()];
        for i in 1..y.len() {
            cum[i] = cum[i - 1] + 0.5 * (dr[i] + dr[i - 1]) * (y[i] - y[i - 1]);
        }
        Ok(RollingRadiusDifference { y, dr, cum })
    }

    /// Δr of a wheelset from a contact geometry at shifts `−y_max..=y_max` step `dy` (m), with
    /// the roll treated as `roll` says.
    pub fn from_geometry(
        geo: &ContactGeometry,
        y_max: f64,
        dy: f64,
        roll: RollTreatment,
    ) -> Result<Self, ConicityError> {
        if !(y_max.is_finite() && y_max > 0.0 && dy.is_finite() && dy > 0.0) {
            return Err(ConicityError::Invalid {
                what: "Δr sampling",
                message: format!("range {y_max} and step {dy} must be finite and positive"),
            });
        }
        let n = (y_max / dy).round() as i64;
        let ys_pos: Vec<f64> = (0..=n).map(|k| k as f64 * dy).collect();
        let ys_neg: Vec<f64> = (0..=n).map(|k| -(k as f64) * dy).collect();
        let sample = |ys: &[f64]| -> Result<Vec<f64>, ConicityError> {
            match roll {
                RollTreatment::Neglected => ys
                    .iter()
                    .map(|&y| {
                        let c = geo.contacts(y, 0.0)?;
                        Ok(c[0].deepest().rolling_radius - c[1].deepest().rolling_radius)
                    })
                    .collect(),
                RollTreatment::Rigid => Ok(geo
                    .rigid_functions(ys)?
                    .iter()
                    .map(|r| r.rolling_radius_difference())
                    .collect()),
            }
        };
        let pos = sample(&ys_pos)?;
        let neg = sample(&ys_neg)?;
        let mut y = Vec::with_capacity(2 * n as usize + 1);
        let mut dr = Vec::with_capacity(2 * n as usize + 1);
        for (yy, d) in ys_neg.iter().zip(&neg).rev() {
            y.push(*yy);
            dr.push(*d);
        }
        for (yy, d) in ys_pos.iter().zip(&pos).skip(1) {
            y.push(*yy);
            dr.push(*d);
        }
        RollingRadiusDifference::new(y, dr)
    }

    /// Lateral shifts (m).
    pub fn y(&self) -> &[f64] {
        &self.y
    }

    /// Rolling radius differences (m).
    pub fn delta_r(&self) -> &[f64] {
        &self.dr
    }

    /// Linear interpolation of Δr at `y` (inside the range).
    pub fn value(&self, y: f64) -> f64 {
        let n = self.y.len();
        let i = self.y.partition_point(|&v| v <= y).clamp(1, n - 1);
        let t = (y - self.y[i - 1]) / (self.y[i] - self.y[i - 1]);
        self.dr[i - 1] + t * (self.dr[i] - self.dr[i - 1])
    }

    /// `∫_{y_0}^{y} Δr` (exact for the linear interpolation).
    fn integral(&self, y: f64) -> f64 {
        let n = self.y.len();
        let i = self.y.partition_point(|&v| v <= y).clamp(1, n - 1);
        let y0 = self.y[i - 1];
        let d0 = self.dr[i - 1];
        let d = y - y0;
        let dv = self.value(y);
        self.cum[i - 1] + 0.5 * (d0 + dv) * d
    }

    /// Equivalent conicity `tan γe` for amplitude `amplitude` (m), nominal rolling radius `r0`
    /// (m) and half contact distance `e0` (m), by the EN 15302 Annex B integration.
    pub fn equivalent_conicity(
        &self,
        amplitude: f64,
        r0: f64,
        e0: f64,
    ) -> Result<f64, ConicityError> {
        for (what, v) in [("amplitude", amplitude), ("r0", r0), ("e0", e0)] {
            if !(v.is_finite() && v > 0.0) {
                return Err(ConicityError::Invalid {
                    what,
                    message: format!("must be finite and positive, got {v}"),
                });
            }
        }
        let (ymin, ymax) = (self.y[0], self.y[self.y.len() - 1]);
        let span = 2.0 * amplitude;
        if span > ymax - ymin {
            return Err(ConicityError::OutOfRange {
                amplitude,
                needed: span,
                min: ymin,
                max: ymax,
            });
        }
        // G(a) = ∫_a^{a+2ŷ} Δr, non-decreasing for a non-decreasing Δr; find its zero set and
        // take its middle (a plateau arises where Δr = 0 over more than 2ŷ).
        let g = |a: f64| self.integral(a + span) - self.integral(a);
        let scale = span
            * self
                .dr
                .iter()
                .fold(0.0_f64, |m, v| m.max(v.abs()))
                .max(1e-12);
        let eps = 1e-12 * scale;
        let (lo, hi) = (ymin, ymax - span);
        if g(lo) > eps || g(hi) < -eps {
            return Err(ConicityError::OutOfRange {
                amplitude,
                needed: span,
                min: ymin,
                max: ymax,
            });
        }
        let bisect = |pred: &dyn Fn(f64) -> bool| {
            // smallest a in [lo, hi] with pred(a) true (pred monotone false → true)
            let (mut a, mut b) = (lo, hi);
            if pred(a) {
                return a;
            }
            for _ in 0..200 {
                let m = 0.5 * (a + b);
                if pred(m) {
                    b = m;
                } else {
                    a = m;
                }
                if b - a < 1e-15 {
                    break;
                }
            }
            0.5 * (a + b)
        };
        let a1 = bisect(&|a| g(a) >= -eps);
        let a2 = bisect(&|a| g(a) > eps);
        let y1 = 0.5 * (a1 + a2);
        let c = y1 + amplitude;
        let i1 = self.integral(y1);
        // S(y) = −∫_{y1}^{y} Δr ≥ 0 between the turning points.
        let n = 4000;
        let mut sum = 0.0;
        for k in 0..n {
            let theta = (k as f64 + 0.5) * std::f64::consts::PI / n as f64;
            let (st, ct) = theta.sin_cos();
            let y = c - amplitude * ct;
            let s = -(self.integral(y) - i1);
            if s < -1e-9 * scale {
                return Err(ConicityError::NoOscillation { amplitude });
            }
            if s <= 1e-14 * scale {
                // Δr vanishes over the oscillation: no restoring effect, infinite wavelength.
                return Ok(0.0);
            }
            sum += amplitude * st / s.sqrt();
        }
        let integral = sum * std::f64::consts::PI / n as f64; // ∫ dy/√S
        // ψ = √(S/(e0 r0)) ⇒ λ = 2 √(e0 r0) ∫ dy/√S
        let lambda = 2.0 * (e0 * r0).sqrt() * integral;
        let four_pi2 = 4.0 * std::f64::consts::PI * std::f64::consts::PI;
        Ok(four_pi2 * e0 * r0 / (lambda * lambda))
    }
}

/// How the wheelset roll enters the Δr function.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum RollTreatment {
    /// Roll neglected: each wheel touches its rail at its own minimum vertical distance for the
    /// lateral shift alone. This reproduces the EN 15302 Annex E reference Δr functions (for
    /// case E1 within 0.04 mm up to y = 6.5 mm, where the rigid roll gives up to 0.3 mm more).
    #[default]
    Neglected,
    /// Rigid wheelset: roll and height such that both wheels touch (see
    /// [`ContactGeometry::rigid`]).
    Rigid,
}

/// Equivalent conicity of a wheelset on a track for the given amplitudes (m): Δr sampled every
/// 0.1 mm (EN 15302 asks for ≤ 0.1 mm) with the roll treated as `roll` says, `r0` the mean
/// nominal radius and `e0` half the lateral distance between the contact points of the centred
/// wheelset (the result does not depend on `r0 e0`: λ² ∝ r0 e0). Returns `(amplitude, tan γe)`.
pub fn conicity_curve(
    geo: &ContactGeometry,
    amplitudes: &[f64],
    roll: RollTreatment,
) -> Result<Vec<(f64, f64)>, ConicityError> {
    let amax = amplitudes.iter().fold(0.0_f64, |m, &a| m.max(a));
    if amplitudes.is_empty() || !(amax.is_finite() && amax > 0.0) {
        return Err(ConicityError::Invalid {
            what: "amplitudes",
            message: "need at least one positive, finite amplitude".into(),
        });
    }
    let dy = 0.1e-3;
    // Range: the largest amplitude plus margin for an asymmetric Δr.
    let y_max = ((amax + 3e-3) / dy).ceil() * dy;
    let drf = RollingRadiusDifference::from_geometry(geo, y_max, dy, roll)?;
    let centre = geo.rigid(0.0)?;
    let e0 = 0.5 * (centre.sides[0].deepest().rail_y - centre.sides[1].deepest().rail_y);
    let r0 = geo.nominal_radius();
    amplitudes
        .iter()
        .map(|&a| Ok((a, drf.equivalent_conicity(a, r0, e0)?)))
        .collect()
}
