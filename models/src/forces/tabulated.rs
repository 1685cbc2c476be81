//! `Tabulated`: a tabulated force–deflection characteristic (bump stops).

use super::{Checks, ForceSpec, ForceSyntax, body_ref};
use crate::expr::Expr;
use crate::load::{Cx, Lookup, Where};
use crate::model::{BodyRef, Interpolation};
use crate::raw::{Value, Vec3, zero3};
use serde::Deserialize;

/// Tabulated force–deflection characteristic (bump stops):
/// F = f(x − x0) + d ẋ, with f through the rows (deflection m, force N) and
/// extended linearly beyond the end rows.
#[derive(Debug, Clone, PartialEq)]
pub struct Tabulated {
    /// Body of the first point.
    pub body1: BodyRef,
    /// First point, in the frame of `body1`, m.
    pub point1: [Expr; 3],
    /// Body of the second point.
    pub body2: BodyRef,
    /// Second point, in the frame of `body2`, m.
    pub point2: [Expr; 3],
    /// (deflection m, force N), deflection increasing.
    pub table: Vec<(Expr, Expr)>,
    /// Between the rows: straight lines, or a monotone cubic.
    pub interpolation: Interpolation,
    /// N s/m.
    pub damping: Expr,
    /// m.
    pub free_length: Expr,
}

/// `Tabulated(name, body1, point1, body2, point2, table, interpolation, d, x0)`.
#[derive(Debug, Deserialize)]
#[serde(rename = "Tabulated", deny_unknown_fields)]
pub(crate) struct RawTabulated {
    name: String,
    body1: String,
    #[serde(default = "zero3")]
    point1: Vec3,
    body2: String,
    #[serde(default = "zero3")]
    point2: Vec3,
    table: Vec<(Value, Value)>,
    #[serde(default)]
    interpolation: Interpolation,
    #[serde(default)]
    d: Value,
    #[serde(default)]
    x0: Value,
}

impl ForceSyntax for RawTabulated {
    type Spec = Tabulated;
    fn name(&self) -> &str {
        &self.name
    }
    fn resolve(&self, cx: &mut Cx, w: &Where, lookup: &Lookup) -> Tabulated {
        let table = &self.table;
        if table.len() < 2 {
            cx.err(
                w,
                Some("table"),
                None,
                format!("table needs at least 2 rows, got {}", table.len()),
            );
        }
        let rows: Vec<(Expr, Expr)> = table
            .iter()
            .enumerate()
            .map(|(k, (x, f))| {
                (
                    cx.expr(w, &format!("table[{k}].deflection"), "table", x, false),
                    cx.expr(w, &format!("table[{k}].force"), "table", f, false),
                )
            })
            .collect();
        let damping = cx.expr(w, "d", "d", &self.d, false);
        let (body1, point1, body2, point2) = cx.two_points(
            w,
            (&self.body1, &self.point1),
            (&self.body2, &self.point2),
            lookup,
        );
        Tabulated {
            body1,
            point1,
            body2,
            point2,
            table: rows,
            interpolation: self.interpolation,
            damping,
            free_length: cx.expr(w, "x0", "x0", &self.x0, false),
        }
    }
}

impl ForceSpec for Tabulated {
    fn exprs_mut(&mut self, f: &mut dyn FnMut(&mut Expr)) {
        self.point1
            .iter_mut()
            .chain(self.point2.iter_mut())
            .for_each(&mut *f);
        for (x, y) in &mut self.table {
            f(x);
            f(y);
        }
        f(&mut self.damping);
        f(&mut self.free_length);
    }
    fn bodies_mut(&mut self, f: &mut dyn FnMut(&mut usize)) {
        body_ref(&mut self.body1, f);
        body_ref(&mut self.body2, f);
    }
    fn check(&self, c: &mut Checks) {
        c.non_negative("d", &self.damping);
        let xs: Vec<f64> = self.table.iter().map(|(x, _)| c.value(x)).collect();
        if let Some(k) = (1..xs.len())
            .find(|&k| xs[k].partial_cmp(&xs[k - 1]) != Some(std::cmp::Ordering::Greater))
        {
            c.push(
                "table",
                format!(
                    "table deflections must increase: row {k} has {} after {}",
                    xs[k],
                    xs[k - 1]
                ),
            );
        }
    }
}
