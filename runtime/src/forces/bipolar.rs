//! Two-point (bipolar) elements: the geometry shared by every element acting
//! along the line of two points ([`TwoPoint`]), and the linear viscoelastic
//! element (Pogorelov 2005, Sect. 3.1).

use super::{
    Attachment, ForceContext, ForceElement, ForceJacobian, Wrench, add_force, eval_scalar,
};
use crate::system::SimError;
use nalgebra::{Matrix3, Vector3};
use railmbs_models::Expr;
use railmbs_models::forces::PointPair;

/// Two attachment points and the kinematics of their distance.
#[derive(Debug, Clone)]
pub(crate) struct TwoPoint {
    ends: [Attachment; 2],
}

/// Distance x (m), its rate (m/s), unit vector from end 1 to end 2 (None at
/// zero length), the end positions (SC0).
pub(crate) struct PairState {
    pub length: f64,
    pub rate: f64,
    pub direction: Option<Vector3<f64>>,
    pub p1: Vector3<f64>,
    pub p2: Vector3<f64>,
    pub relative_velocity: Vector3<f64>,
}

impl TwoPoint {
    /// The ends of the model's point pair.
    pub fn new(ends: &PointPair) -> Self {
        Self {
            ends: [
                Attachment::new(ends.body1, &ends.point1),
                Attachment::new(ends.body2, &ends.point2),
            ],
        }
    }

    /// The two attachment points.
    pub fn ends(&self) -> &[Attachment; 2] {
        &self.ends
    }

    pub fn set_parameters(&mut self, params: &[f64], owner: &str) -> Result<(), SimError> {
        for e in &mut self.ends {
            e.set_parameters(params, owner)?;
        }
        Ok(())
    }

    pub fn state(&self, ctx: &ForceContext) -> PairState {
        let p1 = self.ends[0].position(ctx);
        let p2 = self.ends[1].position(ctx);
        let dv = self.ends[1].velocity(ctx) - self.ends[0].velocity(ctx);
        let d = p2 - p1;
        let length = d.norm();
        if length <= f64::MIN_POSITIVE {
            return PairState {
                length: 0.0,
                rate: 0.0,
                direction: None,
                p1,
                p2,
                relative_velocity: dv,
            };
        }
        let e = d / length;
        PairState {
            length,
            rate: dv.dot(&e),
            direction: Some(e),
            p1,
            p2,
            relative_velocity: dv,
        }
    }

    /// Applies the tension `f` (N, positive pulls the ends together).
    pub fn apply(&self, ctx: &ForceContext, s: &PairState, f: f64, wrenches: &mut [Wrench]) {
        let Some(e) = s.direction else { return };
        let fv = f * e;
        add_force(wrenches, ctx, self.ends[0].body, &s.p1, &fv);
        add_force(wrenches, ctx, self.ends[1].body, &s.p2, &(-fv));
    }

    /// Adds the Jacobian of a tension F(x, ẋ) with ∂F/∂x = `dfdx`, ∂F/∂ẋ =
    /// `dfdv`: for f₂ = −F e, ∂f₂/∂d = −[e (F_x e + F_v (E − e eᵀ) ḋ/x)ᵀ +
    /// (F/x)(E − e eᵀ)] and ∂f₂/∂ḋ = −F_v e eᵀ.
    pub fn add_jacobian(
        &self,
        s: &PairState,
        f: f64,
        dfdx: f64,
        dfdv: f64,
        jac: &mut ForceJacobian,
    ) {
        let Some(e) = s.direction else { return };
        let (kq, kv) = bipolar_jacobian(&e, s.length, &s.relative_velocity, f, dfdx, dfdv);
        jac.add_point_pair(self.ends[0].body, &s.p1, self.ends[1].body, &s.p2, &kq, &kv);
    }
}

/// Local Jacobians (∂f₂/∂d, ∂f₂/∂ḋ) of a bipolar tension F(x, ẋ), see
/// [`TwoPoint::add_jacobian`].
pub(crate) fn bipolar_jacobian(
    e: &Vector3<f64>,
    x: f64,
    dd: &Vector3<f64>,
    f: f64,
    dfdx: f64,
    dfdv: f64,
) -> (Matrix3<f64>, Matrix3<f64>) {
    let transverse = Matrix3::identity() - e * e.transpose();
    let g = dfdx * e + dfdv * (transverse * dd) / x;
    let kq = -(e * g.transpose() + (f / x) * transverse);
    let kv = -dfdv * e * e.transpose();
    (kq, kv)
}

/// Spring–damper between two points: F = c (x − x0) + d ẋ + f0 along the line of
/// the points, x their distance (m). A positive F is tension: it pulls the
/// points together. At zero length the direction is undefined and the force is
/// zero (no NaN).
#[derive(Debug, Clone)]
pub struct LinearBipolar {
    name: String,
    pair: TwoPoint,
    exprs: [Expr; 4],
    /// N/m.
    pub stiffness: f64,
    /// N s/m.
    pub damping: f64,
    /// N.
    pub preload: f64,
    /// m.
    pub free_length: f64,
}

impl LinearBipolar {
    /// From the model's `Bipolar` spec (`railmbs_models::forces::Bipolar`).
    pub fn new(name: String, spec: &railmbs_models::forces::Bipolar) -> Self {
        let railmbs_models::forces::Bipolar {
            ends,
            stiffness,
            damping,
            preload,
            free_length,
        } = spec;
        Self {
            name,
            pair: TwoPoint::new(ends),
            exprs: [
                stiffness.clone(),
                damping.clone(),
                preload.clone(),
                free_length.clone(),
            ],
            stiffness: 0.0,
            damping: 0.0,
            preload: 0.0,
            free_length: 0.0,
        }
    }

    /// Tension F (N); zero at zero length.
    fn force(&self, s: &PairState) -> f64 {
        if s.direction.is_none() {
            return 0.0;
        }
        self.stiffness * (s.length - self.free_length) + self.damping * s.rate + self.preload
    }
}

impl ForceElement for LinearBipolar {
    fn name(&self) -> &str {
        &self.name
    }

    fn set_parameters(&mut self, params: &[f64]) -> Result<(), SimError> {
        self.pair.set_parameters(params, &self.name)?;
        let [c, d, f0, x0] = &self.exprs;
        self.stiffness = eval_scalar(c, params, &self.name, "stiffness c")?;
        self.damping = eval_scalar(d, params, &self.name, "damping d")?;
        self.preload = eval_scalar(f0, params, &self.name, "preload f0")?;
        self.free_length = eval_scalar(x0, params, &self.name, "free length x0")?;
        Ok(())
    }

    fn apply(&self, ctx: &ForceContext, wrenches: &mut [Wrench]) -> Result<(), SimError> {
        let s = self.pair.state(ctx);
        self.pair.apply(ctx, &s, self.force(&s), wrenches);
        Ok(())
    }

    fn output_names(&self) -> Vec<String> {
        ["F[N]", "x[m]", "v[m/s]", "E[J]", "P[W]"]
            .iter()
            .map(|s| s.to_string())
            .collect()
    }

    /// Force, length, rate; the elastic energy ½c(x − x0)² + f0(x − x0) (J)
    /// and the damper's dissipated power d ẋ² (W).
    fn outputs(&self, ctx: &ForceContext, out: &mut Vec<f64>) {
        let s = self.pair.state(ctx);
        let u = s.length - self.free_length;
        out.extend([
            self.force(&s),
            s.length,
            s.rate,
            0.5 * self.stiffness * u * u + self.preload * u,
            self.damping * s.rate * s.rate,
        ]);
    }

    fn add_jacobian(&self, ctx: &ForceContext, jac: &mut ForceJacobian) -> Result<(), SimError> {
        let s = self.pair.state(ctx);
        self.pair
            .add_jacobian(&s, self.force(&s), self.stiffness, self.damping, jac);
        Ok(())
    }
}
