//! `Tabulated`: a tabulated force–deflection characteristic (bump stops).

use super::point_pair::point_pair_syntax;
use super::{Checks, ForceSpec, ForceSyntax, PointPair};
use crate::expr::Expr;
use crate::load::{Cx, Lookup, Where};
use crate::model::Interpolation;
use crate::raw::Value;

/// Tabulated force–deflection characteristic (bump stops):
/// F = f(x − x0) + d ẋ, with f through the rows (deflection m, force N) and
/// extended linearly beyond the end rows.
#[derive(Debug, Clone, PartialEq)]
pub struct Tabulated {
    /// The two points.
    pub ends: PointPair,
    /// (deflection m, force N), deflection increasing.
    pub table: Vec<(Expr, Expr)>,
    /// Between the rows: straight lines, or a monotone cubic.
    pub interpolation: Interpolation,
    /// N s/m.
    pub damping: Expr,
    /// m.
    pub free_length: Expr,
}

point_pair_syntax! {
    /// `Tabulated(name, body1, point1, body2, point2, table, interpolation, d, x0)`.
    #[serde(rename = "Tabulated")]
    pub(crate) struct RawTabulated {
        table: Vec<(Value, Value)>,
        #[serde(default)]
        interpolation: Interpolation,
        #[serde(default)]
        d: Value,
        #[serde(default)]
        x0: Value,
    }
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
        let ends = self.ends().resolve(cx, w, lookup);
        Tabulated {
            ends,
            table: rows,
            interpolation: self.interpolation,
            damping,
            free_length: cx.expr(w, "x0", "x0", &self.x0, false),
        }
    }
}

impl ForceSpec for Tabulated {
    fn exprs_mut(&mut self, f: &mut dyn FnMut(&mut Expr)) {
        self.ends.exprs_mut(f);
        for (x, y) in &mut self.table {
            f(x);
            f(y);
        }
        f(&mut self.damping);
        f(&mut self.free_length);
    }
    fn bodies_mut(&mut self, f: &mut dyn FnMut(&mut usize)) {
        self.ends.bodies_mut(f);
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
