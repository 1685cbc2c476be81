//! `SeriesSpring`: a spring in series with a damper (Pogorelov 2005, Sect. 3.1).

use super::point_pair::point_pair_syntax;
use super::{Checks, ForceSpec, ForceSyntax, PointPair};
use crate::expr::Expr;
use crate::load::{Cx, Lookup, Where};
use crate::raw::Value;

/// Spring c in series with damper d between two points (Pogorelov 2005,
/// Sect. 3.1), with a preload f0 in parallel: the spring's extension s is a
/// first-order state variable integrated with q, and the tension is
/// F = c s + f0 = d (ẋ − ṡ) + f0, x the distance of the points (m). No
/// free length: the damper takes up any static length change, so the
/// force depends on the motion only. Positive F pulls the points together.
#[derive(Debug, Clone, PartialEq)]
pub struct SeriesSpringDamper {
    /// The two points.
    pub ends: PointPair,
    /// N/m.
    pub stiffness: Expr,
    /// N s/m.
    pub damping: Expr,
    /// N.
    pub preload: Expr,
}

point_pair_syntax! {
    /// `SeriesSpring(name, body1, point1, body2, point2, c, d, f0)`.
    #[serde(rename = "SeriesSpring")]
    pub(crate) struct RawSeriesSpring {
        c: Value,
        d: Value,
        #[serde(default)]
        f0: Value,
    }
}

impl ForceSyntax for RawSeriesSpring {
    type Spec = SeriesSpringDamper;
    fn name(&self) -> &str {
        &self.name
    }
    fn resolve(&self, cx: &mut Cx, w: &Where, lookup: &Lookup) -> SeriesSpringDamper {
        let stiffness = cx.expr(w, "c", "c", &self.c, false);
        let damping = cx.expr(w, "d", "d", &self.d, false);
        let ends = self.ends().resolve(cx, w, lookup);
        SeriesSpringDamper {
            ends,
            stiffness,
            damping,
            preload: cx.expr(w, "f0", "f0", &self.f0, false),
        }
    }
}

impl ForceSpec for SeriesSpringDamper {
    fn exprs_mut(&mut self, f: &mut dyn FnMut(&mut Expr)) {
        self.ends.exprs_mut(f);
        for e in [&mut self.stiffness, &mut self.damping, &mut self.preload] {
            f(e);
        }
    }
    fn bodies_mut(&mut self, f: &mut dyn FnMut(&mut usize)) {
        self.ends.bodies_mut(f);
    }
    fn check(&self, c: &mut Checks) {
        c.positive("c", &self.stiffness);
        c.positive("d", &self.damping);
    }
}
