//! `PointPlane`: point–plane and point–Z-surface contact (Pogorelov 2005,
//! Sect. 3.3).

use super::{Checks, ForceSpec, ForceSyntax, body_ref};
use crate::expr::Expr;
use crate::load::{Cx, Lookup, Where, add3};
use crate::model::BodyRef;
use crate::raw::{Value, Vec3, ground_name, some_value, unit_z, zero3};
use serde::Deserialize;

/// Point–plane contact (Pogorelov 2005, Sect. 3.3): points fixed to `body`
/// against the plane through `origin` with outward `normal` fixed to
/// `plane_body` (both in that body's frame). Penetration δ ≥ 0 gives the
/// normal force N = max(0, c δ + d δ̇) (no adhesion); the tangential force is
/// Coulomb friction with sticking (the point tied to an anchor by ct, dt) up
/// to μ0 N, and sliding at μ N.
#[derive(Debug, Clone, PartialEq)]
pub struct PointPlane {
    /// The body carrying the points.
    pub body: BodyRef,
    /// Contact points in the frame of `body`, m.
    pub points: Vec<[Expr; 3]>,
    /// The body carrying the plane.
    pub plane_body: BodyRef,
    /// A point of the plane, m.
    pub origin: [Expr; 3],
    /// Normal pointing out of the plane's solid side (any length > 0).
    pub normal: [Expr; 3],
    /// Point–Z-surface variant: instead of the plane, the surface
    /// z = f(x, y) in the frame of `plane_body` shifted to `origin` (x, y
    /// are the local variables `Var(0)`, `Var(1)`, m), solid below it; the
    /// normal is the surface's upward normal (−f_x, −f_y, 1).
    pub surface: Option<Expr>,
    /// Normal stiffness per point, N/m.
    pub stiffness: Expr,
    /// Normal damping per point, N s/m.
    pub damping: Expr,
    /// Tangential stiffness of the sticking anchor, N/m.
    pub tangential_stiffness: Expr,
    /// Tangential damping of the sticking anchor, N s/m.
    pub tangential_damping: Expr,
    /// Static friction coefficient μ0 (≥ μ).
    pub mu_static: Expr,
    /// Sliding friction coefficient μ (≥ 0).
    pub mu: Expr,
}

/// `PointPlane(name, body, points, plane_body, origin, normal, surface, c, d,
/// ct, dt, mu0, mu)`.
#[derive(Debug, Deserialize)]
#[serde(rename = "PointPlane", deny_unknown_fields)]
pub(crate) struct RawPointPlane {
    name: String,
    body: String,
    points: Vec<Vec3>,
    #[serde(default = "ground_name")]
    plane_body: String,
    #[serde(default = "zero3")]
    origin: Vec3,
    #[serde(default = "unit_z")]
    normal: Vec3,
    #[serde(default, deserialize_with = "some_value")]
    surface: Option<Value>,
    c: Value,
    #[serde(default)]
    d: Value,
    #[serde(default, deserialize_with = "some_value")]
    ct: Option<Value>,
    #[serde(default, deserialize_with = "some_value")]
    dt: Option<Value>,
    #[serde(default, deserialize_with = "some_value")]
    mu0: Option<Value>,
    #[serde(default)]
    mu: Value,
}

impl ForceSyntax for RawPointPlane {
    type Spec = PointPlane;
    fn name(&self) -> &str {
        &self.name
    }
    fn resolve(&self, cx: &mut Cx, w: &Where, lookup: &Lookup) -> PointPlane {
        let (body, plane_body) = (&self.body, &self.plane_body);
        let (body_ref, body_conn) = cx.target(w, "body", body, lookup);
        let (plane_ref, plane_conn) = cx.target(w, "plane_body", plane_body, lookup);
        if body_ref == plane_ref && body == plane_body {
            cx.err(
                w,
                Some("plane_body"),
                None,
                "the plane must belong to another body than the points".into(),
            );
        }
        if self.points.is_empty() {
            cx.err(w, Some("points"), None, "needs at least one point".into());
        }
        let points: Vec<[Expr; 3]> = self
            .points
            .iter()
            .enumerate()
            .map(|(k, p)| {
                let p = cx.vec3(w, &format!("points[{k}]"), p, false);
                match &body_conn {
                    Some(c) => add3(c, p),
                    None => p,
                }
            })
            .collect();
        let normal = cx.vec3(w, "normal", &self.normal, false);
        let surface = self.surface.as_ref().map(|v| cx.surface_expr(w, v));
        if surface.is_some() && self.normal != unit_z() {
            cx.err(
                w,
                Some("normal"),
                None,
                "a Z-surface's normal follows from its slope: leave `normal` out".into(),
            );
        }
        let stiffness = cx.expr(w, "c", "c", &self.c, false);
        let damping = cx.expr(w, "d", "d", &self.d, false);
        let tangential_stiffness = match &self.ct {
            Some(v) => cx.expr(w, "ct", "ct", v, false),
            None => stiffness.clone(),
        };
        let tangential_damping = match &self.dt {
            Some(v) => cx.expr(w, "dt", "dt", v, false),
            None => damping.clone(),
        };
        let mu = cx.expr(w, "mu", "mu", &self.mu, false);
        let mu_static = match &self.mu0 {
            Some(v) => cx.expr(w, "mu0", "mu0", v, false),
            None => mu.clone(),
        };
        let origin = {
            let o = cx.vec3(w, "origin", &self.origin, false);
            match &plane_conn {
                Some(c) => add3(c, o),
                None => o,
            }
        };
        PointPlane {
            body: body_ref,
            points,
            plane_body: plane_ref,
            origin,
            normal,
            surface,
            stiffness,
            damping,
            tangential_stiffness,
            tangential_damping,
            mu_static,
            mu,
        }
    }
}

impl ForceSpec for PointPlane {
    fn exprs_mut(&mut self, f: &mut dyn FnMut(&mut Expr)) {
        self.points.iter_mut().flatten().for_each(&mut *f);
        self.origin
            .iter_mut()
            .chain(self.normal.iter_mut())
            .for_each(&mut *f);
        self.surface.iter_mut().for_each(&mut *f);
        for e in [
            &mut self.stiffness,
            &mut self.damping,
            &mut self.tangential_stiffness,
            &mut self.tangential_damping,
            &mut self.mu_static,
            &mut self.mu,
        ] {
            f(e);
        }
    }
    fn bodies_mut(&mut self, f: &mut dyn FnMut(&mut usize)) {
        body_ref(&mut self.body, f);
        body_ref(&mut self.plane_body, f);
    }
    fn check(&self, c: &mut Checks) {
        c.positive("c", &self.stiffness);
        c.positive("ct", &self.tangential_stiffness);
        c.non_negative("d", &self.damping);
        c.non_negative("dt", &self.tangential_damping);
        c.friction("mu", &self.mu, "mu0", &self.mu_static);
        let len2: f64 = self.normal.iter().map(|e| c.value(e).powi(2)).sum();
        if len2 == 0.0 {
            c.push("normal", "normal must not be zero".into());
        }
    }
}
