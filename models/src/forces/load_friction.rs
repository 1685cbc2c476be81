//! `LoadFriction`: load-dependent friction (Pogorelov 2005, Sect. 3.1, Fig. 3).

use super::point_pair::point_pair_syntax;
use super::{Checks, ForceSpec, ForceSyntax, PointPair};
use crate::expr::Expr;
use crate::load::{Cx, Lookup, Where};
use crate::raw::{Value, some_value};

/// Load-dependent friction (Pogorelov 2005, Sect. 3.1, Fig. 3): spring c1 in
/// series with spring c2 in parallel with friction proportional to the force
/// in c2 (static μ0, sliding μ). x is the distance minus `free_length`.
#[derive(Debug, Clone, PartialEq)]
pub struct LoadFriction {
    /// The two points.
    pub ends: PointPair,
    /// N/m.
    pub c1: Expr,
    /// N/m.
    pub c2: Expr,
    /// Static friction coefficient μ0 (< 1), –.
    pub mu_static: Expr,
    /// Sliding friction coefficient μ, –.
    pub mu: Expr,
    /// m.
    pub free_length: Expr,
}

point_pair_syntax! {
    /// `LoadFriction(name, body1, point1, body2, point2, c1, c2, mu0, mu, x0)`.
    #[serde(rename = "LoadFriction")]
    pub(crate) struct RawLoadFriction {
        c1: Value,
        c2: Value,
        #[serde(default, deserialize_with = "some_value")]
        mu0: Option<Value>,
        mu: Value,
        #[serde(default)]
        x0: Value,
    }
}

impl ForceSyntax for RawLoadFriction {
    type Spec = LoadFriction;
    fn name(&self) -> &str {
        &self.name
    }
    fn resolve(&self, cx: &mut Cx, w: &Where, lookup: &Lookup) -> LoadFriction {
        let c1 = cx.expr(w, "c1", "c1", &self.c1, false);
        let c2 = cx.expr(w, "c2", "c2", &self.c2, false);
        let mu = cx.expr(w, "mu", "mu", &self.mu, false);
        let mu_static = match &self.mu0 {
            Some(v) => cx.expr(w, "mu0", "mu0", v, false),
            None => mu.clone(),
        };
        let ends = self.ends().resolve(cx, w, lookup);
        LoadFriction {
            ends,
            c1,
            c2,
            mu_static,
            mu,
            free_length: cx.expr(w, "x0", "x0", &self.x0, false),
        }
    }
}

impl ForceSpec for LoadFriction {
    fn exprs_mut(&mut self, f: &mut dyn FnMut(&mut Expr)) {
        self.ends.exprs_mut(f);
        for e in [
            &mut self.c1,
            &mut self.c2,
            &mut self.mu_static,
            &mut self.mu,
            &mut self.free_length,
        ] {
            f(e);
        }
    }
    fn bodies_mut(&mut self, f: &mut dyn FnMut(&mut usize)) {
        self.ends.bodies_mut(f);
    }
    fn check(&self, c: &mut Checks) {
        c.positive("c1", &self.c1);
        c.positive("c2", &self.c2);
        c.friction("mu", &self.mu, "mu0", &self.mu_static);
        let m0 = c.value(&self.mu_static);
        if m0.is_finite() && m0 >= 1.0 {
            c.push(
                "mu0",
                format!("mu0 must be below 1 (the unloading branch would lock), got {m0}"),
            );
        }
    }
}
