//! Applied force and torque (constant or a function of time).

use super::{
    Attachment, ForceContext, ForceElement, ForceJacobian, Wrench, add_force, add_moment,
    eval_vector,
};
use crate::system::SimError;
use nalgebra::Vector3;
use railmbs_models::{BodyRef, Expr, VectorFrame};

/// A force (N) at a body point and a torque (N m), given in SC0 or in the body
/// frame, each component an expression that may depend on time.
#[derive(Debug, Clone)]
pub struct AppliedForce {
    name: String,
    point: Attachment,
    force: [Expr; 3],
    torque: [Expr; 3],
    frame: VectorFrame,
}

impl AppliedForce {
    /// From the model's `Applied` spec (`railmbs_models::forces::Applied`).
    pub fn new(name: String, spec: &railmbs_models::forces::Applied) -> Self {
        let railmbs_models::forces::Applied {
            body,
            point,
            force,
            torque,
            frame,
        } = spec;
        Self {
            name,
            point: Attachment::new(BodyRef::Body(*body), point),
            force: force.clone(),
            torque: torque.clone(),
            frame: *frame,
        }
    }

    fn vectors(&self, ctx: &ForceContext) -> Result<(Vector3<f64>, Vector3<f64>), SimError> {
        let f = eval_vector(&self.force, ctx.params, ctx.t, &self.name)?;
        let m = eval_vector(&self.torque, ctx.params, ctx.t, &self.name)?;
        Ok(match (self.frame, self.point.body) {
            (VectorFrame::Body, Some(b)) => {
                let a = ctx.bodies[b].rotation;
                (a * f, a * m)
            }
            _ => (f, m),
        })
    }
}

impl ForceElement for AppliedForce {
    fn name(&self) -> &str {
        &self.name
    }

    fn set_parameters(&mut self, params: &[f64]) -> Result<(), SimError> {
        self.point.set_parameters(params, &self.name)
    }

    fn apply(&self, ctx: &ForceContext, wrenches: &mut [Wrench]) -> Result<(), SimError> {
        let (f, m) = self.vectors(ctx)?;
        let p = self.point.position(ctx);
        add_force(wrenches, ctx, self.point.body, &p, &f);
        add_moment(wrenches, self.point.body, &m);
        Ok(())
    }

    fn output_names(&self) -> Vec<String> {
        ["Fx[N]", "Fy[N]", "Fz[N]"]
            .iter()
            .map(|s| s.to_string())
            .collect()
    }

    /// A prescribed force does not depend on q or q̇ (a body-frame force turns
    /// with the body; that term involves ∂Γ/∂q and is neglected as in Sect. 6).
    fn add_jacobian(&self, _ctx: &ForceContext, _jac: &mut ForceJacobian) -> Result<(), SimError> {
        Ok(())
    }

    fn outputs(&self, ctx: &ForceContext, out: &mut Vec<f64>) {
        let f = self
            .vectors(ctx)
            .map(|(f, _)| f)
            .unwrap_or(Vector3::repeat(f64::NAN));
        out.extend(f.iter());
    }
}
