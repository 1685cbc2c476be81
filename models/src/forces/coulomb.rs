//! `Coulomb`: bipolar Coulomb friction (Pogorelov 2005, Sect. 3.1).

use super::point_pair::point_pair_syntax;
use super::{Checks, ForceSpec, ForceSyntax, PointPair};
use crate::expr::Expr;
use crate::load::{Cx, Lookup, Where};
use crate::raw::{Value, some_value};

/// Bipolar Coulomb friction (Pogorelov 2005, Sect. 3.1) between two points:
/// sticking, F = f0 + c (x − x0) + d ẋ with f0, x0 stored when sticking
/// begins, until |F| reaches the static limit; then sliding, F = F_s sign(ẋ).
/// Positive F pulls the points together.
#[derive(Debug, Clone, PartialEq)]
pub struct Coulomb {
    /// The two points.
    pub ends: PointPair,
    /// Sticking stiffness, N/m.
    pub stiffness: Expr,
    /// Sticking damping, N s/m.
    pub damping: Expr,
    /// Static limit F0, N.
    pub static_limit: Expr,
    /// Sliding force F_s (≤ F0), N.
    pub sliding_force: Expr,
}

point_pair_syntax! {
    /// `Coulomb(name, body1, point1, body2, point2, c, d, limit, sliding)`.
    #[serde(rename = "Coulomb")]
    pub(crate) struct RawCoulomb {
        c: Value,
        #[serde(default)]
        d: Value,
        limit: Value,
        #[serde(default, deserialize_with = "some_value")]
        sliding: Option<Value>,
    }
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
        let ends = self.ends().resolve(cx, w, lookup);
        Coulomb {
            ends,
            stiffness,
            damping,
            static_limit,
            sliding_force,
        }
    }
}

impl ForceSpec for Coulomb {
    fn exprs_mut(&mut self, f: &mut dyn FnMut(&mut Expr)) {
        self.ends.exprs_mut(f);
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
        self.ends.bodies_mut(f);
    }
    fn check(&self, c: &mut Checks) {
        c.positive("c", &self.stiffness);
        c.non_negative("d", &self.damping);
        c.friction("sliding", &self.sliding_force, "limit", &self.static_limit);
    }
}
