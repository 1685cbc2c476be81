//! `TorsionSpring`: a rotational spring–damper between two bodies about an axis.
//!
//! ```text
//! // Moment −(c (φ − φ0) + d φ̇) about `axis` (body1's frame, default z) on
//! // body2, the reaction on body1; φ the relative rotation about the axis.
//! TorsionSpring(name: "anti_roll", body1: "carbody", body2: "bogie", axis: (1, 0, 0),
//!               c: 2.5e6, d: 1e3, phi0: 0),    // N m/rad, N m s/rad, rad; d, phi0 default 0
//! ```

use super::{Checks, ForceSpec, ForceSyntax, body_ref};
use crate::expr::Expr;
use crate::load::{Cx, Lookup, Where};
use crate::model::BodyRef;
use crate::raw::{Value, Vec3, unit_z};
use serde::Deserialize;

/// Torsion spring–damper between two bodies about an axis fixed to body 1:
/// the moment on body 2 is −(c (φ − φ0) + d φ̇) e, body 1 gets the reaction.
/// φ (rad) is the rotation of body 2 relative to body 1 about e, zero when
/// the two body frames are parallel and measured in (−π, π]; φ̇ = e·(ω₂ − ω₁)
/// (rad/s). A pure moment: where on the bodies it acts does not matter.
#[derive(Debug, Clone, PartialEq)]
pub struct TorsionSpring {
    /// Body 1 (the axis is fixed to it).
    pub body1: BodyRef,
    /// Body 2.
    pub body2: BodyRef,
    /// The axis e in the frame of `body1` (any length > 0; normalized).
    pub axis: [Expr; 3],
    /// Torsional stiffness c, N m/rad.
    pub stiffness: Expr,
    /// Torsional damping d, N m s/rad.
    pub damping: Expr,
    /// Preload angle φ0: the angle at which the spring is relaxed, rad.
    pub preload_angle: Expr,
}

/// `TorsionSpring(name, body1, body2, axis, c, d, phi0)`.
#[derive(Debug, Deserialize)]
#[serde(rename = "TorsionSpring", deny_unknown_fields)]
pub(crate) struct RawTorsionSpring {
    name: String,
    body1: String,
    body2: String,
    #[serde(default = "unit_z")]
    axis: Vec3,
    c: Value,
    #[serde(default)]
    d: Value,
    #[serde(default)]
    phi0: Value,
}

impl ForceSyntax for RawTorsionSpring {
    type Spec = TorsionSpring;
    fn name(&self) -> &str {
        &self.name
    }
    fn resolve(&self, cx: &mut Cx, w: &Where, lookup: &Lookup) -> TorsionSpring {
        // A connection point names its body; the point itself is irrelevant
        // to a moment.
        let (body1, _) = cx.target(w, "body1", &self.body1, lookup);
        let (body2, _) = cx.target(w, "body2", &self.body2, lookup);
        if self.body1 == self.body2 {
            cx.err(
                w,
                Some("body2"),
                None,
                format!("connects body \"{}\" to itself", self.body1),
            );
        }
        TorsionSpring {
            body1,
            body2,
            axis: cx.vec3(w, "axis", &self.axis, false),
            stiffness: cx.expr(w, "c", "c", &self.c, false),
            damping: cx.expr(w, "d", "d", &self.d, false),
            preload_angle: cx.expr(w, "phi0", "phi0", &self.phi0, false),
        }
    }
}

impl ForceSpec for TorsionSpring {
    fn exprs_mut(&mut self, f: &mut dyn FnMut(&mut Expr)) {
        self.axis.iter_mut().for_each(&mut *f);
        for e in [
            &mut self.stiffness,
            &mut self.damping,
            &mut self.preload_angle,
        ] {
            f(e);
        }
    }
    fn bodies_mut(&mut self, f: &mut dyn FnMut(&mut usize)) {
        body_ref(&mut self.body1, f);
        body_ref(&mut self.body2, f);
    }
    fn check(&self, c: &mut Checks) {
        c.non_negative("c", &self.stiffness);
        c.non_negative("d", &self.damping);
        let len2: f64 = self.axis.iter().map(|e| c.value(e).powi(2)).sum();
        if len2 == 0.0 {
            c.push("axis", "axis must not be zero".into());
        }
    }
}
