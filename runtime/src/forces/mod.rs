//! Force elements (Pogorelov 2005, Sect. 3). Each element computes the wrenches it
//! applies to bodies from their kinematics; the system projects them on the
//! generalized coordinates with the body Jacobians (Q = Σ Γ_jᵀ F_j).
//!
//! Adding an element: write its model syntax and spec in
//! `railmbs_models::forces`, its module here with a type implementing
//! [`ForceElement`] built from that spec, and add one arm to [`build`].

mod applied;
mod bipolar;
pub mod contact;
mod linear6;
pub mod nonlinear;
mod series;
pub mod torsion;
pub mod wheel_rail;

mod attach;
mod jacobian;

pub use applied::AppliedForce;
pub use bipolar::LinearBipolar;
pub use contact::{PointPlane, contact_stiffness_damping};
pub use linear6::Linear6;
pub use nonlinear::{Characteristic, CoulombFriction, LoadFriction, Tabulated};
pub use series::SeriesSpringDamper;
pub use wheel_rail::{ContactTableCache, TrackBinding, WheelRailContact};

pub(crate) use attach::{
    Attachment, FrameAttachment, add_force, add_generalized_force, add_moment, eval_scalar,
    eval_vector,
};
pub use jacobian::{ForceJacobian, JacobianScratch, PairMatrix, point_twist_map};

use crate::equations::BodyKinematics;
use crate::system::SimError;
use nalgebra::Vector3;
use railmbs_wheelrail::geometry::RigidContact;

use railmbs_models::{ForceKind, Model};

/// Force (N) and moment about the centre of mass (N m) on one body, in SC0.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Wrench {
    /// Force on the body, N, in SC0.
    pub force: Vector3<f64>,
    /// Moment about the body's centre of mass, N m, in SC0.
    pub moment: Vector3<f64>,
}

/// One row of the end-of-run assessment table: the largest value of a
/// quantity over the run, when it occurred, and its limit if there is one.
#[derive(Debug, Clone, PartialEq)]
pub struct Assessment {
    /// Long name of the element.
    pub element: String,
    /// What is measured (e.g. `Y/Q left`).
    pub quantity: String,
    /// Largest value over the accepted steps.
    pub max: f64,
    /// Time of the largest value, s.
    pub time: f64,
    /// The limit it is judged against, same unit.
    pub limit: Option<f64>,
    /// Name of the limit (e.g. `Nadal`).
    pub limit_name: &'static str,
    /// Unit of `max` and `limit`.
    pub unit: &'static str,
}

/// What a force element sees: time, body kinematics (model order), parameters,
/// and the first-order state variables of all elements with their rates.
#[derive(Debug, Clone, Copy)]
pub struct ForceContext<'a> {
    /// s.
    pub t: f64,
    /// Kinematics of every body, in model order (index = body index).
    pub bodies: &'a [BodyKinematics],
    /// Parameter values, in `model.parameters` order.
    pub params: &'a [f64],
    /// First-order element states z of the whole system (see
    /// [`ForceElement::state_count`]); each element reads its own slice.
    pub states: &'a [f64],
    /// Their rates ż, same layout.
    pub state_rates: &'a [f64],
}

/// A wheelset's loads at an accepted state, for the assessment of a run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct WheelLoads {
    /// Distance of the wheelset along the track, m (`None` off a track).
    pub distance: Option<f64>,
    /// (Q, Y) per wheel (left, right): vertical load and lateral force on
    /// the rail, positive towards the field side, N.
    pub loads: [(f64, f64); 2],
    /// Nadal's limit of Y/Q for the flange angle and friction, –.
    pub nadal: Option<f64>,
}

/// A force element of the runtime.
pub trait ForceElement: std::fmt::Debug + Send {
    /// Long name (as in the model).
    fn name(&self) -> &str;
    /// Re-evaluates parameter-dependent constants.
    fn set_parameters(&mut self, params: &[f64]) -> Result<(), SimError>;
    /// Adds the element's wrenches to `wrenches` (one per body; forces on the
    /// ground are dropped).
    fn apply(&self, ctx: &ForceContext, wrenches: &mut [Wrench]) -> Result<(), SimError>;
    /// Names of the element's output variables, without the element's name
    /// (e.g. `F`, `x`); the writer prefixes `<element>.`. Units in brackets.
    fn output_names(&self) -> Vec<String>;
    /// Values of the outputs, appended to `out`, same order as the names.
    fn outputs(&self, ctx: &ForceContext, out: &mut Vec<f64>);
    /// Called once per accepted step (elements with state update here only);
    /// an error ends the run with its message (the rows written are kept).
    /// An element that changes its forces here must also return `true` from
    /// [`ForceElement::remembers_accepted_steps`].
    fn accept_step(&mut self, _ctx: &ForceContext) -> Result<(), SimError> {
        Ok(())
    }
    /// Whether [`ForceElement::accept_step`] can change the element's forces
    /// for the same state (stick anchors, friction modes, elastic rails):
    /// solvers then evaluate the end of a step again after accepting it.
    fn remembers_accepted_steps(&self) -> bool {
        false
    }
    /// Connects the element to the scenario's track (wheel–rail contact);
    /// elements that do not need the track ignore it.
    fn bind_track(&mut self, _binding: &TrackBinding) -> Result<(), SimError> {
        Ok(())
    }
    /// Whether the element cannot work without a track (see
    /// [`ForceElement::bind_track`]).
    fn needs_track(&self) -> bool {
        false
    }
    /// The wheel loads at an accepted state, for the EN 14363 assessment
    /// of the run ([`crate::run::assessment`]); `None` for elements that are
    /// not wheel–rail contacts.
    fn assessment_loads(&self, _ctx: &ForceContext) -> Option<WheelLoads> {
        None
    }
    /// The rigid contact geometry of a wheel–rail element bound to its
    /// track, for estimates such as the first guess of quasi-static curving
    /// ([`crate::analysis::curving`]): the nominal rolling radius r₀ (m) and
    /// the contact table's rigid contact functions (roll, axle height and
    /// both wheels' contacts at each lateral shift y of the wheelset, m,
    /// positive to the left, in increasing y; see
    /// [`RigidContact::rolling_radius_difference`]). `None` for other
    /// elements and before the track is bound.
    fn rigid_contact(&self) -> Option<(f64, Vec<RigidContact>)> {
        None
    }
    /// Number of first-order state variables the element adds to the system
    /// (a spring in series with a damper: its spring extension). They are
    /// appended to the generalized coordinates with zero mass-matrix rows; the
    /// element's state equations r(q, q̇, z, ż) = 0 take those rows of the
    /// force vector, so an implicit integrator solves them together with the
    /// equations of motion (Park's method treats them with the same
    /// derivative formula as q).
    fn state_count(&self) -> usize {
        0
    }
    /// Names of the states (without the element's name), units in brackets.
    fn state_names(&self) -> Vec<String> {
        Vec::new()
    }
    /// Tells the element where its states start in [`ForceContext::states`].
    fn set_state_offset(&mut self, _offset: usize) {}
    /// Initial states and rates consistent with the state equations at the
    /// initial kinematics, written to the element's own slices (`z`, `zdot`
    /// have `state_count` entries).
    fn initial_states(&self, _ctx: &ForceContext, _z: &mut [f64], _zdot: &mut [f64]) {}
    /// Residuals of the element's state equations (in force units, so that
    /// the rows scale like the equations of motion), `state_count` entries.
    fn state_residuals(&self, _ctx: &ForceContext, _out: &mut [f64]) {}
    /// Adds the element's approximate contribution to ∂Q/∂q and ∂Q/∂q̇ (Pogorelov 2005,
    /// Sect. 6, Eq. 31): its local stiffness and damping matrices mapped by the
    /// Jacobians of its attachment points, neglecting the derivatives of the
    /// body Jacobians Γ themselves. Uses the element's current state (mode,
    /// anchors) like [`ForceElement::apply`].
    fn add_jacobian(&self, ctx: &ForceContext, jac: &mut ForceJacobian) -> Result<(), SimError>;
}

/// Builds the runtime force elements of a model, each from its own model
/// spec ([`build_element`]).
pub fn build(model: &Model) -> Vec<Box<dyn ForceElement>> {
    model
        .forces
        .iter()
        .map(|f| build_element(f.name.clone(), &f.kind))
        .collect()
}

/// Builds the runtime force element `name` of the model spec `kind` (the
/// registry, one line per element; its body indices are those of the
/// [`ForceContext::bodies`] it will be evaluated with).
pub fn build_element(name: String, kind: &ForceKind) -> Box<dyn ForceElement> {
    match kind {
        ForceKind::Bipolar(spec) => Box::new(LinearBipolar::new(name, spec)),
        ForceKind::SeriesSpringDamper(spec) => Box::new(SeriesSpringDamper::new(name, spec)),
        ForceKind::Linear6(spec) => Box::new(Linear6::new(name, spec)),
        ForceKind::PointPlane(spec) => Box::new(PointPlane::new(name, spec)),
        ForceKind::Coulomb(spec) => Box::new(CoulombFriction::new(name, spec)),
        ForceKind::LoadFriction(spec) => Box::new(LoadFriction::new(name, spec)),
        ForceKind::Tabulated(spec) => Box::new(Tabulated::new(name, spec)),
        ForceKind::WheelRail(spec) => Box::new(WheelRailContact::new(name, spec)),
        ForceKind::Applied(spec) => Box::new(AppliedForce::new(name, spec)),
        ForceKind::TorsionSpring(spec) => Box::new(torsion::TorsionSpring::new(name, spec)),
    }
}
