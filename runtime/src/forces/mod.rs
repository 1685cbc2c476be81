//! Force elements (seed paper Sect. 3). Each element computes the wrenches it
//! applies to bodies from their kinematics; the system projects them on the
//! generalized coordinates with the body Jacobians (Q = Σ Γ_jᵀ F_j).
//!
//! Adding an element: write its module with a type implementing
//! [`ForceElement`], and add one arm to [`build`].

mod applied;
mod bipolar;
mod linear6;

pub use applied::AppliedForce;
pub use bipolar::LinearBipolar;
pub use linear6::Linear6;

use crate::equations::BodyKinematics;
use crate::system::SimError;
use nalgebra::{Matrix3, Vector3};
use railmbs_models::{BodyRef, Expr, ForceKind, Frame, Model};

/// Force (N) and moment about the centre of mass (N m) on one body, in SC0.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Wrench {
    pub force: Vector3<f64>,
    pub moment: Vector3<f64>,
}

/// What a force element sees: time, body kinematics (model order), parameters.
#[derive(Debug, Clone, Copy)]
pub struct ForceContext<'a> {
    /// s.
    pub t: f64,
    pub bodies: &'a [BodyKinematics],
    pub params: &'a [f64],
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
    /// Called once per accepted step (elements with state update here only).
    fn accept_step(&mut self, _ctx: &ForceContext) {}
}

/// Builds the runtime force elements of a model.
pub fn build(model: &Model) -> Vec<Box<dyn ForceElement>> {
    model
        .forces
        .iter()
        .map(|f| -> Box<dyn ForceElement> {
            let name = f.name.clone();
            match &f.kind {
                ForceKind::Bipolar { .. } => Box::new(LinearBipolar::new(name, &f.kind)),
                ForceKind::Linear6 { .. } => Box::new(Linear6::new(name, &f.kind)),
                ForceKind::Applied { .. } => Box::new(AppliedForce::new(name, &f.kind)),
            }
        })
        .collect()
}

/// A point fixed to a body (or to SC0), with its parameter expressions.
#[derive(Debug, Clone)]
pub(crate) struct Attachment {
    pub body: Option<usize>,
    expr: [Expr; 3],
    /// Body coordinates (or SC0 for the ground), m.
    pub local: Vector3<f64>,
}

impl Attachment {
    pub fn new(body: BodyRef, point: &[Expr; 3]) -> Self {
        Self {
            body: match body {
                BodyRef::Ground => None,
                BodyRef::Body(i) => Some(i),
            },
            expr: point.clone(),
            local: Vector3::zeros(),
        }
    }
    pub fn set_parameters(&mut self, params: &[f64], owner: &str) -> Result<(), SimError> {
        self.local = eval_vector(&self.expr, params, 0.0, owner)?;
        Ok(())
    }
    /// Position in SC0, m.
    pub fn position(&self, ctx: &ForceContext) -> Vector3<f64> {
        match self.body {
            Some(b) => ctx.bodies[b].point_position(&self.local),
            None => self.local,
        }
    }
    /// Velocity in SC0, m/s.
    pub fn velocity(&self, ctx: &ForceContext) -> Vector3<f64> {
        match self.body {
            Some(b) => ctx.bodies[b].point_velocity(&self.local),
            None => Vector3::zeros(),
        }
    }
}

/// A frame fixed to a body (or SC0): an attachment point plus an orientation.
#[derive(Debug, Clone)]
pub(crate) struct FrameAttachment {
    pub point: Attachment,
    angles: [Expr; 3],
    /// Orientation relative to the body frame.
    pub rotation: Matrix3<f64>,
}

impl FrameAttachment {
    pub fn new(body: BodyRef, frame: &Frame) -> Self {
        Self {
            point: Attachment::new(body, &frame.origin),
            angles: frame.rotation_xyz.clone(),
            rotation: Matrix3::identity(),
        }
    }
    pub fn set_parameters(&mut self, params: &[f64], owner: &str) -> Result<(), SimError> {
        self.point.set_parameters(params, owner)?;
        let a = eval_vector(&self.angles, params, 0.0, owner)?;
        self.rotation = crate::numeric::xyz_rotation([a[0], a[1], a[2]]);
        Ok(())
    }
    /// Direction cosines of the frame in SC0 and its angular velocity.
    pub fn orientation(&self, ctx: &ForceContext) -> (Matrix3<f64>, Vector3<f64>) {
        match self.point.body {
            Some(b) => (
                ctx.bodies[b].rotation * self.rotation,
                ctx.bodies[b].angular_velocity,
            ),
            None => (self.rotation, Vector3::zeros()),
        }
    }
}

/// Evaluates three expressions, refusing non-finite results.
pub(crate) fn eval_vector(
    e: &[Expr; 3],
    params: &[f64],
    t: f64,
    owner: &str,
) -> Result<Vector3<f64>, SimError> {
    let v = Vector3::new(e[0].eval(params, t), e[1].eval(params, t), e[2].eval(params, t));
    if v.iter().all(|x| x.is_finite()) {
        Ok(v)
    } else {
        Err(SimError::NonFinite {
            t,
            what: format!("force element \"{owner}\": a vector component is not finite: {v:?}"),
        })
    }
}

/// Evaluates one parameter expression, refusing non-finite results.
pub(crate) fn eval_scalar(e: &Expr, params: &[f64], owner: &str, field: &str) -> Result<f64, SimError> {
    let v = e.eval(params, 0.0);
    if v.is_finite() {
        Ok(v)
    } else {
        Err(SimError::Other(format!(
            "force element \"{owner}\": {field} is not finite ({v})"
        )))
    }
}

/// Adds force `f` acting at the SC0 point `p` to the wrench of `body`.
pub(crate) fn add_force(
    wrenches: &mut [Wrench],
    ctx: &ForceContext,
    body: Option<usize>,
    p: &Vector3<f64>,
    f: &Vector3<f64>,
) {
    if let Some(b) = body {
        let w = &mut wrenches[b];
        w.force += f;
        w.moment += (p - ctx.bodies[b].position).cross(f);
    }
}

/// Adds a pure moment to the wrench of `body`.
pub(crate) fn add_moment(wrenches: &mut [Wrench], body: Option<usize>, m: &Vector3<f64>) {
    if let Some(b) = body {
        wrenches[b].moment += m;
    }
}
