//! Unit tests of each simplification rule, of differentiation against hand-derived derivatives,
//! of substitution, evaluation errors and the straight-line program.
//!
//! Expected values are textbook identities and derivatives, or numbers computed here by hand.

use railmbs_cas::{
    CasError, Context, ExprId, Func, Instr, Node, ONE, Operand, Program, Symbol, Values, ZERO,
};

fn xyz(ctx: &mut Context) -> (ExprId, ExprId, ExprId) {
    (ctx.q(0), ctx.q(1), ctx.q(2))
}

#[test]
fn hash_consing_and_commutativity() {
    let mut c = Context::new();
    let (x, y, z) = xyz(&mut c);
    assert_eq!(c.q(0), x, "a symbol is one node");
    let a = c.add(x, y);
    let b = c.add(y, x);
    assert_eq!(a, b);
    let a = c.mul(x, y);
    let b = c.mul(y, x);
    assert_eq!(a, b);
    // flattening: (x + y) + z = x + (y + z), (x·y)·z = x·(y·z)
    let xy = c.add(x, y);
    let l = c.add(xy, z);
    let yz = c.add(y, z);
    let r = c.add(x, yz);
    assert_eq!(l, r);
    let xy = c.mul(x, y);
    let l = c.mul(xy, z);
    let yz = c.mul(y, z);
    let r = c.mul(x, yz);
    assert_eq!(l, r);
    assert!(matches!(c.node(l), Node::Mul { factors } if factors.len() == 3));
    let n = c.len();
    let _ = c.mul_many(&[z, y, x]);
    assert_eq!(
        c.len(),
        n,
        "rebuilding an existing expression creates no node"
    );
}

#[test]
fn large_sums_stay_shared_operands() {
    use railmbs_cas::FLATTEN_LIMIT;
    let mut c = Context::new();
    let qs: Vec<ExprId> = (0..FLATTEN_LIMIT as u32 + 2).map(|i| c.q(i)).collect();
    let x = c.p(0);
    // a sum of FLATTEN_LIMIT terms is merged into an enclosing sum …
    let small = c.add_many(&qs[..FLATTEN_LIMIT]);
    let s1 = c.add(small, x);
    assert!(matches!(c.node(s1), Node::Add { terms, .. } if terms.len() == FLATTEN_LIMIT + 1));
    // … a larger one stays one operand (same value)
    let big = c.add_many(&qs[..FLATTEN_LIMIT + 1]);
    let s2 = c.add(big, x);
    assert!(matches!(c.node(s2), Node::Add { terms, .. } if terms.len() == 2));
    let q: Vec<f64> = (0..FLATTEN_LIMIT + 2).map(|i| 0.25 * i as f64).collect();
    let vals = Values {
        q: &q,
        p: &[0.5],
        ..Default::default()
    };
    let v = c.eval(&[s2], &vals).unwrap()[0];
    let want: f64 = q[..FLATTEN_LIMIT + 1].iter().sum::<f64>() + 0.5;
    assert_eq!(v, want, "sums of quarters are exact");
    // like terms are still collected between whole shared sums: big − big = 0, 2·big + big
    assert_eq!(c.sub(big, big), ZERO);
    let b2 = c.scale(2.0, big);
    let b3 = c.add(b2, big);
    assert_eq!(c.eval(&[b3], &vals).unwrap()[0], 3.0 * (want - 0.5));
}

#[test]
fn constant_folding() {
    let mut c = Context::new();
    let two = c.num(2.0);
    let three = c.num(3.0);
    let s = c.add(two, three);
    assert_eq!(c.as_num(s), Some(5.0));
    let p = c.mul(two, three);
    assert_eq!(c.as_num(p), Some(6.0));
    let d = c.div(three, two);
    assert_eq!(c.as_num(d), Some(1.5));
    let q = c.powi(two, -2);
    assert_eq!(c.as_num(q), Some(0.25));
    let s0 = c.sin(ZERO);
    assert_eq!(s0, ZERO);
    let c0 = c.cos(ZERO);
    assert_eq!(c0, ONE);
    let four = c.num(4.0);
    let r = c.sqrt(four);
    assert_eq!(c.as_num(r), Some(2.0));
    let e0 = c.exp(ZERO);
    assert_eq!(e0, ONE);
    let l1 = c.ln(ONE);
    assert_eq!(l1, ZERO);
    let m = c.num(-1.0);
    let at = c.atan2(ONE, m);
    assert_eq!(c.as_num(at), Some(3.0 * std::f64::consts::FRAC_PI_4));
    // not folded: the result would not be finite
    let l = c.ln(m);
    assert!(matches!(c.node(l), Node::Call(Func::Ln, _)));
    let negzero = c.num(-0.0);
    assert_eq!(negzero, ZERO);
}

#[test]
fn division_by_numbers_folds_only_when_exact() {
    let mut c = Context::new();
    let (x, y, _) = xyz(&mut c);
    let (three, four, twelve) = (c.num(3.0), c.num(4.0), c.num(12.0));
    // exact: x/4 = 0.25·x
    let q = c.div(x, four);
    assert_eq!(q, c.scale(0.25, x));
    // inexact: x/3 keeps the factor 3⁻¹ …
    let t = c.div(x, three);
    assert!(
        matches!(c.node(t), Node::Mul { factors } if factors.len() == 2),
        "{}",
        c.display(t)
    );
    // … so that 3·(x/3) = x, x/3 + 2x/3 = x, (x/3)·(y/4)·12 = x·y
    assert_eq!(c.mul(three, t), x);
    let two_t = c.scale(2.0, t);
    assert_eq!(c.add(t, two_t), x);
    let q2 = c.div(y, four);
    let p = c.mul_many(&[t, q2, twelve]);
    assert_eq!(p, c.mul(x, y));
    // 1/3 + 2/3 = 1 and 6/3 = 2 fold
    let third = c.recip(three);
    let two = c.num(2.0);
    let two_thirds = c.div(two, three);
    assert_eq!(c.add(third, two_thirds), ONE);
    let six = c.num(6.0);
    let q6 = c.div(six, three);
    assert_eq!(c.as_num(q6), Some(2.0));
    // division by a negative number: canonical positive base, sign in the coefficient
    let m3 = c.num(-3.0);
    let d = c.div(x, m3);
    assert_eq!(d, c.neg(t));
    // evaluated as a division, bit-exact: x/3 at x = 1 is the correctly rounded 1/3
    let v = c
        .eval(
            &[t],
            &Values {
                q: &[1.0],
                ..Default::default()
            },
        )
        .unwrap()[0];
    assert_eq!(v, 1.0 / 3.0);
    let prog = Program::compile(&c, &[t]);
    assert_eq!(
        prog.eval(&Values {
            q: &[1.0],
            ..Default::default()
        })
        .unwrap()[0],
        1.0 / 3.0
    );
    // division by zero is kept symbolic and reported on evaluation
    let z = c.div(x, ZERO);
    assert!(
        c.eval(
            &[z],
            &Values {
                q: &[1.0],
                ..Default::default()
            }
        )
        .is_err()
    );
}

#[test]
fn zero_one_identities() {
    let mut c = Context::new();
    let (x, _, _) = xyz(&mut c);
    assert_eq!(c.add(x, ZERO), x);
    assert_eq!(c.mul(x, ONE), x);
    assert_eq!(c.mul(x, ZERO), ZERO);
    assert_eq!(c.powi(x, 0), ONE);
    assert_eq!(c.powi(x, 1), x);
    assert_eq!(c.scale(1.0, x), x);
    assert_eq!(c.scale(0.0, x), ZERO);
    assert_eq!(c.sub(x, x), ZERO);
    assert_eq!(c.div(x, x), ONE);
    let nx = c.neg(x);
    assert_eq!(c.neg(nx), x);
}

#[test]
fn like_terms_and_factors() {
    let mut c = Context::new();
    let (x, y, _) = xyz(&mut c);
    let x2 = c.scale(2.0, x);
    let x3 = c.scale(3.0, x);
    let s = c.add(x2, x3);
    assert_eq!(s, c.scale(5.0, x));
    let xx = c.mul(x, x);
    assert_eq!(xx, c.powi(x, 2));
    let xxx = c.mul(xx, x);
    assert_eq!(xxx, c.powi(x, 3));
    // x²·y / (x·y) = x
    let xxy = c.mul(xx, y);
    let xy = c.mul(x, y);
    assert_eq!(c.div(xxy, xy), x);
    // (x·y)² = x²·y² (integer powers of products distribute)
    let p = c.powi(xy, 2);
    let y2 = c.powi(y, 2);
    assert_eq!(p, c.mul(xx, y2));
    // numeric factors are pulled out: (2x)·(3y) = 6·(x·y)
    let y3 = c.scale(3.0, y);
    let m = c.mul(x2, y3);
    assert_eq!(m, c.scale(6.0, xy));
    // a number times a sum distributes: 2(x + y) = 2x + 2y
    let xpy = c.add(x, y);
    let l = c.scale(2.0, xpy);
    let y2t = c.scale(2.0, y);
    assert_eq!(l, c.add(x2, y2t));
    // x·y + 2·y·x = 3xy
    let yx2 = c.scale(2.0, xy);
    let s = c.add(xy, yx2);
    assert_eq!(s, c.scale(3.0, xy));
}

#[test]
fn odd_and_even_functions() {
    let mut c = Context::new();
    let (x, y, _) = xyz(&mut c);
    let nx = c.neg(x);
    let s = c.sin(nx);
    let sx = c.sin(x);
    assert_eq!(s, c.neg(sx));
    assert_eq!(c.cos(nx), c.cos(x));
    let t = c.tan(nx);
    let tx = c.tan(x);
    assert_eq!(t, c.neg(tx));
    assert_eq!(c.abs(nx), c.abs(x));
    let ax = c.abs(x);
    assert_eq!(c.abs(ax), ax);
    // sin(x − y) = −sin(y − x), cos(x − y) = cos(y − x)
    let a = c.sub(x, y);
    let b = c.sub(y, x);
    let sa = c.sin(a);
    let sb = c.sin(b);
    assert_eq!(sa, c.neg(sb));
    assert_eq!(c.cos(a), c.cos(b));
    // sin(−2x) = −sin(2x)
    let m2x = c.scale(-2.0, x);
    let p2x = c.scale(2.0, x);
    let s1 = c.sin(m2x);
    let s2 = c.sin(p2x);
    assert_eq!(s1, c.neg(s2));
}

#[test]
fn sqrt_exp_ln_rules() {
    let mut c = Context::new();
    let (x, _, _) = xyz(&mut c);
    let x2 = c.powi(x, 2);
    assert_eq!(c.sqrt(x2), c.abs(x));
    let r = c.sqrt(x);
    let rr = c.mul(r, r);
    assert_eq!(rr, x);
    let r3 = c.powi(r, 3);
    assert_eq!(r3, c.mul(x, r));
    let l = c.ln(x);
    assert_eq!(c.exp(l), x);
    let e = c.exp(x);
    assert_eq!(c.ln(e), x);
}

#[test]
fn pythagoras_plain_and_with_monomial() {
    let mut c = Context::new();
    let (x, y, _) = xyz(&mut c);
    let s = c.sin(x);
    let co = c.cos(x);
    let s2 = c.powi(s, 2);
    let c2 = c.powi(co, 2);
    assert_eq!(c.add(s2, c2), ONE);
    // m·l²·sin²x + m·l²·cos²x = m·l²
    let m = c.p(0);
    let l = c.p(1);
    let l2 = c.powi(l, 2);
    let ml2 = c.mul(m, l2);
    let a = c.mul_many(&[ml2, s2]);
    let b = c.mul_many(&[ml2, c2]);
    assert_eq!(c.add(a, b), ml2);
    // 3·y·sin²x + 3·y·cos²x + y = 4y
    let ys = c.mul(y, s2);
    let yc = c.mul(y, c2);
    let t = c.sum(0.0, &[(ys, 3.0), (yc, 3.0), (y, 1.0)]);
    assert_eq!(t, c.scale(4.0, y));
    // sin⁴x + sin²x·cos²x = sin²x (remainder after removing sin² matches cos²·sin²)
    let s4 = c.powi(s, 4);
    let s2c2 = c.mul(s2, c2);
    assert_eq!(c.add(s4, s2c2), s2);
    // different coefficients are left alone (documented): 2sin²x + cos²x stays a sum
    let t = c.sum(0.0, &[(s2, 2.0), (c2, 1.0)]);
    assert!(matches!(c.node(t), Node::Add { terms, .. } if terms.len() == 2));
}

type Mat = Vec<Vec<ExprId>>;

fn matmul(c: &mut Context, a: &Mat, b: &Mat) -> Mat {
    let n = a.len();
    let m = b[0].len();
    (0..n)
        .map(|i| {
            (0..m)
                .map(|j| {
                    let ps: Vec<ExprId> = (0..b.len()).map(|k| c.mul(a[i][k], b[k][j])).collect();
                    c.add_many(&ps)
                })
                .collect()
        })
        .collect()
}

fn transpose(a: &Mat) -> Mat {
    (0..a[0].len())
        .map(|j| (0..a.len()).map(|i| a[i][j]).collect())
        .collect()
}

/// Elementary rotation matrices (frame rotation about z or x by angle a, rad).
fn rot_z(c: &mut Context, a: ExprId) -> Mat {
    let (s, co) = (c.sin(a), c.cos(a));
    let ms = c.neg(s);
    vec![vec![co, ms, ZERO], vec![s, co, ZERO], vec![ZERO, ZERO, ONE]]
}

fn rot_x(c: &mut Context, a: ExprId) -> Mat {
    let (s, co) = (c.sin(a), c.cos(a));
    let ms = c.neg(s);
    vec![vec![ONE, ZERO, ZERO], vec![ZERO, co, ms], vec![ZERO, s, co]]
}

fn assert_identity(c: &Context, m: &Mat) {
    for (i, row) in m.iter().enumerate() {
        for (j, &e) in row.iter().enumerate() {
            assert_eq!(
                e,
                if i == j { ONE } else { ZERO },
                "entry ({i},{j}): {}",
                c.display(e)
            );
        }
    }
}

#[test]
fn rotation_transpose_times_rotation_is_identity() {
    let mut c = Context::new();
    let (a, b, g) = xyz(&mut c);
    let rz = rot_z(&mut c, a);
    let p = matmul(&mut c, &transpose(&rz), &rz);
    assert_identity(&c, &p);
    // a product of two elementary rotations, as recursive kinematics builds it: its entries
    // are monomials, so RᵀR = I needs no expansion
    let rx = rot_x(&mut c, b);
    let r = matmul(&mut c, &rz, &rx);
    let p = matmul(&mut c, &transpose(&r), &r);
    assert_identity(&c, &p);
    let p = matmul(&mut c, &r, &transpose(&r));
    assert_identity(&c, &p);
    // three rotations: entries of R are sums, so RᵀR has squares of sums; after the explicit
    // `expand` the repeated sin²+cos² rule reduces every entry to 0 or 1
    let rz2 = rot_z(&mut c, g);
    let r3 = matmul(&mut c, &r, &rz2);
    let p = matmul(&mut c, &transpose(&r3), &r3);
    let p: Mat = p
        .iter()
        .map(|row| row.iter().map(|&e| c.expand(e)).collect())
        .collect();
    assert_identity(&c, &p);
}

#[test]
fn linalg_helpers() {
    use railmbs_cas::IDENTITY;
    let mut c = Context::new();
    let (a, b, _) = xyz(&mut c);
    // every elementary rotation is orthogonal, and R(a)·R(−a) = I
    let na = c.neg(a);
    for k in 0..3 {
        let r = match k {
            0 => c.rot_x(a),
            1 => c.rot_y(a),
            _ => c.rot_z(a),
        };
        let rt = c.transpose(&r);
        assert_eq!(c.mat_mul(&rt, &r), IDENTITY, "axis {k}");
        let rn = match k {
            0 => c.rot_x(na),
            1 => c.rot_y(na),
            _ => c.rot_z(na),
        };
        assert_eq!(c.mat_mul(&r, &rn), IDENTITY, "axis {k}");
    }
    // right-handed: R_z(a) maps e_x to (cos a, sin a, 0); e_x × e_y = e_z
    let rz = c.rot_z(a);
    let ex = [ONE, ZERO, ZERO];
    let ey = [ZERO, ONE, ZERO];
    assert_eq!(c.mat_vec(&rz, &ex), [c.cos(a), c.sin(a), ZERO]);
    assert_eq!(c.cross(&ex, &ey), [ZERO, ZERO, ONE]);
    // Rᵀ(R v) = v for a rotation two rotations deep (R v has sums as entries: the product is
    // a product of sums, equal to v after the explicit expansion)
    let rx = c.rot_x(b);
    let r = c.mat_mul(&rz, &rx);
    let v = [c.p(0), c.p(1), c.p(2)];
    let w = c.mat_vec(&r, &v);
    let back = c.mat_t_vec(&r, &w);
    assert_eq!(back.map(|e| c.expand(e)), v);
    // ω × r for ω = (0, 0, b), r = (a, 0, 0): (0, a·b, 0)
    let om = [ZERO, ZERO, b];
    let rr = [a, ZERO, ZERO];
    assert_eq!(c.cross(&om, &rr), [ZERO, c.mul(a, b), ZERO]);
    let s = c.vec_add(&ex, &ey);
    assert_eq!(c.dot(&s, &s), c.num(2.0));
    let two = c.num(2.0);
    assert_eq!(c.vec_scale(two, &ex), [two, ZERO, ZERO]);
}

#[test]
fn derivatives_of_elementary_functions() {
    let mut c = Context::new();
    let (x, y, _) = xyz(&mut c);
    let sx = Symbol::q(0);
    let s = c.sin(x);
    assert_eq!(c.diff(s, sx), c.cos(x));
    let co = c.cos(x);
    let ds = c.diff(co, sx);
    assert_eq!(ds, c.neg(s));
    let x3 = c.powi(x, 3);
    let x2 = c.powi(x, 2);
    let d = c.diff(x3, sx);
    assert_eq!(d, c.scale(3.0, x2));
    let xy = c.mul(x, y);
    assert_eq!(c.diff(xy, sx), y);
    assert_eq!(c.diff(y, sx), ZERO);
    let r = c.recip(x);
    let d = c.diff(r, sx);
    let xm2 = c.powi(x, -2);
    assert_eq!(d, c.neg(xm2));
    let e = c.exp(x);
    assert_eq!(c.diff(e, sx), e);
    let l = c.ln(x);
    assert_eq!(c.diff(l, sx), c.recip(x));
    // chain rule: d sin(x²) = 2x·cos(x²)
    let sx2 = c.sin(x2);
    let d = c.diff(sx2, sx);
    let cx2 = c.cos(x2);
    let e2 = c.mul(x, cx2);
    assert_eq!(d, c.scale(2.0, e2));
    // memoized: a second call returns the same node without creating any
    let n = c.len();
    assert_eq!(c.diff(sx2, sx), d);
    assert_eq!(c.len(), n);
    // numeric checks at a point for tan, sqrt, abs, atan2 (hand-derived values)
    let t = c.tan(x);
    let rt = c.sqrt(x);
    let ab = c.abs(x);
    let at = c.atan2(y, x);
    let ds: Vec<ExprId> = [t, rt, ab, at].iter().map(|&e| c.diff(e, sx)).collect();
    let dy = c.diff(at, Symbol::q(1));
    let (xv, yv) = (0.7_f64, -0.4_f64);
    let vals = Values {
        q: &[xv, yv],
        ..Default::default()
    };
    let got = c.eval(&[ds[0], ds[1], ds[2], ds[3], dy], &vals).unwrap();
    let r2 = xv * xv + yv * yv;
    let want = [
        1.0 / xv.cos().powi(2),
        0.5 / xv.sqrt(),
        1.0,
        -yv / r2,
        xv / r2,
    ];
    for (g, w) in got.iter().zip(want) {
        // a few roundings apart: 4 ulp relative
        assert!((g - w).abs() <= 4.0 * f64::EPSILON * w.abs(), "{g} vs {w}");
    }
}

#[test]
fn derivative_with_symbols_sharing_a_dependency_bit() {
    // q[0] and q[64] share a bit of the dependency summary: the summary may only make the
    // independence test less sharp, never give a wrong derivative or substitution
    let mut c = Context::new();
    let (a, b) = (c.q(0), c.q(64));
    let ab = c.mul(a, b);
    assert_eq!(c.diff(ab, Symbol::q(64)), a);
    let s = c.sin(a);
    assert_eq!(c.diff(s, Symbol::q(64)), ZERO);
    let v = c.v(0);
    assert_eq!(c.diff(v, Symbol::q(0)), ZERO);
    assert_eq!(c.diff(ab, Symbol::v(0)), ZERO);
    let two = c.num(2.0);
    let out = c.subs(&[s, ab, v], &[(Symbol::q(64), two)]);
    assert_eq!(out[0], s);
    assert_eq!(out[1], c.scale(2.0, a));
    assert_eq!(out[2], v);
}

#[test]
fn jacobian_and_substitution() {
    let mut c = Context::new();
    let (x, y, _) = xyz(&mut c);
    // f = (x·y, sin x + y²)
    let f0 = c.mul(x, y);
    let s = c.sin(x);
    let y2 = c.powi(y, 2);
    let f1 = c.add(s, y2);
    let j = c.jacobian(&[f0, f1], &[Symbol::q(0), Symbol::q(1)]);
    let cx = c.cos(x);
    let y2x = c.scale(2.0, y);
    assert_eq!(j, vec![vec![y, x], vec![cx, y2x]]);
    // substitute x → y + 1 simultaneously with y → x: (y+1)·x
    let yp1 = c.sum(1.0, &[(y, 1.0)]);
    let out = c.subs(&[f0], &[(Symbol::q(0), yp1), (Symbol::q(1), x)]);
    assert_eq!(out[0], c.mul(yp1, x));
    // substituting a number folds: sin(0) = 0
    let out = c.subs(&[f1], &[(Symbol::q(0), ZERO)]);
    assert_eq!(out[0], y2);
}

#[test]
fn expand_products_of_sums() {
    let mut c = Context::new();
    let (x, y, _) = xyz(&mut c);
    let s = c.add(x, y);
    let s2 = c.powi(s, 2);
    let e = c.expand(s2);
    let x2 = c.powi(x, 2);
    let y2 = c.powi(y, 2);
    let xy = c.mul(x, y);
    assert_eq!(e, c.sum(0.0, &[(x2, 1.0), (xy, 2.0), (y2, 1.0)]));
}

#[test]
fn evaluation_errors_are_reported() {
    let mut c = Context::new();
    let (x, _, _) = xyz(&mut c);
    let p3 = c.q(3);
    let err = c
        .eval(
            &[p3],
            &Values {
                q: &[1.0],
                ..Default::default()
            },
        )
        .unwrap_err();
    assert_eq!(
        err,
        CasError::MissingValue {
            symbol: Symbol::q(3),
            len: 1
        }
    );
    let r = c.recip(x);
    let err = c
        .eval(
            &[r],
            &Values {
                q: &[0.0],
                ..Default::default()
            },
        )
        .unwrap_err();
    assert!(matches!(err, CasError::NonFinite { .. }), "{err}");
    let prog = Program::compile(&c, &[r]);
    let err = prog
        .eval(&Values {
            q: &[0.0],
            ..Default::default()
        })
        .unwrap_err();
    assert!(matches!(err, CasError::NonFinite { .. }), "{err}");
    let m1 = c.num(-1.0);
    let l = c.ln(m1);
    assert!(c.eval(&[l], &Values::default()).is_err());
    assert!(prog.split(0).is_err());
    // a NaN input passed straight to an output is reported too
    let p = Program::compile(&c, &[x]);
    let nan = Values {
        q: &[f64::NAN],
        ..Default::default()
    };
    assert!(matches!(p.eval(&nan), Err(CasError::NonFinite { .. })));
    assert!(matches!(
        p.split(4).unwrap().eval(&p, &nan),
        Err(CasError::NonFinite { .. })
    ));
    assert!(matches!(
        c.eval(&[x], &nan),
        Err(CasError::NonFinite { .. })
    ));
}

#[test]
fn program_shares_and_lowers() {
    let mut c = Context::new();
    let (x, y, z) = xyz(&mut c);
    // out0 = x·y + z, out1 = (x·y)·sin(z), out2 = x⁴ − 2y, out3 = x²/y
    let xy = c.mul(x, y);
    let o0 = c.add(xy, z);
    let sz = c.sin(z);
    let o1 = c.mul(xy, sz);
    let x4 = c.powi(x, 4);
    let o2 = c.sum(0.0, &[(x4, 1.0), (y, -2.0)]);
    let x2 = c.powi(x, 2);
    let o3 = c.div(x2, y);
    let prog = Program::compile(&c, &[o0, o1, o2, o3]);
    // x·y once; x² = x·x once (shared by x⁴ = x²·x² and x²/y); x·y·sin z as one product chain
    let counts = prog.op_counts();
    // x·y, +z, sin z, (x·y)·sin z ... hand count: muls: x·y, x·y·sin z (chain of 3 factors: 2
    // muls, the first x·y shared), x², x⁴, 2y; adds: +z, −2y; divs: x²/y; calls: sin
    assert_eq!(counts.calls, 1);
    assert_eq!(counts.divs, 1);
    assert_eq!(counts.adds, 2);
    assert_eq!(counts.muls, 5, "{prog}");
    let tree = c.tree_op_counts(&[o0, o1, o2, o3]);
    assert!(tree.total() > counts.total());
    let q = [0.3, -1.2, 2.5];
    let vals = Values {
        q: &q,
        ..Default::default()
    };
    let a = prog.eval(&vals).unwrap();
    let b = c.eval(&[o0, o1, o2, o3], &vals).unwrap();
    for (u, v) in a.iter().zip(&b) {
        // the same operations in the same order, up to the order of commutative operands
        assert!((u - v).abs() <= 4.0 * f64::EPSILON * v.abs(), "{u} vs {v}");
    }
    // pure negation: −x·y is one Neg; −3x is one multiplication by −3, no Neg
    let nxy = c.neg(xy);
    let m3x = c.scale(-3.0, x);
    let p = Program::compile(&c, &[nxy, m3x]);
    assert_eq!(p.instrs.len(), 3, "{p}");
    assert!(p.instrs.contains(&Instr::Mul(
        Operand::Const(-3.0),
        Operand::Sym(Symbol::q(0))
    )));
    // equal coefficients are multiplied once: 2x + 2y − 2z + 3w = 2·(x + y − z) + 3w
    let w = c.q(3);
    let g = c.sum(0.0, &[(x, 2.0), (y, 2.0), (z, -2.0), (w, 3.0)]);
    let p = Program::compile(&c, &[g]);
    let n = p.op_counts();
    assert_eq!((n.muls, n.adds), (2, 3), "{p}");
    // only negative terms: −2x − 2y = (x + y)·(−2), −x − y = −(x + y)
    let g1 = c.sum(0.0, &[(x, -2.0), (y, -2.0)]);
    let g2 = c.sum(0.0, &[(x, -1.0), (y, -1.0)]);
    let p = Program::compile(&c, &[g1, g2]);
    let n = p.op_counts();
    assert_eq!((n.muls, n.adds), (1, 2), "{p}");
    let q4 = [0.5, 0.25, -1.0, 2.0];
    let vals4 = Values {
        q: &q4,
        ..Default::default()
    };
    assert_eq!(p.eval(&vals4).unwrap(), vec![-1.5, -0.75]);
    // sin/cos pairing info
    let cz = c.cos(z);
    let p = Program::compile(&c, &[sz, cz]);
    assert_eq!(p.sin_cos_pairs().len(), 1);
    assert_eq!(p.symbols(), vec![Symbol::q(2)]);
}

#[test]
fn split_program_matches_and_reuses_slots() {
    let mut c = Context::new();
    let qs: Vec<ExprId> = (0..6).map(|i| c.q(i)).collect();
    let mut outs = Vec::new();
    let mut acc = ONE;
    for &q in &qs {
        let s = c.sin(q);
        acc = c.mul(acc, s);
        let o = c.add(acc, q);
        outs.push(o);
    }
    let prog = Program::compile(&c, &outs);
    let q: Vec<f64> = (0..6).map(|i| 0.3 + 0.2 * i as f64).collect();
    let vals = Values {
        q: &q,
        ..Default::default()
    };
    let want = prog.eval(&vals).unwrap();
    // a program without instructions (outputs are an input and a constant)
    let p0 = Program::compile(&c, &[qs[0], ONE]);
    assert!(p0.instrs.is_empty());
    let sp0 = p0.split(4).unwrap();
    assert_eq!(sp0.eval(&p0, &vals).unwrap(), vec![q[0], 1.0]);
    // extreme exponents do not overflow
    let big = c.powi(qs[0], i32::MIN);
    let d = c.diff(big, Symbol::q(0));
    assert_ne!(d, ZERO);
    let last = prog.last_uses();
    assert_eq!(last.len(), prog.instrs.len());
    for max in 1..=prog.instrs.len() + 1 {
        let sp = prog.split(max).unwrap();
        assert!(sp.chunks.iter().all(|ch| ch.instrs.len() <= max));
        let got = sp.eval(&prog, &vals).unwrap();
        assert_eq!(got, want, "max {max}");
        assert!(sp.n_slots <= prog.instrs.len());
    }
}

#[test]
fn sums_reuse_the_sums_they_contain() {
    // M_0 = x0 + … + x5, M_1 = x1 + … + x5, …: the recursion M_i = M_(i+1) + x_i that
    // flattening hid comes back as one addition per sum, in whatever order the sums are asked
    // for (the largest first here). A sum containing another's terms negated subtracts it,
    // and a sum that is another plus a constant adds the constant.
    let mut c = Context::new();
    let x: Vec<ExprId> = (0..6).map(|i| c.q(i)).collect();
    let sums: Vec<ExprId> = (0..5).map(|i| c.add_many(&x[i..])).collect();
    let tail = c.add_many(&x[3..]);
    let minus_tail = c.neg(tail);
    let y = c.p(0);
    let opposite = c.add(minus_tail, y); // y − (x3 + x4 + x5)
    let two = c.num(2.0);
    let shifted = c.add(sums[0], two); // 2 + x0 + … + x5
    let mut outputs = sums.clone();
    outputs.extend([opposite, shifted]);
    let prog = Program::compile(&c, &outputs);
    let adds = prog.op_counts().adds;
    // x4 + x5, then one addition each for the four larger sums, one subtraction for
    // `opposite` and one addition for `shifted`.
    assert_eq!(adds, 1 + 4 + 1 + 1, "{prog}");
    let q: Vec<f64> = (0..6).map(|i| 1.0 + 0.5 * i as f64).collect();
    let vals = Values {
        q: &q,
        p: &[0.25],
        ..Default::default()
    };
    assert_eq!(prog.eval(&vals).unwrap(), c.eval(&outputs, &vals).unwrap());
}

#[test]
fn sums_of_sums_reuse_their_differences() {
    // a_k = x_0 + … + x_k (the velocity-product acceleration of link k of a chain) and
    // F_i = a_i + … + a_(n−1) (the force on the links beyond joint i). Flattened, F_i is
    // Σ_m (n − max(i, m))·x_m: its coefficients change with i, so no F_(i+1) is a subset of
    // F_i with equal coefficients. F_i − F_(i+1) = a_i is, though: one addition per sum,
    // where lowering each F_i by itself takes O(n) operations (O(n²) in all).
    let n: usize = 10;
    let mut c = Context::new();
    let x: Vec<ExprId> = (0..n).map(|i| c.q(i as u32)).collect();
    let a: Vec<ExprId> = (0..n).map(|k| c.add_many(&x[..=k])).collect();
    let f: Vec<ExprId> = (0..n).map(|i| c.add_many(&a[i..])).collect();
    let mut outputs = f.clone();
    outputs.extend(&a);
    let prog = Program::compile(&c, &outputs);
    let total = prog.op_counts().total();
    // Linear: n − 1 additions for the a_k and about one per F_i (the first F lowered may
    // keep a few scaled terms: at most four partial sums are taken into one sum).
    assert!(total <= 3 * n as u128, "{total} operations:\n{prog}");
    // Each F_i lowered alone: n − 1 additions and a multiplication per distinct coefficient.
    let separately: u128 = f
        .iter()
        .map(|&fi| Program::compile(&c, &[fi]).op_counts().total())
        .sum();
    assert!(separately > 5 * total, "{separately} vs {total}");
    let q: Vec<f64> = (0..n).map(|i| 0.3 + 0.7 * i as f64).collect();
    let vals = Values {
        q: &q,
        ..Default::default()
    };
    for (g, w) in prog
        .eval(&vals)
        .unwrap()
        .iter()
        .zip(c.eval(&outputs, &vals).unwrap())
    {
        assert!((g - w).abs() <= 1e-13 * w.abs(), "{g} vs {w}");
    }
}

#[test]
fn column_recursions_pack_into_lanes() {
    // Four columns c of M_i,c = M_(i+1),c + s_i·x_c + k_i·y_c (s_i, k_i shared by the
    // columns, x_c and y_c each column's own: the shape of a chain's mass matrix), asked for
    // row by row. The rows of the four columns grow into one tree of packs, four per row
    // (two products, their sum, the recursion's addition); values stay bit-identical.
    let (rows, w) = (6usize, 4usize);
    let mut c = Context::new();
    let s: Vec<ExprId> = (0..rows).map(|i| c.q(i as u32)).collect();
    let k: Vec<ExprId> = (0..rows).map(|i| c.v(i as u32)).collect();
    let x: Vec<ExprId> = (0..w).map(|l| c.p(l as u32)).collect();
    let y: Vec<ExprId> = (0..w).map(|l| c.p((w + l) as u32)).collect();
    let mut entries = vec![vec![ZERO; w]; rows + 1];
    for l in 0..w {
        entries[rows][l] = c.p((2 * w + l) as u32); // the diagonal
        for i in (0..rows).rev() {
            let a = c.mul(s[i], x[l]);
            let b = c.mul(k[i], y[l]);
            entries[i][l] = c.add_many(&[entries[i + 1][l], a, b]);
        }
    }
    let outputs: Vec<ExprId> = (0..rows).flat_map(|i| entries[i].clone()).collect();
    let prog = Program::compile(&c, &outputs);
    let seeds: Vec<Vec<u32>> = (0..rows)
        .map(|i| {
            (0..w)
                .map(|l| match prog.outputs[i * w + l] {
                    Operand::Tmp(t) => t,
                    other => panic!("entry ({i}, {l}) is {other}"),
                })
                .collect()
        })
        .collect();
    let packed = prog.pack_lanes(&seeds, w, &[]);
    assert_eq!(packed.packs.len(), 4 * rows, "{}", packed.program);
    let q: Vec<f64> = (0..rows).map(|i| 0.3 + 0.1 * i as f64).collect();
    let v: Vec<f64> = (0..rows).map(|i| -0.7 + 0.2 * i as f64).collect();
    let p: Vec<f64> = (0..3 * w).map(|i| 1.0 + 0.37 * i as f64).collect();
    let vals = Values {
        q: &q,
        v: &v,
        p: &p,
        ..Default::default()
    };
    assert_eq!(
        packed.program.eval(&vals).unwrap(),
        prog.eval(&vals).unwrap()
    );
    // Too few lanes to pay, or a seed of lanes that depend on each other: nothing packed.
    assert!(prog.pack_lanes(&seeds, 1, &[]).packs.is_empty());
    let chain: Vec<u32> = seeds.iter().map(|s| s[0]).take(w).collect();
    assert!(prog.pack_lanes(&[chain], w, &[]).packs.is_empty());
}
