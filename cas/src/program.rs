//! Common-subexpression elimination into straight-line code, operation counts, and splitting
//! of the code into chunks of bounded size.

use std::fmt;
use std::ops::Range;

use crate::eval::{CasError, Values};
use crate::graph::{Context, ExprId, Func, FxBuild, FxMap, Node, Symbol};

/// An instruction operand: a temporary (the result of instruction `k`), a symbol (an input), or
/// a constant.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Operand {
    /// Result of instruction `k` of the program.
    Tmp(u32),
    /// An input value.
    Sym(Symbol),
    /// A constant.
    Const(f64),
}

impl fmt::Display for Operand {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            Operand::Tmp(k) => write!(f, "t{k}"),
            Operand::Sym(s) => write!(f, "{s}"),
            Operand::Const(c) => write!(f, "{c:?}"),
        }
    }
}

/// One instruction `tmp_k = op(args)`; `k` is its position in [`Program::instrs`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Instr {
    /// `a + b`.
    Add(Operand, Operand),
    /// `a − b`.
    Sub(Operand, Operand),
    /// `a · b`.
    Mul(Operand, Operand),
    /// `a / b`.
    Div(Operand, Operand),
    /// `−a`.
    Neg(Operand),
    /// `f(a)`.
    Call(Func, Operand),
    /// `atan2(y, x)`.
    Atan2(Operand, Operand),
}

impl Instr {
    /// Calls `f` on each operand.
    pub fn for_each_operand(&self, mut f: impl FnMut(Operand)) {
        match *self {
            Instr::Add(a, b)
            | Instr::Sub(a, b)
            | Instr::Mul(a, b)
            | Instr::Div(a, b)
            | Instr::Atan2(a, b) => {
                f(a);
                f(b)
            }
            Instr::Neg(a) | Instr::Call(_, a) => f(a),
        }
    }

    fn counts(&self) -> OpCounts {
        let mut c = OpCounts::default();
        match self {
            Instr::Add(..) | Instr::Sub(..) | Instr::Neg(_) => c.adds = 1,
            Instr::Mul(..) => c.muls = 1,
            Instr::Div(..) => c.divs = 1,
            Instr::Call(..) | Instr::Atan2(..) => c.calls = 1,
        }
        c
    }

    fn apply(&self, get: impl Fn(Operand) -> Result<f64, CasError>) -> Result<f64, CasError> {
        Ok(match *self {
            Instr::Add(a, b) => get(a)? + get(b)?,
            Instr::Sub(a, b) => get(a)? - get(b)?,
            Instr::Mul(a, b) => get(a)? * get(b)?,
            Instr::Div(a, b) => get(a)? / get(b)?,
            Instr::Neg(a) => -get(a)?,
            Instr::Call(f, a) => f.apply(get(a)?),
            Instr::Atan2(y, x) => get(y)?.atan2(get(x)?),
        })
    }
}

/// Operation counts. `adds` counts additions, subtractions and negations; `calls` counts
/// elementary-function calls (sin, cos, tan, sqrt, exp, ln, abs, atan2). Saturating `u128`, so
/// the (possibly astronomically large) count of the unshared tree form cannot overflow.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct OpCounts {
    /// Additions, subtractions, negations.
    pub adds: u128,
    /// Multiplications.
    pub muls: u128,
    /// Divisions.
    pub divs: u128,
    /// Function calls.
    pub calls: u128,
}

impl OpCounts {
    /// Sum of all operations.
    pub fn total(&self) -> u128 {
        self.adds
            .saturating_add(self.muls)
            .saturating_add(self.divs)
            .saturating_add(self.calls)
    }

    fn plus(self, o: OpCounts) -> OpCounts {
        OpCounts {
            adds: self.adds.saturating_add(o.adds),
            muls: self.muls.saturating_add(o.muls),
            divs: self.divs.saturating_add(o.divs),
            calls: self.calls.saturating_add(o.calls),
        }
    }
}

impl fmt::Display for OpCounts {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(
            f,
            "{} ops ({} add/sub/neg, {} mul, {} div, {} calls)",
            self.total(),
            self.adds,
            self.muls,
            self.divs,
            self.calls
        )
    }
}

/// Hashable form of an operand for value numbering.
#[derive(Clone, Copy, PartialEq, Eq, Hash, PartialOrd, Ord)]
enum OpKey {
    Const(u64),
    Sym(Symbol),
    Tmp(u32),
}

fn key(o: Operand) -> OpKey {
    match o {
        Operand::Tmp(k) => OpKey::Tmp(k),
        Operand::Sym(s) => OpKey::Sym(s),
        Operand::Const(c) => OpKey::Const(c.to_bits()),
    }
}

#[derive(Clone, Copy, PartialEq, Eq, Hash)]
enum InstrKey {
    Add(OpKey, OpKey),
    Sub(OpKey, OpKey),
    Mul(OpKey, OpKey),
    Div(OpKey, OpKey),
    Neg(OpKey),
    Call(Func, OpKey),
    Atan2(OpKey, OpKey),
}

/// Emits instructions; with `share`, equal instructions (commutative operands ordered) and equal
/// integer powers are emitted once.
struct Builder {
    instrs: Vec<Instr>,
    /// Per instruction: the length of the longest chain of instructions ending in it.
    depth: Vec<u32>,
    share: bool,
    vn: FxMap<InstrKey, u32>,
    pows: FxMap<(ExprId, u32), Operand>,
}

impl Builder {
    fn new(share: bool, capacity: usize) -> Self {
        Builder {
            instrs: Vec::with_capacity(capacity),
            depth: Vec::with_capacity(capacity),
            share,
            vn: FxMap::with_capacity_and_hasher(
                if share { capacity } else { 0 },
                FxBuild::default(),
            ),
            pows: FxMap::default(),
        }
    }

    fn emit(&mut self, i: Instr) -> Operand {
        let i = match i {
            Instr::Add(a, b) if key(b) < key(a) => Instr::Add(b, a),
            Instr::Mul(a, b) if key(b) < key(a) => Instr::Mul(b, a),
            other => other,
        };
        let k = self.instrs.len() as u32;
        if self.share {
            let ik = match i {
                Instr::Add(a, b) => InstrKey::Add(key(a), key(b)),
                Instr::Sub(a, b) => InstrKey::Sub(key(a), key(b)),
                Instr::Mul(a, b) => InstrKey::Mul(key(a), key(b)),
                Instr::Div(a, b) => InstrKey::Div(key(a), key(b)),
                Instr::Neg(a) => InstrKey::Neg(key(a)),
                Instr::Call(f, a) => InstrKey::Call(f, key(a)),
                Instr::Atan2(a, b) => InstrKey::Atan2(key(a), key(b)),
            };
            if let Some(&t) = self.vn.get(&ik) {
                return Operand::Tmp(t);
            }
            self.vn.insert(ik, k);
        }
        let mut d = 0;
        i.for_each_operand(|o| d = d.max(self.depth_of(o)));
        self.depth.push(d + 1);
        self.instrs.push(i);
        Operand::Tmp(k)
    }

    /// Chain length ending in `o` (0 for inputs, constants and temporaries this builder did
    /// not emit, such as the placeholders of [`Context::tree_op_counts`]).
    fn depth_of(&self, o: Operand) -> u32 {
        match o {
            Operand::Tmp(k) => self.depth.get(k as usize).copied().unwrap_or(0),
            _ => 0,
        }
    }

    /// `t^n` (n ≥ 1) by binary powering: n even → (t^(n/2))², n odd → t^(n−1)·t.
    fn pow(&mut self, b: ExprId, t: Operand, n: u32) -> Operand {
        if n == 1 {
            return t;
        }
        if self.share
            && let Some(&p) = self.pows.get(&(b, n))
        {
            return p;
        }
        let r = if n.is_multiple_of(2) {
            let h = self.pow(b, t, n / 2);
            self.emit(Instr::Mul(h, h))
        } else {
            let h = self.pow(b, t, n - 1);
            self.emit(Instr::Mul(h, t))
        };
        if self.share {
            self.pows.insert((b, n), r);
        }
        r
    }

    /// Lowers one DAG node whose operands are already available through `op`.
    fn lower(&mut self, node: &Node, op: impl Fn(ExprId) -> Operand) -> Operand {
        match node {
            Node::Num(v) => Operand::Const(*v),
            Node::Sym(s) => Operand::Sym(*s),
            Node::Add { constant, terms } => self.lower_sum(*constant, terms, &[], op),
            Node::Mul { factors } => {
                let mut num: Option<Operand> = None;
                let mut den: Option<Operand> = None;
                for &(b, k) in factors.iter() {
                    let p = self.pow(b, op(b), k.unsigned_abs());
                    let acc = if k > 0 { &mut num } else { &mut den };
                    *acc = Some(match *acc {
                        None => p,
                        Some(a) => self.emit(Instr::Mul(a, p)),
                    });
                }
                match (num, den) {
                    (Some(n), None) => n,
                    (Some(n), Some(d)) => self.emit(Instr::Div(n, d)),
                    (None, Some(d)) => self.emit(Instr::Div(Operand::Const(1.0), d)),
                    (None, None) => Operand::Const(1.0),
                }
            }
            Node::Call(f, a) => self.emit(Instr::Call(*f, op(*a))),
            Node::Atan2(y, x) => self.emit(Instr::Atan2(op(*y), op(*x))),
        }
    }

    /// `Σ ±v` over signed items, combining the two shallowest items first (Huffman's rule on
    /// the chain lengths): the same number of operations as a chain, the shortest dependency
    /// chain for the result, and a deep item such as the previous link of a recursion
    /// (M_ij = M_(i+1)j + …) enters last, with one operation. Two items of one sign add; of
    /// opposite signs, the negative is subtracted. `None` for no items; the flag is `true`
    /// when the result enters negated (all items were negative).
    fn signed_sum(&mut self, items: &[(Operand, bool)]) -> Option<(Operand, bool)> {
        use std::cmp::Reverse;
        let mut heap: std::collections::BinaryHeap<Reverse<(u32, usize)>> = Default::default();
        let mut slots: Vec<(Operand, bool)> = items.to_vec();
        for (i, &(o, _)) in items.iter().enumerate() {
            heap.push(Reverse((self.depth_of(o), i)));
        }
        while heap.len() > 1 {
            let Reverse((_, i)) = heap.pop().expect("two items");
            let Reverse((_, j)) = heap.pop().expect("two items");
            let ((a, na), (b, nb)) = (slots[i], slots[j]);
            let combined = match (na, nb) {
                (false, false) => (self.emit(Instr::Add(a, b)), false),
                (true, true) => (self.emit(Instr::Add(a, b)), true),
                (false, true) => (self.emit(Instr::Sub(a, b)), false),
                (true, false) => (self.emit(Instr::Sub(b, a)), false),
            };
            slots.push(combined);
            heap.push(Reverse((self.depth_of(combined.0), slots.len() - 1)));
        }
        heap.pop().map(|Reverse((_, i))| slots[i])
    }

    /// `constant + Σ c·t + Σ ±pre`. Terms with the same |c| ≠ 1 are grouped and multiplied once:
    /// `c·a + c·b − c·d = c·(a + b − d)`. All items (scaled terms, the constant, `pre`: already
    /// lowered partial sums, negated when the flag is set) are combined by
    /// [`Builder::signed_sum`]. With no positive part, an item with |c| ≠ 1 takes the sign into
    /// its multiplication; only a sum of unit-negative items needs an explicit negation.
    fn lower_sum(
        &mut self,
        constant: f64,
        terms: &[(ExprId, f64)],
        pre: &[(Operand, bool)],
        op: impl Fn(ExprId) -> Operand,
    ) -> Operand {
        // Items: (operand, |coefficient|, negative?), groups in order of first appearance.
        let mut items: Vec<(Operand, f64, bool)> = Vec::with_capacity(terms.len());
        let mut groups: Vec<(f64, Vec<(Operand, bool)>)> = Vec::new();
        let mut group_of: FxMap<u64, usize> = FxMap::default();
        for &(b, c) in terms {
            let m = c.abs();
            if m == 1.0 {
                items.push((op(b), 1.0, c < 0.0));
                continue;
            }
            let g = *group_of.entry(m.to_bits()).or_insert_with(|| {
                groups.push((m, Vec::new()));
                groups.len() - 1
            });
            groups[g].1.push((op(b), c < 0.0));
        }
        for (m, members) in groups {
            let (inner, negated) = self.signed_sum(&members).expect("a group has a term");
            items.push((inner, m, negated));
        }
        let scaled = |s: &mut Self, t: Operand, m: f64| {
            if m == 1.0 {
                t
            } else {
                s.emit(Instr::Mul(Operand::Const(m), t))
            }
        };
        let nothing_positive =
            constant <= 0.0 && pre.iter().all(|p| p.1) && items.iter().all(|i| i.2);
        // With nothing positive, a scaled negative item starts the sum as (−m)·t.
        let signed_start = if nothing_positive {
            items.iter().position(|i| i.1 != 1.0)
        } else {
            None
        };
        let mut all: Vec<(Operand, bool)> = Vec::with_capacity(items.len() + pre.len() + 1);
        for (i, &(t, m, negative)) in items.iter().enumerate() {
            if Some(i) == signed_start {
                all.push((scaled(self, t, -m), false));
            } else {
                all.push((scaled(self, t, m), negative));
            }
        }
        if constant != 0.0 {
            all.push((Operand::Const(constant.abs()), constant < 0.0));
        }
        all.extend_from_slice(pre);
        match self.signed_sum(&all) {
            None => Operand::Const(0.0),
            Some((v, false)) => v,
            Some((v, true)) => self.emit(Instr::Neg(v)),
        }
    }
}

/// Straight-line code computing a list of outputs: instruction `k` defines temporary `t_k` from
/// inputs, constants and earlier temporaries (so the list is in topological order), each shared
/// subexpression computed once.
///
/// Lowering: n-ary sums and products become chains of binary operations; terms of a sum with
/// the same coefficient are multiplied by it once; negative coefficients become subtractions;
/// integer powers use binary powering with `x²` etc. shared between all uses; negative powers are collected into one division per product (`x⁻¹` becomes `1/x`).
/// Equal instructions are emitted once (value numbering on top of the DAG's hash-consing).
/// `sin` and `cos` of the same argument are separate instructions with the same operand;
/// a code generator may pair them into `sin_cos` (see [`Program::sin_cos_pairs`]).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Program {
    /// The instructions; `t_k` is the result of `instrs[k]`.
    pub instrs: Vec<Instr>,
    /// The value of each output (a temporary, an input or a constant).
    pub outputs: Vec<Operand>,
}

impl Program {
    /// Common-subexpression elimination of `outputs` (all together) into a program.
    ///
    /// Besides equal nodes (hash-consing) and equal instructions, sums share their common
    /// parts: a sum that contains all terms of another sum of the program (with the same or
    /// all opposite coefficients) is lowered as that sum plus the rest. Recursive formulas that
    /// simplification flattened, such as the mass matrix's M_ij = M_(i+1)j + …, get their
    /// recursion back this way.
    pub fn compile(ctx: &Context, outputs: &[ExprId]) -> Program {
        let order = ctx.reachable(outputs);
        // about 1.5 instructions per node in practice (binary chains of n-ary nodes)
        let b = Builder::new(true, order.len() + order.len() / 2);
        let size = order.last().map_or(0, |l| l.index() + 1);
        let mut lowering = Lowering {
            ctx,
            b,
            ops: vec![None; size],
            sums: SumIndex::new(ctx, &order),
        };
        for &id in &order {
            lowering.lower(id);
        }
        let ops = lowering.ops;
        Program {
            instrs: lowering.b.instrs,
            outputs: outputs
                .iter()
                .map(|o| ops[o.index()].expect("every output lowered"))
                .collect(),
        }
    }

    /// Operation counts of the program.
    pub fn op_counts(&self) -> OpCounts {
        self.instrs
            .iter()
            .fold(OpCounts::default(), |acc, i| acc.plus(i.counts()))
    }

    /// Inputs read by the program, sorted and deduplicated.
    pub fn symbols(&self) -> Vec<Symbol> {
        let mut out = Vec::new();
        for i in &self.instrs {
            i.for_each_operand(|o| {
                if let Operand::Sym(s) = o {
                    out.push(s)
                }
            });
        }
        for o in &self.outputs {
            if let Operand::Sym(s) = o {
                out.push(*s);
            }
        }
        out.sort_unstable();
        out.dedup();
        out
    }

    /// Pairs `(k_sin, k_cos)` of instructions computing sin and cos of the same operand.
    pub fn sin_cos_pairs(&self) -> Vec<(u32, u32)> {
        let mut sins: FxMap<OpKey, u32> = FxMap::default();
        for (k, i) in self.instrs.iter().enumerate() {
            if let Instr::Call(Func::Sin, a) = i {
                sins.insert(key(*a), k as u32);
            }
        }
        let mut out = Vec::new();
        for (k, i) in self.instrs.iter().enumerate() {
            if let Instr::Call(Func::Cos, a) = i
                && let Some(&s) = sins.get(&key(*a))
            {
                out.push((s, k as u32));
            }
        }
        out
    }

    /// The program with its instructions in `order` (a permutation of the instructions that
    /// keeps every operand before its user), temporaries renumbered; commutative instructions
    /// `k` with `swap(k)` get their operands exchanged (bit-identical values).
    pub(crate) fn reordered(&self, order: &[u32], swap: impl Fn(usize) -> bool) -> Program {
        let mut new_index = vec![0u32; self.instrs.len()];
        for (new, &old) in order.iter().enumerate() {
            new_index[old as usize] = new as u32;
        }
        let remap = |o: Operand| match o {
            Operand::Tmp(t) => Operand::Tmp(new_index[t as usize]),
            other => other,
        };
        let instrs = order
            .iter()
            .map(|&old| match self.instrs[old as usize] {
                Instr::Add(a, b) if swap(old as usize) => Instr::Add(remap(b), remap(a)),
                Instr::Mul(a, b) if swap(old as usize) => Instr::Mul(remap(b), remap(a)),
                Instr::Add(a, b) => Instr::Add(remap(a), remap(b)),
                Instr::Sub(a, b) => Instr::Sub(remap(a), remap(b)),
                Instr::Mul(a, b) => Instr::Mul(remap(a), remap(b)),
                Instr::Div(a, b) => Instr::Div(remap(a), remap(b)),
                Instr::Atan2(a, b) => Instr::Atan2(remap(a), remap(b)),
                Instr::Neg(a) => Instr::Neg(remap(a)),
                Instr::Call(f, a) => Instr::Call(f, remap(a)),
            })
            .collect();
        Program {
            instrs,
            outputs: self.outputs.iter().map(|&o| remap(o)).collect(),
        }
    }

    /// The same program with every sin and cos whose argument needs no function call moved into
    /// one contiguous range of instructions, returned with it; a code generator can then compute
    /// them in one vectorized batch. The instructions the batched arguments depend on come
    /// first (in their original order), then the batch (ordered by argument, sin before cos),
    /// then everything else in its original order, so the program stays in dependency order
    /// and evaluates to the same values. Trigonometric calls whose argument depends on another
    /// call (`sin(atan2(y, x))`, say) stay where they are.
    pub fn batch_sin_cos(&self) -> (Program, Range<usize>) {
        let n = self.instrs.len();
        let is_call = |i: &Instr| matches!(i, Instr::Call(..) | Instr::Atan2(..));
        // after_call[k]: the value of t_k depends on a function call (or is one).
        let mut after_call = vec![false; n];
        for (k, i) in self.instrs.iter().enumerate() {
            let mut c = is_call(i);
            i.for_each_operand(|o| {
                if let Operand::Tmp(t) = o {
                    c |= after_call[t as usize];
                }
            });
            after_call[k] = c;
        }
        let batchable = |k: usize| match self.instrs[k] {
            Instr::Call(Func::Sin | Func::Cos, a) => match a {
                Operand::Tmp(t) => !after_call[t as usize],
                _ => true,
            },
            _ => false,
        };
        // Instructions the batched arguments need (all call-free), found backwards.
        let mut needed = vec![false; n];
        for k in (0..n).rev() {
            if needed[k] || batchable(k) {
                self.instrs[k].for_each_operand(|o| {
                    if let Operand::Tmp(t) = o {
                        needed[t as usize] = true;
                    }
                });
            }
        }
        // The batch, grouped by argument in order of first appearance, sin before cos.
        let mut arg_rank: FxMap<OpKey, usize> = FxMap::default();
        let mut batch: Vec<(usize, bool, usize)> = Vec::new();
        for k in (0..n).filter(|&k| batchable(k)) {
            let Instr::Call(f, a) = self.instrs[k] else {
                unreachable!("batchable instructions are sin or cos calls")
            };
            let next = arg_rank.len();
            let rank = *arg_rank.entry(key(a)).or_insert(next);
            batch.push((rank, f == Func::Cos, k));
        }
        batch.sort_unstable();
        let mut order: Vec<usize> = (0..n).filter(|&k| needed[k]).collect();
        let start = order.len();
        order.extend(batch.iter().map(|&(_, _, k)| k));
        let end = order.len();
        let mut placed = vec![false; n];
        for &k in &order {
            placed[k] = true;
        }
        order.extend((0..n).filter(|&k| !placed[k]));
        let order: Vec<u32> = order.iter().map(|&k| k as u32).collect();
        let program = self.reordered(&order, |_| false);
        (program, start..end)
    }

    /// For each temporary, the index of the last instruction reading it, or `instrs.len()` if
    /// it is an output (live to the end).
    pub fn last_uses(&self) -> Vec<usize> {
        let n = self.instrs.len();
        let mut last: Vec<usize> = (0..n).collect();
        for (k, i) in self.instrs.iter().enumerate() {
            i.for_each_operand(|o| {
                if let Operand::Tmp(t) = o {
                    last[t as usize] = k;
                }
            });
        }
        for o in &self.outputs {
            if let Operand::Tmp(t) = o {
                last[*t as usize] = n;
            }
        }
        last
    }

    /// Evaluates the program (reference interpreter). A non-finite intermediate value is an
    /// error naming the instruction.
    pub fn eval(&self, values: &Values) -> Result<Vec<f64>, CasError> {
        let mut tmp = Vec::with_capacity(self.instrs.len());
        for (k, i) in self.instrs.iter().enumerate() {
            let x = i.apply(|o| operand_value(o, &tmp, values))?;
            if !x.is_finite() {
                return Err(CasError::NonFinite {
                    value: x,
                    location: format!("instruction t{k}"),
                });
            }
            tmp.push(x);
        }
        self.outputs
            .iter()
            .enumerate()
            .map(|(i, &o)| operand_value(o, &tmp, values).and_then(|x| check_output(i, x)))
            .collect()
    }

    /// Splits the program into chunks of at most `max_instrs` consecutive instructions, for
    /// code generators that emit one function per chunk. Temporaries used outside the chunk
    /// that defines them (and all temporary outputs) travel through a scratch array: their
    /// defining chunk stores them into a slot, later chunks load them from it. Slots are reused
    /// once a temporary is dead (greedy allocation in chunk order).
    pub fn split(&self, max_instrs: usize) -> Result<SplitProgram, CasError> {
        self.split_keeping(max_instrs, &[])
    }

    /// [`Program::split`], but the instructions of each range of `together` (sorted and
    /// disjoint, such as the batch of [`Program::batch_sin_cos`] and the packs of
    /// [`Program::pack_lanes`]) end up in one chunk: a chunk that would end inside a range
    /// ends before it instead, or, if the range starts the chunk, grows to its end.
    pub fn split_keeping(
        &self,
        max_instrs: usize,
        together: &[Range<usize>],
    ) -> Result<SplitProgram, CasError> {
        if max_instrs == 0 {
            return Err(CasError::InvalidArgument(
                "split: max_instrs must be at least 1".to_string(),
            ));
        }
        let n = self.instrs.len();
        let mut bounds = Vec::new();
        let mut start = 0;
        while start < n {
            let mut end = (start + max_instrs).min(n);
            // The last range starting before the cut, if the cut falls inside it.
            let i = together.partition_point(|r| r.start < end);
            if let Some(r) = i.checked_sub(1).map(|i| &together[i])
                && end < r.end
            {
                end = if r.start > start { r.start } else { r.end };
            }
            bounds.push(start..end);
            start = end;
        }
        let n_chunks = bounds.len();
        let mut chunk_index = vec![0u32; n];
        for (c, r) in bounds.iter().enumerate() {
            chunk_index[r.clone()].fill(c as u32);
        }
        let chunk_of = |k: usize| chunk_index[k] as usize;
        // Last chunk using each temporary (n_chunks = an output).
        let mut last_chunk: Vec<usize> = (0..n).map(chunk_of).collect();
        for (k, i) in self.instrs.iter().enumerate() {
            i.for_each_operand(|o| {
                if let Operand::Tmp(t) = o {
                    last_chunk[t as usize] = last_chunk[t as usize].max(chunk_of(k));
                }
            });
        }
        for o in &self.outputs {
            if let Operand::Tmp(t) = o {
                last_chunk[*t as usize] = n_chunks;
            }
        }
        let mut slot_of_tmp: Vec<Option<u32>> = vec![None; n];
        let mut free: Vec<u32> = Vec::new();
        let mut active: Vec<(usize, u32)> = Vec::new(); // (last chunk, slot)
        let mut n_slots = 0u32;
        // chunk that last loaded each temporary (dedup of loads in O(1))
        let mut loaded_in: Vec<usize> = vec![usize::MAX; n];
        let mut chunks = Vec::with_capacity(n_chunks);
        for (c, range) in bounds.into_iter().enumerate() {
            active.retain(|&(l, s)| {
                if l < c {
                    free.push(s);
                    false
                } else {
                    true
                }
            });
            let mut loads = Vec::new();
            let mut stores = Vec::new();
            for k in range.clone() {
                self.instrs[k].for_each_operand(|o| {
                    if let Operand::Tmp(t) = o
                        && (t as usize) < range.start
                    {
                        let s = slot_of_tmp[t as usize];
                        if let Some(s) = s
                            && loaded_in[t as usize] != c
                        {
                            loaded_in[t as usize] = c;
                            loads.push((t, s));
                        }
                    }
                });
                if last_chunk[k] > c {
                    let s = free.pop().unwrap_or_else(|| {
                        n_slots += 1;
                        n_slots - 1
                    });
                    slot_of_tmp[k] = Some(s);
                    active.push((last_chunk[k], s));
                    stores.push((k as u32, s));
                }
            }
            chunks.push(Chunk {
                instrs: range,
                loads,
                stores,
            });
        }
        Ok(SplitProgram {
            chunks,
            n_slots: n_slots as usize,
            slot_of_tmp,
            chunk_index,
        })
    }
}

/// Outputs that are inputs or constants bypass the instruction checks: check them here.
/// A sum split into partial sums (each with `true` when it enters negated), the terms left
/// over and the constant left over.
type SumParts = (Vec<(ExprId, bool)>, Vec<(ExprId, f64)>, f64);

/// `(base, coefficient)` pairs of a sum.
type Terms = Box<[(ExprId, f64)]>;

/// The sums (of at least two terms) among the nodes being compiled, indexed by term.
struct SumIndex {
    /// Per sum: node, constant, terms (sorted by base).
    sums: Vec<(ExprId, f64, Terms)>,
    /// Sum number of each sum node.
    of_node: FxMap<ExprId, u32>,
    /// For each term base: the sums containing it, with its coefficient there.
    by_term: FxMap<ExprId, Vec<(u32, f64)>>,
    /// Per sum: the search (generation) that last looked at it.
    seen: Vec<u32>,
    generation: u32,
}

impl SumIndex {
    /// At most this many partial sums are taken into one sum.
    const MAX_PARTS: usize = 4;
    /// Candidate partial sums are looked up through this many of a sum's rarest terms.
    const PROBES: usize = 8;

    fn new(ctx: &Context, order: &[ExprId]) -> Self {
        let mut index = SumIndex {
            sums: Vec::new(),
            of_node: FxMap::default(),
            by_term: FxMap::default(),
            seen: Vec::new(),
            generation: 0,
        };
        for &id in order {
            if let Node::Add { constant, terms } = ctx.node(id)
                && terms.len() >= 2
            {
                let k = index.sums.len() as u32;
                let mut sorted = terms.clone();
                sorted.sort_unstable_by_key(|&(b, _)| b);
                index.sums.push((id, *constant, sorted));
                index.of_node.insert(id, k);
                for &(base, c) in terms.iter() {
                    index.by_term.entry(base).or_default().push((k, c));
                }
            }
        }
        index.seen = vec![0; index.sums.len()];
        index
    }

    /// Operations to lower `terms + constant` directly: the additions, plus one
    /// multiplication per distinct coefficient magnitude other than 1 (`Builder::lower_sum`).
    fn direct_cost(terms: &[(ExprId, f64)], constant: f64) -> usize {
        let mut scales: Vec<u64> = terms
            .iter()
            .map(|t| t.1.abs())
            .filter(|&m| m != 1.0)
            .map(f64::to_bits)
            .collect();
        scales.sort_unstable();
        scales.dedup();
        terms.len().saturating_sub(1) + usize::from(constant != 0.0) + scales.len()
    }

    /// Splits the sum `id` = `constant + terms` into other sums of the program and a rest:
    /// `S = ±T₁ ± T₂ … + D`. A partial sum T qualifies when each of its terms is a term of
    /// what is left of S (coefficients may differ: the rest keeps the difference), and is
    /// taken when that makes the sum cheaper to lower ([`Self::direct_cost`]). With equal
    /// coefficients this recovers recursions like M_ij = M_(i+1)j + …; with differing ones,
    /// sums of sums such as a composite force F_i = F_(i+1) + m·a_i, whose flattened terms
    /// carry a coefficient that grows with the number of bodies beyond i.
    ///
    /// The recursion ends: a partial sum has fewer terms than S, or as many and a smaller node
    /// id, so no two sums take each other.
    fn parts(&mut self, id: ExprId, constant: f64, terms: &[(ExprId, f64)]) -> SumParts {
        let mut rest: Vec<(ExprId, f64)> = terms.to_vec();
        rest.sort_unstable_by_key(|&(b, _)| b);
        let mut rest_constant = constant;
        let mut parts = Vec::new();
        let Some(&me) = self.of_node.get(&id) else {
            return (parts, rest, rest_constant);
        };
        while parts.len() < Self::MAX_PARTS && rest.len() >= 2 {
            // Candidates: the sums containing one of the rarest terms (short lists). A large
            // partial sum contains most terms, so it is among them unless it misses all the
            // probed ones; checking every sum that shares any term would cost O(n⁴) on a
            // chain's mass matrix.
            let mut probes: Vec<ExprId> = rest.iter().map(|&(b, _)| b).collect();
            probes.sort_unstable_by_key(|b| (self.by_term.get(b).map_or(0, Vec::len), *b));
            probes.truncate(Self::PROBES);
            self.generation += 1;
            let mut best_cost = Self::direct_cost(&rest, rest_constant);
            // (sum number, negated)
            let mut best: Option<(u32, bool)> = None;
            let mut at: Vec<usize> = Vec::new();
            for base in &probes {
                for &(k, _) in self.by_term.get(base).map_or(&[][..], |v| v) {
                    if k == me || self.seen[k as usize] == self.generation {
                        continue;
                    }
                    self.seen[k as usize] = self.generation;
                    let (node, kc, ref t_terms) = self.sums[k as usize];
                    let len = t_terms.len();
                    if len > rest.len() || !(len < terms.len() || (len == terms.len() && node < id))
                    {
                        continue;
                    }
                    at.clear();
                    let contained = t_terms.iter().all(|&(b, _)| {
                        rest.binary_search_by_key(&b, |t| t.0)
                            .map(|i| at.push(i))
                            .is_ok()
                    });
                    if !contained {
                        continue;
                    }
                    for negated in [false, true] {
                        let sign = if negated { -1.0 } else { 1.0 };
                        let mut left = rest.clone();
                        for (&i, &(_, c)) in at.iter().zip(t_terms.iter()) {
                            left[i].1 -= sign * c;
                        }
                        left.retain(|t| t.1 != 0.0);
                        let cost = 1 + Self::direct_cost(&left, rest_constant - sign * kc);
                        if cost < best_cost {
                            best_cost = cost;
                            best = Some((k, negated));
                        }
                    }
                }
            }
            let Some((k, negated)) = best else {
                break;
            };
            let (node, kc, ref t_terms) = self.sums[k as usize];
            let sign = if negated { -1.0 } else { 1.0 };
            for &(b, c) in t_terms.iter() {
                let i = rest
                    .binary_search_by_key(&b, |t| t.0)
                    .expect("a partial sum's terms are in the rest");
                rest[i].1 -= sign * c;
            }
            rest.retain(|t| t.1 != 0.0);
            rest_constant -= sign * kc;
            parts.push((node, negated));
        }
        (parts, rest, rest_constant)
    }
}

/// Lowering of the reachable nodes in dependency order, a sum's partial sums first.
struct Lowering<'a> {
    ctx: &'a Context,
    b: Builder,
    ops: Vec<Option<Operand>>,
    sums: SumIndex,
}

impl Lowering<'_> {
    /// Lowers `id` unless done; its operands must be lowered already.
    fn lower(&mut self, id: ExprId) -> Operand {
        if let Some(o) = self.ops[id.index()] {
            return o;
        }
        let node = self.ctx.node(id);
        let result = match node {
            Node::Add { constant, terms } if terms.len() >= 2 => {
                let (parts, rest, rest_constant) = self.sums.parts(id, *constant, terms);
                // A partial sum's terms are terms of this sum, so they are lowered; its
                // own partial sums have fewer terms still (the recursion ends).
                let pre: Vec<(Operand, bool)> = parts
                    .iter()
                    .map(|&(p, negated)| (self.lower(p), negated))
                    .collect();
                let ops = &self.ops;
                self.b.lower_sum(rest_constant, &rest, &pre, |c| {
                    ops[c.index()].expect("operand lowered before its user")
                })
            }
            _ => {
                let ops = &self.ops;
                self.b.lower(node, |c| {
                    ops[c.index()].expect("operand lowered before its user")
                })
            }
        };
        self.ops[id.index()] = Some(result);
        result
    }
}

fn check_output(i: usize, x: f64) -> Result<f64, CasError> {
    if x.is_finite() {
        Ok(x)
    } else {
        Err(CasError::NonFinite {
            value: x,
            location: format!("output {i}"),
        })
    }
}

fn operand_value(o: Operand, tmp: &[f64], values: &Values) -> Result<f64, CasError> {
    match o {
        Operand::Tmp(k) => tmp.get(k as usize).copied().ok_or_else(|| {
            CasError::InvalidArgument(format!("temporary t{k} read before it is defined"))
        }),
        Operand::Sym(s) => values.get(s),
        Operand::Const(c) => Ok(c),
    }
}

impl fmt::Display for Program {
    /// One line per instruction (`t3 = t1 * q[0]`), then `out[i] = ...`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (k, i) in self.instrs.iter().enumerate() {
            write!(f, "t{k} = ")?;
            match i {
                Instr::Add(a, b) => writeln!(f, "{a} + {b}")?,
                Instr::Sub(a, b) => writeln!(f, "{a} - {b}")?,
                Instr::Mul(a, b) => writeln!(f, "{a} * {b}")?,
                Instr::Div(a, b) => writeln!(f, "{a} / {b}")?,
                Instr::Neg(a) => writeln!(f, "-{a}")?,
                Instr::Call(func, a) => writeln!(f, "{}({a})", func.name())?,
                Instr::Atan2(y, x) => writeln!(f, "atan2({y}, {x})")?,
            }
        }
        for (i, o) in self.outputs.iter().enumerate() {
            writeln!(f, "out[{i}] = {o}")?;
        }
        Ok(())
    }
}

/// One chunk of a [`SplitProgram`].
#[derive(Clone, Debug, PartialEq)]
pub struct Chunk {
    /// The instructions of the chunk (indices into [`Program::instrs`]).
    pub instrs: Range<usize>,
    /// `(temporary, slot)`: temporaries of earlier chunks read here, to load from the scratch
    /// array before the chunk runs.
    pub loads: Vec<(u32, u32)>,
    /// `(temporary, slot)`: temporaries defined here and needed later (by later chunks or as
    /// outputs), to store into the scratch array.
    pub stores: Vec<(u32, u32)>,
}

/// A [`Program`] split into chunks (see [`Program::split`]). Outputs that are temporaries are
/// read from the scratch array at `slot_of_tmp[t]` after the last chunk.
#[derive(Clone, Debug, PartialEq)]
pub struct SplitProgram {
    /// Chunks in execution order.
    pub chunks: Vec<Chunk>,
    /// Length of the scratch array.
    pub n_slots: usize,
    /// Scratch slot of each temporary that crosses a chunk boundary (`None`: local to its chunk).
    pub slot_of_tmp: Vec<Option<u32>>,
    /// The chunk of each instruction.
    chunk_index: Vec<u32>,
}

impl SplitProgram {
    /// The chunk that computes instruction `k`.
    pub fn chunk_of(&self, k: usize) -> usize {
        self.chunk_index[k] as usize
    }

    /// Evaluates `prog` chunk by chunk, each chunk seeing only its own temporaries and its
    /// loads (as generated code would), to check the split.
    pub fn eval(&self, prog: &Program, values: &Values) -> Result<Vec<f64>, CasError> {
        let mut scratch = vec![f64::NAN; self.n_slots];
        let mut local: Vec<Option<f64>> = vec![None; prog.instrs.len()];
        for chunk in &self.chunks {
            local.iter_mut().for_each(|x| *x = None);
            for &(t, s) in &chunk.loads {
                local[t as usize] = Some(scratch[s as usize]);
            }
            for k in chunk.instrs.clone() {
                let get = |o: Operand| match o {
                    Operand::Tmp(t) => local[t as usize].ok_or_else(|| {
                        CasError::InvalidArgument(format!(
                            "chunk at t{} reads t{t}, which it neither defines nor loads",
                            chunk.instrs.start
                        ))
                    }),
                    Operand::Sym(s) => values.get(s),
                    Operand::Const(c) => Ok(c),
                };
                let x = prog.instrs[k].apply(get)?;
                if !x.is_finite() {
                    return Err(CasError::NonFinite {
                        value: x,
                        location: format!("instruction t{k}"),
                    });
                }
                local[k] = Some(x);
            }
            for &(t, s) in &chunk.stores {
                scratch[s as usize] = local[t as usize].unwrap_or(f64::NAN);
            }
        }
        prog.outputs
            .iter()
            .map(|&o| match o {
                Operand::Tmp(t) => match self.slot_of_tmp.get(t as usize).copied().flatten() {
                    Some(s) => Ok(scratch[s as usize]),
                    None => Err(CasError::InvalidArgument(format!(
                        "output temporary t{t} has no scratch slot"
                    ))),
                },
                Operand::Sym(s) => values.get(s),
                Operand::Const(c) => Ok(c),
            })
            .enumerate()
            .map(|(i, r)| r.and_then(|x| check_output(i, x)))
            .collect()
    }
}

impl Context {
    /// Operation counts of `roots` as fully expanded trees (no sharing at all: every use of a
    /// subexpression is counted again), lowered like [`Program::compile`] does.
    pub fn tree_op_counts(&self, roots: &[ExprId]) -> OpCounts {
        let order = self.reachable(roots);
        let size = order.last().map_or(0, |l| l.index() + 1);
        let mut tree: Vec<OpCounts> = vec![OpCounts::default(); size];
        let mut b = Builder::new(false, 16);
        for id in order {
            let node = self.node(id);
            b.instrs.clear();
            b.depth.clear();
            b.lower(node, |_| Operand::Tmp(0));
            let mut c = b
                .instrs
                .iter()
                .fold(OpCounts::default(), |acc, i| acc.plus(i.counts()));
            node.for_each_child(|ch| c = c.plus(tree[ch.index()]));
            tree[id.index()] = c;
        }
        roots
            .iter()
            .fold(OpCounts::default(), |acc, r| acc.plus(tree[r.index()]))
    }
}
