//! Differentiation (memoized per variable) and substitution (memoized per substitution).

use crate::graph::{Context, ExprId, Func, FxMap, Node, ONE, Symbol, ZERO, symbol_bit};

const UNKNOWN: u32 = u32::MAX;
const PENDING: u32 = u32::MAX - 1;

impl Context {
    /// Partial derivative ∂e/∂s.
    ///
    /// Memoized per variable for the life of the context: differentiating many expressions that
    /// share subexpressions (a Jacobian, or repeated calls) differentiates each node once.
    /// Iterative over the DAG (no recursion), cost linear in the number of new nodes visited.
    /// `d|u|/du = u/|u|` is undefined at `u = 0` (evaluation reports it as non-finite).
    pub fn diff(&mut self, e: ExprId, s: Symbol) -> ExprId {
        let mut cache = self.diff_cache.remove(&s).unwrap_or_default();
        let r = self.diff_with(&mut cache, e, s);
        self.diff_cache.insert(s, cache);
        r
    }

    /// Frees the differentiation memo (one `u32` per node and variable differentiated by).
    /// Later derivatives are recomputed (to the same nodes, by hash-consing).
    pub fn clear_diff_cache(&mut self) {
        self.diff_cache.clear();
    }

    /// Jacobian `J[i][j] = ∂fs[i]/∂vars[j]`.
    pub fn jacobian(&mut self, fs: &[ExprId], vars: &[Symbol]) -> Vec<Vec<ExprId>> {
        let mut out = vec![Vec::with_capacity(vars.len()); fs.len()];
        for &s in vars {
            let mut cache = self.diff_cache.remove(&s).unwrap_or_default();
            for (row, &f) in out.iter_mut().zip(fs) {
                row.push(self.diff_with(&mut cache, f, s));
            }
            self.diff_cache.insert(s, cache);
        }
        out
    }

    fn diff_with(&mut self, cache: &mut Vec<u32>, e: ExprId, s: Symbol) -> ExprId {
        if cache.len() < self.nodes.len() {
            cache.resize(self.nodes.len(), UNKNOWN);
        }
        if cache[e.index()] < PENDING {
            return ExprId(cache[e.index()]);
        }
        // Collect the not-yet-differentiated part of the DAG below e; subtrees whose
        // dependency summary excludes s have derivative 0 and are not entered.
        let bit = symbol_bit(s);
        if self.deps[e.index()] & bit == 0 {
            cache[e.index()] = ZERO.0;
            return ZERO;
        }
        let mut order = Vec::new();
        let mut stack = vec![e];
        cache[e.index()] = PENDING;
        while let Some(id) = stack.pop() {
            order.push(id);
            let deps = &self.deps;
            self.nodes[id.index()].for_each_child(|c| {
                if cache[c.index()] == UNKNOWN {
                    if deps[c.index()] & bit == 0 {
                        cache[c.index()] = ZERO.0;
                    } else {
                        cache[c.index()] = PENDING;
                        stack.push(c);
                    }
                }
            });
        }
        // Children have smaller ids: ascending order differentiates children first.
        order.sort_unstable();
        for id in order {
            let d = self.diff_node(id, s, cache);
            cache[id.index()] = d.0;
        }
        ExprId(cache[e.index()])
    }

    fn diff_node(&mut self, id: ExprId, s: Symbol, cache: &[u32]) -> ExprId {
        let d = |c: ExprId| ExprId(cache[c.index()]);
        match self.node(id) {
            Node::Num(_) => ZERO,
            Node::Sym(x) => {
                if *x == s {
                    ONE
                } else {
                    ZERO
                }
            }
            Node::Add { terms, .. } => {
                let ts: Vec<(ExprId, f64)> = terms
                    .iter()
                    .map(|&(b, c)| (d(b), c))
                    .filter(|t| t.0 != ZERO)
                    .collect();
                if ts.is_empty() {
                    ZERO
                } else {
                    self.sum(0.0, &ts)
                }
            }
            Node::Mul { factors } => {
                // d Π bᵢ^kᵢ = Σᵢ kᵢ·bᵢ^(kᵢ−1)·dbᵢ·Π_{j≠i} bⱼ^kⱼ
                let factors = factors.clone();
                let mut ts = Vec::new();
                for (i, &(b, k)) in factors.iter().enumerate() {
                    let db = d(b);
                    if db == ZERO {
                        continue;
                    }
                    let mut fs: Vec<(ExprId, i32)> = factors.to_vec();
                    fs[i].1 = fs[i].1.saturating_sub(1);
                    fs.push((db, 1));
                    let p = self.product(&fs);
                    ts.push((p, k as f64));
                }
                if ts.is_empty() {
                    ZERO
                } else {
                    self.sum(0.0, &ts)
                }
            }
            &Node::Call(f, u) => {
                let du = d(u);
                if du == ZERO {
                    return ZERO;
                }
                match f {
                    Func::Sin => {
                        let c = self.cos(u);
                        self.mul(c, du)
                    }
                    Func::Cos => {
                        let sn = self.sin(u);
                        let p = self.mul(sn, du);
                        self.neg(p)
                    }
                    // d tan u = du / cos²u
                    Func::Tan => {
                        let c = self.cos(u);
                        self.product(&[(c, -2), (du, 1)])
                    }
                    // d √u = du / (2√u)
                    Func::Sqrt => {
                        let p = self.product(&[(id, -1), (du, 1)]);
                        self.scale(0.5, p)
                    }
                    Func::Exp => self.mul(id, du),
                    Func::Ln => self.product(&[(u, -1), (du, 1)]),
                    // d|u| = (u/|u|)·du
                    Func::Abs => self.product(&[(u, 1), (id, -1), (du, 1)]),
                }
            }
            &Node::Atan2(y, x) => {
                // d atan2(y, x) = (x·dy − y·dx) / (x² + y²)
                let (dy, dx) = (d(y), d(x));
                if dy == ZERO && dx == ZERO {
                    return ZERO;
                }
                let a = self.mul(x, dy);
                let b = self.mul(y, dx);
                let num = self.sub(a, b);
                let x2 = self.powi(x, 2);
                let y2 = self.powi(y, 2);
                let den = self.add(x2, y2);
                self.div(num, den)
            }
        }
    }

    /// Replaces symbols by expressions in all `roots` (simultaneously: replacements are not
    /// substituted again). One memo is shared by all roots. For repeated use of the same
    /// replacement, keep a [`Substitution`].
    pub fn subs(&mut self, roots: &[ExprId], map: &[(Symbol, ExprId)]) -> Vec<ExprId> {
        let mut s = Substitution::new(map);
        roots.iter().map(|&r| s.apply(self, r)).collect()
    }

    /// Rebuilds `node` through the simplifying constructors, with operands mapped by `f`.
    pub fn rebuild(&mut self, node: &Node, f: impl Fn(ExprId) -> ExprId) -> ExprId {
        match node {
            Node::Num(v) => self.num(*v),
            Node::Sym(s) => self.sym(*s),
            Node::Add { constant, terms } => {
                let ts: Vec<(ExprId, f64)> = terms.iter().map(|&(b, c)| (f(b), c)).collect();
                self.sum(*constant, &ts)
            }
            Node::Mul { factors } => {
                let fs: Vec<(ExprId, i32)> = factors.iter().map(|&(b, k)| (f(b), k)).collect();
                self.product(&fs)
            }
            Node::Call(func, a) => {
                let a = f(*a);
                self.apply(*func, a)
            }
            Node::Atan2(y, x) => {
                let (y, x) = (f(*y), f(*x));
                self.atan2(y, x)
            }
        }
    }
}

/// A memoized substitution symbol → expression, reusable across many [`Substitution::apply`]
/// calls on the same [`Context`].
#[derive(Clone, Debug, Default)]
pub struct Substitution {
    map: FxMap<Symbol, ExprId>,
    memo: FxMap<ExprId, ExprId>,
}

impl Substitution {
    /// A substitution replacing each `symbol` by its expression. Later pairs win on duplicates.
    pub fn new(pairs: &[(Symbol, ExprId)]) -> Self {
        Substitution {
            map: pairs.iter().copied().collect(),
            memo: FxMap::default(),
        }
    }

    /// `e` with the symbols replaced, simplified by the constructors.
    pub fn apply(&mut self, ctx: &mut Context, e: ExprId) -> ExprId {
        if let Some(&r) = self.memo.get(&e) {
            return r;
        }
        // Subtrees whose dependency summary has none of the replaced symbols stay unchanged.
        let mask = self.map.keys().fold(0u128, |m, &s| m | symbol_bit(s));
        if ctx.deps[e.index()] & mask == 0 {
            return e;
        }
        // Unvisited part of the DAG below e, in ascending (topological) order.
        let mut order = Vec::new();
        let mut stack = vec![e];
        let mut seen: std::collections::HashSet<ExprId, crate::graph::FxBuild> = Default::default();
        seen.insert(e);
        while let Some(id) = stack.pop() {
            order.push(id);
            ctx.node(id).for_each_child(|c| {
                if self.memo.contains_key(&c) {
                    return;
                }
                if ctx.deps[c.index()] & mask == 0 {
                    self.memo.insert(c, c);
                } else if seen.insert(c) {
                    stack.push(c);
                }
            });
        }
        order.sort_unstable();
        for id in order {
            let node = ctx.node(id).clone();
            let r = match node {
                Node::Sym(s) => self.map.get(&s).copied().unwrap_or(id),
                Node::Num(_) => id,
                _ => {
                    let mut changed = false;
                    node.for_each_child(|c| changed |= self.memo[&c] != c);
                    if changed {
                        let memo = &self.memo;
                        ctx.rebuild(&node, |c| memo[&c])
                    } else {
                        id
                    }
                }
            };
            self.memo.insert(id, r);
        }
        self.memo[&e]
    }
}
