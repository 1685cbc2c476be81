//! `Linear6`: the generalized linear 6×6 element (Pogorelov 2005, Sect. 3.2).

use super::{Checks, ForceSpec, ForceSyntax, body_ref};
use crate::expr::Expr;
use crate::load::{Cx, Lookup, Where};
use crate::model::{BodyRef, Frame};
use crate::raw::{Value, Vec3, Vec6, zero3};
use serde::Deserialize;

/// Generalized linear 6×6 elastic and dissipative element (Pogorelov 2005,
/// Sect. 3.2) between frame 1 on body 1 and frame 2 on body 2. The relative
/// displacement (three translations, three small rotations, in frame 1) is
/// δ = (A₁ᵀ(r₂ − r₁), g_rot) and the wrench on body 2, in frame 1, is
/// −(C δ + D δ̇ + preload); body 1 gets the reaction.
#[derive(Debug, Clone, PartialEq)]
pub struct Linear6 {
    /// Body of frame 1.
    pub body1: BodyRef,
    /// Frame 1, fixed to `body1`.
    pub frame1: Frame,
    /// Body of frame 2.
    pub body2: BodyRef,
    /// Frame 2, fixed to `body2`.
    pub frame2: Frame,
    /// Row-major 6×6, N/m, N/rad, N m/m, N m/rad.
    pub stiffness: Box<[Expr; 36]>,
    /// Row-major 6×6, damping units as stiffness per second.
    pub damping: Box<[Expr; 36]>,
    /// Static preload wrench (N, N m), in frame 1.
    pub preload: [Expr; 6],
}

/// A 6×6 matrix of a `Linear6` element, as written.
#[derive(Debug, Deserialize)]
#[serde(rename = "Matrix6")]
pub(crate) enum RawMatrix6 {
    Diag(Vec6),
    Full(Vec<Value>),
    /// A coil spring between its lower and upper plates (frames at the lower
    /// plate): vertical, shear, bending and torsion stiffness (or damping)
    /// and the height.
    VerticalSpring {
        vertical: Value,
        shear: Value,
        bending: Value,
        torsion: Value,
        height: Value,
    },
}

fn zero_matrix() -> RawMatrix6 {
    RawMatrix6::Diag(Default::default())
}

/// `Linear6(name, body1, point1, rotation1, body2, point2, rotation2,
/// stiffness, damping, preload)`.
#[derive(Debug, Deserialize)]
#[serde(rename = "Linear6", deny_unknown_fields)]
pub(crate) struct RawLinear6 {
    name: String,
    body1: String,
    #[serde(default = "zero3")]
    point1: Vec3,
    #[serde(default = "zero3")]
    rotation1: Vec3,
    body2: String,
    #[serde(default = "zero3")]
    point2: Vec3,
    #[serde(default = "zero3")]
    rotation2: Vec3,
    stiffness: RawMatrix6,
    #[serde(default = "zero_matrix")]
    damping: RawMatrix6,
    #[serde(default)]
    preload: Vec6,
}

impl ForceSyntax for RawLinear6 {
    type Spec = Linear6;
    fn name(&self) -> &str {
        &self.name
    }
    fn resolve(&self, cx: &mut Cx, w: &Where, lookup: &Lookup) -> Linear6 {
        let (body1, frame1) = cx.attach_frame(
            w,
            ("body1", &self.body1),
            ("point1", &self.point1),
            "rotation1",
            &self.rotation1,
            lookup,
        );
        let (body2, frame2) = cx.attach_frame(
            w,
            ("body2", &self.body2),
            ("point2", &self.point2),
            "rotation2",
            &self.rotation2,
            lookup,
        );
        let stiffness = matrix6(cx, w, "stiffness", &self.stiffness);
        let damping = matrix6(cx, w, "damping", &self.damping);
        let preload = cx.vec6(w, "preload", &self.preload);
        Linear6 {
            body1,
            frame1,
            body2,
            frame2,
            stiffness,
            damping,
            preload,
        }
    }
}

impl ForceSpec for Linear6 {
    fn exprs_mut(&mut self, f: &mut dyn FnMut(&mut Expr)) {
        self.frame1.exprs_mut(f);
        self.frame2.exprs_mut(f);
        self.stiffness
            .iter_mut()
            .chain(self.damping.iter_mut())
            .chain(self.preload.iter_mut())
            .for_each(f);
    }
    fn bodies_mut(&mut self, f: &mut dyn FnMut(&mut usize)) {
        body_ref(&mut self.body1, f);
        body_ref(&mut self.body2, f);
    }
    fn check(&self, _c: &mut Checks) {}
}

/// A 6×6 matrix as written: diagonal, full (row-major) or a coil spring's.
fn matrix6(cx: &mut Cx, w: &Where, key: &str, m: &RawMatrix6) -> Box<[Expr; 36]> {
    let mut out: Box<[Expr; 36]> = Box::new(std::array::from_fn(|_| Expr::Num(0.0)));
    match m {
        RawMatrix6::Diag(d) => {
            let d = cx.vec6(w, key, d);
            for (k, e) in d.into_iter().enumerate() {
                out[7 * k] = e;
            }
        }
        RawMatrix6::VerticalSpring {
            vertical,
            shear,
            bending,
            torsion,
            height,
        } => {
            // Energy ½ c_s |s|² + ½ c_b (θx² + θy²) + ½ c_z u_z² + ½ c_t θz²,
            // the shear s = (u_x + θy H/2, u_y − θx H/2) being the offset of
            // the upper plate's material point at mid-height (frames at the
            // lower plate; u, θ the upper body's displacement and rotation
            // there). Its Hessian couples shear and tilt by ±c_s H/2.
            let e = |this: &mut Cx, name: &str, v: &Value| {
                this.expr(w, &format!("{key}.{name}"), key, v, false)
            };
            let cz = e(cx, "vertical", vertical);
            let cs = e(cx, "shear", shear);
            let cb = e(cx, "bending", bending);
            let ct = e(cx, "torsion", torsion);
            let h = e(cx, "height", height);
            let half = Expr::Div(Box::new(h), Box::new(Expr::Num(2.0)));
            let cs_half = Expr::Mul(Box::new(cs.clone()), Box::new(half.clone()));
            let tilt = Expr::Add(
                Box::new(cb),
                Box::new(Expr::Mul(Box::new(cs_half.clone()), Box::new(half))),
            );
            out[0] = cs.clone();
            out[7] = cs;
            out[14] = cz;
            out[21] = tilt.clone();
            out[28] = tilt;
            out[35] = ct;
            out[4] = cs_half.clone(); // (u_x, θy)
            out[24] = cs_half.clone();
            out[9] = Expr::Neg(Box::new(cs_half.clone())); // (u_y, θx)
            out[19] = Expr::Neg(Box::new(cs_half));
        }
        RawMatrix6::Full(v) => {
            if v.len() != 36 {
                cx.err(
                    w,
                    Some(key),
                    None,
                    format!(
                        "{key} must have 36 values (6×6, row-major), got {}",
                        v.len()
                    ),
                );
            }
            for (k, x) in v.iter().take(36).enumerate() {
                out[k] = cx.expr(w, &format!("{key}[{}][{}]", k / 6, k % 6), key, x, false);
            }
        }
    }
    out
}
