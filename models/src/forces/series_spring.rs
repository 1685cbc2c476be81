//! `SeriesSpring`: a spring in series with a damper (Pogorelov 2005, Sect. 3.1).

use super::{Checks, ForceSpec, ForceSyntax, body_ref};
use crate::expr::Expr;
use crate::load::{Cx, Lookup, Where};
use crate::model::BodyRef;
use crate::raw::{Value, Vec3, zero3};
use serde::Deserialize;

/// Spring c in series with damper d between two points (Pogorelov 2005,
/// Sect. 3.1), with a preload f0 in parallel: the spring's extension s is a
/// first-order state variable integrated with q, and the tension is
/// F = c s + f0 = d (ẋ − ṡ) + f0, x the distance of the points (m). No
/// free length: the damper takes up any static length change, so the
/// force depends on the motion only. Positive F pulls the points together.
#[derive(Debug, Clone, PartialEq)]
pub struct SeriesSpringDamper {
    /// Body of the first point.
    pub body1: BodyRef,
    /// First point, in the frame of `body1`, m.
    pub point1: [Expr; 3],
    /// Body of the second point.
    pub body2: BodyRef,
    /// Second point, in the frame of `body2`, m.
    pub point2: [Expr; 3],
    /// N/m.
    pub stiffness: Expr,
    /// N s/m.
    pub damping: Expr,
    /// N.
    pub preload: Expr,
}

/// `SeriesSpring(name, body1, point1, body2, point2, c, d, f0)`.
#[derive(Debug, Deserialize)]
#[serde(rename = "SeriesSpring", deny_unknown_fields)]
pub(crate) struct RawSeriesSpring {
    name: String,
    body1: String,
    #[serde(default = "zero3")]
    point1: Vec3,
    body2: String,
    #[serde(default = "zero3")]
    point2: Vec3,
    c: Value,
    d: Value,
    #[serde(default)]
    f0: Value,
}

impl ForceSyntax for RawSeriesSpring {
    type Spec = SeriesSpringDamper;
    fn name(&self) -> &str {
        &self.name
    }
    fn resolve(&self, cx: &mut Cx, w: &Where, lookup: &Lookup) -> SeriesSpringDamper {
        let stiffness = cx.expr(w, "c", "c", &self.c, false);
        let damping = cx.expr(w, "d", "d", &self.d, false);
        let (body1, point1, body2, point2) = cx.two_points(
            w,
            (&self.body1, &self.point1),
            (&self.body2, &self.point2),
            lookup,
        );
        SeriesSpringDamper {
            body1,
            point1,
            body2,
            point2,
            stiffness,
            damping,
            preload: cx.expr(w, "f0", "f0", &self.f0, false),
        }
    }
}

impl ForceSpec for SeriesSpringDamper {
    fn exprs_mut(&mut self, f: &mut dyn FnMut(&mut Expr)) {
        self.point1
            .iter_mut()
            .chain(self.point2.iter_mut())
            .for_each(&mut *f);
        for e in [&mut self.stiffness, &mut self.damping, &mut self.preload] {
            f(e);
        }
    }
    fn bodies_mut(&mut self, f: &mut dyn FnMut(&mut usize)) {
        body_ref(&mut self.body1, f);
        body_ref(&mut self.body2, f);
    }
    fn check(&self, c: &mut Checks) {
        c.positive("c", &self.stiffness);
        c.positive("d", &self.damping);
    }
}
