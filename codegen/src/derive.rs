//! Symbolic derivation of the equations of motion: the same recursive
//! kinematics and composite-body method as the numeric engine
//! (`railmbs_runtime::numeric`), carried out on expressions of the `cas` crate.
//!
//! Symbols: `q[i]`, `v[i]` (generalized coordinates and velocities), `p[i]`
//! (the model's identifiers: runtime inputs, so a new value needs no
//! recompilation), `t` (time, for rheonomic transformations and time-dependent
//! expressions).
//!
//! The composite bodies are kept division-free: for the subtree of body b,
//! its mass m, first moment h = Σ m_k (c_k − r_b) and inertia J about r_b
//! (J = Σ [I_k + m_k(|ρ_k|²E − ρ_kρ_kᵀ)], ρ_k = c_k − r_b). For a rotation of
//! unit rate about axis u through p, the subtree's momentum is
//! L = u × (m d + h) and its angular momentum about r_b is H = J u + h × (u × d)
//! with d = r_b − p; a translation along u gives L = m u, H = h × u. Then
//! M_ij = u_j·(H + (r_b − p_j) × L) for a rotation j and u_j·L for a translation.

use railmbs_cas::{Context, ExprId, Symbol};
use railmbs_models::{BodyRef, Component, ElementaryKind, Expr, Frame, Func, Model, Motion};

/// A 3-vector of expressions.
pub type V3 = [ExprId; 3];
/// A 3×3 matrix of expressions, row-major `m[r][c]`.
pub type M3 = [[ExprId; 3]; 3];

/// Symbolic vector algebra on a [`Context`].
pub struct Alg<'a> {
    /// The expression DAG the vectors and matrices live in.
    pub ctx: &'a mut Context,
    zero: ExprId,
    one: ExprId,
}

impl<'a> Alg<'a> {
    /// Algebra on `ctx`.
    pub fn new(ctx: &'a mut Context) -> Self {
        let zero = ctx.num(0.0);
        let one = ctx.num(1.0);
        Self { ctx, zero, one }
    }
    /// The expression 0.
    pub fn zero(&self) -> ExprId {
        self.zero
    }
    /// The zero vector.
    pub fn v_zero(&self) -> V3 {
        [self.zero; 3]
    }
    /// The identity matrix E.
    pub fn identity(&self) -> M3 {
        let (z, o) = (self.zero, self.one);
        [[o, z, z], [z, o, z], [z, z, o]]
    }
    /// a + b.
    pub fn add(&mut self, a: V3, b: V3) -> V3 {
        [0, 1, 2].map(|k| self.ctx.add(a[k], b[k]))
    }
    /// a − b.
    pub fn sub(&mut self, a: V3, b: V3) -> V3 {
        [0, 1, 2].map(|k| self.ctx.sub(a[k], b[k]))
    }
    /// s·a for an expression s.
    pub fn scale(&mut self, s: ExprId, a: V3) -> V3 {
        [0, 1, 2].map(|k| self.ctx.mul(s, a[k]))
    }
    /// s·a for a number s.
    pub fn scale_num(&mut self, s: f64, a: V3) -> V3 {
        [0, 1, 2].map(|k| self.ctx.scale(s, a[k]))
    }
    /// a · b.
    pub fn dot(&mut self, a: V3, b: V3) -> ExprId {
        let t = [0, 1, 2].map(|k| self.ctx.mul(a[k], b[k]));
        self.ctx.add_many(&t)
    }
    /// a × b.
    pub fn cross(&mut self, a: V3, b: V3) -> V3 {
        let c = |s: &mut Self, i: usize, j: usize| {
            let x = s.ctx.mul(a[i], b[j]);
            let y = s.ctx.mul(a[j], b[i]);
            s.ctx.sub(x, y)
        };
        [c(self, 1, 2), c(self, 2, 0), c(self, 0, 1)]
    }
    /// Column k of m.
    pub fn column(&self, m: &M3, k: usize) -> V3 {
        [m[0][k], m[1][k], m[2][k]]
    }
    /// m x.
    pub fn mat_vec(&mut self, m: &M3, x: V3) -> V3 {
        [0, 1, 2].map(|r| {
            let t = [0, 1, 2].map(|c| self.ctx.mul(m[r][c], x[c]));
            self.ctx.add_many(&t)
        })
    }
    /// mᵀ x.
    pub fn mat_t_vec(&mut self, m: &M3, x: V3) -> V3 {
        [0, 1, 2].map(|c| {
            let t = [0, 1, 2].map(|r| self.ctx.mul(m[r][c], x[r]));
            self.ctx.add_many(&t)
        })
    }
    /// a b.
    pub fn mat_mul(&mut self, a: &M3, b: &M3) -> M3 {
        [0, 1, 2].map(|r| {
            [0, 1, 2].map(|c| {
                let t = [0, 1, 2].map(|k| self.ctx.mul(a[r][k], b[k][c]));
                self.ctx.add_many(&t)
            })
        })
    }
    /// a + b.
    pub fn mat_add(&mut self, a: &M3, b: &M3) -> M3 {
        [0, 1, 2].map(|r| [0, 1, 2].map(|c| self.ctx.add(a[r][c], b[r][c])))
    }
    /// A R Aᵀ for symmetric R.
    pub fn rotate_tensor(&mut self, a: &M3, r: &M3) -> M3 {
        let ar = self.mat_mul(a, r);
        let mut out = [[self.zero; 3]; 3];
        for i in 0..3 {
            for j in i..3 {
                let t = [0, 1, 2].map(|k| self.ctx.mul(ar[i][k], a[j][k]));
                out[i][j] = self.ctx.add_many(&t);
                out[j][i] = out[i][j];
            }
        }
        out
    }
    /// m(|d|² E − d dᵀ) (parallel-axis term).
    pub fn steiner(&mut self, m: ExprId, d: V3) -> M3 {
        let sq = d.map(|x| self.ctx.powi(x, 2));
        let mut out = [[self.zero; 3]; 3];
        for i in 0..3 {
            for j in i..3 {
                let e = if i == j {
                    let (a, b) = ((i + 1) % 3, (i + 2) % 3);
                    self.ctx.add(sq[a], sq[b])
                } else {
                    let x = self.ctx.mul(d[i], d[j]);
                    self.ctx.neg(x)
                };
                out[i][j] = self.ctx.mul(m, e);
                out[j][i] = out[i][j];
            }
        }
        out
    }
    /// h eᵀ + e hᵀ (symmetric).
    pub fn sym_outer(&mut self, h: V3, e: V3) -> M3 {
        let mut out = [[self.zero; 3]; 3];
        for i in 0..3 {
            for j in i..3 {
                let a = self.ctx.mul(h[i], e[j]);
                let b = self.ctx.mul(e[i], h[j]);
                out[i][j] = self.ctx.add(a, b);
                out[j][i] = out[i][j];
            }
        }
        out
    }
    /// Elementary rotation matrix about axis k by angle s.
    pub fn rotation(&mut self, axis: usize, s: ExprId) -> M3 {
        let c = self.ctx.cos(s);
        let sn = self.ctx.sin(s);
        let ms = self.ctx.neg(sn);
        let (z, o) = (self.zero, self.one);
        match axis {
            0 => [[o, z, z], [z, c, ms], [z, sn, c]],
            1 => [[c, z, sn], [z, o, z], [ms, z, c]],
            _ => [[c, ms, z], [sn, c, z], [z, z, o]],
        }
    }
}

/// Which identifiers are replaced by their default values at generation time.
#[derive(Debug, Clone, Default)]
pub struct DeriveOptions {
    /// Parameter indices to fix (constant-folded; changing them then needs regeneration).
    pub fixed: Vec<usize>,
    /// Default parameter values (needed for `fixed`).
    pub defaults: Vec<f64>,
}

/// The derived equations: expression lists in the order the plugin ABI writes them.
pub struct Derived {
    /// The expression DAG all lists below point into.
    pub ctx: Context,
    /// Upper triangle of M by columns: for j in 0..n, i in 0..=j → M[(i, j)]; with the
    /// (i, j) pairs in `mass_index`. Structural zeros are left out.
    pub mass: Vec<ExprId>,
    /// (row, column) of each entry of `mass`.
    pub mass_index: Vec<(usize, usize)>,
    /// k, n entries.
    pub bias: Vec<ExprId>,
    /// Q_g, n entries.
    pub gravity: Vec<ExprId>,
    /// Per body: r (3), A column-major (9), v (3), ω (3).
    pub kinematics: Vec<ExprId>,
    /// Nonzero entries of the stacked Γ (6·nb × n): value and (row, column).
    pub jacobians: Vec<ExprId>,
    /// (row, column) of each entry of `jacobians`.
    pub jacobian_index: Vec<(usize, usize)>,
    /// g, nc entries.
    pub constraints: Vec<ExprId>,
    /// Nonzero entries of G (nc × n).
    pub constraint_jacobian: Vec<ExprId>,
    /// (row, column) of each entry of `constraint_jacobian`.
    pub constraint_jacobian_index: Vec<(usize, usize)>,
    /// Generalized coordinates n.
    pub dof: usize,
    /// Bodies (ground excluded).
    pub bodies: usize,
    /// Runtime inputs (each with value, rate, acceleration in `u`).
    pub inputs: usize,
}

/// Converts a model expression into the context.
pub fn expr_to_cas(ctx: &mut Context, e: &Expr, opts: &DeriveOptions) -> ExprId {
    match e {
        Expr::Num(x) => ctx.num(*x),
        Expr::Param(i) => {
            if opts.fixed.contains(i) {
                ctx.num(opts.defaults[*i])
            } else {
                ctx.sym(Symbol::p(*i as u32))
            }
        }
        Expr::Time => ctx.sym(Symbol::t()),
        // Local variables exist only in force-element fields evaluated by the
        // runtime (the loader refuses them elsewhere); never in kinematics.
        Expr::Var(_) => ctx.num(f64::NAN),
        Expr::Neg(a) => {
            let a = expr_to_cas(ctx, a, opts);
            ctx.neg(a)
        }
        Expr::Add(a, b) | Expr::Sub(a, b) | Expr::Mul(a, b) | Expr::Div(a, b) => {
            let x = expr_to_cas(ctx, a, opts);
            let y = expr_to_cas(ctx, b, opts);
            match e {
                Expr::Add(..) => ctx.add(x, y),
                Expr::Sub(..) => ctx.sub(x, y),
                Expr::Mul(..) => ctx.mul(x, y),
                _ => ctx.div(x, y),
            }
        }
        Expr::Pow(a, b) => {
            let x = expr_to_cas(ctx, a, opts);
            let y = expr_to_cas(ctx, b, opts);
            match ctx.as_num(y) {
                Some(n) if n.fract() == 0.0 && n.abs() <= 64.0 => ctx.powi(x, n as i32),
                Some(0.5) => ctx.sqrt(x),
                Some(-0.5) => {
                    let s = ctx.sqrt(x);
                    ctx.recip(s)
                }
                _ => {
                    // a^b = exp(b ln a) (a > 0), as f64::powf.
                    let l = ctx.ln(x);
                    let m = ctx.mul(y, l);
                    ctx.exp(m)
                }
            }
        }
        Expr::Call(f, a) => {
            let x = expr_to_cas(ctx, a, opts);
            match f {
                Func::Sin => ctx.sin(x),
                Func::Cos => ctx.cos(x),
                Func::Tan => ctx.tan(x),
                Func::Sqrt => ctx.sqrt(x),
                Func::Abs => ctx.abs(x),
                Func::Exp => ctx.exp(x),
                Func::Ln => ctx.ln(x),
                Func::Atan => {
                    let one = ctx.num(1.0);
                    ctx.atan2(x, one)
                }
            }
        }
    }
}

#[derive(Clone, Copy)]
struct State {
    r: V3,
    a: M3,
    v: V3,
    w: V3,
    acc0: V3,
    alpha0: V3,
    /// Gravity, m/s², in the basis the other vectors are expressed in.
    g: V3,
    /// In the tree-local pass: no generalized coordinate on the path yet
    /// (the vectors are expressed in the current frame; see [`forward`]).
    pre: bool,
    /// The last rotations on the path, when they share one axis: the axis,
    /// the rotation before them and their summed angle, so that
    /// A = A_before · R_axis(Σ angles) (one sine and cosine of the sum instead of a
    /// matrix product per rotation: planar chains).
    same_axis: Option<(usize, M3, ExprId)>,
}

#[derive(Clone, Copy)]
struct OpNode {
    parent: Option<usize>,
    /// Translation of this elementary transformation (SC0), if it is one.
    d: Option<V3>,
}

#[derive(Clone, Copy)]
struct AxisInfo {
    rotation: bool,
    u: V3,
    p: V3,
}

/// The result of one forward pass over the bodies.
struct Forward {
    states: Vec<State>,
    axes: Vec<Option<AxisInfo>>,
    chains: Vec<Vec<usize>>,
    children: Vec<Vec<usize>>,
    masses: Vec<ExprId>,
    /// Inertia about the centre of mass in the pass's basis.
    inertia_g: Vec<M3>,
    /// The path of elementary transformations as a tree of op nodes:
    /// translation vector and parent node of each.
    ops: Vec<OpNode>,
    /// Each body's last op node.
    body_end: Vec<Option<usize>>,
    /// Op node of each coordinate.
    op_of: Vec<usize>,
}

/// Consecutive translations, applied to the velocity and acceleration at once
/// (at the next rotation or the body's end): while the frame only translates,
/// its ω and α⁰ stay, so for the summed displacement D, relative velocity V
/// and relative acceleration A
///
/// ```text
///   v' = v + ω×D + V,   a⁰' = a⁰ + α⁰×D + ω×(ω×D) + 2 ω×V + A
/// ```
///
/// (one set of cross products instead of one per elementary translation: a
/// body's x, y, z coordinates in a moving frame).
#[derive(Default)]
struct Shift {
    sum: Option<[V3; 3]>,
}

impl Shift {
    /// Adds the translation by `val` along `u` (rate, acceleration); returns its displacement.
    fn add(&mut self, alg: &mut Alg, val: ExprId, rate: ExprId, acc: ExprId, u: V3) -> V3 {
        let d = alg.scale(val, u);
        let v = alg.scale(rate, u);
        let a = alg.scale(acc, u);
        self.sum = Some(match self.sum {
            None => [d, v, a],
            Some([sd, sv, sa]) => [alg.add(sd, d), alg.add(sv, v), alg.add(sa, a)],
        });
        d
    }

    /// Applies the pending translations to `s.v` and `s.acc0`.
    fn apply(&mut self, alg: &mut Alg, s: &mut State) {
        let Some([d, v_rel, a_rel]) = self.sum.take() else {
            return;
        };
        let t1 = alg.cross(s.alpha0, d);
        let wd = alg.cross(s.w, d);
        let t2 = alg.cross(s.w, wd);
        let wv = alg.cross(s.w, v_rel);
        let t3 = alg.scale_num(2.0, wv);
        let sum = alg.add(t1, t2);
        let sum = alg.add(sum, t3);
        let sum = alg.add(sum, a_rel);
        s.acc0 = alg.add(s.acc0, sum);
        let dv = alg.add(wd, v_rel);
        s.v = alg.add(s.v, dv);
    }
}

/// The forward pass (see runtime::numeric for the formulas).
///
/// `local == false`: everything in SC0 (body kinematics, Jacobians,
/// constraints). `local == true`: the pass for M, k and Q_g, which are scalar
/// projections and so do not depend on the basis or the reference point the
/// vectors are taken in. On each path from SC0, the transformations before the
/// first generalized coordinate (a vehicle body's track-following frame: six
/// runtime inputs) are walked with every vector expressed in the current frame,
/// and from the first coordinate on the vectors stay in that frame's basis with
/// its origin as the reference point. The frame's own motion then enters only
/// through its velocity, angular velocity, accelerations and gravity in its own
/// basis (a few expressions per tree) instead of through its rotation matrix in
/// every entry of M and k.
fn forward(
    alg: &mut Alg,
    model: &Model,
    opts: &DeriveOptions,
    gravity: V3,
    local: bool,
) -> Forward {
    let n = model.coordinates.len();
    let nb = model.bodies.len();
    let mut f = Forward {
        states: Vec::with_capacity(nb),
        axes: vec![None; n],
        chains: Vec::with_capacity(nb),
        children: vec![Vec::new(); nb],
        masses: Vec::with_capacity(nb),
        inertia_g: Vec::with_capacity(nb),
        ops: Vec::new(),
        body_end: Vec::with_capacity(nb),
        op_of: vec![0; n],
    };
    for (j, body) in model.bodies.iter().enumerate() {
        let parent = match body.parent {
            BodyRef::Ground => None,
            BodyRef::Body(p) => Some(p),
        };
        if let Some(p) = parent {
            f.children[p].push(j);
        }
        let mut chain = parent.map(|p| f.chains[p].clone()).unwrap_or_default();
        let mut last_op = parent.and_then(|p| f.body_end[p]);
        let mut s = match parent {
            Some(p) => f.states[p],
            None => State {
                r: alg.v_zero(),
                a: alg.identity(),
                v: alg.v_zero(),
                w: alg.v_zero(),
                acc0: alg.v_zero(),
                alpha0: alg.v_zero(),
                g: gravity,
                pre: local,
                same_axis: None,
            },
        };
        let mut shift = Shift::default();
        for el in &body.joint {
            let (rotation, axis) = match el.kind {
                ElementaryKind::Translation(a) => (false, a.index()),
                ElementaryKind::Rotation(a) => (true, a.index()),
            };
            let zero = alg.zero();
            let (val, rate, acc) = match &el.motion {
                Motion::Fixed(e) => (expr_to_cas(alg.ctx, e, opts), zero, zero),
                Motion::Coordinate(i) => {
                    chain.push(*i);
                    (
                        alg.ctx.sym(Symbol::q(*i as u32)),
                        alg.ctx.sym(Symbol::v(*i as u32)),
                        zero,
                    )
                }
                Motion::Time(e) => {
                    let x = expr_to_cas(alg.ctx, e, opts);
                    let xd = alg.ctx.diff(x, Symbol::t());
                    let xdd = alg.ctx.diff(xd, Symbol::t());
                    (x, xd, xdd)
                }
                // Runtime input k: value, rate, acceleration in u[3k..3k+3].
                Motion::Input(k) => {
                    let k = 3 * *k as u32;
                    (
                        alg.ctx.sym(Symbol::u(k)),
                        alg.ctx.sym(Symbol::u(k + 1)),
                        alg.ctx.sym(Symbol::u(k + 2)),
                    )
                }
            };
            let coord = match &el.motion {
                Motion::Coordinate(i) => Some(*i),
                _ => None,
            };
            if s.pre && coord.is_some() {
                // From here on the vectors stay in this frame's basis (whose
                // origin is the reference point: r = 0, A = E).
                s.pre = false;
            }
            // Before the first coordinate of the local pass A stays E, so `u` is the
            // current frame's own axis and the vectors are in that frame's basis.
            let u = alg.column(&s.a, axis);
            if let Some(i) = coord {
                f.axes[i] = Some(AxisInfo {
                    rotation,
                    u,
                    p: s.r,
                });
                f.op_of[i] = f.ops.len();
            }
            let mut d_op = None;
            if rotation {
                shift.apply(alg, &mut s);
                let w_rel = alg.scale(rate, u);
                let c = alg.cross(s.w, w_rel);
                let ua = alg.scale(acc, u);
                let t = alg.add(c, ua);
                s.alpha0 = alg.add(s.alpha0, t);
                s.w = alg.add(s.w, w_rel);
                if s.pre {
                    // The rotated frame's basis: x' = Rᵀ x.
                    let r = alg.rotation(axis, val);
                    let rt = [0, 1, 2].map(|i| [0, 1, 2].map(|k| r[k][i]));
                    for x in [&mut s.w, &mut s.alpha0, &mut s.v, &mut s.acc0, &mut s.g] {
                        *x = alg.mat_vec(&rt, *x);
                    }
                } else {
                    let (before, angle) = match s.same_axis {
                        Some((a, before, angle)) if a == axis => (before, alg.ctx.add(angle, val)),
                        _ => (s.a, val),
                    };
                    let r = alg.rotation(axis, angle);
                    s.a = alg.mat_mul(&before, &r);
                    s.same_axis = Some((axis, before, angle));
                }
            } else {
                let d = shift.add(alg, val, rate, acc, u);
                if !s.pre {
                    s.r = alg.add(s.r, d);
                    d_op = Some(d);
                }
            }
            f.ops.push(OpNode {
                parent: last_op,
                d: d_op,
            });
            last_op = Some(f.ops.len() - 1);
        }
        shift.apply(alg, &mut s);
        let m = expr_to_cas(alg.ctx, &body.mass, opts);
        let iv = body.inertia.clone().map(|e| expr_to_cas(alg.ctx, &e, opts));
        let ib = [
            [iv[0], iv[3], iv[4]],
            [iv[3], iv[1], iv[5]],
            [iv[4], iv[5], iv[2]],
        ];
        f.inertia_g.push(alg.rotate_tensor(&s.a, &ib));
        f.masses.push(m);
        f.states.push(s);
        f.chains.push(chain);
        f.body_end.push(last_op);
    }
    f
}

/// Where body `b`'s own coordinates are in its chain (after its parent's).
fn own_range(model: &Model, chains: &[Vec<usize>], b: usize) -> std::ops::RangeFrom<usize> {
    match model.bodies[b].parent {
        BodyRef::Ground => 0..,
        BodyRef::Body(p) => chains[p].len()..,
    }
}

/// Derives all equations of `model`.
pub fn derive(model: &Model, opts: &DeriveOptions) -> Derived {
    let mut ctx = Context::new();
    let n = model.coordinates.len();
    let nb = model.bodies.len();
    let mut alg = Alg::new(&mut ctx);
    let gravity: V3 = [0, 1, 2].map(|k| expr_to_cas(alg.ctx, &model.gravity[k], opts));
    // SC0 pass for the kinematics, Jacobians and constraints; the tree-local
    // pass for M, k and Q_g.
    let global = forward(&mut alg, model, opts, gravity, false);
    let Forward {
        states,
        axes,
        chains,
        children,
        masses,
        inertia_g,
        ops,
        body_end,
        op_of,
    } = forward(&mut alg, model, opts, gravity, true);

    // Σ of the translations on the path from node `from` up to (not including) `stop`.
    let sum_d = |alg: &mut Alg, from: Option<usize>, stop: Option<usize>| -> V3 {
        let mut terms: [Vec<ExprId>; 3] = [Vec::new(), Vec::new(), Vec::new()];
        let mut x = from;
        while x != stop {
            let Some(node) = x else { break };
            if let Some(d) = ops[node].d {
                for k in 0..3 {
                    terms[k].push(d[k]);
                }
            }
            x = ops[node].parent;
        }
        [0, 1, 2].map(|k| alg.ctx.add_many(&terms[k]))
    };
    let parent_end = |b: usize| match model.bodies[b].parent {
        BodyRef::Ground => None,
        BodyRef::Body(p) => body_end[p],
    };
    // r_c − r_parent(c) for every body.
    let seg_body: Vec<V3> = (0..nb)
        .map(|c| sum_d(&mut alg, body_end[c], parent_end(c)))
        .collect();
    // r_b − p_i for every coordinate i of body b.
    let mut to_com: Vec<V3> = vec![alg.v_zero(); n];
    for b in 0..nb {
        for &i in &chains[b][own_range(model, &chains, b)] {
            let stop = ops[op_of[i]].parent;
            to_com[i] = sum_d(&mut alg, body_end[b], stop);
        }
    }
    // p_i − p_prev(i) for consecutive coordinates on a chain (prev = the
    // coordinate before i on the path from SC0).
    let mut seg_coord: Vec<V3> = vec![alg.v_zero(); n];
    for b in 0..nb {
        let chain = &chains[b];
        let own = own_range(model, &chains, b);
        for pos in own.start.max(1)..chain.len() {
            let (i, prev) = (chain[pos], chain[pos - 1]);
            seg_coord[i] = sum_d(&mut alg, ops[op_of[i]].parent, ops[op_of[prev]].parent);
        }
    }

    let own_coordinates = |b: usize| -> &[usize] { &chains[b][own_range(model, &chains, b)] };

    // Composite bodies, division-free (module docs).
    let mut cm: Vec<ExprId> = vec![alg.zero(); nb];
    let mut ch: Vec<V3> = vec![alg.v_zero(); nb];
    let mut cj: Vec<M3> = vec![[[alg.zero(); 3]; 3]; nb];
    for b in (0..nb).rev() {
        let mut m = masses[b];
        let mut h = alg.v_zero();
        let mut j = inertia_g[b];
        for &c in &children[b] {
            let e = seg_body[c];
            m = alg.ctx.add(m, cm[c]);
            let me = alg.scale(cm[c], e);
            let he = alg.add(me, ch[c]);
            h = alg.add(h, he);
            // Shift J_c from r_c to r_b: J_c + 2(h_c·e)E − (h_c eᵀ + e h_cᵀ) + m_c(|e|²E − e eᵀ).
            let hd = alg.dot(ch[c], e);
            let hd2 = alg.ctx.scale(2.0, hd);
            let outer = alg.sym_outer(ch[c], e);
            let st = alg.steiner(cm[c], e);
            let mut shift = [[alg.zero(); 3]; 3];
            for r in 0..3 {
                for k in 0..3 {
                    let diag = if r == k { hd2 } else { alg.zero() };
                    let x = alg.ctx.sub(diag, outer[r][k]);
                    let x = alg.ctx.add(x, st[r][k]);
                    shift[r][k] = alg.ctx.add(cj[c][r][k], x);
                }
            }
            j = alg.mat_add(&j, &shift);
        }
        cm[b] = m;
        ch[b] = h;
        cj[b] = j;
    }

    // Mass matrix: momentum (L, H) of the composite subtree for a unit rate of
    // q_i, carried from joint point to joint point up the chain
    // (H_prev = H + (p_i − p_prev) × L) and projected on each coordinate. (The
    // alternative with every entry independent, M_ki = u_k·H_o − (u_k × (p_k − o))·L
    // about one point o per tree, was measured 2.5 % slower on chain30: more
    // operations, and out-of-order execution overlaps the columns' recursions.)
    let mut mass_entries: Vec<((usize, usize), ExprId)> = Vec::new();
    for b in 0..nb {
        let own = own_coordinates(b).to_vec();
        let chain = chains[b].clone();
        for &i in &own {
            let ax = axes[i].expect("coordinate axis set in the forward pass");
            let d = to_com[i];
            let (l, h_com) = if ax.rotation {
                let md = alg.scale(cm[b], d);
                let mdh = alg.add(md, ch[b]);
                let l = alg.cross(ax.u, mdh);
                let ju = alg.mat_vec(&cj[b], ax.u);
                let ud = alg.cross(ax.u, d);
                let hud = alg.cross(ch[b], ud);
                (l, alg.add(ju, hud))
            } else {
                (alg.scale(cm[b], ax.u), alg.cross(ch[b], ax.u))
            };
            // About p_i.
            let dl = alg.cross(d, l);
            let mut h = alg.add(h_com, dl);
            let pos_i = chain
                .iter()
                .position(|&c| c == i)
                .expect("own coordinate in chain");
            for pos in (0..=pos_i).rev() {
                let k = chain[pos];
                if pos < pos_i {
                    // Move the reference point from p_next to p_k.
                    let next = chain[pos + 1];
                    let sl = alg.cross(seg_coord[next], l);
                    h = alg.add(h, sl);
                }
                let axk = axes[k].expect("coordinate axis set");
                let value = if axk.rotation {
                    alg.dot(axk.u, h)
                } else {
                    alg.dot(axk.u, l)
                };
                mass_entries.push(((k, i), value));
            }
        }
    }
    mass_entries.sort_by_key(|((r, c), _)| (*c, *r));
    let zero = alg.zero();
    mass_entries.retain(|(_, e)| *e != zero);

    // Body wrenches projected on the coordinates (backward accumulation).
    let project = |alg: &mut Alg, wrench: &dyn Fn(&mut Alg, usize) -> (V3, V3)| -> Vec<ExprId> {
        let mut f_sub = vec![alg.v_zero(); nb];
        let mut n_sub = vec![alg.v_zero(); nb];
        for b in (0..nb).rev() {
            let (mut f, mut nn) = wrench(alg, b);
            for &c in &children[b] {
                f = alg.add(f, f_sub[c]);
                let ef = alg.cross(seg_body[c], f_sub[c]);
                let t = alg.add(n_sub[c], ef);
                nn = alg.add(nn, t);
            }
            f_sub[b] = f;
            n_sub[b] = nn;
        }
        let mut out = vec![alg.zero(); n];
        for b in 0..nb {
            for &i in own_coordinates(b) {
                let ax = axes[i].expect("coordinate axis set");
                out[i] = if ax.rotation {
                    let df = alg.cross(to_com[i], f_sub[b]);
                    let mo = alg.add(n_sub[b], df);
                    alg.dot(ax.u, mo)
                } else {
                    alg.dot(ax.u, f_sub[b])
                };
            }
        }
        out
    };
    let bias = project(&mut alg, &|alg, j| {
        let s = states[j];
        let f = alg.scale(masses[j], s.acc0);
        let ia = alg.mat_vec(&inertia_g[j], s.alpha0);
        let iw = alg.mat_vec(&inertia_g[j], s.w);
        let wiw = alg.cross(s.w, iw);
        (f, alg.add(ia, wiw))
    });
    let gravity_q = project(&mut alg, &|alg, j| {
        (alg.scale(masses[j], states[j].g), alg.v_zero())
    });

    // Kinematics and Jacobians.
    let mut kinematics = Vec::with_capacity(18 * nb);
    let mut jac = Vec::new();
    for (j, s) in global.states.iter().enumerate() {
        kinematics.extend_from_slice(&s.r);
        for c in 0..3 {
            for r in 0..3 {
                kinematics.push(s.a[r][c]);
            }
        }
        kinematics.extend_from_slice(&s.v);
        kinematics.extend_from_slice(&s.w);
        for &i in &global.chains[j] {
            let ax = global.axes[i].expect("coordinate axis set");
            let (lin, ang) = if ax.rotation {
                let d = alg.sub(s.r, ax.p);
                (alg.cross(ax.u, d), ax.u)
            } else {
                (ax.u, alg.v_zero())
            };
            for k in 0..3 {
                jac.push(((6 * j + k, i), lin[k]));
                jac.push(((6 * j + 3 + k, i), ang[k]));
            }
        }
    }
    jac.retain(|(_, e)| *e != zero);

    // Cut-joint constraints.
    let mut constraints = Vec::new();
    let mut cjac: Vec<((usize, usize), ExprId)> = Vec::new();
    let mut row = 0;
    for cut in &model.cut_joints {
        let frame_pose = |alg: &mut Alg, body: BodyRef, f: &Frame| -> (V3, M3, Option<usize>) {
            let o = f.origin.clone().map(|e| expr_to_cas(alg.ctx, &e, opts));
            let ang = f
                .rotation_xyz
                .clone()
                .map(|e| expr_to_cas(alg.ctx, &e, opts));
            let rx = alg.rotation(0, ang[0]);
            let ry = alg.rotation(1, ang[1]);
            let rz = alg.rotation(2, ang[2]);
            let rxy = alg.mat_mul(&rx, &ry);
            let rf = alg.mat_mul(&rxy, &rz);
            match body {
                BodyRef::Ground => (o, rf, None),
                BodyRef::Body(b) => {
                    let ao = alg.mat_vec(&global.states[b].a, o);
                    let p = alg.add(global.states[b].r, ao);
                    (p, alg.mat_mul(&global.states[b].a, &rf), Some(b))
                }
            }
        };
        let (p1, a1, b1) = frame_pose(&mut alg, cut.body1, &cut.frame1);
        let (p2, a2, b2) = frame_pose(&mut alg, cut.body2, &cut.frame2);
        let d = alg.sub(p2, p1);
        // Partial (δP, δθ) of a frame point w.r.t. coordinate i.
        let partial = |alg: &mut Alg, b: Option<usize>, p: V3, i: usize| -> Option<(V3, V3)> {
            let b = b?;
            if !global.chains[b].contains(&i) {
                return None;
            }
            let ax = global.axes[i].expect("coordinate axis set");
            Some(if ax.rotation {
                let dd = alg.sub(p, ax.p);
                (alg.cross(ax.u, dd), ax.u)
            } else {
                (ax.u, alg.v_zero())
            })
        };
        for comp in &cut.constrained {
            let mut grads = vec![alg.zero(); n];
            let g = match comp {
                Component::Tx | Component::Ty | Component::Tz => {
                    let k = match comp {
                        Component::Tx => 0,
                        Component::Ty => 1,
                        _ => 2,
                    };
                    let e = alg.column(&a1, k);
                    let ed = alg.cross(e, d);
                    for (i, gi) in grads.iter_mut().enumerate() {
                        let p1i = partial(&mut alg, b1, p1, i);
                        let p2i = partial(&mut alg, b2, p2, i);
                        let mut terms = Vec::new();
                        if let Some((dp2, _)) = p2i {
                            terms.push(alg.dot(dp2, e));
                        }
                        if let Some((dp1, dt1)) = p1i {
                            let x = alg.dot(dp1, e);
                            terms.push(alg.ctx.neg(x));
                            terms.push(alg.dot(dt1, ed));
                        }
                        *gi = alg.ctx.add_many(&terms);
                    }
                    alg.dot(d, e)
                }
                Component::Rx | Component::Ry | Component::Rz => {
                    let (k1, k2) = match comp {
                        Component::Rx => (1, 2),
                        Component::Ry => (2, 0),
                        _ => (0, 1),
                    };
                    let a_k2 = alg.column(&a1, k2);
                    let b_k1 = alg.column(&a2, k1);
                    let a_k1 = alg.column(&a1, k1);
                    let b_k2 = alg.column(&a2, k2);
                    let c1 = alg.cross(a_k2, b_k1);
                    let c2 = alg.cross(a_k1, b_k2);
                    let dc = alg.sub(c1, c2);
                    for (i, gi) in grads.iter_mut().enumerate() {
                        let mut dt = alg.v_zero();
                        if let Some((_, t1)) = partial(&mut alg, b1, p1, i) {
                            dt = alg.add(dt, t1);
                        }
                        if let Some((_, t2)) = partial(&mut alg, b2, p2, i) {
                            dt = alg.sub(dt, t2);
                        }
                        let x = alg.dot(dt, dc);
                        *gi = alg.ctx.scale(0.5, x);
                    }
                    let x = alg.dot(a_k2, b_k1);
                    let y = alg.dot(a_k1, b_k2);
                    let diff = alg.ctx.sub(x, y);
                    alg.ctx.scale(0.5, diff)
                }
            };
            constraints.push(g);
            for (i, gi) in grads.into_iter().enumerate() {
                if gi != zero {
                    cjac.push(((row, i), gi));
                }
            }
            row += 1;
        }
    }

    Derived {
        mass_index: mass_entries.iter().map(|(ix, _)| *ix).collect(),
        mass: mass_entries.into_iter().map(|(_, e)| e).collect(),
        bias,
        gravity: gravity_q,
        kinematics,
        jacobian_index: jac.iter().map(|(ix, _)| *ix).collect(),
        jacobians: jac.into_iter().map(|(_, e)| e).collect(),
        constraints,
        constraint_jacobian_index: cjac.iter().map(|(ix, _)| *ix).collect(),
        constraint_jacobian: cjac.into_iter().map(|(_, e)| e).collect(),
        dof: n,
        bodies: nb,
        inputs: 6 * model.track_frames.len(),
        ctx,
    }
}
