//! Torsion spring–damper between two bodies about an axis fixed to body 1.

use super::{
    ForceContext, ForceElement, ForceJacobian, Wrench, add_moment, eval_scalar, eval_vector,
};
use crate::system::SimError;
use nalgebra::{Matrix3, Matrix6, Vector3};
use railmbs_models::{BodyRef, Expr};

/// Rotational spring c and damper d about the unit axis e fixed to body 1,
/// relaxed at the angle φ0: the moment on body 2 is −M e with
/// M = c (φ − φ0) + d φ̇ (N m), body 1 gets +M e.
///
/// φ is the rotation of body 2 relative to body 1 about e: with u ⟂ e and
/// v = e × u (body 1's frame) and R = A₁ᵀA₂, φ = atan2(v·Ru, u·Ru), exact
/// when the relative rotation is about e (a revolute joint) and in (−π, π];
/// φ̇ = e·A₁ᵀ(ω₂ − ω₁) (rad/s).
#[derive(Debug, Clone)]
pub struct TorsionSpring {
    name: String,
    bodies: [Option<usize>; 2],
    exprs: [Expr; 3],
    axis_expr: [Expr; 3],
    /// Unit axis in body 1's frame.
    axis: Vector3<f64>,
    /// A unit vector ⟂ `axis` (body 1's frame), from which φ is measured.
    reference: Vector3<f64>,
    /// N m/rad.
    pub stiffness: f64,
    /// N m s/rad.
    pub damping: f64,
    /// rad.
    pub preload_angle: f64,
}

/// Index of a body, `None` for the ground.
fn body_index(b: BodyRef) -> Option<usize> {
    match b {
        BodyRef::Ground => None,
        BodyRef::Body(i) => Some(i),
    }
}

impl TorsionSpring {
    /// From the model's `TorsionSpring` spec (`railmbs_models::forces::TorsionSpring`).
    pub fn new(name: String, spec: &railmbs_models::forces::TorsionSpring) -> Self {
        Self {
            name,
            bodies: [body_index(spec.body1), body_index(spec.body2)],
            exprs: [
                spec.stiffness.clone(),
                spec.damping.clone(),
                spec.preload_angle.clone(),
            ],
            axis_expr: spec.axis.clone(),
            axis: Vector3::z(),
            reference: Vector3::x(),
            stiffness: 0.0,
            damping: 0.0,
            preload_angle: 0.0,
        }
    }

    /// Orientation (A, SC0) and angular velocity (rad/s) of body `k` (0, 1).
    fn orientation(&self, ctx: &ForceContext, k: usize) -> (Matrix3<f64>, Vector3<f64>) {
        match self.bodies[k] {
            Some(b) => (ctx.bodies[b].rotation, ctx.bodies[b].angular_velocity),
            None => (Matrix3::identity(), Vector3::zeros()),
        }
    }

    /// The angle φ (rad), its rate φ̇ (rad/s) and body 1's orientation A₁.
    fn angle(&self, ctx: &ForceContext) -> (f64, f64, Matrix3<f64>) {
        let (a1, w1) = self.orientation(ctx, 0);
        let (a2, w2) = self.orientation(ctx, 1);
        let ru = a1.transpose() * a2 * self.reference;
        let v = self.axis.cross(&self.reference);
        let phi = v.dot(&ru).atan2(self.reference.dot(&ru));
        let rate = self.axis.dot(&(a1.transpose() * (w2 - w1)));
        (phi, rate, a1)
    }

    /// The moment M = c (φ − φ0) + d φ̇ (N m) at angle `phi` and rate `rate`.
    fn moment(&self, phi: f64, rate: f64) -> f64 {
        self.stiffness * (phi - self.preload_angle) + self.damping * rate
    }
}

impl ForceElement for TorsionSpring {
    fn name(&self) -> &str {
        &self.name
    }

    fn set_parameters(&mut self, params: &[f64]) -> Result<(), SimError> {
        let [c, d, phi0] = &self.exprs;
        self.stiffness = eval_scalar(c, params, &self.name, "stiffness c")?;
        self.damping = eval_scalar(d, params, &self.name, "damping d")?;
        self.preload_angle = eval_scalar(phi0, params, &self.name, "preload angle phi0")?;
        let e = eval_vector(&self.axis_expr, params, 0.0, &self.name)?;
        let Some(e) = e.try_normalize(0.0) else {
            return Err(SimError::Other(format!(
                "force element \"{}\": the axis is zero",
                self.name
            )));
        };
        // The reference direction: e × x, or e × y when e is close to x.
        let across = e.cross(&Vector3::x());
        let u = if across.norm() > 0.5 {
            across
        } else {
            e.cross(&Vector3::y())
        };
        self.axis = e;
        self.reference = u.normalize();
        Ok(())
    }

    fn apply(&self, ctx: &ForceContext, wrenches: &mut [Wrench]) -> Result<(), SimError> {
        let (phi, rate, a1) = self.angle(ctx);
        let m = self.moment(phi, rate) * (a1 * self.axis);
        add_moment(wrenches, self.bodies[1], &-m);
        add_moment(wrenches, self.bodies[0], &m);
        Ok(())
    }

    fn output_names(&self) -> Vec<String> {
        ["M[N m]", "phi[rad]", "omega[rad/s]", "E[J]", "P[W]"]
            .iter()
            .map(|s| s.to_string())
            .collect()
    }

    /// Moment, angle, rate; the elastic energy ½c(φ − φ0)² (J) and the
    /// damper's dissipated power d φ̇² (W).
    fn outputs(&self, ctx: &ForceContext, out: &mut Vec<f64>) {
        let (phi, rate, _) = self.angle(ctx);
        let u = phi - self.preload_angle;
        out.extend([
            self.moment(phi, rate),
            phi,
            rate,
            0.5 * self.stiffness * u * u,
            self.damping * rate * rate,
        ]);
    }

    /// In body 1's frame the moment on body 2 is −(c (φ − φ0) + d φ̇) e with
    /// ∂φ/∂θ = ∂φ̇/∂θ̇ = eᵀ for a small relative rotation θ: the local
    /// Jacobians are −c eeᵀ and −d eeᵀ on the rotation rows (Pogorelov 2005,
    /// Sect. 6; the turning of e with body 1, proportional to the moment, is
    /// neglected as the other elements neglect ∂Γ/∂q).
    fn add_jacobian(&self, ctx: &ForceContext, jac: &mut ForceJacobian) -> Result<(), SimError> {
        let (a1, _) = self.orientation(ctx, 0);
        let eet = self.axis * self.axis.transpose();
        let mut kq = Matrix6::zeros();
        let mut kv = Matrix6::zeros();
        kq.fixed_view_mut::<3, 3>(3, 3)
            .copy_from(&(-self.stiffness * eet));
        kv.fixed_view_mut::<3, 3>(3, 3)
            .copy_from(&(-self.damping * eet));
        // A pure moment: the point of the translation rows does not matter.
        jac.add_frame_pair(
            self.bodies[0],
            self.bodies[1],
            &Vector3::zeros(),
            &a1,
            &kq,
            &kv,
        );
        Ok(())
    }
}
