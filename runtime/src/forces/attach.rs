//! Helpers of the force elements: points and frames fixed to bodies, the
//! evaluation of their parameter expressions, and adding forces and moments
//! to the bodies' wrenches.

use super::{ForceContext, Wrench};
use crate::system::SimError;
use nalgebra::{DMatrix, Matrix3, Vector3};
use railmbs_models::{BodyRef, Expr, Frame};

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
    let v = Vector3::new(
        e[0].eval(params, t),
        e[1].eval(params, t),
        e[2].eval(params, t),
    );
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
pub(crate) fn eval_scalar(
    e: &Expr,
    params: &[f64],
    owner: &str,
    field: &str,
) -> Result<f64, SimError> {
    let v = e.eval(params, 0.0);
    if v.is_finite() {
        Ok(v)
    } else {
        Err(SimError::Other(format!(
            "force element \"{owner}\": {field} is not finite ({v})"
        )))
    }
}

/// Adds the generalized force Γ_bᵀ w of the wrench `w` on body `b` to `out`:
/// `gamma` holds the stacked body Jacobians (rows 6b..6b+6 of body b, one
/// column per coordinate); entries of `out` beyond its columns (first-order
/// element states) take nothing.
pub(crate) fn add_generalized_force(gamma: &DMatrix<f64>, b: usize, w: &Wrench, out: &mut [f64]) {
    let comps = [
        w.force.x, w.force.y, w.force.z, w.moment.x, w.moment.y, w.moment.z,
    ];
    if comps.iter().all(|c| *c == 0.0) {
        return;
    }
    for (i, qi) in out.iter_mut().take(gamma.ncols()).enumerate() {
        let mut s = 0.0;
        for (k, c) in comps.iter().enumerate() {
            s += gamma[(6 * b + k, i)] * c;
        }
        *qi += s;
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
