//! `Coulomb`: bipolar Coulomb friction (Pogorelov 2005, Sect. 3.1).

use super::{Checks, ForceSpec, ForceSyntax, body_ref};
use crate::expr::Expr;
use crate::load::{Cx, Lookup, Where};
use crate::model::BodyRef;
use crate::raw::{Value, Vec3, some_value, zero3};
use serde::Deserialize;

/// Bipolar Coulomb friction (Pogorelov 2005, Sect. 3.1) between two points:
/// sticking, F = f0 + c (x − x0) + d ẋ with f0, x0 stored when sticking
/// begins, until |F| reaches the static limit; then sliding, F = F_s sign(ẋ).
/// Positive F pulls the points together.
#[derive(Debug, Clone, PartialEq)]
pub struct Coulomb {
    /// Body of the first point.
    pub body1: BodyRef,
    /// First point, in the frame of `body1`, m.
    pub point1: [Expr; 3],
    /// Body of the second point.
    pub body2: BodyRef,
    /// Second point, in the frame of `body2`, m.
    pub point2: [Expr; 3],
    /// Sticking stiffness, N/m.
    pub stiffness: Expr,
    /// Sticking damping, N s/m.
    pub damping: Expr,
    /// Static limit F0, N.
    pub static_limit: Expr,
    /// Sliding force F_s (≤ F0), N.
    pub sliding_force: Expr,
}

/// `Coulomb(name, body1, point1, body2, point2, c, d, limit, sliding)`.
#[derive(Debug, Deserialize)]
#[serde(rename = "Coulomb", deny_unknown_fields)]
pub(crate) struct RawCoulomb {
    name: String,
    body1: String,
    #[serde(default = "zero3")]
    point1: Vec3,
    body2: String,
    #[serde(default = "zero3")]
    point2: Vec3,
    c: Value,
    #[serde(default)]
    d: Value,
    limit: Value,
    #[serde(default, deserialize_with = "some_value")]
    sliding: Option<Value>,
}

impl ForceSyntax for RawCoulomb {
    type Spec = Coulomb;
    fn name(&self) -> &str {
        &self.name
    }
    fn resolve(&self, cx: &mut Cx, w: &Where, lookup: &Lookup) -> Coulomb {
        let stiffness = cx.expr(w, "c", "c", &self.c, false);
        let damping = cx.expr(w, "d", "d", &self.d, false);
        let static_limit = cx.expr(w, "limit", "limit", &self.limit, false);
        let sliding_force = match &self.sliding {
            Some(v) => cx.expr(w, "sliding", "sliding", v, false),
            None => static_limit.clone(),
        };
        let (body1, point1, body2, point2) = cx.two_points(
            w,
            (&self.body1, &self.point1),
            (&self.body2, &self.point2),
            lookup,
        );
        Coulomb {
            body1,
            point1,
            body2,
            point2,
            stiffness,
            damping,
            static_limit,
            sliding_force,
        }
    }
}

impl ForceSpec for Coulomb {
    fn exprs_mut(&mut self, f: &mut dyn FnMut(&mut Expr)) {
        self.point1
            .iter_mut()
            .chain(self.point2.iter_mut())
            .for_each(&mut *f);
        for e in [
            &mut self.stiffness,
            &mut self.damping,
            &mut self.static_limit,
            &mut self.sliding_force,
        ] {
            f(e);
        }
    }
    fn bodies_mut(&mut self, f: &mut dyn FnMut(&mut usize)) {
        body_ref(&mut self.body1, f);
        body_ref(&mut self.body2, f);
    }
    fn check(&self, c: &mut Checks) {
        c.positive("c", &self.stiffness);
        c.non_negative("d", &self.damping);
        c.friction("sliding", &self.sliding_force, "limit", &self.static_limit);
    }
}
