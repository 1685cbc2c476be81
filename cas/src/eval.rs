//! Numeric evaluation of expressions (a reference interpreter over the DAG).

use crate::graph::{Context, ExprId, Node, Symbol, SymbolKind};

/// Errors of the computer-algebra crate.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CasError {
    /// A symbol's index is outside the value array given for its kind.
    #[error("no value for symbol {symbol}: {len} value(s) given for that kind")]
    MissingValue {
        /// The symbol without a value.
        symbol: Symbol,
        /// Length of the array given for its kind.
        len: usize,
    },
    /// An operation produced NaN or ±∞ (division by zero, ln of a negative number, ...).
    #[error("evaluation produced the non-finite value {value} at {location}")]
    NonFinite {
        /// The value produced.
        value: f64,
        /// Where: the node or instruction that produced it.
        location: String,
    },
    /// A bad argument to a function of this crate.
    #[error("invalid argument: {0}")]
    InvalidArgument(String),
}

/// Values of the symbols, one array per [`SymbolKind`] (SI units as the model defines them).
#[derive(Clone, Copy, Debug, Default)]
pub struct Values<'a> {
    /// Generalized coordinates `q`.
    pub q: &'a [f64],
    /// Generalized velocities `v`.
    pub v: &'a [f64],
    /// Parameters `p`.
    pub p: &'a [f64],
    /// Inputs `u`.
    pub u: &'a [f64],
    /// Time `t` (s).
    pub t: f64,
}

impl Values<'_> {
    /// The value of one symbol, or [`CasError::MissingValue`].
    pub fn get(&self, s: Symbol) -> Result<f64, CasError> {
        let arr = match s.kind {
            SymbolKind::Coordinate => self.q,
            SymbolKind::Velocity => self.v,
            SymbolKind::Parameter => self.p,
            SymbolKind::Input => self.u,
            SymbolKind::Time => return Ok(self.t),
        };
        arr.get(s.index as usize)
            .copied()
            .ok_or(CasError::MissingValue {
                symbol: s,
                len: arr.len(),
            })
    }
}

fn node_kind(n: &Node) -> &'static str {
    match n {
        Node::Num(_) => "number",
        Node::Sym(_) => "symbol",
        Node::Add { .. } => "sum",
        Node::Mul { .. } => "product",
        Node::Call(f, _) => f.name(),
        Node::Atan2(..) => "atan2",
    }
}

impl Context {
    /// Evaluates `roots` at the given symbol values, each shared node once.
    ///
    /// Every intermediate value is checked: a NaN or infinity anywhere gives
    /// [`CasError::NonFinite`] naming the node, never a silent NaN.
    pub fn eval(&self, roots: &[ExprId], values: &Values) -> Result<Vec<f64>, CasError> {
        let order = self.reachable(roots);
        let Some(&last) = order.last() else {
            return Ok(Vec::new());
        };
        let mut val = vec![0.0; last.index() + 1];
        for id in order {
            let node = self.node(id);
            let x = match node {
                Node::Num(v) => *v,
                Node::Sym(s) => values.get(*s)?,
                Node::Add { constant, terms } => terms
                    .iter()
                    .fold(*constant, |acc, &(b, c)| acc + c * val[b.index()]),
                Node::Mul { factors } => {
                    // numerator / denominator, as the generated code computes it
                    let (mut num, mut den) = (1.0, 1.0);
                    for &(b, k) in factors.iter() {
                        if k > 0 {
                            num *= val[b.index()].powi(k);
                        } else {
                            den *= val[b.index()].powi(k.saturating_neg());
                        }
                    }
                    num / den
                }
                Node::Call(f, a) => f.apply(val[a.index()]),
                Node::Atan2(y, x) => val[y.index()].atan2(val[x.index()]),
            };
            if !x.is_finite() {
                return Err(CasError::NonFinite {
                    value: x,
                    location: format!("expression node {} ({})", id.index(), node_kind(node)),
                });
            }
            val[id.index()] = x;
        }
        Ok(roots.iter().map(|r| val[r.index()]).collect())
    }
}
