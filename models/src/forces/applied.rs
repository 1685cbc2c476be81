//! `Applied`: a force and torque applied to one body, possibly depending on time.

use super::{Checks, ForceSpec, ForceSyntax};
use crate::expr::Expr;
use crate::load::{Cx, Lookup, Target, Where};
use crate::model::{BodyRef, VectorFrame};
use crate::raw::{Vec3, zero3};
use serde::Deserialize;

/// An applied force and torque on one body; expressions may depend on `t`.
#[derive(Debug, Clone, PartialEq)]
pub struct Applied {
    /// Index of the body it acts on.
    pub body: usize,
    /// Point of application in the body frame, m.
    pub point: [Expr; 3],
    /// N.
    pub force: [Expr; 3],
    /// N m.
    pub torque: [Expr; 3],
    /// The frame `force` and `torque` are expressed in.
    pub frame: VectorFrame,
}

/// The frame of an applied force's vectors, as written.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename = "Frame")]
pub(crate) enum RawFrame {
    #[default]
    Global,
    Body,
}

/// `Applied(name, body, point, force, torque, frame)`.
#[derive(Debug, Deserialize)]
#[serde(rename = "Applied", deny_unknown_fields)]
pub(crate) struct RawApplied {
    name: String,
    body: String,
    #[serde(default = "zero3")]
    point: Vec3,
    #[serde(default = "zero3")]
    force: Vec3,
    #[serde(default = "zero3")]
    torque: Vec3,
    #[serde(default)]
    frame: RawFrame,
}

impl ForceSyntax for RawApplied {
    type Spec = Applied;
    fn name(&self) -> &str {
        &self.name
    }
    fn resolve(&self, cx: &mut Cx, w: &Where, lookup: &Lookup) -> Applied {
        let body = &self.body;
        let (body_ref, point) = cx.attach(w, ("body", body), ("point", &self.point), lookup);
        let body = match body_ref {
            BodyRef::Body(k) => k,
            BodyRef::Ground => {
                let on_ground = body == "ground"
                    || matches!(lookup.names.get(body.as_str()), Some(Target::Conn(..)));
                if on_ground {
                    cx.err(
                        w,
                        Some("body"),
                        None,
                        "an applied force acts on a body, not on ground".into(),
                    );
                }
                0
            }
        };
        Applied {
            body,
            point,
            force: cx.vec3(w, "force", &self.force, true),
            torque: cx.vec3(w, "torque", &self.torque, true),
            frame: match self.frame {
                RawFrame::Body => VectorFrame::Body,
                RawFrame::Global => VectorFrame::Global,
            },
        }
    }
}

impl ForceSpec for Applied {
    fn exprs_mut(&mut self, f: &mut dyn FnMut(&mut Expr)) {
        self.point
            .iter_mut()
            .chain(self.force.iter_mut())
            .chain(self.torque.iter_mut())
            .for_each(f);
    }
    fn bodies_mut(&mut self, f: &mut dyn FnMut(&mut usize)) {
        f(&mut self.body);
    }
    fn check(&self, _c: &mut Checks) {}
}
