//! The two ends of an element acting along the line of two points (`Spring`,
//! `SeriesSpring`, `Coulomb`, `LoadFriction`, `Tabulated`; Pogorelov 2005,
//! Sect. 3.1): their model syntax, resolution and traversal, written once.
//!
//! ```text
//! // body1/body2 name a body, "ground" or a connection point; point1/point2
//! // are in that body's frame (relative to the connection point), m,
//! // default (0, 0, 0).
//! Spring(name: "k", body1: "ground", point1: (0, 0, 1), body2: "mass", c: 1e5)
//! ```

use super::body_ref;
use crate::expr::Expr;
use crate::load::{Cx, Lookup, Where};
use crate::model::BodyRef;
use crate::raw::Vec3;

/// Two points fixed to two bodies (or ground): the ends of a two-point
/// element. The element's force acts along the line from `point1` to
/// `point2`.
#[derive(Debug, Clone, PartialEq)]
pub struct PointPair {
    /// Body of the first point.
    pub body1: BodyRef,
    /// First point, in the frame of `body1`, m.
    pub point1: [Expr; 3],
    /// Body of the second point.
    pub body2: BodyRef,
    /// Second point, in the frame of `body2`, m.
    pub point2: [Expr; 3],
}

impl PointPair {
    /// Calls `f` on the six coordinates of the points (`point1`, then
    /// `point2`).
    pub fn exprs_mut(&mut self, f: &mut dyn FnMut(&mut Expr)) {
        self.point1
            .iter_mut()
            .chain(self.point2.iter_mut())
            .for_each(f);
    }

    /// Calls `f` on the body indices of the ends (ground is not visited).
    pub fn bodies_mut(&mut self, f: &mut dyn FnMut(&mut usize)) {
        body_ref(&mut self.body1, f);
        body_ref(&mut self.body2, f);
    }
}

/// The ends as written in a two-point element's constructor: the fields
/// `body1`, `point1`, `body2`, `point2` that [`point_pair_syntax!`] adds to
/// its raw struct.
pub(crate) struct RawPointPair<'a> {
    pub body1: &'a str,
    pub point1: &'a Vec3,
    pub body2: &'a str,
    pub point2: &'a Vec3,
}

impl RawPointPair<'_> {
    /// Resolves the bodies (or connection points) and the points, reporting
    /// unknown names and invalid coordinates at their RON keys (a point is
    /// relative to its connection point, see `Cx::attach`).
    pub(crate) fn resolve(&self, cx: &mut Cx, w: &Where, lookup: &Lookup) -> PointPair {
        let (body1, point1) = cx.attach(w, ("body1", self.body1), ("point1", self.point1), lookup);
        let (body2, point2) = cx.attach(w, ("body2", self.body2), ("point2", self.point2), lookup);
        PointPair {
            body1,
            point1,
            body2,
            point2,
        }
    }
}

/// Declares the raw (RON) struct of a two-point element: the fields `name`,
/// `body1`, `point1` (default (0, 0, 0)), `body2` and `point2` (default
/// (0, 0, 0)), in this order, followed by the element's own fields, with
/// unknown fields denied; and its `ends()`, the [`RawPointPair`]. The fields
/// are spelled out rather than flattened, because serde's `flatten` loses
/// `deny_unknown_fields` and RON's error positions; the model syntax is the
/// same as if they were written in each element's struct.
macro_rules! point_pair_syntax {
    ($(#[$meta:meta])* $vis:vis struct $raw:ident { $($fields:tt)* }) => {
        #[derive(Debug, serde::Deserialize)]
        $(#[$meta])*
        #[serde(deny_unknown_fields)]
        $vis struct $raw {
            name: String,
            body1: String,
            #[serde(default = "crate::raw::zero3")]
            point1: $crate::raw::Vec3,
            body2: String,
            #[serde(default = "crate::raw::zero3")]
            point2: $crate::raw::Vec3,
            $($fields)*
        }

        impl $raw {
            /// The two ends as written.
            fn ends(&self) -> $crate::forces::point_pair::RawPointPair<'_> {
                $crate::forces::point_pair::RawPointPair {
                    body1: &self.body1,
                    point1: &self.point1,
                    body2: &self.body2,
                    point2: &self.point2,
                }
            }
        }
    };
}
pub(crate) use point_pair_syntax;
