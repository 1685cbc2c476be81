//! Mueller's method as Pogorelov 2005, Sect. 4.2 gives it (the paper's
//! reference [7]): an empirical creep law whose slope depends on the wheel
//! load only, not on the contact ellipse, and that ignores spin.
//!
//! With the resultant creepage `ρ = √(ξ² + η²)` (–), the load in kilonewtons
//! `P = 0.001 N` (N in newtons) and the empirical slope
//!
//! ```text
//! k_c(P) = P (235 + P (2.4 − 0.01 P))          (kN per unit creepage)
//! F_xy   = 1000 k_c / (1 + (k_c ρ / (μ P))^m)^(1/m)     (N)
//! Fx = −ξ F_xy,   Fy = −η F_xy,   Mz = 0
//! ```
//!
//! so the force grows as `1000 k_c ρ` (N) at small creepage and tends to `μN`
//! at large creepage (`1000 k_c ρ · μP/(k_c ρ) = 1000 μ P = μ N`). The paper
//! writes `Fx = −ξ F_xy` with its own sign convention; here the forces act on
//! the wheel and oppose the creepage, as every law of [`crate::creep`]. The
//! exponent `m` is not given in the paper; the default is
//! [`MUELLER_EXPONENT`] (2), the same as [`super::MuellerKalkerSaturated`]'s.
//!
//! The slope polynomial has its largest value at `P ≈ 199 kN` and falls to
//! zero at [`MUELLER_MAX_LOAD`] (`P ≈ 314.7 kN`); loads from there on are
//! refused (the fit has no meaning there; a zero or negative slope would
//! reverse the force).
//!
//! **Flange contact.** "If the two-point contact is presented, forces at the
//! flange contact are computed as simple friction forces in the sliding mode"
//! (Pogorelov 2005, Sect. 4.2): in [`ContactMode::TwoPointFlange`] the force is
//! `−μN (ξ, η)/ρ` (zero if `ρ = 0`), `Mz = 0`. How the flange contact is
//! recognised is [`ContactMode::of_wheel`]'s rule. A one-point contact on the
//! flange uses the formula above, as in the paper (whose text notes the law's
//! low accuracy there, where spin is large).

use super::mueller_kalker_saturated::{check_exponent, saturation};
use super::{
    ContactMode, ContactPatch, CreepError, CreepForces, CreepLaw, Creepages, MUELLER_EXPONENT, bad,
    validate,
};

/// Largest wheel load of [`Mueller`], N: the root `P = (2.4 + √(2.4² +
/// 0.04·235))/0.02` kN of the slope `k_c(P) = P(235 + P(2.4 − 0.01P))`.
pub const MUELLER_MAX_LOAD: f64 = 314_679.22;

/// Mueller's method (Pogorelov 2005, Sect. 4.2): empirical load-dependent
/// slope, no spin, pure sliding at the flange contact of a two-point contact
/// (see the module documentation of `creep::mueller`).
#[derive(Debug, Clone, Copy)]
pub struct Mueller {
    exponent: f64,
}

impl Default for Mueller {
    fn default() -> Self {
        Self {
            exponent: MUELLER_EXPONENT,
        }
    }
}

impl Mueller {
    /// Law with exponent `m` (> 0, finite).
    pub fn new(exponent: f64) -> Result<Self, CreepError> {
        Ok(Self {
            exponent: check_exponent(exponent)?,
        })
    }

    /// The empirical slope `1000 k_c(P)`, N per unit creepage, at normal
    /// force `n` (N), `P = n/1000` (kN).
    pub fn slope(n: f64) -> f64 {
        let p = 0.001 * n;
        1000.0 * p * (235.0 + p * (2.4 - 0.01 * p))
    }
}

impl CreepLaw for Mueller {
    fn name(&self) -> &'static str {
        "mueller"
    }

    fn forces(&self, p: &ContactPatch, c: &Creepages) -> Result<CreepForces, CreepError> {
        self.forces_in_contact(p, c, 0.0, ContactMode::Single)
    }

    fn forces_in_contact(
        &self,
        p: &ContactPatch,
        c: &Creepages,
        _speed: f64,
        mode: ContactMode,
    ) -> Result<CreepForces, CreepError> {
        validate(p, c)?;
        if p.n >= MUELLER_MAX_LOAD {
            return Err(bad(
                "N",
                p.n,
                "below 314.68 kN for Mueller's law (its slope k_c(P) is zero there), N",
            ));
        }
        let limit = p.mu * p.n;
        let rho = c.xi.hypot(c.eta);
        if limit <= 0.0 || rho == 0.0 {
            return Ok(CreepForces::default());
        }
        // Force per unit creepage along −(ξ, η): F_xy (N).
        let fxy = match mode {
            ContactMode::TwoPointFlange => limit / rho,
            ContactMode::Single | ContactMode::TwoPointTread => {
                let slope = Self::slope(p.n);
                slope * saturation(slope * rho / limit, self.exponent)
            }
        };
        Ok(CreepForces {
            fx: -c.xi * fxy,
            fy: -c.eta * fxy,
            mz: 0.0,
        })
    }
}
