//! Visiting every expression and every body index of a resolved model: used to
//! renumber the parameters and bodies of an included subsystem when it is
//! flattened into its parent, and useful to tools that rewrite models.

use crate::expr::Expr;
use crate::model::*;

impl Frame {
    fn exprs_mut(&mut self, f: &mut dyn FnMut(&mut Expr)) {
        self.origin.iter_mut().for_each(&mut *f);
        self.rotation_xyz.iter_mut().for_each(f);
    }
}

fn body_ref(b: &mut BodyRef, f: &mut dyn FnMut(&mut usize)) {
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

impl ForceKind {
    /// Every expression of the force element.
    pub fn exprs_mut(&mut self, f: &mut dyn FnMut(&mut Expr)) {
        match self {
            ForceKind::Bipolar {
                point1,
                point2,
                stiffness,
                damping,
                preload,
                free_length,
                ..
            } => {
                point1.iter_mut().chain(point2.iter_mut()).for_each(&mut *f);
                for e in [stiffness, damping, preload, free_length] {
                    f(e);
                }
            }
            ForceKind::SeriesSpringDamper {
                point1,
                point2,
                stiffness,
                damping,
                preload,
                ..
            } => {
                point1.iter_mut().chain(point2.iter_mut()).for_each(&mut *f);
                for e in [stiffness, damping, preload] {
                    f(e);
                }
            }
            ForceKind::Linear6 {
                frame1,
                frame2,
                stiffness,
                damping,
                preload,
                ..
            } => {
                frame1.exprs_mut(f);
                frame2.exprs_mut(f);
                stiffness
                    .iter_mut()
                    .chain(damping.iter_mut())
                    .chain(preload.iter_mut())
                    .for_each(f);
            }
            ForceKind::PointPlane {
                points,
                origin,
                normal,
                surface,
                stiffness,
                damping,
                tangential_stiffness,
                tangential_damping,
                mu_static,
                mu,
                ..
            } => {
                points.iter_mut().flatten().for_each(&mut *f);
                origin.iter_mut().chain(normal.iter_mut()).for_each(&mut *f);
                surface.iter_mut().for_each(&mut *f);
                for e in [
                    stiffness,
                    damping,
                    tangential_stiffness,
                    tangential_damping,
                    mu_static,
                    mu,
                ] {
                    f(e);
                }
            }
            ForceKind::Coulomb {
                point1,
                point2,
                stiffness,
                damping,
                static_limit,
                sliding_force,
                ..
            } => {
                point1.iter_mut().chain(point2.iter_mut()).for_each(&mut *f);
                for e in [stiffness, damping, static_limit, sliding_force] {
                    f(e);
                }
            }
            ForceKind::LoadFriction {
                point1,
                point2,
                c1,
                c2,
                mu_static,
                mu,
                free_length,
                ..
            } => {
                point1.iter_mut().chain(point2.iter_mut()).for_each(&mut *f);
                for e in [c1, c2, mu_static, mu, free_length] {
                    f(e);
                }
            }
            ForceKind::Tabulated {
                point1,
                point2,
                table,
                damping,
                free_length,
                ..
            } => {
                point1.iter_mut().chain(point2.iter_mut()).for_each(&mut *f);
                for (x, y) in table {
                    f(x);
                    f(y);
                }
                f(damping);
                f(free_length);
            }
            ForceKind::WheelRail(w) => {
                let WheelRail {
                    radius,
                    flange_back_distance,
                    taping_offset,
                    mu,
                    young,
                    poisson,
                    normal_damping,
                    creep,
                    rail,
                    ..
                } = &mut **w;
                for e in [
                    radius,
                    flange_back_distance,
                    taping_offset,
                    mu,
                    young,
                    poisson,
                    normal_damping,
                ] {
                    f(e);
                }
                creep.for_each_value_mut(|_, e| f(e));
                match rail {
                    RailKind::Elastic { ky, cy, kz, cz } => {
                        for e in [ky, cy, kz, cz] {
                            f(e);
                        }
                    }
                    RailKind::Rigid => {}
                }
            }
            ForceKind::Applied {
                point,
                force,
                torque,
                ..
            } => {
                point
                    .iter_mut()
                    .chain(force.iter_mut())
                    .chain(torque.iter_mut())
                    .for_each(f);
            }
        }
    }

    /// Every body index the element refers to (ground is not visited).
    pub fn bodies_mut(&mut self, f: &mut dyn FnMut(&mut usize)) {
        match self {
            ForceKind::Bipolar { body1, body2, .. }
            | ForceKind::SeriesSpringDamper { body1, body2, .. }
            | ForceKind::Linear6 { body1, body2, .. }
            | ForceKind::Coulomb { body1, body2, .. }
            | ForceKind::LoadFriction { body1, body2, .. }
            | ForceKind::Tabulated { body1, body2, .. } => {
                body_ref(body1, f);
                body_ref(body2, f);
            }
            ForceKind::PointPlane {
                body, plane_body, ..
            } => {
                body_ref(body, f);
                body_ref(plane_body, f);
            }
            ForceKind::WheelRail(w) => {
                f(&mut w.wheelset);
                if let Some(wheels) = &mut w.wheels {
                    wheels.iter_mut().for_each(&mut *f);
                }
            }
            ForceKind::Applied { body, .. } => f(body),
        }
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
