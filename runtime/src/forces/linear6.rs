//! Generalized linear 6×6 elastic and dissipative element (Pogorelov 2005, Sect. 3.2).

use super::{
    Characteristic, ForceContext, ForceElement, ForceJacobian, FrameAttachment, Wrench, add_force,
    add_moment, eval_scalar,
};
use crate::system::SimError;
use nalgebra::{Matrix6, Vector3, Vector6};
use railmbs_models::Expr;

/// Linear element between frame 1 (on body 1) and frame 2 (on body 2).
///
/// Relative displacement in frame 1: δ = (A₁ᵀ(P₂ − P₁), θ) with θ the small
/// relative rotation (antisymmetric part of A₁ᵀA₂: θ_x = (R_zy − R_yz)/2, …);
/// its rate δ̇ = (A₁ᵀ(v_P₂ − v_P₁ − ω₁×(P₂ − P₁)), A₁ᵀ(ω₂ − ω₁)). The wrench on
/// body 2, in frame 1 and acting at P₂, is W = −(C δ + D δ̇ + W₀); body 1 gets
/// the reaction at the same point, so angular momentum is conserved.
#[derive(Debug, Clone)]
pub struct Linear6 {
    name: String,
    frames: [FrameAttachment; 2],
    stiffness_expr: Box<[Expr; 36]>,
    damping_expr: Box<[Expr; 36]>,
    preload_expr: [Expr; 6],
    /// N/m, N/rad, N m/m, N m/rad.
    pub stiffness: Matrix6<f64>,
    /// Damping matrix D, multiplying δ̇: N s/m, N s/rad, N m s/m,
    /// N m s/rad (same layout as `stiffness`).
    pub damping: Matrix6<f64>,
    /// Preload W₀ (force N, then moment N m), in frame 1.
    pub preload: Vector6<f64>,
    /// Nonlinear characteristic f(δx) replacing the stiffness term C₀₀ δx
    /// of the x force (a coupler's draw gear and buffers).
    longitudinal: Option<Characteristic>,
}

impl Linear6 {
    /// From the model's `Linear6` spec (`railmbs_models::forces::Linear6`).
    pub fn new(name: String, spec: &railmbs_models::forces::Linear6) -> Self {
        let railmbs_models::forces::Linear6 {
            body1,
            frame1,
            body2,
            frame2,
            stiffness,
            damping,
            preload,
        } = spec;
        Self {
            name,
            frames: [
                FrameAttachment::new(*body1, frame1),
                FrameAttachment::new(*body2, frame2),
            ],
            stiffness_expr: stiffness.clone(),
            damping_expr: damping.clone(),
            preload_expr: preload.clone(),
            stiffness: Matrix6::zeros(),
            damping: Matrix6::zeros(),
            preload: Vector6::zeros(),
            longitudinal: None,
        }
    }

    /// Replaces the stiffness term C₀₀ δx of the x force by f(δx).
    pub fn with_longitudinal(mut self, f: Characteristic) -> Self {
        self.longitudinal = Some(f);
        self
    }

    /// The stiffness matrix at deflection δ: C, with C₀₀ = f′(δx) when the x
    /// characteristic is nonlinear.
    fn tangent_stiffness(&self, x: &Vector6<f64>) -> Matrix6<f64> {
        let mut c = self.stiffness;
        if let Some(f) = &self.longitudinal {
            c[(0, 0)] = f.eval(x[0]).1;
        }
        c
    }

    /// Relative displacement and its rate, in frame 1.
    fn deflection(&self, ctx: &ForceContext) -> (Vector6<f64>, Vector6<f64>) {
        let p1 = self.frames[0].point.position(ctx);
        let p2 = self.frames[1].point.position(ctx);
        let (a1, w1) = self.frames[0].orientation(ctx);
        let (a2, w2) = self.frames[1].orientation(ctx);
        let d = p2 - p1;
        let r = a1.transpose() * a2;
        let theta = Vector3::new(
            0.5 * (r[(2, 1)] - r[(1, 2)]),
            0.5 * (r[(0, 2)] - r[(2, 0)]),
            0.5 * (r[(1, 0)] - r[(0, 1)]),
        );
        let dv =
            self.frames[1].point.velocity(ctx) - self.frames[0].point.velocity(ctx) - w1.cross(&d);
        let lin = a1.transpose() * d;
        let lin_rate = a1.transpose() * dv;
        let ang_rate = a1.transpose() * (w2 - w1);
        (
            Vector6::new(lin.x, lin.y, lin.z, theta.x, theta.y, theta.z),
            Vector6::new(
                lin_rate.x, lin_rate.y, lin_rate.z, ang_rate.x, ang_rate.y, ang_rate.z,
            ),
        )
    }

    /// Elastic energy ½ δᵀ C δ + W₀ᵀ δ (J; the x term by the nonlinear
    /// characteristic's integral when there is one; C symmetric, small
    /// relative rotations) and the damper's dissipated power δ̇ᵀ D δ̇ (W).
    fn energy_and_dissipation(&self, ctx: &ForceContext) -> (f64, f64) {
        let (x, xd) = self.deflection(ctx);
        let mut c = self.stiffness;
        let mut energy = 0.0;
        if let Some(f) = &self.longitudinal {
            energy += f.energy(x[0]);
            c[(0, 0)] = 0.0;
        }
        energy += 0.5 * x.dot(&(c * x)) + self.preload.dot(&x);
        (energy, xd.dot(&(self.damping * xd)))
    }

    fn wrench_in_frame1(&self, ctx: &ForceContext) -> Vector6<f64> {
        let (x, xd) = self.deflection(ctx);
        let mut elastic = self.stiffness * x;
        if let Some(f) = &self.longitudinal {
            elastic[0] += f.eval(x[0]).0 - self.stiffness[(0, 0)] * x[0];
        }
        -(elastic + self.damping * xd + self.preload)
    }
}

impl ForceElement for Linear6 {
    fn name(&self) -> &str {
        &self.name
    }

    fn set_parameters(&mut self, params: &[f64]) -> Result<(), SimError> {
        for f in &mut self.frames {
            f.set_parameters(params, &self.name)?;
        }
        for k in 0..36 {
            self.stiffness[(k / 6, k % 6)] =
                eval_scalar(&self.stiffness_expr[k], params, &self.name, "stiffness")?;
            self.damping[(k / 6, k % 6)] =
                eval_scalar(&self.damping_expr[k], params, &self.name, "damping")?;
        }
        for k in 0..6 {
            self.preload[k] = eval_scalar(&self.preload_expr[k], params, &self.name, "preload")?;
        }
        Ok(())
    }

    fn apply(&self, ctx: &ForceContext, wrenches: &mut [Wrench]) -> Result<(), SimError> {
        let w = self.wrench_in_frame1(ctx);
        let (a1, _) = self.frames[0].orientation(ctx);
        let f = a1 * Vector3::new(w[0], w[1], w[2]);
        let m = a1 * Vector3::new(w[3], w[4], w[5]);
        let p2 = self.frames[1].point.position(ctx);
        add_force(wrenches, ctx, self.frames[1].point.body, &p2, &f);
        add_moment(wrenches, self.frames[1].point.body, &m);
        add_force(wrenches, ctx, self.frames[0].point.body, &p2, &(-f));
        add_moment(wrenches, self.frames[0].point.body, &(-m));
        Ok(())
    }

    fn output_names(&self) -> Vec<String> {
        [
            "Fx[N]", "Fy[N]", "Fz[N]", "Mx[N m]", "My[N m]", "Mz[N m]", "E[J]", "P[W]",
        ]
        .iter()
        .map(|s| s.to_string())
        .collect()
    }

    /// The wrench body 1 exerts on body 2, in frame 1; the elastic energy
    /// and the damper's dissipated power.
    fn outputs(&self, ctx: &ForceContext, out: &mut Vec<f64>) {
        out.extend(self.wrench_in_frame1(ctx).iter());
        let (e, p) = self.energy_and_dissipation(ctx);
        out.extend([e, p]);
    }

    /// W = −(C δ + D δ̇ + W₀): ∂W/∂δ = −C (with C₀₀ = f′(δx) for a nonlinear
    /// x characteristic), ∂W/∂δ̇ = −D, mapped by the relative motion Jacobian
    /// of the frames (exact at zero deflection and rate).
    fn add_jacobian(&self, ctx: &ForceContext, jac: &mut ForceJacobian) -> Result<(), SimError> {
        let p2 = self.frames[1].point.position(ctx);
        let (a1, _) = self.frames[0].orientation(ctx);
        let c = if self.longitudinal.is_some() {
            self.tangent_stiffness(&self.deflection(ctx).0)
        } else {
            self.stiffness
        };
        jac.add_frame_pair(
            self.frames[0].point.body,
            self.frames[1].point.body,
            &p2,
            &a1,
            &(-c),
            &(-self.damping),
        );
        Ok(())
    }
}
