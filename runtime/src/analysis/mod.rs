//! Analyses besides time simulation, on the same system the integrators
//! see (a [`MechanicalSystem`], e.g. a [`ModelSystem`] of either engine):
//!
//! - [`equilibrium`]: the static (steady) equilibrium, f(q, q̇) = 0 at
//!   q̈ = 0, by Newton's method with a line search;
//! - [`linear`]: the Jacobian A of the first-order equations
//!   d/dt [q; q̇] = F(q, q̇) at such a state, by central differences of the
//!   full model;
//! - [`modes`]: eigenvalues, frequencies, damping ratios and mode shapes
//!   of A, named by their dominant coordinates;
//! - [`curving`]: the quasi-static curving solution, the equilibrium of a
//!   vehicle on a circular curve at constant speed in its track-following
//!   frames, with every wheelset's position, angle of attack and contact
//!   outputs;
//! - [`speed`]: all three for a scenario at a speed, root loci over speed
//!   and the linear critical speed;
//! - [`critical`]: the nonlinear critical speed from runs (a decelerating
//!   run, a bifurcation diagram by continuation in speed).
//!
//! Every analysis evaluates the model only through
//! [`MechanicalSystem::dynamics`] and [`MechanicalSystem::constraints`]:
//! there is no second model evaluation to keep consistent.

pub mod critical;
pub mod curving;
pub mod equilibrium;
pub mod linear;
pub mod modes;
pub mod speed;

use crate::model_system::ModelSystem;
use crate::system::{MechanicalSystem, SimError};
use nalgebra::{DMatrix, DVector};
use railmbs_models::{Axis, ElementaryKind, Model};

/// What a coordinate of the system is, for units and mode names.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CoordinateKind {
    /// A translation along a body's joint axis (m).
    Translation(Axis),
    /// A rotation about a body's joint axis (rad).
    Rotation(Axis),
    /// A first-order state of a force element (a series spring's extension).
    ElementState,
}

impl CoordinateKind {
    /// Unit of the coordinate (`m`, `rad`; element states carry theirs in
    /// their names).
    pub fn unit(self) -> &'static str {
        match self {
            Self::Translation(_) => "m",
            Self::Rotation(_) => "rad",
            Self::ElementState => "-",
        }
    }

    /// Unit of its rate.
    pub fn rate_unit(self) -> &'static str {
        match self {
            Self::Translation(_) => "m/s",
            Self::Rotation(_) => "rad/s",
            Self::ElementState => "-/s",
        }
    }

    /// The motion a vehicle engineer calls it by (x forward, y left, z up):
    /// longitudinal, lateral, vertical, roll, pitch, yaw.
    pub fn motion(self) -> &'static str {
        match self {
            Self::Translation(Axis::X) => "longitudinal",
            Self::Translation(Axis::Y) => "lateral",
            Self::Translation(Axis::Z) => "vertical",
            Self::Rotation(Axis::X) => "roll",
            Self::Rotation(Axis::Y) => "pitch",
            Self::Rotation(Axis::Z) => "yaw",
            Self::ElementState => "state",
        }
    }
}

/// One coordinate of a system, in system order (the model's coordinates,
/// then the force elements' first-order states).
#[derive(Debug, Clone, PartialEq)]
pub struct CoordinateInfo {
    /// Long name, as in the CSV header (`Bogie1.WS1.ws.y`).
    pub name: String,
    /// Long name of the body whose joint holds it (`Bogie1.WS1.ws`); the
    /// element's name for an element state.
    pub owner: String,
    /// Translation, rotation or element state.
    pub kind: CoordinateKind,
}

/// The coordinates of `system`, a system of `model`, in system order.
pub fn coordinates(model: &Model, system: &ModelSystem) -> Vec<CoordinateInfo> {
    let mut out: Vec<CoordinateInfo> = model
        .coordinates
        .iter()
        .map(|c| {
            let body = &model.bodies[c.body];
            let kind = match body.joint[c.elementary].kind {
                ElementaryKind::Translation(a) => CoordinateKind::Translation(a),
                ElementaryKind::Rotation(a) => CoordinateKind::Rotation(a),
            };
            CoordinateInfo {
                name: c.name.clone(),
                owner: body.name.clone(),
                kind,
            }
        })
        .collect();
    out.extend(system.state_names().into_iter().map(|name| {
        CoordinateInfo {
            owner: name
                .rsplit_once('.')
                .map_or(name.clone(), |(o, _)| o.into()),
            name,
            kind: CoordinateKind::ElementState,
        }
    }));
    out
}

/// The wheel loads of every wheel–rail element of `system` at the state
/// (t, q, q̇), with the element's long name. The state is accepted
/// ([`MechanicalSystem::accept_step`]): the force elements' states (stick
/// anchors, friction modes) are set there, as at the start of a run.
pub fn wheel_loads(
    system: &mut ModelSystem,
    t: f64,
    q: &[f64],
    v: &[f64],
) -> Result<Vec<(String, crate::forces::WheelLoads)>, SimError> {
    system.accept_step(t, q, v)?;
    let mut samples = Vec::new();
    system.take_assessment_loads(&mut samples);
    Ok(samples
        .into_iter()
        .map(|s| (system.forces()[s.key].name().to_string(), s.loads))
        .collect())
}

/// Evaluates f = Q − k of a system at (t, q, q̇) into reusable buffers.
pub(crate) struct ForceEvaluator {
    /// Time of every evaluation, s.
    pub t: f64,
    mass: DMatrix<f64>,
    /// f of the last evaluation.
    pub force: DVector<f64>,
    g: DVector<f64>,
    /// G = ∂g/∂q of the last constraint evaluation.
    pub g_jacobian: DMatrix<f64>,
}

impl ForceEvaluator {
    /// Buffers for `system` at time `t`.
    pub fn new<S: MechanicalSystem + ?Sized>(system: &S, t: f64) -> Self {
        let (n, nc) = (system.dof(), system.n_constraints());
        Self {
            t,
            mass: DMatrix::zeros(n, n),
            force: DVector::zeros(n),
            g: DVector::zeros(nc),
            g_jacobian: DMatrix::zeros(nc, n),
        }
    }

    /// f(q, q̇) into `self.force`.
    pub fn force<S: MechanicalSystem + ?Sized>(
        &mut self,
        system: &mut S,
        q: &[f64],
        v: &[f64],
    ) -> Result<&DVector<f64>, SimError> {
        system.dynamics(self.t, q, v, &mut self.mass, &mut self.force)?;
        crate::analysis::check_finite(self.t, "f", self.force.as_slice())?;
        Ok(&self.force)
    }

    /// M(q) of the last [`ForceEvaluator::force`] call.
    pub fn mass(&self) -> &DMatrix<f64> {
        &self.mass
    }

    /// g(q) and G(q) (into `self.g_jacobian`); empty without constraints.
    pub fn constraints<S: MechanicalSystem + ?Sized>(
        &mut self,
        system: &mut S,
        q: &[f64],
    ) -> Result<&DVector<f64>, SimError> {
        if self.g.is_empty() {
            return Ok(&self.g);
        }
        system.constraints(self.t, q, &mut self.g, &mut self.g_jacobian)?;
        Ok(&self.g)
    }
}

/// A non-finite entry of `values` as an error.
fn check_finite(t: f64, what: &str, values: &[f64]) -> Result<(), SimError> {
    match values.iter().position(|x| !x.is_finite()) {
        None => Ok(()),
        Some(i) => Err(SimError::NonFinite {
            t,
            what: format!("{what}[{i}] = {}", values[i]),
        }),
    }
}

/// Difference step for a coordinate at value `x` (m or rad): 1e-7 of
/// max(1, |x|). The contact forces are the stiffest and most curved part of
/// a vehicle model (Hertz: F ∝ δ^1.5 at δ ≈ 2e-4 m): a central difference
/// with h = 1e-7 m has a truncation error of (h/δ)²/8 ≈ 3e-8 relative, and
/// rounding noise of ε|f|/h ≈ 2e-4 N/m at |f| = 1e5 N, far below any
/// stiffness of the model.
pub(crate) fn position_step(x: f64) -> f64 {
    1e-7 * x.abs().max(1.0)
}

/// Difference step for a rate at value `v` (m/s, rad/s): 1e-6 of
/// max(1, |v|); a wheel spinning at 65 rad/s then changes its longitudinal
/// creepage by r h / V ≈ 1e-6, well within the linear range of the creep laws.
pub(crate) fn rate_step(v: f64) -> f64 {
    1e-6 * v.abs().max(1.0)
}

/// The level below which a column of a difference Jacobian of f is noise:
/// a thousand roundings of |f|∞ (or of `scale`, N) over the step `h`.
pub(crate) fn noise_level(force_scale: f64, h: f64) -> f64 {
    1e3 * f64::EPSILON * force_scale / h
}
