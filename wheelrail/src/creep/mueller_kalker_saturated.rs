//! Kalker's linear forces (spin included) saturated towards `μN` by a
//! Mueller-type formula: this project's law, formerly called `Mueller`.

use super::{ContactPatch, CreepError, CreepForces, CreepLaw, Creepages, KalkerLinear, validate};

/// Mueller-type saturation of Kalker's linear forces: with the linear tangential
/// force `F_lin = |(Fx, Fy)|` and `u = F_lin/(μN)`, all of `Fx, Fy, Mz` are
/// scaled by `1/(1 + uⁿ)^(1/n)`, so the force follows the linear theory at small
/// creepage and tends to `μN` at large creepage. The exponent `n` (default
/// [`MUELLER_EXPONENT`] = 2) sets the sharpness of the transition.
///
/// This is not the law Pogorelov 2005, Sect. 4.2 calls Mueller's method
/// ([`super::Mueller`]): that one saturates the same way (exponent `m`) but
/// from an empirical, load-dependent slope `k_c(P) = P(235 + P(2.4 − 0.01P))`,
/// `P = 0.001 N`, independent of the contact ellipse and of spin, with the
/// flange contact of a two-point contact as pure sliding. Here the slope is
/// Kalker's linear theory, spin included, in every contact. Until this law
/// got its own name it was this project's `Mueller`.
#[derive(Debug, Clone, Copy)]
pub struct MuellerKalkerSaturated {
    exponent: f64,
}

/// Default exponent `n` of [`MuellerKalkerSaturated`] and of
/// [`super::Mueller`], –: used by model files, `umsim creep` and `umsim bench
/// --creep` alike.
pub const MUELLER_EXPONENT: f64 = 2.0;

impl Default for MuellerKalkerSaturated {
    fn default() -> Self {
        Self {
            exponent: MUELLER_EXPONENT,
        }
    }
}

impl MuellerKalkerSaturated {
    /// Law with exponent `n` (> 0, finite).
    pub fn new(exponent: f64) -> Result<Self, CreepError> {
        Ok(Self {
            exponent: check_exponent(exponent)?,
        })
    }
}

impl CreepLaw for MuellerKalkerSaturated {
    fn name(&self) -> &'static str {
        "mueller-kalker-saturated"
    }
    fn forces(&self, p: &ContactPatch, c: &Creepages) -> Result<CreepForces, CreepError> {
        let k = validate(p, c)?;
        let lin = KalkerLinear::eval(p, c, &k);
        let limit = p.mu * p.n;
        if limit <= 0.0 {
            return Ok(CreepForces::default());
        }
        let u = (lin.fx * lin.fx + lin.fy * lin.fy).sqrt() / limit;
        let s = saturation(u, self.exponent);
        Ok(CreepForces {
            fx: lin.fx * s,
            fy: lin.fy * s,
            mz: lin.mz * s,
        })
    }
}

/// `(1 + uᵐ)^(−1/m)` for `u ≥ 0`, `m > 0`: the saturation factor of both
/// Mueller laws (force = linear force × factor), overflow-free.
#[inline]
pub(super) fn saturation(u: f64, exponent: f64) -> f64 {
    if u == 0.0 {
        1.0
    } else if u > 1e8 {
        // (1 + uᵐ)^(−1/m) = 1/u to within u⁻ᵐ/m relative; avoids overflow.
        1.0 / u
    } else if exponent == 3.0 {
        1.0 / (1.0 + u * u * u).cbrt()
    } else {
        (1.0 + u.powf(exponent)).powf(-1.0 / exponent)
    }
}

/// Checks a Mueller exponent (> 0, finite).
pub(super) fn check_exponent(exponent: f64) -> Result<f64, CreepError> {
    if exponent.is_finite() && exponent > 0.0 {
        Ok(exponent)
    } else {
        Err(CreepError::Parameter(format!(
            "Mueller exponent must be positive and finite, got {exponent}"
        )))
    }
}
