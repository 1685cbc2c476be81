//! Kalker's linear theory of rolling contact (Kalker 1967; coefficients
//! `C11, C22, C23, C33` from [`crate::kalker`]): creep forces proportional to
//! the creepages, no saturation.

use super::{ContactPatch, CreepError, CreepForces, CreepLaw, Creepages, validate};
use crate::kalker::KalkerCoefficients;

/// Kalker's linear theory (no saturation), coefficients from [`crate::kalker`].
/// Independent of `N` and `μ`, except that `N = 0` (no contact) gives zero force.
#[derive(Debug, Clone, Copy, Default)]
pub struct KalkerLinear;

impl KalkerLinear {
    #[inline]
    pub(super) fn eval(p: &ContactPatch, c: &Creepages, k: &KalkerCoefficients) -> CreepForces {
        let c2 = p.a * p.b;
        let cc = c2.sqrt();
        let gc2 = p.g * c2;
        let gc3 = gc2 * cc;
        let gc4 = gc2 * c2;
        CreepForces {
            fx: -gc2 * k.c11 * c.xi,
            fy: -gc2 * k.c22 * c.eta - gc3 * k.c23 * c.phi,
            mz: gc3 * k.c23 * c.eta - gc4 * k.c33 * c.phi,
        }
    }
}

impl CreepLaw for KalkerLinear {
    fn name(&self) -> &'static str {
        "kalker"
    }
    fn forces(&self, p: &ContactPatch, c: &Creepages) -> Result<CreepForces, CreepError> {
        let k = validate(p, c)?;
        if p.n == 0.0 {
            // No normal force, no contact: no tangential force.
            return Ok(CreepForces::default());
        }
        Ok(Self::eval(p, c, &k))
    }
}
