//! `Spring`: the linear bipolar spring–damper (Pogorelov 2005, Sect. 3.1).

use super::{Checks, ForceSpec, ForceSyntax, body_ref};
use crate::expr::Expr;
use crate::load::{Cx, Lookup, Where};
use crate::model::BodyRef;
use crate::raw::{Value, Vec3, zero3};
use serde::Deserialize;

/// Linear bipolar spring–damper between two points (Pogorelov 2005, Sect. 3.1):
/// F = c (x − x0) + d ẋ + f0 along the line of the points, x the distance (m).
/// Positive force pulls the points together (tension).
#[derive(Debug, Clone, PartialEq)]
pub struct Bipolar {
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
    /// Free length, m.
    pub free_length: Expr,
}

/// `Spring(name, body1, point1, body2, point2, c, d, f0, x0)`.
#[derive(Debug, Deserialize)]
#[serde(rename = "Spring", deny_unknown_fields)]
pub(crate) struct RawSpring {
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
    #[serde(default)]
    f0: Value,
    #[serde(default)]
    x0: Value,
}

impl ForceSyntax for RawSpring {
    type Spec = Bipolar;
    fn name(&self) -> &str {
        &self.name
    }
    fn resolve(&self, cx: &mut Cx, w: &Where, lookup: &Lookup) -> Bipolar {
        let (body1, point1, body2, point2) = cx.two_points(
            w,
            (&self.body1, &self.point1),
            (&self.body2, &self.point2),
            lookup,
        );
        Bipolar {
            body1,
            point1,
            body2,
            point2,
            stiffness: cx.expr(w, "c", "c", &self.c, false),
            damping: cx.expr(w, "d", "d", &self.d, false),
            preload: cx.expr(w, "f0", "f0", &self.f0, false),
            free_length: cx.expr(w, "x0", "x0", &self.x0, false),
        }
    }
}

impl ForceSpec for Bipolar {
    fn exprs_mut(&mut self, f: &mut dyn FnMut(&mut Expr)) {
        self.point1
            .iter_mut()
            .chain(self.point2.iter_mut())
            .for_each(&mut *f);
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
        body_ref(&mut self.body1, f);
        body_ref(&mut self.body2, f);
    }
    fn check(&self, _c: &mut Checks) {}
}
