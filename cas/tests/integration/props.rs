//! Property tests: random expression trees are built through the simplifying constructors and
//! compared with a plain (unsimplified) evaluation of the same tree written here, independent
//! of the crate; derivatives are compared with central finite differences; straight-line
//! programs (whole and split) with the DAG.
//!
//! Error model. Every f64 operation has relative rounding error ≤ ε = 2.2e-16. The simplifier
//! reorders and regroups operations, so the two evaluations differ by rounding only, bounded to
//! first order by ε·(number of operations)·M, where M (`mag` below) propagates the magnitudes of
//! operands through the tree: |a|+|b| for sums (the guard for cancellation: x − x may be tiny
//! while its rounding error is relative to |x|), |a|·|b| for products, and Lipschitz constant ×
//! argument magnitude for functions, whose arguments are kept in domains where that constant is
//! bounded (denominators and ln/sqrt arguments are 1 + b² ≥ 1, tan of sin, exp of sin).
//! Trees have at most ~60 operations; 1e-12·M ≈ 4500 ε·M leaves a wide margin.

use proptest::prelude::*;
use railmbs_cas::{Context, ExprId, Func, Instr, ONE, Operand, Program, Symbol, Values};

#[derive(Clone, Debug)]
enum T {
    Num(f64),
    /// q[i] for i in 0..3, v[0] as 3, p[0] as 4.
    Sym(u32),
    Add(Box<T>, Box<T>),
    Sub(Box<T>, Box<T>),
    Mul(Box<T>, Box<T>),
    Neg(Box<T>),
    Scale(f64, Box<T>),
    /// a / (1 + b²)
    DivSafe(Box<T>, Box<T>),
    /// a^n, n in 0..=3
    Pow(Box<T>, i32),
    /// a / k for a number k
    DivNum(Box<T>, f64),
    /// (1 + b²)^(−n), n in 1..=2
    PowNegSafe(Box<T>, i32),
    Sin(Box<T>),
    Cos(Box<T>),
    /// tan(sin a)
    TanSin(Box<T>),
    /// √(1 + b²)
    SqrtSafe(Box<T>),
    /// exp(sin a)
    ExpSin(Box<T>),
    /// ln(1 + b²)
    LnSafe(Box<T>),
    Abs(Box<T>),
    /// atan2(a, 1 + b²)
    Atan2Safe(Box<T>, Box<T>),
    /// sin²(a)·b + b·cos²(a), to exercise the sin²+cos² rule
    Pyth(Box<T>, Box<T>),
}

const SYMS: [Symbol; 5] = [
    Symbol {
        kind: railmbs_cas::SymbolKind::Coordinate,
        index: 0,
    },
    Symbol {
        kind: railmbs_cas::SymbolKind::Coordinate,
        index: 1,
    },
    Symbol {
        kind: railmbs_cas::SymbolKind::Coordinate,
        index: 2,
    },
    Symbol {
        kind: railmbs_cas::SymbolKind::Velocity,
        index: 0,
    },
    Symbol {
        kind: railmbs_cas::SymbolKind::Parameter,
        index: 0,
    },
];

fn leaf() -> impl Strategy<Value = T> {
    prop_oneof![
        prop::sample::select(vec![0.0, 1.0, -1.0, 2.0, 0.5, -3.0, 1.5, 0.1]).prop_map(T::Num),
        (0u32..5).prop_map(T::Sym),
        (0u32..5).prop_map(T::Sym),
    ]
}

fn tree() -> impl Strategy<Value = T> {
    leaf().prop_recursive(4, 48, 2, |inner| {
        let b = |t: T| Box::new(t);
        prop_oneof![
            (inner.clone(), inner.clone()).prop_map(move |(x, y)| T::Add(b(x), b(y))),
            (inner.clone(), inner.clone()).prop_map(move |(x, y)| T::Sub(b(x), b(y))),
            (inner.clone(), inner.clone()).prop_map(move |(x, y)| T::Mul(b(x), b(y))),
            inner.clone().prop_map(move |x| T::Neg(b(x))),
            (
                prop::sample::select(vec![2.0, -1.0, -0.5, 3.0]),
                inner.clone()
            )
                .prop_map(move |(c, x)| T::Scale(c, b(x))),
            (inner.clone(), inner.clone()).prop_map(move |(x, y)| T::DivSafe(b(x), b(y))),
            (inner.clone(), 0i32..=3).prop_map(move |(x, n)| T::Pow(b(x), n)),
            (
                inner.clone(),
                prop::sample::select(vec![3.0, -4.0, 0.1, 12.0, 7.0])
            )
                .prop_map(move |(x, k)| T::DivNum(b(x), k)),
            (inner.clone(), 1i32..=2).prop_map(move |(x, n)| T::PowNegSafe(b(x), n)),
            inner.clone().prop_map(move |x| T::Sin(b(x))),
            inner.clone().prop_map(move |x| T::Cos(b(x))),
            inner.clone().prop_map(move |x| T::TanSin(b(x))),
            inner.clone().prop_map(move |x| T::SqrtSafe(b(x))),
            inner.clone().prop_map(move |x| T::ExpSin(b(x))),
            inner.clone().prop_map(move |x| T::LnSafe(b(x))),
            inner.clone().prop_map(move |x| T::Abs(b(x))),
            (inner.clone(), inner.clone()).prop_map(move |(x, y)| T::Atan2Safe(b(x), b(y))),
            (inner.clone(), inner.clone()).prop_map(move |(x, y)| T::Pyth(b(x), b(y))),
        ]
    })
}

/// Plain evaluation: (value, magnitude M for the error bound, see the module comment).
fn plain(t: &T, s: &[f64; 5]) -> (f64, f64) {
    let safe = |b: &T| {
        let (v, m) = plain(b, s);
        (1.0 + v * v, 1.0 + m * m)
    };
    match t {
        T::Num(v) => (*v, v.abs()),
        T::Sym(i) => (s[*i as usize], s[*i as usize].abs()),
        T::Add(a, b) => {
            let ((x, mx), (y, my)) = (plain(a, s), plain(b, s));
            (x + y, mx + my)
        }
        T::Sub(a, b) => {
            let ((x, mx), (y, my)) = (plain(a, s), plain(b, s));
            (x - y, mx + my)
        }
        T::Mul(a, b) => {
            let ((x, mx), (y, my)) = (plain(a, s), plain(b, s));
            (x * y, mx * my)
        }
        T::Neg(a) => {
            let (x, m) = plain(a, s);
            (-x, m)
        }
        T::Scale(c, a) => {
            let (x, m) = plain(a, s);
            (c * x, c.abs() * m)
        }
        T::DivSafe(a, b) => {
            let (x, mx) = plain(a, s);
            let (d, md) = safe(b);
            let q = x / d;
            (q, (mx + q.abs() * md) / d)
        }
        T::Pow(a, n) => {
            let (x, m) = plain(a, s);
            let v = x.powi(*n);
            (v, *n as f64 * m.powi(*n) + v.abs())
        }
        T::DivNum(a, k) => {
            let (x, m) = plain(a, s);
            (x / k, m / k.abs())
        }
        T::PowNegSafe(b, n) => {
            let (d, md) = safe(b);
            let v = d.powi(-*n);
            (v, *n as f64 * v * md / d + v)
        }
        T::Sin(a) => {
            let (x, m) = plain(a, s);
            (x.sin(), m + 1.0)
        }
        T::Cos(a) => {
            let (x, m) = plain(a, s);
            (x.cos(), m + 1.0)
        }
        T::TanSin(a) => {
            // d tan(sin x)/dx ≤ 1/cos²(1) < 3.5
            let (x, m) = plain(a, s);
            let v = x.sin().tan();
            (v, 3.5 * (m + 1.0) + v.abs())
        }
        T::SqrtSafe(b) => {
            let (d, md) = safe(b);
            let v = d.sqrt();
            (v, 0.5 * md + v)
        }
        T::ExpSin(a) => {
            let (x, m) = plain(a, s);
            let v = x.sin().exp();
            (v, std::f64::consts::E * (m + 1.0) + v)
        }
        T::LnSafe(b) => {
            let (d, md) = safe(b);
            let v = d.ln();
            (v, md / d + v)
        }
        T::Abs(a) => {
            let (x, m) = plain(a, s);
            (x.abs(), m)
        }
        T::Atan2Safe(a, b) => {
            let (x, mx) = plain(a, s);
            let (d, md) = safe(b);
            let v = x.atan2(d);
            (v, mx + md + v.abs())
        }
        T::Pyth(a, b) => {
            let (x, mx) = plain(a, s);
            let (y, my) = plain(b, s);
            let v = x.sin().powi(2) * y + y * x.cos().powi(2);
            (v, 2.0 * (mx + 1.0) * my + v.abs())
        }
    }
}

/// The same tree through the simplifying constructors.
fn build(c: &mut Context, t: &T) -> ExprId {
    let safe = |c: &mut Context, b: &T| {
        let e = build(c, b);
        let sq = c.mul(e, e);
        c.add(ONE, sq)
    };
    match t {
        T::Num(v) => c.num(*v),
        T::Sym(i) => c.sym(SYMS[*i as usize]),
        T::Add(a, b) => {
            let (x, y) = (build(c, a), build(c, b));
            c.add(x, y)
        }
        T::Sub(a, b) => {
            let (x, y) = (build(c, a), build(c, b));
            c.sub(x, y)
        }
        T::Mul(a, b) => {
            let (x, y) = (build(c, a), build(c, b));
            c.mul(x, y)
        }
        T::Neg(a) => {
            let x = build(c, a);
            c.neg(x)
        }
        T::Scale(k, a) => {
            let x = build(c, a);
            c.scale(*k, x)
        }
        T::DivSafe(a, b) => {
            let x = build(c, a);
            let d = safe(c, b);
            c.div(x, d)
        }
        T::Pow(a, n) => {
            let x = build(c, a);
            c.powi(x, *n)
        }
        T::DivNum(a, k) => {
            let x = build(c, a);
            let kn = c.num(*k);
            c.div(x, kn)
        }
        T::PowNegSafe(b, n) => {
            let d = safe(c, b);
            c.powi(d, -*n)
        }
        T::Sin(a) => {
            let x = build(c, a);
            c.sin(x)
        }
        T::Cos(a) => {
            let x = build(c, a);
            c.cos(x)
        }
        T::TanSin(a) => {
            let x = build(c, a);
            let s = c.sin(x);
            c.tan(s)
        }
        T::SqrtSafe(b) => {
            let d = safe(c, b);
            c.sqrt(d)
        }
        T::ExpSin(a) => {
            let x = build(c, a);
            let s = c.sin(x);
            c.exp(s)
        }
        T::LnSafe(b) => {
            let d = safe(c, b);
            c.ln(d)
        }
        T::Abs(a) => {
            let x = build(c, a);
            c.abs(x)
        }
        T::Atan2Safe(a, b) => {
            let x = build(c, a);
            let d = safe(c, b);
            c.atan2(x, d)
        }
        T::Pyth(a, b) => {
            let x = build(c, a);
            let y = build(c, b);
            let s = c.sin(x);
            let s2 = c.powi(s, 2);
            let co = c.cos(x);
            let c2 = c.powi(co, 2);
            let l = c.mul(s2, y);
            let r = c.mul(y, c2);
            c.add(l, r)
        }
    }
}

fn point() -> impl Strategy<Value = [f64; 5]> {
    prop::array::uniform5(-1.5f64..1.5)
}

fn values(s: &[f64; 5]) -> Values<'_> {
    Values {
        q: &s[0..3],
        v: &s[3..4],
        p: &s[4..5],
        ..Default::default()
    }
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 400, ..ProptestConfig::default() })]

    #[test]
    fn simplification_preserves_value(t in tree(), s in point()) {
        let mut c = Context::new();
        let e = build(&mut c, &t);
        let (want, mag) = plain(&t, &s);
        let got = c.eval(&[e], &values(&s)).unwrap()[0];
        prop_assert!((got - want).abs() <= 1e-12 * mag, "{got} vs {want} (M = {mag}) for {}", c.display(e));
    }

    #[test]
    fn commuted_operands_give_the_same_node(t in tree()) {
        // canonical operand order: a + b and b + a, a·b and b·a are one node, at every level
        let mut c = Context::new();
        let a = build(&mut c, &t);
        let n = c.len();
        let b = build(&mut c, &mirror(&t));
        prop_assert_eq!(a, b);
        prop_assert_eq!(c.len(), n, "the mirrored tree created new nodes");
    }

    #[test]
    fn program_evaluates_equal_to_dag(ts in prop::collection::vec(tree(), 1..5), s in point()) {
        let mut c = Context::new();
        let es: Vec<ExprId> = ts.iter().map(|t| build(&mut c, t)).collect();
        let prog = Program::compile(&c, &es);
        let vals = values(&s);
        let dag = c.eval(&es, &vals).unwrap();
        let got = prog.eval(&vals).unwrap();
        for ((t, d), g) in ts.iter().zip(&dag).zip(&got) {
            let (_, mag) = plain(t, &s);
            // both are roundings of the same value (module comment)
            prop_assert!((d - g).abs() <= 1e-12 * mag, "{g} vs {d} (M = {mag})");
        }
        // the split program runs the same instructions in the same order: bit-equal
        for max in [1usize, 3, 16] {
            let sp = prog.split(max).unwrap();
            prop_assert_eq!(&sp.eval(&prog, &vals).unwrap(), &got);
        }
        // moving the call-free sin and cos into one batch reorders, never changes, instructions:
        // bit-equal again, the batch is sin/cos of call-free arguments, and every split keeps
        // it in one chunk
        let (batched, range) = prog.batch_sin_cos();
        prop_assert_eq!(batched.instrs.len(), prog.instrs.len());
        prop_assert_eq!(&batched.eval(&vals).unwrap(), &got);
        for k in range.clone() {
            let is_trig = matches!(batched.instrs[k], Instr::Call(Func::Sin | Func::Cos, _));
            prop_assert!(is_trig, "t{k} in the batch {range:?} of\n{batched}");
        }
        let n_trig = prog.instrs.iter().filter(|i| matches!(i, Instr::Call(Func::Sin | Func::Cos, Operand::Sym(_) | Operand::Const(_)))).count();
        prop_assert!(range.len() >= n_trig, "sin/cos of inputs left out of the batch {range:?} of\n{batched}");
        for max in [1usize, 3, 16] {
            let sp = batched.split_keeping(max, std::slice::from_ref(&range)).unwrap();
            if !range.is_empty() {
                prop_assert_eq!(sp.chunk_of(range.start), sp.chunk_of(range.end - 1));
            }
            prop_assert_eq!(&sp.eval(&batched, &vals).unwrap(), &got);
        }
        // topological order and liveness: every read is of an earlier temporary, at or before
        // its recorded last use; outputs live to the end
        let last = prog.last_uses();
        for (k, i) in prog.instrs.iter().enumerate() {
            let mut ok = true;
            i.for_each_operand(|o| {
                if let Operand::Tmp(t) = o {
                    ok &= (t as usize) < k && last[t as usize] >= k;
                }
            });
            prop_assert!(ok, "instruction t{k} of\n{prog}");
        }
        for o in &prog.outputs {
            if let Operand::Tmp(t) = o {
                prop_assert_eq!(last[*t as usize], prog.instrs.len());
            }
        }
        // CSE never costs more than the tree
        prop_assert!(prog.op_counts().total() <= c.tree_op_counts(&es).total());
    }

    #[test]
    fn derivative_matches_finite_differences(t in tree(), s in point(), var in 0usize..5) {
        // |x| has a kink at 0, where its derivative x/|x| is 0/0: skip points within h of a
        // kink of an abs node's argument before evaluating (the evaluator refuses the NaN,
        // e.g. d|(−x)·atan2(0, 1 + x²)|/dx, whose argument is identically 0).
        let h = 1e-3;
        prop_assume!(!has_kink_near(&t, &s, var, h));
        let mut c = Context::new();
        let e = build(&mut c, &t);
        let d = c.diff(e, SYMS[var]);
        let got = c.eval(&[d], &values(&s)).unwrap()[0];
        // Central difference D(h) = f' + f'''h²/6 + O(h⁴); Richardson R(h) = (4D(h/2) − D(h))/3
        // = f' + O(h⁴). With h = 1e-3 the truncation is ~1e-12·|f⁽⁵⁾| and the rounding
        // ~ (3 ε M / h) ≈ 7e-13·M, M the magnitude bound of f; tolerance 1e-7·(1 + M + |f'|)
        // covers derivatives of order 5 up to ~1e5 times the function's scale. Steeper trees
        // (tan(sin(100 p)) has |f⁽⁵⁾| ~ 1e12) are covered by the difference estimate's own
        // truncation error: R(h/2) is compared, and |R(h) − R(h/2)| ≈ 15× its O(h⁴) error is
        // added to the tolerance.
        let f = |x: f64| {
            let mut p = s;
            p[var] = x;
            plain(&t, &p).0
        };
        let x0 = s[var];
        let dh = |h: f64| (f(x0 + h) - f(x0 - h)) / (2.0 * h);
        let richardson = |h: f64| (4.0 * dh(h / 2.0) - dh(h)) / 3.0;
        let fd = richardson(h / 2.0);
        let truncation = (richardson(h) - fd).abs();
        let (_, mag) = plain(&t, &s);
        prop_assert!(
            (got - fd).abs() <= 1e-7 * (1.0 + mag + got.abs()) + truncation,
            "{got} vs {fd} (truncation {truncation:e}) for {}",
            c.display(e)
        );
    }

    #[test]
    fn substitution_matches_plain_evaluation(t in tree(), r in tree(), s in point()) {
        // e(q1 := r) evaluated at s equals e evaluated with q1 set to r(s)
        let mut c = Context::new();
        let e = build(&mut c, &t);
        let re = build(&mut c, &r);
        let out = c.subs(&[e], &[(Symbol::q(1), re)])[0];
        let (rv, _) = plain(&r, &s);
        let mut p = s;
        p[1] = rv;
        let (want, mag) = plain(&t, &p);
        let got = c.eval(&[out], &values(&s)).unwrap()[0];
        // r(s) itself carries a rounding error that propagates through t; allow 1e-9 · M
        prop_assert!((got - want).abs() <= 1e-9 * (1.0 + mag), "{got} vs {want}");
    }
}

/// The same tree with the operands of every commutative operation swapped.
fn mirror(t: &T) -> T {
    let m = |x: &T| Box::new(mirror(x));
    match t {
        T::Num(_) | T::Sym(_) => t.clone(),
        T::Add(a, b) => T::Add(m(b), m(a)),
        T::Mul(a, b) => T::Mul(m(b), m(a)),
        T::Sub(a, b) => T::Sub(m(a), m(b)),
        T::Neg(a) => T::Neg(m(a)),
        T::Scale(c, a) => T::Scale(*c, m(a)),
        T::DivSafe(a, b) => T::DivSafe(m(a), m(b)),
        T::Pow(a, n) => T::Pow(m(a), *n),
        T::DivNum(a, k) => T::DivNum(m(a), *k),
        T::PowNegSafe(a, n) => T::PowNegSafe(m(a), *n),
        T::Sin(a) => T::Sin(m(a)),
        T::Cos(a) => T::Cos(m(a)),
        T::TanSin(a) => T::TanSin(m(a)),
        T::SqrtSafe(a) => T::SqrtSafe(m(a)),
        T::ExpSin(a) => T::ExpSin(m(a)),
        T::LnSafe(a) => T::LnSafe(m(a)),
        T::Abs(a) => T::Abs(m(a)),
        T::Atan2Safe(a, b) => T::Atan2Safe(m(a), m(b)),
        T::Pyth(a, b) => T::Pyth(m(a), m(b)),
    }
}

/// Whether moving symbol `var` by ±h could cross a zero of the argument of an `Abs` node
/// (where |x| is not differentiable and finite differences are meaningless).
fn has_kink_near(t: &T, s: &[f64; 5], var: usize, h: f64) -> bool {
    let kids: Vec<&T> = match t {
        T::Num(_) | T::Sym(_) => vec![],
        T::Add(a, b)
        | T::Sub(a, b)
        | T::Mul(a, b)
        | T::DivSafe(a, b)
        | T::Atan2Safe(a, b)
        | T::Pyth(a, b) => vec![a, b],
        T::Neg(a)
        | T::Scale(_, a)
        | T::Pow(a, _)
        | T::DivNum(a, _)
        | T::PowNegSafe(a, _)
        | T::Sin(a)
        | T::Cos(a)
        | T::TanSin(a)
        | T::SqrtSafe(a)
        | T::ExpSin(a)
        | T::LnSafe(a) => vec![a],
        T::Abs(a) => {
            let at = |x: f64| {
                let mut p = *s;
                p[var] = s[var] + x;
                plain(a, &p).0
            };
            if at(-h).signum() != at(h).signum() || at(0.0).abs() < 1e-6 {
                return true;
            }
            vec![a]
        }
    };
    kids.into_iter().any(|k| has_kink_near(k, s, var, h))
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    #[test]
    fn packed_lanes_keep_values_and_are_valid(t in tree(), u in tree(), s in point(), width in 2usize..=4) {
        // Lanes of the same tree with the coordinates rotated (isomorphic, different data),
        // then an unrelated tree's lanes: packs grow where the lanes stay alike, and the
        // reordered program evaluates bit-identically (only commutative operands swap).
        let mut c = Context::new();
        let base = build(&mut c, &t);
        let other = build(&mut c, &u);
        let q: Vec<ExprId> = (0..3).map(|i| c.sym(SYMS[i])).collect();
        let mut outputs = Vec::new();
        for lane in 0..width {
            let rotate: Vec<(Symbol, ExprId)> =
                (0..3).map(|i| (SYMS[i], q[(i + lane) % 3])).collect();
            let mut sub = railmbs_cas::Substitution::new(&rotate);
            let e = sub.apply(&mut c, base);
            let p0 = c.sym(SYMS[4]);
            let shifted = c.mul(e, p0);
            outputs.push(shifted);
            let f = sub.apply(&mut c, other);
            outputs.push(f);
        }
        let prog = Program::compile(&c, &outputs);
        let vals = values(&s);
        let want = match prog.eval(&vals) {
            Ok(v) => v,
            Err(_) => return Ok(()), // a non-finite value: nothing to compare
        };
        let (batched, batch) = prog.batch_sin_cos();
        let lane_seed = |k: usize| -> Option<Vec<u32>> {
            (0..width)
                .map(|l| match batched.outputs[2 * l + k] {
                    Operand::Tmp(t) => Some(t),
                    _ => None,
                })
                .collect()
        };
        let seeds: Vec<Vec<u32>> = [lane_seed(0), lane_seed(1)].into_iter().flatten().collect();
        let packed = batched.pack_lanes(&seeds, width, std::slice::from_ref(&batch));
        let p = &packed.program;
        prop_assert_eq!(&p.eval(&vals).unwrap(), &want);
        prop_assert_eq!(packed.keep[0].len(), batch.len());
        for k in packed.keep[0].clone() {
            prop_assert!(matches!(p.instrs[k], Instr::Call(Func::Sin | Func::Cos, _)));
        }
        for &start in &packed.packs {
            let lanes = &p.instrs[start..start + width];
            let muls = lanes.iter().filter(|i| matches!(i, Instr::Mul(..))).count();
            let adds = lanes.iter().filter(|i| matches!(i, Instr::Add(..) | Instr::Sub(..))).count();
            prop_assert!(muls == width || adds == width, "pack at t{start}:\n{p}");
            // Independent lanes: no lane reads another.
            for (l, i) in lanes.iter().enumerate() {
                let mut reads_lane = false;
                i.for_each_operand(|o| {
                    if let Operand::Tmp(x) = o {
                        reads_lane |= (start..start + width).contains(&(x as usize));
                    }
                });
                prop_assert!(!reads_lane, "lane {l} of the pack at t{start} reads another lane");
            }
        }
        // Every split keeps packs and the batch whole, and evaluates the same.
        for max in [1usize, 3, 16] {
            let sp = p.split_keeping(max, &packed.together()).unwrap();
            for r in packed.together() {
                prop_assert_eq!(sp.chunk_of(r.start), sp.chunk_of(r.end - 1));
            }
            prop_assert_eq!(&sp.eval(p, &vals).unwrap(), &want);
        }
    }
}

/// The case proptest once found (issue 18): the derivative of |(−x)·atan2(0, 1 + x²)| at
/// x = 0 is 0/0, so the property must skip it before evaluating, as a kink.
#[test]
fn abs_of_an_identically_zero_argument_counts_as_a_kink() {
    let t = T::Abs(Box::new(T::Mul(
        Box::new(T::Neg(Box::new(T::Sym(0)))),
        Box::new(T::Atan2Safe(Box::new(T::Num(0.0)), Box::new(T::Sym(0)))),
    )));
    assert!(has_kink_near(&t, &[0.0; 5], 0, 1e-3));
    let mut c = Context::new();
    let e = build(&mut c, &t);
    let d = c.diff(e, SYMS[0]);
    assert!(
        c.eval(&[d], &values(&[0.0; 5])).is_err(),
        "0/0 is refused, not returned"
    );
}
