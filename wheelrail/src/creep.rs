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
//! - [`Mueller`]: Mueller's method as Pogorelov 2005, Sect. 4.2 gives it
//!   (empirical load-dependent slope, no spin, pure sliding at the flange
//!   contact of a two-point contact);
//! - [`MuellerKalkerSaturated`]: Kalker's linear force saturated towards `μN`
//!   (this project's law, called `Mueller` until the paper's came);
//! - [`Fastsim`]: Kalker's FASTSIM algorithm (simplified theory);
//! - [`FastsimA`]: Pogorelov's semi-analytic FastSim_A (Pogorelov 2005, Sect. 4.3):
//!   closed-form strips, cost proportional to the number of strips only;
//! - [`FastsimSa`]: FastSim_SA (Pogorelov 2005, Sect. 4.3, Fig. 24): the
//!   analytic adhesion zone, FASTSIM's elements in the sliding zone;
//! - [`Polach`]: Polach's closed-form method (1999) with spin, and the 2005
//!   extension (reduction factors `k_A`, `k_S`, falling friction) as options;
//! - [`StripTheory`]: strip theory calibrated to Kalker's linear theory, spin
//!   through FASTSIM's flexibility (FaStrip-like; this project's derivation).
//!
//! [`CreepLawSpec`] names a law and its settings (model files, command line)
//! and builds it.

mod fastsim;
mod fastsim_a;
mod fastsim_sa;
mod kalker_linear;
mod mueller;
mod mueller_kalker_saturated;
mod polach;
mod spec;
mod strip;

pub use fastsim::{Fastsim, FastsimLayout, TractionBound};
pub use fastsim_a::{FastsimA, INTEGRATED_NODES, SlidingZone};
pub use fastsim_sa::FastsimSa;
pub use kalker_linear::KalkerLinear;
pub use mueller::{MUELLER_MAX_LOAD, Mueller};
pub use mueller_kalker_saturated::{MUELLER_EXPONENT, MuellerKalkerSaturated};
pub use polach::Polach;
pub use spec::{
    CREEP_LAW_SYNTAX, CreepLawSpec, FASTSIM_A_STRIPS, FASTSIM_DIVISIONS, ParseCreepLawError,
};
pub(crate) use strip::StripSolution;
pub use strip::{STRIP_THEORY_STRIPS, StripTheory};

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
    #[error("creep force: {name} = {} is invalid ({expected})", crate::readable(*value))]
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

/// A creep-force law.
pub trait CreepLaw {
    /// Short name, as on the command line (`kalker`, `fastsim`, …).
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
    /// Forces of a contact in `mode` (one of a wheel's contacts in a one- or
    /// two-point contact) at the rolling speed `speed` (m/s), for laws that
    /// treat the flange contact of a two-point contact apart (the paper's
    /// [`Mueller`]); the others give [`Self::forces_at_speed`].
    fn forces_in_contact(
        &self,
        patch: &ContactPatch,
        c: &Creepages,
        speed: f64,
        _mode: ContactMode,
    ) -> Result<CreepForces, CreepError> {
        self.forces_at_speed(patch, c, speed)
    }
}

/// Smallest contact angle of a flange contact, rad (20°): see
/// [`ContactMode::of_wheel`]. Tread contacts of S1002 on UIC60 stay below
/// about 0.1 rad, the flange flank is near 70° (1.22 rad).
pub const FLANGE_CONTACT_ANGLE: f64 = 0.349_065_850_398_865_9;

/// The role of one of a wheel's contacts, for the laws that treat the
/// flange contact of a two-point contact apart (Pogorelov 2005, Sect. 4.2,
/// Mueller's method).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum ContactMode {
    /// The wheel's only loaded contact (on the tread or on the flange).
    #[default]
    Single,
    /// The tread contact of a two-point contact.
    TwoPointTread,
    /// The flange contact of a two-point contact.
    TwoPointFlange,
}

impl ContactMode {
    /// The modes of a wheel's (up to two) contacts from their contact angles
    /// `angles` (rad, either sign) and whether each carries load: with one
    /// loaded contact it is [`Self::Single`]; with two, the contact of the
    /// larger `|angle|` is the flange contact ([`Self::TwoPointFlange`]) if
    /// that angle is at least [`FLANGE_CONTACT_ANGLE`], the other the tread
    /// contact ([`Self::TwoPointTread`]); two loaded contacts both below the
    /// threshold are both [`Self::TwoPointTread`]. An unloaded contact is
    /// [`Self::Single`] (it has no force).
    pub fn of_wheel(angles: [f64; 2], loaded: [bool; 2]) -> [Self; 2] {
        if !(loaded[0] && loaded[1]) {
            return [Self::Single; 2];
        }
        let flange = usize::from(angles[1].abs() > angles[0].abs());
        let mut modes = [Self::TwoPointTread; 2];
        if angles[flange].abs() >= FLANGE_CONTACT_ANGLE {
            modes[flange] = Self::TwoPointFlange;
        }
        modes
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
