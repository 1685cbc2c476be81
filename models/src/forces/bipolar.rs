//! `Spring`: the linear bipolar spring–damper (Pogorelov 2005, Sect. 3.1).

use super::point_pair::point_pair_syntax;
use super::{Checks, ForceSpec, ForceSyntax, PointPair};
use crate::expr::Expr;
use crate::load::{Cx, Lookup, Where};
use crate::raw::Value;

/// Linear bipolar spring–damper between two points (Pogorelov 2005, Sect. 3.1):
/// F = c (x − x0) + d ẋ + f0 along the line of the points, x the distance (m).
/// Positive force pulls the points together (tension).
#[derive(Debug, Clone, PartialEq)]
pub struct Bipolar {
    /// The two points.
    pub ends: PointPair,
    /// N/m.
    pub stiffness: Expr,
    /// N s/m.
    pub damping: Expr,
    /// N.
    pub preload: Expr,
    /// Free length, m.
    pub free_length: Expr,
}

point_pair_syntax! {
    /// `Spring(name, body1, point1, body2, point2, c, d, f0, x0)`.
    #[serde(rename = "Spring")]
    pub(crate) struct RawSpring {
        c: Value,
        #[serde(default)]
        d: Value,
        #[serde(default)]
        f0: Value,
        #[serde(default)]
        x0: Value,
    }
}

impl ForceSyntax for RawSpring {
    type Spec = Bipolar;
    fn name(&self) -> &str {
        &self.name
    }
    fn resolve(&self, cx: &mut Cx, w: &Where, lookup: &Lookup) -> Bipolar {
        Bipolar {
            ends: self.ends().resolve(cx, w, lookup),
            stiffness: cx.expr(w, "c", "c", &self.c, false),
            damping: cx.expr(w, "d", "d", &self.d, false),
            preload: cx.expr(w, "f0", "f0", &self.f0, false),
            free_length: cx.expr(w, "x0", "x0", &self.x0, false),
        }
    }
}

impl ForceSpec for Bipolar {
    fn exprs_mut(&mut self, f: &mut dyn FnMut(&mut Expr)) {
        self.ends.exprs_mut(f);
        for e in [
            &mut self.stiffness,
            &mut self.damping,
            &mut self.preload,
            &mut self.free_length,
        ] {
            f(e);
        }
    }
    fn bodies_mut(&mut self, f: &mut dyn FnMut(&mut usize)) {
        self.ends.bodies_mut(f);
    }
    fn check(&self, _c: &mut Checks) {}
}
