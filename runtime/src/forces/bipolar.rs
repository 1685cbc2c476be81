//! Linear bipolar viscoelastic element (seed paper Sect. 3.1).

use super::{
    Attachment, ForceContext, ForceElement, ForceJacobian, Wrench, add_force, eval_scalar,
};
use crate::system::SimError;
use nalgebra::{Matrix3, Vector3};
use railmbs_models::{Expr, ForceKind};

/// Spring–damper between two points: F = c (x − x0) + d ẋ + f0 along the line of
/// the points, x their distance (m). A positive F is tension: it pulls the
/// points together. At zero length the direction is undefined and the force is
/// zero (no NaN).
#[derive(Debug, Clone)]
pub struct LinearBipolar {
    name: String,
    ends: [Attachment; 2],
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

/// Length (m), its rate (m/s), unit vector from end 1 to end 2.
pub(crate) struct Deflection {
    pub length: f64,
    pub rate: f64,
    pub direction: Option<nalgebra::Vector3<f64>>,
}

impl LinearBipolar {
    /// From a model's `ForceKind::Bipolar`.
    pub fn new(name: String, kind: &ForceKind) -> Self {
        let ForceKind::Bipolar {
            body1,
            point1,
            body2,
            point2,
            stiffness,
            damping,
            preload,
            free_length,
        } = kind
        else {
            unreachable!("LinearBipolar::new takes a Bipolar element")
        };
        Self {
            name,
            ends: [
                Attachment::new(*body1, point1),
                Attachment::new(*body2, point2),
            ],
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

    fn deflection(&self, ctx: &ForceContext) -> Deflection {
        let d = self.ends[1].position(ctx) - self.ends[0].position(ctx);
        let length = d.norm();
        if length <= f64::MIN_POSITIVE {
            return Deflection {
                length: 0.0,
                rate: 0.0,
                direction: None,
            };
        }
        let e = d / length;
        let rate = (self.ends[1].velocity(ctx) - self.ends[0].velocity(ctx)).dot(&e);
        Deflection {
            length,
            rate,
            direction: Some(e),
        }
    }

    fn force(&self, x: &Deflection) -> f64 {
        self.stiffness * (x.length - self.free_length) + self.damping * x.rate + self.preload
    }

    /// Local Jacobians of the force on end 2, f₂ = −F e, with respect to
    /// d = P₂ − P₁ and ḋ (F the tension, x = |d|, e = d/x, ẋ = e·ḋ):
    /// ∂f₂/∂d = −[e (c e + d (E − e eᵀ) ḋ / x)ᵀ + (F/x)(E − e eᵀ)], ∂f₂/∂ḋ = −d e eᵀ.
    /// Zero at zero length (no direction, no force).
    pub(crate) fn local_jacobian(
        d: &Vector3<f64>,
        dd: &Vector3<f64>,
        force_rate: (f64, f64),
        force: impl Fn(f64, f64) -> f64,
    ) -> (Matrix3<f64>, Matrix3<f64>) {
        let x = d.norm();
        if x <= f64::MIN_POSITIVE {
            return (Matrix3::zeros(), Matrix3::zeros());
        }
        let e = d / x;
        let rate = e.dot(dd);
        let (c, dmp) = force_rate;
        let f = force(x, rate);
        let transverse = Matrix3::identity() - e * e.transpose();
        let g = c * e + dmp * (transverse * dd) / x;
        let kq = -(e * g.transpose() + (f / x) * transverse);
        let kv = -dmp * e * e.transpose();
        (kq, kv)
    }
}

impl ForceElement for LinearBipolar {
    fn name(&self) -> &str {
        &self.name
    }

    fn set_parameters(&mut self, params: &[f64]) -> Result<(), SimError> {
        for end in &mut self.ends {
            end.set_parameters(params, &self.name)?;
        }
        let [c, d, f0, x0] = &self.exprs;
        self.stiffness = eval_scalar(c, params, &self.name, "stiffness c")?;
        self.damping = eval_scalar(d, params, &self.name, "damping d")?;
        self.preload = eval_scalar(f0, params, &self.name, "preload f0")?;
        self.free_length = eval_scalar(x0, params, &self.name, "free length x0")?;
        Ok(())
    }

    fn apply(&self, ctx: &ForceContext, wrenches: &mut [Wrench]) -> Result<(), SimError> {
        let x = self.deflection(ctx);
        let Some(e) = x.direction else {
            return Ok(());
        };
        let f = self.force(&x) * e;
        let p1 = self.ends[0].position(ctx);
        let p2 = self.ends[1].position(ctx);
        add_force(wrenches, ctx, self.ends[0].body, &p1, &f);
        add_force(wrenches, ctx, self.ends[1].body, &p2, &(-f));
        Ok(())
    }

    fn output_names(&self) -> Vec<String> {
        vec!["F[N]".into(), "x[m]".into(), "v[m/s]".into()]
    }

    fn outputs(&self, ctx: &ForceContext, out: &mut Vec<f64>) {
        let x = self.deflection(ctx);
        let f = if x.direction.is_some() {
            self.force(&x)
        } else {
            0.0
        };
        out.extend([f, x.length, x.rate]);
    }

    fn add_jacobian(&self, ctx: &ForceContext, jac: &mut ForceJacobian) -> Result<(), SimError> {
        let p1 = self.ends[0].position(ctx);
        let p2 = self.ends[1].position(ctx);
        let dd = self.ends[1].velocity(ctx) - self.ends[0].velocity(ctx);
        let (kq, kv) =
            Self::local_jacobian(&(p2 - p1), &dd, (self.stiffness, self.damping), |x, v| {
                self.stiffness * (x - self.free_length) + self.damping * v + self.preload
            });
        jac.add_point_pair(self.ends[0].body, &p1, self.ends[1].body, &p2, &kq, &kv);
        Ok(())
    }
}
