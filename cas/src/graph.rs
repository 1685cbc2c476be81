//! The hash-consed expression arena and its simplifying constructors.

use std::fmt;

/// Largest sum that is merged (flattened) into an enclosing sum; see `push_term`.
pub const FLATTEN_LIMIT: usize = 8;

/// Handle of an expression node in a [`Context`]: a `u32` index into the arena.
///
/// Ids are only meaningful for the context that created them. A node's operands always have
/// smaller ids than the node itself (the arena is append-only), so ascending id order is a
/// topological order of any sub-DAG.
#[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Debug)]
pub struct ExprId(pub(crate) u32);

impl ExprId {
    /// Position of the node in the arena.
    pub fn index(self) -> usize {
        self.0 as usize
    }
}

/// What a symbol stands for; code generation maps each kind to one input array.
#[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Debug)]
pub enum SymbolKind {
    /// Generalized coordinate `q[i]` (m or rad).
    Coordinate,
    /// Generalized velocity `v[i]` = `dq[i]/dt` (m/s or rad/s).
    Velocity,
    /// Model parameter `p[i]` (any unit), a runtime input of the plugin.
    Parameter,
    /// Other time-dependent input `u[i]` (e.g. track-frame kinematics).
    Input,
    /// Time `t` (s); its index is ignored and always 0.
    Time,
}

/// A symbol: a kind and an index into the input array of that kind.
#[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Debug)]
pub struct Symbol {
    /// Which input array the symbol lives in.
    pub kind: SymbolKind,
    /// Index in that array.
    pub index: u32,
}

impl Symbol {
    /// Generalized coordinate `q[index]`.
    pub fn q(index: u32) -> Self {
        Symbol {
            kind: SymbolKind::Coordinate,
            index,
        }
    }
    /// Generalized velocity `v[index]`.
    pub fn v(index: u32) -> Self {
        Symbol {
            kind: SymbolKind::Velocity,
            index,
        }
    }
    /// Parameter `p[index]`.
    pub fn p(index: u32) -> Self {
        Symbol {
            kind: SymbolKind::Parameter,
            index,
        }
    }
    /// Input `u[index]`.
    pub fn u(index: u32) -> Self {
        Symbol {
            kind: SymbolKind::Input,
            index,
        }
    }
    /// Time `t`.
    pub fn t() -> Self {
        Symbol {
            kind: SymbolKind::Time,
            index: 0,
        }
    }
}

impl fmt::Display for Symbol {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.kind {
            SymbolKind::Coordinate => write!(f, "q[{}]", self.index),
            SymbolKind::Velocity => write!(f, "v[{}]", self.index),
            SymbolKind::Parameter => write!(f, "p[{}]", self.index),
            SymbolKind::Input => write!(f, "u[{}]", self.index),
            SymbolKind::Time => write!(f, "t"),
        }
    }
}

/// Elementary functions of one argument.
#[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord, Debug)]
pub enum Func {
    /// sin x (x in rad).
    Sin,
    /// cos x (x in rad).
    Cos,
    /// tan x (x in rad).
    Tan,
    /// Square root (principal, x ≥ 0).
    Sqrt,
    /// e^x.
    Exp,
    /// Natural logarithm (x > 0).
    Ln,
    /// |x|.
    Abs,
}

impl Func {
    /// Rust method name of the function on `f64`.
    pub fn name(self) -> &'static str {
        match self {
            Func::Sin => "sin",
            Func::Cos => "cos",
            Func::Tan => "tan",
            Func::Sqrt => "sqrt",
            Func::Exp => "exp",
            Func::Ln => "ln",
            Func::Abs => "abs",
        }
    }

    /// Evaluates the function in f64.
    pub fn apply(self, x: f64) -> f64 {
        match self {
            Func::Sin => x.sin(),
            Func::Cos => x.cos(),
            Func::Tan => x.tan(),
            Func::Sqrt => x.sqrt(),
            Func::Exp => x.exp(),
            Func::Ln => x.ln(),
            Func::Abs => x.abs(),
        }
    }
}

/// One node of the DAG. Invariants (kept by the constructors of [`Context`]):
///
/// * `Num` holds a number with `-0.0` normalized to `0.0`.
/// * `Add { constant, terms }` is `constant + Σ cᵢ·bᵢ`: terms sorted by id, distinct bases, no zero
///   coefficient, no base that is a `Num` or an `Add` of at most [`FLATTEN_LIMIT`] terms (larger
///   sums stay one shared operand). Either it has ≥ 2 terms, or one term with
///   `constant ≠ 0` or `c ≠ 1`. A *scaled term* `c·b` is an `Add` with `constant = 0` and one term;
///   negation is the scaled term with `c = −1`.
/// * `Mul { factors }` is `Π bᵢ^kᵢ` with integer `kᵢ ≠ 0`: sorted by id, distinct bases, no base
///   that is a `Mul` or a scaled term (numeric factors are pulled out into a scaled term around
///   the product). A `Num` base occurs only as `v^k` with `v > 0`, `k < 0` and `c/v^|k|` not
///   exactly representable for the coefficient `c` around the product (so `x/3` stays a
///   division by 3 while `x/4 = 0.25·x`). Either ≥ 2 factors or one factor with `k ≠ 1`.
///   Division is a negative exponent; integer powers are single-factor products.
#[derive(Clone, Debug)]
pub enum Node {
    /// A number.
    Num(f64),
    /// A symbol.
    Sym(Symbol),
    /// `constant + Σ c·base`.
    Add {
        /// Numeric constant term.
        constant: f64,
        /// `(base, coefficient)` pairs.
        terms: Box<[(ExprId, f64)]>,
    },
    /// `Π base^exponent`.
    Mul {
        /// `(base, exponent)` pairs.
        factors: Box<[(ExprId, i32)]>,
    },
    /// An elementary function of one argument.
    Call(Func, ExprId),
    /// `atan2(y, x)`: the angle of the point (x, y), in (−π, π].
    Atan2(ExprId, ExprId),
}

impl Node {
    /// Calls `f` on every operand of the node.
    pub fn for_each_child(&self, mut f: impl FnMut(ExprId)) {
        match self {
            Node::Num(_) | Node::Sym(_) => {}
            Node::Add { terms, .. } => terms.iter().for_each(|&(b, _)| f(b)),
            Node::Mul { factors } => factors.iter().for_each(|&(b, _)| f(b)),
            Node::Call(_, a) => f(*a),
            Node::Atan2(y, x) => {
                f(*y);
                f(*x)
            }
        }
    }
}

impl PartialEq for Node {
    fn eq(&self, other: &Self) -> bool {
        match (self, other) {
            (Node::Num(a), Node::Num(b)) => a.to_bits() == b.to_bits(),
            (Node::Sym(a), Node::Sym(b)) => a == b,
            (
                Node::Add {
                    constant: c1,
                    terms: t1,
                },
                Node::Add {
                    constant: c2,
                    terms: t2,
                },
            ) => {
                c1.to_bits() == c2.to_bits()
                    && t1.len() == t2.len()
                    && t1
                        .iter()
                        .zip(t2.iter())
                        .all(|(a, b)| a.0 == b.0 && a.1.to_bits() == b.1.to_bits())
            }
            (Node::Mul { factors: f1 }, Node::Mul { factors: f2 }) => f1 == f2,
            (Node::Call(f1, a1), Node::Call(f2, a2)) => f1 == f2 && a1 == a2,
            (Node::Atan2(y1, x1), Node::Atan2(y2, x2)) => y1 == y2 && x1 == x2,
            _ => false,
        }
    }
}

/// A node's hash for the interning table (nodes are hashed once, on interning).
fn hash_node(n: &Node) -> u64 {
    use std::hash::Hasher;
    let mut h = rustc_hash::FxHasher::default();
    match n {
        Node::Num(v) => {
            h.write_u64(1);
            h.write_u64(v.to_bits());
        }
        Node::Sym(s) => {
            h.write_u64(2);
            h.write_u64(s.kind as u64);
            h.write_u64(s.index as u64);
        }
        Node::Add { constant, terms } => {
            h.write_u64(3);
            h.write_u64(constant.to_bits());
            for (b, c) in terms.iter() {
                h.write_u64(b.0 as u64);
                h.write_u64(c.to_bits());
            }
        }
        Node::Mul { factors } => {
            h.write_u64(4);
            for (b, k) in factors.iter() {
                h.write_u64(((b.0 as u64) << 32) | (*k as u32 as u64));
            }
        }
        Node::Call(f, a) => {
            h.write_u64(5);
            h.write_u64(*f as u64);
            h.write_u64(a.0 as u64);
        }
        Node::Atan2(y, x) => {
            h.write_u64(6);
            h.write_u64(((y.0 as u64) << 32) | x.0 as u64);
        }
    }
    h.finish()
}

/// `BuildHasher` for the crate's internal maps (keys are small integers; SipHash's
/// DoS-resistance is not needed and costs a large share of CSE time).
pub(crate) type FxBuild = rustc_hash::FxBuildHasher;

/// Hash map with [`FxBuild`].
pub(crate) type FxMap<K, V> = std::collections::HashMap<K, V, FxBuild>;

const EMPTY: u32 = u32::MAX;

/// The dependency bit of a symbol: coordinates use bits 0–63 (index mod 64), velocities bits
/// 64–119 (index mod 56), parameters, inputs and time share bits 120–127. Symbols sharing a
/// bit only make the independence test less sharp, never wrong.
pub(crate) fn symbol_bit(s: Symbol) -> u128 {
    let b = match s.kind {
        SymbolKind::Coordinate => s.index % 64,
        SymbolKind::Velocity => 64 + s.index % 56,
        SymbolKind::Parameter => 120 + s.index % 4,
        SymbolKind::Input => 124 + s.index % 3,
        SymbolKind::Time => 127,
    };
    1u128 << b
}

/// Normalizes a number for storage: `-0.0` becomes `0.0`.
fn norm(v: f64) -> f64 {
    if v == 0.0 { 0.0 } else { v }
}

/// The arena owning all expression nodes, with hash-consing (structurally equal nodes are stored
/// once) and the memo tables of differentiation.
pub struct Context {
    pub(crate) nodes: Vec<Node>,
    hashes: Vec<u64>,
    /// Per node: a 128-bit summary of the symbols it depends on (see [`symbol_bit`]); a clear
    /// bit proves independence, so differentiation skips such subtrees without visiting them.
    pub(crate) deps: Vec<u128>,
    table: Vec<u32>,
    /// Per differentiation variable: derivative of node `i` at index `i` (`EMPTY` = unknown).
    pub(crate) diff_cache: FxMap<Symbol, Vec<u32>>,
}

impl Default for Context {
    fn default() -> Self {
        Self::new()
    }
}

impl fmt::Debug for Context {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "Context({} nodes)", self.nodes.len())
    }
}

/// The number 0 (always id 0).
pub const ZERO: ExprId = ExprId(0);
/// The number 1 (always id 1).
pub const ONE: ExprId = ExprId(1);

impl Context {
    /// An empty context holding the numbers 0 ([`ZERO`]) and 1 ([`ONE`]).
    pub fn new() -> Self {
        let mut c = Context {
            nodes: Vec::new(),
            hashes: Vec::new(),
            deps: Vec::new(),
            table: vec![EMPTY; 64],
            diff_cache: Default::default(),
        };
        let z = c.intern(Node::Num(0.0));
        let o = c.intern(Node::Num(1.0));
        debug_assert_eq!((z, o), (ZERO, ONE));
        c
    }

    /// Number of nodes in the arena.
    pub fn len(&self) -> usize {
        self.nodes.len()
    }

    /// Always false: a context holds at least 0 and 1.
    pub fn is_empty(&self) -> bool {
        self.nodes.is_empty()
    }

    /// The node behind an id.
    ///
    /// Panics if `id` does not belong to this context (a programming error, like an out-of-range
    /// slice index).
    pub fn node(&self, id: ExprId) -> &Node {
        &self.nodes[id.index()]
    }

    /// The value if the node is a number.
    pub fn as_num(&self, id: ExprId) -> Option<f64> {
        match self.node(id) {
            Node::Num(v) => Some(*v),
            _ => None,
        }
    }

    /// The symbol if the node is a symbol.
    pub fn as_symbol(&self, id: ExprId) -> Option<Symbol> {
        match self.node(id) {
            Node::Sym(s) => Some(*s),
            _ => None,
        }
    }

    pub(crate) fn intern(&mut self, node: Node) -> ExprId {
        let h = hash_node(&node);
        if (self.nodes.len() + 1) * 2 > self.table.len() {
            self.grow();
        }
        let mask = self.table.len() - 1;
        let mut i = (h as usize) & mask;
        loop {
            let slot = self.table[i];
            if slot == EMPTY {
                let id = u32::try_from(self.nodes.len())
                    .ok()
                    .filter(|&id| id < EMPTY)
                    .expect("railmbs-cas: more than 2^32-1 expression nodes");
                let mut d = 0u128;
                match &node {
                    Node::Sym(s) => d = symbol_bit(*s),
                    other => other.for_each_child(|c| d |= self.deps[c.index()]),
                }
                self.deps.push(d);
                self.nodes.push(node);
                self.hashes.push(h);
                self.table[i] = id;
                return ExprId(id);
            }
            let s = slot as usize;
            if self.hashes[s] == h && self.nodes[s] == node {
                return ExprId(slot);
            }
            i = (i + 1) & mask;
        }
    }

    fn grow(&mut self) {
        let n = self.table.len() * 2;
        let mask = n - 1;
        let mut table = vec![EMPTY; n];
        for (id, &h) in self.hashes.iter().enumerate() {
            let mut i = (h as usize) & mask;
            while table[i] != EMPTY {
                i = (i + 1) & mask;
            }
            table[i] = id as u32;
        }
        self.table = table;
    }

    // ----------------------------------------------------------------------------------------
    // Leaves
    // ----------------------------------------------------------------------------------------

    /// A number. Non-finite values are accepted (they are reported by evaluation).
    pub fn num(&mut self, v: f64) -> ExprId {
        let v = norm(v);
        if v == 0.0 {
            return ZERO;
        }
        if v == 1.0 {
            return ONE;
        }
        self.intern(Node::Num(v))
    }

    /// A symbol.
    pub fn sym(&mut self, s: Symbol) -> ExprId {
        let s = if s.kind == SymbolKind::Time {
            Symbol::t()
        } else {
            s
        };
        self.intern(Node::Sym(s))
    }

    /// Generalized coordinate `q[i]`.
    pub fn q(&mut self, i: u32) -> ExprId {
        self.sym(Symbol::q(i))
    }

    /// Generalized velocity `v[i]`.
    pub fn v(&mut self, i: u32) -> ExprId {
        self.sym(Symbol::v(i))
    }

    /// Parameter `p[i]`.
    pub fn p(&mut self, i: u32) -> ExprId {
        self.sym(Symbol::p(i))
    }

    /// Input `u[i]`.
    pub fn u(&mut self, i: u32) -> ExprId {
        self.sym(Symbol::u(i))
    }

    /// Time `t`.
    pub fn t(&mut self) -> ExprId {
        self.sym(Symbol::t())
    }

    // ----------------------------------------------------------------------------------------
    // Sums
    // ----------------------------------------------------------------------------------------

    /// `a + b`.
    pub fn add(&mut self, a: ExprId, b: ExprId) -> ExprId {
        if a == ZERO {
            return b;
        }
        if b == ZERO {
            return a;
        }
        self.sum(0.0, &[(a, 1.0), (b, 1.0)])
    }

    /// `a − b`.
    pub fn sub(&mut self, a: ExprId, b: ExprId) -> ExprId {
        self.sum(0.0, &[(a, 1.0), (b, -1.0)])
    }

    /// `−a`.
    pub fn neg(&mut self, a: ExprId) -> ExprId {
        self.scale(-1.0, a)
    }

    /// `c·a`.
    pub fn scale(&mut self, c: f64, a: ExprId) -> ExprId {
        self.sum(0.0, &[(a, c)])
    }

    /// `Σ xᵢ`, n-ary (cost O(n log n), independent of how the operands were built).
    pub fn add_many(&mut self, xs: &[ExprId]) -> ExprId {
        let mut constant = 0.0;
        let mut terms = Vec::with_capacity(xs.len());
        for &x in xs {
            self.push_term(&mut constant, &mut terms, x, 1.0);
        }
        self.finish_sum(constant, terms)
    }

    /// `constant + Σ cᵢ·xᵢ`, n-ary.
    pub fn sum(&mut self, constant: f64, terms: &[(ExprId, f64)]) -> ExprId {
        let mut k = constant;
        let mut out = Vec::with_capacity(terms.len());
        for &(x, c) in terms {
            self.push_term(&mut k, &mut out, x, c);
        }
        self.finish_sum(k, out)
    }

    /// Splits `x` into coefficient and base: `c·b` for a scaled term, `(1, x)` otherwise.
    /// Numbers give `(v, ONE)`.
    pub fn split_coeff(&self, x: ExprId) -> (f64, ExprId) {
        match self.node(x) {
            Node::Num(v) => (*v, ONE),
            Node::Add { constant, terms } if *constant == 0.0 && terms.len() == 1 => {
                (terms[0].1, terms[0].0)
            }
            _ => (1.0, x),
        }
    }

    fn push_term(&self, constant: &mut f64, terms: &mut Vec<(ExprId, f64)>, x: ExprId, c: f64) {
        match self.node(x) {
            Node::Num(v) => *constant += c * v,
            // Sums of more than FLATTEN_LIMIT terms stay one shared operand: recursive
            // accumulations (positions down a chain, composite bodies, moments carried
            // joint by joint) then cost O(1) per step instead of a fresh O(depth) sum,
            // which made the equations of an N-link chain O(N³). Like terms inside such
            // a sum no longer meet terms outside it (a lost cancellation, never a wrong
            // value).
            Node::Add {
                constant: k,
                terms: ts,
            } if ts.len() <= FLATTEN_LIMIT => {
                *constant += c * k;
                terms.extend(ts.iter().map(|&(b, d)| (b, c * d)));
            }
            _ => terms.push((x, c)),
        }
    }

    fn finish_sum(&mut self, constant: f64, mut terms: Vec<(ExprId, f64)>) -> ExprId {
        let mut constant = constant;
        collect_like(&mut terms);
        // c·(product with numbers kept as factors, e.g. x·3⁻¹) may now fold exactly:
        // 3·(x·3⁻¹) = x. Re-multiplying may merge terms again: a few rounds at most.
        for _ in 0..4 {
            if !terms
                .iter()
                .any(|&(b, c)| c != 1.0 && self.has_numeric_factor(b))
            {
                break;
            }
            let mut changed = false;
            let old = std::mem::take(&mut terms);
            for (b, c) in old {
                if c != 1.0 && self.has_numeric_factor(b) {
                    let cn = self.num(c);
                    let p = self.mul(cn, b);
                    if self.split_coeff(p) != (c, b) {
                        changed = true;
                        self.push_term(&mut constant, &mut terms, p, 1.0);
                        continue;
                    }
                }
                terms.push((b, c));
            }
            if !changed {
                break;
            }
            collect_like(&mut terms);
        }
        // sin²+cos² may produce new terms that merge with existing ones: repeat (each round
        // removes at least one term, so this terminates).
        while self.pythagoras(&mut constant, &mut terms) {
            collect_like(&mut terms);
        }
        let constant = norm(constant);
        match terms.len() {
            0 => self.num(constant),
            1 if constant == 0.0 && terms[0].1 == 1.0 => terms[0].0,
            _ => self.intern(Node::Add {
                constant,
                terms: terms.into_boxed_slice(),
            }),
        }
    }

    /// A product with a number among its factors (kept because its reciprocal is inexact).
    fn has_numeric_factor(&self, b: ExprId) -> bool {
        match self.node(b) {
            Node::Mul { factors } => factors
                .iter()
                .any(|&(f, _)| matches!(self.node(f), Node::Num(_))),
            _ => false,
        }
    }

    /// Replaces pairs `c·sin(u)^k·P + c·cos(u)^m·P'` where both exponents are ≥ 2 and
    /// `sin(u)^(k−2)·P = cos(u)^(m−2)·P'` (equal coefficient, same remaining monomial) by `c·R`
    /// with `R` that common remainder. Returns whether anything changed.
    fn pythagoras(&mut self, constant: &mut f64, terms: &mut Vec<(ExprId, f64)>) -> bool {
        if terms.len() < 2 {
            return false;
        }
        // Candidates: (term index, argument u, factor position in the Mul).
        let mut sins: Vec<(usize, ExprId, usize)> = Vec::new();
        let mut coss: Vec<(usize, ExprId, usize)> = Vec::new();
        for (i, &(b, _)) in terms.iter().enumerate() {
            if let Node::Mul { factors } = self.node(b) {
                for (j, &(f, k)) in factors.iter().enumerate() {
                    if k >= 2 {
                        match self.node(f) {
                            Node::Call(Func::Sin, u) => sins.push((i, *u, j)),
                            Node::Call(Func::Cos, u) => coss.push((i, *u, j)),
                            _ => {}
                        }
                    }
                }
            }
        }
        if sins.is_empty() || coss.is_empty() {
            return false;
        }
        // Cheap filter: only arguments that appear squared under both sin and cos.
        let sin_args: std::collections::HashSet<ExprId, FxBuild> =
            sins.iter().map(|s| s.1).collect();
        coss.retain(|c| sin_args.contains(&c.1));
        if coss.is_empty() {
            return false;
        }
        let cos_args: std::collections::HashSet<ExprId, FxBuild> =
            coss.iter().map(|c| c.1).collect();
        sins.retain(|s| cos_args.contains(&s.1));
        // (argument, remainder, coefficient bits) → sine terms with that key.
        let mut by_key: FxMap<(ExprId, ExprId, u64), Vec<usize>> = FxMap::default();
        for &(i, u, j) in &sins {
            let r = self.remove_square(terms[i].0, j);
            by_key
                .entry((u, r, terms[i].1.to_bits()))
                .or_default()
                .push(i);
        }
        let mut used = vec![false; terms.len()];
        let mut new_terms = Vec::new();
        for &(i, u, j) in &coss {
            if used[i] {
                continue;
            }
            let r = self.remove_square(terms[i].0, j);
            let c = terms[i].1;
            if let Some(list) = by_key.get_mut(&(u, r, c.to_bits()))
                && let Some(pos) = list.iter().position(|&si| !used[si] && si != i)
            {
                let si = list.swap_remove(pos);
                used[si] = true;
                used[i] = true;
                new_terms.push((r, c));
            }
        }
        if new_terms.is_empty() {
            return false;
        }
        let mut k = 0;
        terms.retain(|_| {
            let keep = !used[k];
            k += 1;
            keep
        });
        for (r, c) in new_terms {
            self.push_term(constant, terms, r, c);
        }
        true
    }

    /// The product `b` (a `Mul`) with the exponent of its factor `j` lowered by 2.
    fn remove_square(&mut self, b: ExprId, j: usize) -> ExprId {
        let Node::Mul { factors } = self.node(b) else {
            return b;
        };
        let mut fs: Vec<(ExprId, i32)> = factors.to_vec();
        fs[j].1 -= 2;
        if fs[j].1 == 0 {
            fs.remove(j);
        }
        self.mul_canonical(fs)
    }

    /// Interns a product from factors that are already canonical (sorted, merged, non-zero
    /// exponents, valid bases).
    fn mul_canonical(&mut self, fs: Vec<(ExprId, i32)>) -> ExprId {
        match fs.len() {
            0 => ONE,
            1 if fs[0].1 == 1 => fs[0].0,
            _ => self.intern(Node::Mul {
                factors: fs.into_boxed_slice(),
            }),
        }
    }

    // ----------------------------------------------------------------------------------------
    // Products
    // ----------------------------------------------------------------------------------------

    /// `a·b`.
    pub fn mul(&mut self, a: ExprId, b: ExprId) -> ExprId {
        if a == ZERO || b == ZERO {
            return ZERO;
        }
        if a == ONE {
            return b;
        }
        if b == ONE {
            return a;
        }
        self.product(&[(a, 1), (b, 1)])
    }

    /// `a / b` (the product `a·b⁻¹`).
    pub fn div(&mut self, a: ExprId, b: ExprId) -> ExprId {
        self.product(&[(a, 1), (b, -1)])
    }

    /// `1 / a`.
    pub fn recip(&mut self, a: ExprId) -> ExprId {
        self.product(&[(a, -1)])
    }

    /// `aⁿ` for an integer n.
    pub fn powi(&mut self, a: ExprId, n: i32) -> ExprId {
        self.product(&[(a, n)])
    }

    /// `Π xᵢ`, n-ary.
    pub fn mul_many(&mut self, xs: &[ExprId]) -> ExprId {
        let fs: Vec<(ExprId, i32)> = xs.iter().map(|&x| (x, 1)).collect();
        self.product(&fs)
    }

    /// `Π xᵢ^kᵢ`, n-ary with integer exponents.
    pub fn product(&mut self, factors: &[(ExprId, i32)]) -> ExprId {
        let mut coeff = 1.0;
        let mut fs = Vec::with_capacity(factors.len() + 2);
        let mut nums = Vec::new();
        for &(x, k) in factors {
            self.push_factor(&mut coeff, &mut fs, &mut nums, x, k);
        }
        self.finish_product(coeff, fs, nums)
    }

    /// Adds `x^k` to a product under construction: numeric coefficients with positive powers
    /// go into `coeff`, with negative powers into `nums` (folded later only if exact),
    /// products are flattened.
    fn push_factor(
        &self,
        coeff: &mut f64,
        fs: &mut Vec<(ExprId, i32)>,
        nums: &mut Vec<(f64, i32)>,
        x: ExprId,
        k: i32,
    ) {
        if k == 0 {
            return;
        }
        let (c, b) = self.split_coeff(x);
        if c != 1.0 {
            if k > 0 {
                *coeff *= c.powi(k);
            } else {
                nums.push((c, k));
            }
        }
        if b == ONE {
            return;
        }
        match self.node(b) {
            Node::Mul { factors } => {
                fs.extend(factors.iter().map(|&(f, e)| (f, e.saturating_mul(k))));
            }
            _ => fs.push((b, k)),
        }
    }

    fn finish_product(
        &mut self,
        coeff: f64,
        mut fs: Vec<(ExprId, i32)>,
        mut nums: Vec<(f64, i32)>,
    ) -> ExprId {
        let mut coeff = coeff;
        // Numeric bases kept from earlier products (inexact reciprocals) join the numbers.
        fs.retain(|&(f, k)| match self.nodes[f.index()] {
            Node::Num(v) => {
                nums.push((v, k));
                false
            }
            _ => true,
        });
        if !nums.is_empty() {
            // Canonical sign: (−v)^k = (−1)^k·v^k.
            for n in nums.iter_mut() {
                if n.0 < 0.0 {
                    n.0 = -n.0;
                    if n.1 % 2 != 0 {
                        coeff = -coeff;
                    }
                }
            }
            nums.sort_unstable_by(|a, b| a.0.total_cmp(&b.0));
            let mut merged: Vec<(f64, i32)> = Vec::with_capacity(nums.len());
            for (v, k) in nums {
                match merged.last_mut() {
                    Some(last) if last.0.to_bits() == v.to_bits() => {
                        last.1 = last.1.saturating_add(k)
                    }
                    _ => merged.push((v, k)),
                }
            }
            // Positive powers fold (like all products of numbers); negative powers fold only
            // when the quotient is exact, otherwise the number stays a factor `v^k` (so x/3
            // is evaluated as a division, and 3·(x/3) = x).
            for &(v, k) in merged.iter().filter(|n| n.1 > 0) {
                coeff *= v.powi(k);
            }
            for &(v, k) in merged.iter().filter(|n| n.1 < 0) {
                match exact_div_pow(coeff, v, k.unsigned_abs()) {
                    Some(r) => coeff = r,
                    None => {
                        let id = self.num(v);
                        if id != ONE {
                            fs.push((id, k));
                        }
                    }
                }
            }
        }
        if coeff == 0.0 {
            return ZERO;
        }
        fs.sort_unstable_by_key(|f| f.0);
        let mut w = 0;
        for r in 0..fs.len() {
            if w > 0 && fs[w - 1].0 == fs[r].0 {
                fs[w - 1].1 = fs[w - 1].1.saturating_add(fs[r].1);
            } else {
                fs[w] = fs[r];
                w += 1;
            }
        }
        fs.truncate(w);
        fs.retain(|f| f.1 != 0);
        // sqrt(u)^k with |k| ≥ 2: u^(k/2) · sqrt(u)^(k mod 2), valid on sqrt's domain u ≥ 0.
        if let Some((pos, u)) = fs
            .iter()
            .enumerate()
            .find_map(|(i, &(f, k))| match self.node(f) {
                Node::Call(Func::Sqrt, u) if k.unsigned_abs() >= 2 => Some((i, *u)),
                _ => None,
            })
        {
            let k = fs[pos].1;
            fs[pos].1 = k % 2;
            let mut rest: Vec<(ExprId, i32)> = fs.into_iter().filter(|f| f.1 != 0).collect();
            let mut c = coeff;
            let mut more = Vec::new();
            let mut nums = Vec::new();
            self.push_factor(&mut c, &mut more, &mut nums, u, k / 2);
            rest.extend(more);
            return self.finish_product(c, rest, nums);
        }
        let base = self.mul_canonical(fs);
        if base == ONE {
            return self.num(coeff);
        }
        if coeff == 1.0 {
            base
        } else {
            self.intern(Node::Add {
                constant: 0.0,
                terms: Box::new([(base, norm(coeff))]),
            })
        }
    }

    // ----------------------------------------------------------------------------------------
    // Functions
    // ----------------------------------------------------------------------------------------

    /// True if `x` is in "negative form": a negative scaled term, or a sum whose constant (if
    /// non-zero) or else first term's coefficient is negative. Exactly one of `x` and `−x` is in
    /// negative form (for non-numbers), which gives odd/even functions a canonical argument.
    pub fn is_negative_form(&self, x: ExprId) -> bool {
        match self.node(x) {
            Node::Num(v) => *v < 0.0,
            Node::Add { constant, terms } => {
                if *constant != 0.0 {
                    *constant < 0.0
                } else {
                    terms[0].1 < 0.0
                }
            }
            _ => false,
        }
    }

    fn fold(&mut self, f: Func, x: ExprId) -> Option<ExprId> {
        let v = self.as_num(x)?;
        let r = f.apply(v);
        // Fold only results that stay finite; others are kept symbolic and reported by evaluation.
        r.is_finite().then(|| self.num(r))
    }

    fn call(&mut self, f: Func, x: ExprId) -> ExprId {
        self.intern(Node::Call(f, x))
    }

    /// `sin x`; `sin(−x) = −sin x`.
    pub fn sin(&mut self, x: ExprId) -> ExprId {
        if let Some(r) = self.fold(Func::Sin, x) {
            return r;
        }
        if self.is_negative_form(x) {
            let m = self.neg(x);
            let s = self.call(Func::Sin, m);
            return self.neg(s);
        }
        self.call(Func::Sin, x)
    }

    /// `cos x`; `cos(−x) = cos x`.
    pub fn cos(&mut self, x: ExprId) -> ExprId {
        if let Some(r) = self.fold(Func::Cos, x) {
            return r;
        }
        if self.is_negative_form(x) {
            let m = self.neg(x);
            return self.call(Func::Cos, m);
        }
        self.call(Func::Cos, x)
    }

    /// `tan x`; `tan(−x) = −tan x`.
    pub fn tan(&mut self, x: ExprId) -> ExprId {
        if let Some(r) = self.fold(Func::Tan, x) {
            return r;
        }
        if self.is_negative_form(x) {
            let m = self.neg(x);
            let s = self.call(Func::Tan, m);
            return self.neg(s);
        }
        self.call(Func::Tan, x)
    }

    /// `√x`; `√(x²) = |x|`.
    pub fn sqrt(&mut self, x: ExprId) -> ExprId {
        if let Some(r) = self.fold(Func::Sqrt, x) {
            return r;
        }
        if let Node::Mul { factors } = self.node(x)
            && factors.len() == 1
            && factors[0].1 == 2
        {
            let b = factors[0].0;
            return self.abs(b);
        }
        self.call(Func::Sqrt, x)
    }

    /// `eˣ`; `exp(ln y) = y`.
    pub fn exp(&mut self, x: ExprId) -> ExprId {
        if let Some(r) = self.fold(Func::Exp, x) {
            return r;
        }
        if let Node::Call(Func::Ln, y) = *self.node(x) {
            return y;
        }
        self.call(Func::Exp, x)
    }

    /// `ln x`; `ln(eʸ) = y`.
    pub fn ln(&mut self, x: ExprId) -> ExprId {
        if let Some(r) = self.fold(Func::Ln, x) {
            return r;
        }
        if let Node::Call(Func::Exp, y) = *self.node(x) {
            return y;
        }
        self.call(Func::Ln, x)
    }

    /// `|x|`; `|−x| = |x|`, `||x|| = |x|`.
    pub fn abs(&mut self, x: ExprId) -> ExprId {
        if let Some(r) = self.fold(Func::Abs, x) {
            return r;
        }
        if matches!(self.node(x), Node::Call(Func::Abs, _)) {
            return x;
        }
        if self.is_negative_form(x) {
            let m = self.neg(x);
            return self.abs(m);
        }
        self.call(Func::Abs, x)
    }

    /// Applies `f` through its simplifying constructor.
    pub fn apply(&mut self, f: Func, x: ExprId) -> ExprId {
        match f {
            Func::Sin => self.sin(x),
            Func::Cos => self.cos(x),
            Func::Tan => self.tan(x),
            Func::Sqrt => self.sqrt(x),
            Func::Exp => self.exp(x),
            Func::Ln => self.ln(x),
            Func::Abs => self.abs(x),
        }
    }

    /// `atan2(y, x)`, folded when both are numbers.
    pub fn atan2(&mut self, y: ExprId, x: ExprId) -> ExprId {
        if let (Some(a), Some(b)) = (self.as_num(y), self.as_num(x)) {
            return self.num(a.atan2(b));
        }
        self.intern(Node::Atan2(y, x))
    }

    /// Distributes products and positive integer powers over sums (recursively through the
    /// arguments of functions too). Cost can grow exponentially with nesting: use on small
    /// expressions only (e.g. to compare forms in tests). Negative powers of sums are kept.
    pub fn expand(&mut self, x: ExprId) -> ExprId {
        let order = self.reachable(&[x]);
        let mut map: FxMap<ExprId, ExprId> = Default::default();
        for id in order {
            let node = self.node(id).clone();
            let r = match node {
                Node::Num(_) | Node::Sym(_) => id,
                Node::Add { constant, terms } => {
                    let ts: Vec<(ExprId, f64)> = terms.iter().map(|&(b, c)| (map[&b], c)).collect();
                    self.sum(constant, &ts)
                }
                Node::Mul { factors } => {
                    // Multiply out positive powers of sums; keep the rest as one product.
                    let mut acc: Vec<(f64, ExprId)> = vec![(1.0, ONE)];
                    let mut rest: Vec<(ExprId, i32)> = Vec::new();
                    for &(b, k) in factors.iter() {
                        let b = map[&b];
                        let sum_parts = match self.node(b) {
                            Node::Add { constant, terms } if k > 0 => {
                                let mut parts: Vec<(f64, ExprId)> =
                                    terms.iter().map(|&(t, c)| (c, t)).collect();
                                if *constant != 0.0 {
                                    parts.push((*constant, ONE));
                                }
                                Some(parts)
                            }
                            _ => None,
                        };
                        match sum_parts {
                            Some(parts) => {
                                for _ in 0..k {
                                    let mut next = Vec::with_capacity(acc.len() * parts.len());
                                    for &(c1, t1) in &acc {
                                        for &(c2, t2) in &parts {
                                            let t = self.mul(t1, t2);
                                            next.push((c1 * c2, t));
                                        }
                                    }
                                    acc = next;
                                }
                            }
                            None => rest.push((b, k)),
                        }
                    }
                    let r = self.product(&rest);
                    let ts: Vec<(ExprId, f64)> = acc
                        .into_iter()
                        .map(|(c, t)| {
                            let m = self.mul(t, r);
                            (m, c)
                        })
                        .collect();
                    self.sum(0.0, &ts)
                }
                Node::Call(f, a) => {
                    let a = map[&a];
                    self.apply(f, a)
                }
                Node::Atan2(y, x) => {
                    let (y, x) = (map[&y], map[&x]);
                    self.atan2(y, x)
                }
            };
            map.insert(id, r);
        }
        map[&x]
    }

    /// All nodes reachable from `roots`, in ascending id (= topological) order. Iterative, so
    /// deep expressions cannot overflow the stack.
    pub fn reachable(&self, roots: &[ExprId]) -> Vec<ExprId> {
        // Visited set as a bitset over the arena: one bit per node.
        let mut seen = vec![0u64; self.nodes.len().div_ceil(64)];
        let mut visit = |id: ExprId| {
            let (w, b) = (id.index() / 64, id.index() % 64);
            let new = seen[w] & (1 << b) == 0;
            seen[w] |= 1 << b;
            new
        };
        let mut stack: Vec<ExprId> = Vec::new();
        let mut out = Vec::new();
        for &r in roots {
            if visit(r) {
                stack.push(r);
            }
        }
        while let Some(id) = stack.pop() {
            out.push(id);
            self.node(id).for_each_child(|c| {
                if visit(c) {
                    stack.push(c);
                }
            });
        }
        out.sort_unstable();
        out
    }

    /// A displayable view of an expression (as a tree, for debugging and messages; shared
    /// subexpressions are printed each time they occur).
    pub fn display(&self, id: ExprId) -> Display<'_> {
        Display { ctx: self, id }
    }
}

/// `c / vⁿ` if it is exactly representable (and finite, non-zero), else `None`. Each
/// multiplication and the division are checked with a fused multiply-add: `fma(a, b, −p) = 0`
/// iff `p = a·b` exactly.
fn exact_div_pow(c: f64, v: f64, n: u32) -> Option<f64> {
    if n > 64 {
        return None;
    }
    let mut p = 1.0f64;
    for _ in 0..n {
        let np = p * v;
        if !np.is_finite() || np == 0.0 || p.mul_add(v, -np) != 0.0 {
            return None;
        }
        p = np;
    }
    let r = c / p;
    (r.is_finite() && r != 0.0 && r.mul_add(p, -c) == 0.0).then_some(r)
}

/// Sorts terms by base, merges equal bases (adding coefficients) and drops zero coefficients.
fn collect_like(terms: &mut Vec<(ExprId, f64)>) {
    terms.sort_unstable_by_key(|t| t.0);
    let mut w = 0;
    for r in 0..terms.len() {
        if w > 0 && terms[w - 1].0 == terms[r].0 {
            terms[w - 1].1 += terms[r].1;
        } else {
            terms[w] = terms[r];
            w += 1;
        }
    }
    terms.truncate(w);
    terms.retain(|t| t.1 != 0.0);
    for t in terms.iter_mut() {
        t.1 = norm(t.1);
    }
}

/// See [`Context::display`].
pub struct Display<'a> {
    ctx: &'a Context,
    id: ExprId,
}

impl Display<'_> {
    fn write(&self, f: &mut fmt::Formatter<'_>, id: ExprId) -> fmt::Result {
        match self.ctx.node(id) {
            Node::Num(v) => write!(f, "{v}"),
            Node::Sym(s) => write!(f, "{s}"),
            Node::Add { constant, terms } => {
                write!(f, "(")?;
                let mut first = true;
                if *constant != 0.0 {
                    write!(f, "{constant}")?;
                    first = false;
                }
                for &(b, c) in terms.iter() {
                    if !first {
                        write!(f, " + ")?;
                    }
                    first = false;
                    if c != 1.0 {
                        write!(f, "{c}*")?;
                    }
                    self.write(f, b)?;
                }
                write!(f, ")")
            }
            Node::Mul { factors } => {
                for (i, &(b, k)) in factors.iter().enumerate() {
                    if i > 0 {
                        write!(f, "*")?;
                    }
                    self.write(f, b)?;
                    if k != 1 {
                        write!(f, "^{k}")?;
                    }
                }
                Ok(())
            }
            Node::Call(func, a) => {
                write!(f, "{}(", func.name())?;
                self.write(f, *a)?;
                write!(f, ")")
            }
            Node::Atan2(y, x) => {
                write!(f, "atan2(")?;
                self.write(f, *y)?;
                write!(f, ", ")?;
                self.write(f, *x)?;
                write!(f, ")")
            }
        }
    }
}

impl fmt::Display for Display<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        self.write(f, self.id)
    }
}
