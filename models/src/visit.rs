//! Visiting every expression and every body index of a resolved model: used to
//! renumber the parameters and bodies of an included subsystem when it is
//! flattened into its parent, and useful to tools that rewrite models.

use crate::expr::Expr;
use crate::model::*;

impl Frame {
    pub(crate) fn exprs_mut(&mut self, f: &mut dyn FnMut(&mut Expr)) {
        self.origin.iter_mut().for_each(&mut *f);
        self.rotation_xyz.iter_mut().for_each(f);
    }
}

pub(crate) fn body_ref(b: &mut BodyRef, f: &mut dyn FnMut(&mut usize)) {
    if let BodyRef::Body(i) = b {
        f(i);
    }
}

impl CutJoint {
    /// Every expression of the cut joint (both frames).
    pub fn exprs_mut(&mut self, f: &mut dyn FnMut(&mut Expr)) {
        self.frame1.exprs_mut(f);
        self.frame2.exprs_mut(f);
    }

    /// Every body index (ground is not a body and is not visited).
    pub fn bodies_mut(&mut self, f: &mut dyn FnMut(&mut usize)) {
        body_ref(&mut self.body1, f);
        body_ref(&mut self.body2, f);
    }
}

impl Model {
    /// Calls `f` on every expression of the model: gravity, parameter
    /// defaults, macro assignments, masses, inertias, joints, initial values,
    /// cut joints, force elements and track-frame offsets.
    pub fn exprs_mut(&mut self, f: &mut dyn FnMut(&mut Expr)) {
        self.gravity.iter_mut().for_each(&mut *f);
        for p in &mut self.parameters {
            f(&mut p.default);
        }
        for m in &mut self.macros {
            for (_, e) in &mut m.assignments {
                f(e);
            }
        }
        for b in &mut self.bodies {
            f(&mut b.mass);
            b.inertia.iter_mut().for_each(&mut *f);
            for el in &mut b.joint {
                match &mut el.motion {
                    Motion::Fixed(e) | Motion::Time(e) => f(e),
                    Motion::Coordinate(_) | Motion::Input(_) => {}
                }
            }
        }
        for c in &mut self.coordinates {
            f(&mut c.initial);
            f(&mut c.initial_velocity);
        }
        for c in &mut self.cut_joints {
            c.exprs_mut(f);
        }
        for fe in &mut self.forces {
            fe.kind.exprs_mut(f);
        }
        for t in &mut self.track_frames {
            f(&mut t.offset);
        }
    }
}
