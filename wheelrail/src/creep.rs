//! Creep-force laws: tangential forces and spin moment in an elliptic Hertzian
//! contact from creepages and spin.
//!
//! All laws implement [`CreepLaw`]: inputs are the contact ellipse and load
//! ([`ContactPatch`]: semi-axes `a` (rolling direction) and `b`, shear modulus
//! `G`, Poisson ratio `ν`, friction coefficient `μ`, normal force `N`) and the
//! [`Creepages`] `ξ, η, φ`; the output ([`CreepForces`]) is `Fx, Fy, Mz` acting
//! **on the wheel** in the contact frame, CONTACT's sign convention (`Fx < 0`
//! for `ξ > 0`; see [`crate::creepage`]).
//!
//! Laws:
//! - [`KalkerLinear`]: Kalker's linear theory with the tabulated coefficients of
//!   [`crate::kalker`];
//! - [`Mueller`]: the linear force saturated towards `μN`;
//! - [`Fastsim`]: Kalker's FASTSIM algorithm (simplified theory);
//! - [`FastsimA`]: Pogorelov's semi-analytic FastSim_A (Pogorelov 2005, Sect. 4.3):
//!   closed-form strips, cost proportional to the number of strips only;
//! - [`Polach`]: Polach's closed-form method (1999) with spin, and the 2005
//!   extension (reduction factors `k_A`, `k_S`, falling friction) as options.
//!
//! [`CreepLawSpec`] names a law and its settings (model files, command line)
//! and builds it.

mod fastsim;
mod fastsim_a;
mod polach;
mod spec;

pub use fastsim::{Fastsim, FastsimLayout, TractionBound};
pub use fastsim_a::{FastsimA, INTEGRATED_NODES, SlidingZone};
pub use polach::Polach;
pub use spec::{
    CREEP_LAW_SYNTAX, CreepLawSpec, FASTSIM_A_STRIPS, FASTSIM_DIVISIONS, ParseCreepLawError,
};

pub use crate::creepage::Creepages;
use crate::kalker::KalkerCoefficients;

/// The contact ellipse and its load.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactPatch {
    /// Semi-axis in the rolling direction, m.
    pub a: f64,
    /// Semi-axis in the lateral direction, m.
    pub b: f64,
    /// Combined shear modulus `G`, Pa.
    pub g: f64,
    /// Combined Poisson ratio `ν`, –.
    pub nu: f64,
    /// Coefficient of friction `μ`, –.
    pub mu: f64,
    /// Normal force `N`, N (≥ 0).
    pub n: f64,
}

/// Creep forces on the wheel in the contact frame.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct CreepForces {
    /// Longitudinal force, N.
    pub fx: f64,
    /// Lateral force, N.
    pub fy: f64,
    /// Spin moment about the contact normal, N·m.
    pub mz: f64,
}

/// Errors of the creep-force laws: which input is wrong and its value.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CreepError {
    /// An input is out of its valid range or not finite.
    #[error("creep force: {name} = {} is invalid ({expected})", readable(*value))]
    Input {
        /// Input name as in the CSV interface (`a`, `b`, `G`, `nu`, `mu`, `N`, `xi`, `eta`, `phi`).
        name: &'static str,
        /// The offending value.
        value: f64,
        /// What is expected.
        expected: &'static str,
    },
    /// Bad law parameters (number of strips, elements, exponent).
    #[error("creep force law: {0}")]
    Parameter(String),
}

/// `x` as written for a reader: plain between 10⁻⁴ and 10⁶, else with an
/// exponent (Rust's `{}` writes 1e100 with 100 digits).
fn readable(x: f64) -> String {
    if x == 0.0 || !x.is_finite() || (1e-4..1e6).contains(&x.abs()) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

/// A creep-force law.
pub trait CreepLaw {
    /// Short name (`kalker`, `mueller`, `fastsim`, `fastsim-a`, `polach`).
    fn name(&self) -> &'static str;
    /// Forces on the wheel for the given patch and creepages; validates inputs.
    fn forces(&self, patch: &ContactPatch, c: &Creepages) -> Result<CreepForces, CreepError>;
    /// Forces at the rolling speed `speed` (m/s), for laws whose friction
    /// depends on the slip velocity (Polach's friction decrease); the others
    /// ignore it.
    fn forces_at_speed(
        &self,
        patch: &ContactPatch,
        c: &Creepages,
        _speed: f64,
    ) -> Result<CreepForces, CreepError> {
        self.forces(patch, c)
    }
}

fn bad(name: &'static str, value: f64, expected: &'static str) -> CreepError {
    CreepError::Input {
        name,
        value,
        expected,
    }
}

/// Largest magnitude of a creepage (ξ, η, and the spin made dimensionless
/// by the patch, φ√(ab)) that the laws accept, –.
pub const MAX_CREEPAGE: f64 = 1e6;

/// Validates a patch and creepages; returns Kalker's coefficients for them.
#[inline]
pub(crate) fn validate(p: &ContactPatch, c: &Creepages) -> Result<KalkerCoefficients, CreepError> {
    if !(p.a.is_finite() && p.a > 0.0) {
        return Err(bad("a", p.a, "positive and finite, m"));
    }
    if !(p.b.is_finite() && p.b > 0.0) {
        return Err(bad("b", p.b, "positive and finite, m"));
    }
    if !(p.g.is_finite() && p.g > 0.0) {
        return Err(bad("G", p.g, "positive and finite, Pa"));
    }
    if !(p.nu.is_finite() && (0.0..=0.5).contains(&p.nu)) {
        return Err(bad("nu", p.nu, "in [0, 0.5]"));
    }
    if !(p.mu.is_finite() && p.mu >= 0.0) {
        return Err(bad("mu", p.mu, "non-negative and finite"));
    }
    if !(p.n.is_finite() && p.n >= 0.0) {
        return Err(bad("N", p.n, "non-negative and finite, N"));
    }
    if !c.xi.is_finite() {
        return Err(bad("xi", c.xi, "finite"));
    }
    if !c.eta.is_finite() {
        return Err(bad("eta", c.eta, "finite"));
    }
    if !c.phi.is_finite() {
        return Err(bad("phi", c.phi, "finite, 1/m"));
    }
    // Beyond this the contact is no longer rolling (a wheel spinning or
    // skidding a million times faster than it rolls), and the laws' squares
    // overflow from about 1e100 on (NaN or zero forces).
    if c.xi.abs() > MAX_CREEPAGE {
        return Err(bad("xi", c.xi, "at most 1e6 in magnitude"));
    }
    if c.eta.abs() > MAX_CREEPAGE {
        return Err(bad("eta", c.eta, "at most 1e6 in magnitude"));
    }
    if c.phi.abs() * (p.a * p.b).sqrt() > MAX_CREEPAGE {
        return Err(bad("phi", c.phi, "at most 1e6/√(ab) in magnitude, 1/m"));
    }
    KalkerCoefficients::interpolate_ab(p.a, p.b, p.nu).ok_or(bad("nu", p.nu, "in [0, 0.5]"))
}

/// Kalker's flexibilities of the simplified theory (FASTSIM), m/Pa:
/// `L1 = 8a/(3 C11 G)`, `L2 = 8a/(3 C22 G)`, `L3 = π a √(a/b)/(4 C23 G)`
/// (Kalker 1982; they make the simplified theory reproduce the linear theory's
/// `Fx(ξ)`, `Fy(η)` and `Fy(φ)` exactly).
#[derive(Debug, Clone, Copy)]
pub(crate) struct Flexibilities {
    pub inv_l1: f64,
    pub inv_l2: f64,
    pub inv_l3: f64,
}

impl Flexibilities {
    #[inline]
    pub(crate) fn new(p: &ContactPatch, k: &KalkerCoefficients) -> Self {
        // One division: 1/a; 1/(π a √(a/b)) = √(b/a)/(π a).
        let inv_a = 1.0 / p.a;
        let g_a = p.g * inv_a;
        Self {
            inv_l1: 0.375 * k.c11 * g_a,
            inv_l2: 0.375 * k.c22 * g_a,
            inv_l3: 4.0 / std::f64::consts::PI * k.c23 * g_a * (p.b * inv_a).sqrt(),
        }
    }
}

/// Kalker's linear theory (no saturation), coefficients from [`crate::kalker`].
/// Independent of `N` and `μ`, except that `N = 0` (no contact) gives zero force.
#[derive(Debug, Clone, Copy, Default)]
pub struct KalkerLinear;

impl KalkerLinear {
    #[inline]
    fn eval(p: &ContactPatch, c: &Creepages, k: &KalkerCoefficients) -> CreepForces {
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

/// Mueller-type saturation of Kalker's linear forces: with the linear tangential
/// force `F_lin = |(Fx, Fy)|` and `u = F_lin/(μN)`, all of `Fx, Fy, Mz` are
/// scaled by `1/(1 + uⁿ)^(1/n)`, so the force follows the linear theory at small
/// creepage and tends to `μN` at large creepage. The exponent `n` (default
/// [`MUELLER_EXPONENT`] = 2) sets the sharpness of the transition.
///
/// This is not the law Pogorelov 2005, Sect. 4.2 calls Mueller's method: that
/// one saturates the same way (exponent `m`) but from an empirical,
/// load-dependent slope `k_c(P) = P(235 + P(2.4 − 0.01P))`, `P = 0.001 N`,
/// independent of the contact ellipse and of spin, with the flange contact as
/// pure sliding. Here the slope is Kalker's linear theory, spin included.
#[derive(Debug, Clone, Copy)]
pub struct Mueller {
    exponent: f64,
}

/// Default exponent `n` of [`Mueller`], –: used by model files, `umsim creep`
/// and `umsim bench --creep` alike.
pub const MUELLER_EXPONENT: f64 = 2.0;

impl Default for Mueller {
    fn default() -> Self {
        Self {
            exponent: MUELLER_EXPONENT,
        }
    }
}

impl Mueller {
    /// Law with exponent `n` (> 0, finite).
    pub fn new(exponent: f64) -> Result<Self, CreepError> {
        if !(exponent.is_finite() && exponent > 0.0) {
            return Err(CreepError::Parameter(format!(
                "Mueller exponent must be positive and finite, got {exponent}"
            )));
        }
        Ok(Self { exponent })
    }
}

impl CreepLaw for Mueller {
    fn name(&self) -> &'static str {
        "mueller"
    }
    fn forces(&self, p: &ContactPatch, c: &Creepages) -> Result<CreepForces, CreepError> {
        let k = validate(p, c)?;
        let lin = KalkerLinear::eval(p, c, &k);
        let limit = p.mu * p.n;
        if limit <= 0.0 {
            return Ok(CreepForces::default());
        }
        let u = (lin.fx * lin.fx + lin.fy * lin.fy).sqrt() / limit;
        let s = if u == 0.0 {
            1.0
        } else if u > 1e8 {
            // (1 + uⁿ)^(−1/n) = 1/u to within u⁻ⁿ/n relative; avoids overflow.
            1.0 / u
        } else if self.exponent == 3.0 {
            1.0 / (1.0 + u * u * u).cbrt()
        } else {
            (1.0 + u.powf(self.exponent)).powf(-1.0 / self.exponent)
        };
        Ok(CreepForces {
            fx: lin.fx * s,
            fy: lin.fy * s,
            mz: lin.mz * s,
        })
    }
}
