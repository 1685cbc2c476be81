//! Polach's method: closed-form creep forces for an elliptic contact with
//! creepage and spin, and its 2005 extension for large creepage (traction and
//! braking at the adhesion limit).
//!
//! Sources:
//! - [P99] O. Polach, "A fast wheel–rail forces calculation computer code",
//!   Vehicle System Dynamics Suppl. 33 (1999) 728–739;
//! - [P05] O. Polach, "Creep forces in simulations of traction vehicles running
//!   on adhesion limit", Wear 258 (2005) 992–1000.
//!
//! Neither paper is in the project's library (`../shared/papers` holds
//! Pogorelov 2005, whose Sect. 4.2 does not treat Polach's method), so their
//! equation numbers are not cited; the formulas below are the published ones
//! as commonly reproduced, cross-checked against a public port of [P99]'s
//! FORTRAN listing. That port differs in two spin details,
//! where this module follows the paper as commonly stated: it takes
//! `s_yC = η + φa` only when that is *smaller* than `|η|` (then pure spin would
//! give no force at all, contradicting Kalker's `C23` term which the method
//! reproduces), and it uses `|s_yC|` instead of `s_C` in `ε_M`.
//!
//! Measured (tests `polach.rs`): Kalker's linear forces at small creepage to
//! 1e-6; against CONTACT's exact traction curve (a/b = 0.5, pure ξ) within
//! 0.060 μFn, Polach saturating more gradually in the transition; on CONTACT's
//! spin example (φa = 0.005) `Fy/μFn = −0.6476` against the exact −0.6074
//! (6.6 %). Cost: about 8–10 million evaluations per second on one core
//! (criterion bench `creep`, shared machine).
//!
//! **Creepage part** ([P99]; notation: `Q = N`, `f = μ`, `sx = ξ`, `sy = η`,
//! `ψ = φ`, `a` in the rolling direction):
//!
//! ```text
//! s_yC = η + φa   if |η + φa| > |η|,   else s_yC = η        (spin adds to the lateral creep)
//! s_C  = √(ξ² + s_yC²),   s = √(ξ² + η²)
//! c_jj = √((C11 ξ/s)² + (C22 η/s)²)                          (Kalker's coefficients)
//! ε    = π G a b c_jj s_C / (4 Q μ)                          (gradient of the tangential stress)
//! F    = (2 Q μ/π)·[k_A ε/(1 + (k_A ε)²) + arctan(k_S ε)]    ([P05]; k_A = k_S = 1 is [P99])
//! Fx   = −F ξ/s_C,   Fy = −F η/s_C + Fy_spin                  (forces on the wheel)
//! ```
//!
//! **Spin part** ([P99]):
//!
//! ```text
//! K_s  = 1 + 6.3(1 − e^(−a/b))
//! ε_M  = (8/3)·G b √(ab) C23 s_C / (K_s Q μ)
//! δ    = (ε_M² − 1)/(ε_M² + 1)
//! K_M  = ε_M (δ³/3 − δ²/2 + 1/6) − (1/3)√((1 − δ²)³)
//! Fy_spin = (9/16)·a Q μ K_s K_M φ/s_C
//! ```
//!
//! With `1 − δ = 2/(1 + ε_M²)` and `1 − δ² = 4ε_M²/(1 + ε_M²)²` the bracket
//! simplifies exactly to `K_M = −(2/3)·ε_M/(1 + ε_M²)²` (checked against the
//! original form in a unit test), hence
//!
//! ```text
//! Fy_spin = −G c³ C23 φ / (1 + ε_M²)²,     c = √(ab)
//! ```
//!
//! which is Kalker's linear spin force reduced as the contact saturates, with no
//! division by `s_C` (this form is used; it is cancellation-free).
//!
//! At small creepage `F → G a b c_jj s_C` and `ε_M → 0`: the law reproduces
//! Kalker's linear `Fx = −G c² C11 ξ`, `Fy = −G c² C22 η − G c³ C23 φ` exactly;
//! at large creepage `F → μN` and `Fy_spin → 0`.
//!
//! **Friction decrease** ([P05]): `μ = μ0[(1 − A)e^(−B w) + A]` with `μ0` the
//! patch's `μ`, `w = s_C·V` the slip velocity (m/s) at vehicle speed `V`, `A =
//! μ∞/μ0` and `B` in s/m; the decreased `μ` enters both `ε` and `F`. Default
//! `A = 1` (constant `μ`: [P99]).
//!
//! **Spin moment**: Polach's method gives no spin moment `Mz`. Here `Mz` is
//! Kalker's linear `Mz = G c³ C23 η − G c⁴ C33 φ` scaled by the ratio of
//! Polach's tangential force to Kalker's linear one (as in [`super::Mueller`]):
//! exact at small creepage, zero as the contact saturates. This is this
//! module's choice, not part of [P99]/[P05].
//!
//! Choices not fixed by the papers: [P05] treats no spin; the reduction factors
//! `k_A`, `k_S` act on the creepage part only, and the slip velocity of the
//! friction decrease uses `s_C` (equal to `s` without spin). `ε_M` uses `s_C`
//! (the saturation of the whole contact), as in [P99].

use super::{ContactPatch, CreepError, CreepForces, CreepLaw, Creepages, validate};

/// Polach's creep-force law (see the module documentation).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Polach {
    /// Reduction factor in the area of adhesion `k_A` ([P05]), (0, 1].
    k_a: f64,
    /// Reduction factor in the area of slip `k_S` ([P05]), (0, 1].
    k_s: f64,
    /// Ratio of the friction coefficient at infinite slip velocity to the
    /// maximum one, `A = μ∞/μ0` ([P05]), ≥ 0; 1 = constant friction.
    mu_ratio: f64,
    /// Exponential friction decrease rate `B`, s/m, ≥ 0.
    decay: f64,
    /// Vehicle speed `V`, m/s, ≥ 0 (slip velocity `w = s_C V`).
    speed: f64,
}

impl Default for Polach {
    /// The 1999 law: `k_A = k_S = 1`, constant friction.
    fn default() -> Self {
        Self {
            k_a: 1.0,
            k_s: 1.0,
            mu_ratio: 1.0,
            decay: 0.0,
            speed: 0.0,
        }
    }
}

fn param(what: &str, v: f64, expected: &str) -> CreepError {
    CreepError::Parameter(format!("Polach {what} = {v} is invalid ({expected})"))
}

impl Polach {
    /// The 1999 law (`k_A = k_S = 1`, constant `μ`).
    pub fn new() -> Self {
        Self::default()
    }

    /// With \[P05\]'s reduction factors of the initial slope: `k_A` in the area of
    /// adhesion and `k_S` in the area of slip, each in (0, 1] (the paper has
    /// `k_S ≤ k_A ≤ 1`). The small-creepage slope becomes `(k_A + k_S)/2` times
    /// Kalker's.
    pub fn with_reduction(mut self, k_a: f64, k_s: f64) -> Result<Self, CreepError> {
        for (what, v) in [("k_A", k_a), ("k_S", k_s)] {
            if !(v.is_finite() && v > 0.0 && v <= 1.0) {
                return Err(param(what, v, "must be in (0, 1]"));
            }
        }
        self.k_a = k_a;
        self.k_s = k_s;
        Ok(self)
    }

    /// With \[P05\]'s exponential friction decrease `μ = μ0[(1 − A)e^(−B w) + A]`:
    /// `mu_ratio` = `A = μ∞/μ0` (≥ 0), `decay` = `B` in s/m (≥ 0), `speed` = `V`
    /// in m/s (≥ 0) giving the slip velocity `w = s_C V`.
    pub fn with_falling_friction(
        mut self,
        mu_ratio: f64,
        decay: f64,
        speed: f64,
    ) -> Result<Self, CreepError> {
        if !(mu_ratio.is_finite() && mu_ratio >= 0.0) {
            return Err(param(
                "A = μ∞/μ0",
                mu_ratio,
                "must be non-negative and finite",
            ));
        }
        if !(decay.is_finite() && decay >= 0.0) {
            return Err(param("B", decay, "must be non-negative and finite, s/m"));
        }
        self.mu_ratio = mu_ratio;
        self.decay = decay;
        self.with_speed(speed)
    }

    /// The same law at another vehicle speed `V`, m/s (≥ 0; only used by the
    /// friction decrease).
    pub fn with_speed(mut self, speed: f64) -> Result<Self, CreepError> {
        if !(speed.is_finite() && speed >= 0.0) {
            return Err(param(
                "speed V",
                speed,
                "must be non-negative and finite, m/s",
            ));
        }
        self.speed = speed;
        Ok(self)
    }

    /// Forces at vehicle speed `speed` (m/s) instead of the stored one.
    fn forces_at(
        &self,
        p: &ContactPatch,
        c: &Creepages,
        speed: f64,
    ) -> Result<CreepForces, CreepError> {
        if !(speed.is_finite() && speed >= 0.0) {
            return Err(CreepError::Input {
                name: "speed",
                value: speed,
                expected: "non-negative and finite, m/s",
            });
        }
        let k = validate(p, c)?;
        if p.n == 0.0 || p.mu == 0.0 {
            return Ok(CreepForces::default());
        }
        let (xi, eta, phi) = (c.xi, c.eta, c.phi);
        // Resultant creepage with the spin's lateral contribution where it adds.
        let sy_spin = eta + phi * p.a;
        let syc = if sy_spin.abs() > eta.abs() {
            sy_spin
        } else {
            eta
        };
        let sc = xi.hypot(syc);
        if sc == 0.0 {
            return Ok(CreepForces::default());
        }
        let s = xi.hypot(eta);
        let cjj = if s > 0.0 {
            (k.c11 * xi / s).hypot(k.c22 * eta / s)
        } else {
            k.c11
        };
        // [P05] friction decrease with the slip velocity w = s_C V.
        let mu = if self.mu_ratio == 1.0 {
            p.mu
        } else {
            p.mu * ((1.0 - self.mu_ratio) * (-self.decay * sc * speed).exp() + self.mu_ratio)
        };
        if mu <= 0.0 {
            return Ok(CreepForces::default());
        }
        let qmu = p.n * mu;
        let cc = (p.a * p.b).sqrt();
        let gc2 = p.g * p.a * p.b;
        let gc3 = gc2 * cc;
        // Gradient of the tangential stress.
        let eps = std::f64::consts::FRAC_PI_4 * gc2 * cjj * sc / qmu;
        let f = 2.0 * qmu / std::f64::consts::PI
            * (ratio_term(self.k_a * eps) + (self.k_s * eps).atan());
        // Spin: Fy_spin = −G c³ C23 φ/(1 + ε_M²)².
        let ks = 1.0 + 6.3 * (1.0 - (-p.a / p.b).exp());
        let eps_m = (8.0 / 3.0) * p.g * p.b * cc * k.c23 * sc / (ks * qmu);
        let red = spin_reduction(eps_m);
        let fy_spin = -gc3 * k.c23 * phi * red;
        let fx = -f * xi / sc;
        let fy = -f * eta / sc + fy_spin;
        // Spin moment: Kalker's linear moment scaled by Polach/linear force.
        let lin_fx = -gc2 * k.c11 * xi;
        let lin_fy = -gc2 * k.c22 * eta - gc3 * k.c23 * phi;
        let lin = lin_fx.hypot(lin_fy);
        let scale = if lin > 0.0 {
            (fx.hypot(fy) / lin).min(1.0)
        } else {
            1.0
        };
        let mz = (gc3 * k.c23 * eta - gc2 * p.a * p.b * k.c33 * phi) * scale;
        Ok(CreepForces { fx, fy, mz })
    }
}

/// `x/(1 + x²)` for `x ≥ 0` without overflow for large `x`.
#[inline]
fn ratio_term(x: f64) -> f64 {
    if x > 1.0 {
        1.0 / (x + 1.0 / x)
    } else {
        x / (1.0 + x * x)
    }
}

/// `1/(1 + ε²)²` for `ε ≥ 0` without overflow.
#[inline]
fn spin_reduction(eps: f64) -> f64 {
    if eps > 1e100 {
        0.0
    } else {
        let d = 1.0 + eps * eps;
        1.0 / (d * d)
    }
}

impl CreepLaw for Polach {
    fn name(&self) -> &'static str {
        "polach"
    }
    fn forces(&self, p: &ContactPatch, c: &Creepages) -> Result<CreepForces, CreepError> {
        self.forces_at(p, c, self.speed)
    }
    /// Forces at vehicle speed `speed` (m/s) instead of the stored one.
    fn forces_at_speed(
        &self,
        p: &ContactPatch,
        c: &Creepages,
        speed: f64,
    ) -> Result<CreepForces, CreepError> {
        self.forces_at(p, c, speed)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The simplification of Polach's spin bracket is exact algebra:
    /// `K_M = ε(δ³/3 − δ²/2 + 1/6) − (1/3)√((1 − δ²)³) = −(2/3)ε/(1 + ε²)²`
    /// with `δ = (ε² − 1)/(ε² + 1)`; checked to rounding over six decades.
    #[test]
    fn spin_bracket_simplification() {
        for k in -30..=30 {
            let e = 10f64.powf(f64::from(k) / 10.0);
            let d = (e * e - 1.0) / (e * e + 1.0);
            let km = e * (d * d * d / 3.0 - d * d / 2.0 + 1.0 / 6.0)
                - (1.0 - d * d).powi(3).sqrt() / 3.0;
            let simple = -(2.0 / 3.0) * e * spin_reduction(e);
            // The original form cancels: its absolute rounding error is about
            // ε·1e-16, relative to |K_M| ~ ε⁻³ for large ε.
            let tol = 1e-12 * simple.abs() + 1e-15 * e;
            assert!((km - simple).abs() <= tol, "ε = {e}: {km} vs {simple}");
        }
    }

    #[test]
    fn parameters_are_checked() {
        assert!(Polach::new().with_reduction(0.0, 0.5).is_err());
        assert!(Polach::new().with_reduction(1.0, 1.5).is_err());
        assert!(
            Polach::new()
                .with_falling_friction(-0.1, 0.6, 10.0)
                .is_err()
        );
        assert!(
            Polach::new()
                .with_falling_friction(0.4, f64::NAN, 10.0)
                .is_err()
        );
        assert!(Polach::new().with_speed(-1.0).is_err());
        let e = Polach::new().with_reduction(2.0, 0.5).unwrap_err();
        assert!(e.to_string().contains("k_A = 2"), "{e}");
    }
}
