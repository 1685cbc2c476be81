//! Assembly of the approximate Jacobians ∂Q/∂q, ∂Q/∂q̇ of the generalized
//! applied forces from the force elements' local Jacobians (Pogorelov 2005,
//! Sect. 6, Eq. 31).

use nalgebra::{DMatrix, Matrix3, Matrix6, SMatrix, Vector3};

/// 12×12 matrix over the twists (v, ω) of two bodies (body 1 first).
pub type PairMatrix = SMatrix<f64, 12, 12>;

/// Scratch buffers of [`ForceJacobian`] (kept by the system between calls).
#[derive(Debug, Clone, Default)]
pub struct JacobianScratch {
    /// Per body, the columns where its Γ_j has non-zero entries.
    body_cols: Vec<Vec<usize>>,
    /// Columns of the current pair (union of its two bodies'), m of them.
    cols: Vec<usize>,
    /// Rows of the current relative-motion Jacobian H, row-major (rows × m).
    h: Vec<f64>,
    /// K·H (rows × m).
    kh: Vec<f64>,
}

impl JacobianScratch {
    /// Buffers for `n` generalized coordinates.
    pub fn new(n: usize) -> Self {
        Self {
            body_cols: Vec::new(),
            cols: Vec::with_capacity(n),
            h: Vec::with_capacity(6 * n),
            kh: Vec::with_capacity(6 * n),
        }
    }
}

/// Accumulates the approximate Jacobians of the generalized applied forces,
/// `dq` ≈ ∂Q/∂q and `dv` ≈ ∂Q/∂q̇, from the elements' local Jacobians.
///
/// An element whose force on body 2, f₂, depends on the relative position
/// d = P₂ − P₁ and velocity ḋ of its attachment points (body 1 gets −f₂)
/// contributes Q = Gᵀ f₂ with G = Γ_P₂ − Γ_P₁, where Γ_P = Γ_t + (Γ_r × ρ)
/// column by column (ρ from the centre of mass to the point, SC0) is the point
/// Jacobian. Hence ∂Q/∂q ≈ Gᵀ (∂f₂/∂d) G and ∂Q/∂q̇ ≈ Gᵀ (∂f₂/∂ḋ) G, the terms
/// with ∂Γ/∂q (proportional to the force itself) being neglected as in
/// Pogorelov 2005, Sect. 6. Only the columns where the two bodies' Jacobians are
/// non-zero (their coordinates and their ancestors') are visited.
pub struct ForceJacobian<'a> {
    gamma: &'a DMatrix<f64>,
    bodies: &'a [crate::equations::BodyKinematics],
    /// ≈ ∂Q/∂q, n × n (N/m, N m/rad…).
    pub dq: &'a mut DMatrix<f64>,
    /// ≈ ∂Q/∂q̇, n × n.
    pub dv: &'a mut DMatrix<f64>,
    scratch: &'a mut JacobianScratch,
}

impl<'a> ForceJacobian<'a> {
    /// `gamma`: the stacked body Jacobians Γ_j (rows 6j..6j+3 the velocity of
    /// the centre of mass, 6j+3..6j+6 the angular velocity, SC0); `bodies` the
    /// kinematics at the same state. `dq`, `dv` are added to, not cleared.
    pub fn new(
        gamma: &'a DMatrix<f64>,
        bodies: &'a [crate::equations::BodyKinematics],
        dq: &'a mut DMatrix<f64>,
        dv: &'a mut DMatrix<f64>,
        scratch: &'a mut JacobianScratch,
    ) -> Self {
        let nb = gamma.nrows() / 6;
        scratch.body_cols.resize_with(nb, Vec::new);
        for (j, cols) in scratch.body_cols.iter_mut().enumerate() {
            cols.clear();
            for i in 0..gamma.ncols() {
                if (0..6).any(|r| gamma[(6 * j + r, i)] != 0.0) {
                    cols.push(i);
                }
            }
        }
        Self {
            gamma,
            bodies,
            dq,
            dv,
            scratch,
        }
    }

    /// Starts a pair: the union of the bodies' columns, H zeroed (`rows` rows).
    fn begin(&mut self, body1: Option<usize>, body2: Option<usize>, rows: usize) {
        let s = &mut *self.scratch;
        s.cols.clear();
        let empty: &[usize] = &[];
        let a = body1.map_or(empty, |b| &s.body_cols[b]);
        let b = body2.map_or(empty, |b| &s.body_cols[b]);
        // Merge two sorted lists.
        let (mut i, mut k) = (0, 0);
        while i < a.len() || k < b.len() {
            let next = match (a.get(i), b.get(k)) {
                (Some(&x), Some(&y)) if x == y => {
                    i += 1;
                    k += 1;
                    x
                }
                (Some(&x), Some(&y)) if x < y => {
                    i += 1;
                    x
                }
                (Some(_), Some(&y)) => {
                    k += 1;
                    y
                }
                (Some(&x), None) => {
                    i += 1;
                    x
                }
                (None, Some(&y)) => {
                    k += 1;
                    y
                }
                (None, None) => break,
            };
            s.cols.push(next);
        }
        s.h.clear();
        s.h.resize(rows * s.cols.len(), 0.0);
    }

    /// Adds `sign`·Γ_P of the point `p` (SC0) of `body` to rows row0..row0+3 of H.
    fn point_rows(&mut self, row0: usize, body: Option<usize>, p: &Vector3<f64>, sign: f64) {
        let Some(b) = body else { return };
        let rho = p - self.bodies[b].position;
        let g = self.gamma;
        let s = &mut *self.scratch;
        let m = s.cols.len();
        for (ci, &i) in s.cols.iter().enumerate() {
            let w = Vector3::new(g[(6 * b + 3, i)], g[(6 * b + 4, i)], g[(6 * b + 5, i)]);
            let v = Vector3::new(g[(6 * b, i)], g[(6 * b + 1, i)], g[(6 * b + 2, i)]);
            let c = v + w.cross(&rho);
            for k in 0..3 {
                s.h[(row0 + k) * m + ci] += sign * c[k];
            }
        }
    }

    /// Starts a point pair: H = G = Γ_P₂ − Γ_P₁ (3 rows) for the point `p1`
    /// (SC0) of `body1` and `p2` of `body2`; false (nothing started) when both
    /// are ground.
    fn begin_point_pair(
        &mut self,
        body1: Option<usize>,
        p1: &Vector3<f64>,
        body2: Option<usize>,
        p2: &Vector3<f64>,
    ) -> bool {
        if body1.is_none() && body2.is_none() {
            return false;
        }
        self.begin(body1, body2, 3);
        self.point_rows(0, body2, p2, 1.0);
        self.point_rows(0, body1, p1, -1.0);
        true
    }

    /// Adds `sign`·Γ_r of `body` to rows row0..row0+3 of H.
    fn rotation_rows(&mut self, row0: usize, body: Option<usize>, sign: f64) {
        let Some(b) = body else { return };
        let s = &mut *self.scratch;
        let m = s.cols.len();
        for (ci, &i) in s.cols.iter().enumerate() {
            for k in 0..3 {
                s.h[(row0 + k) * m + ci] += sign * self.gamma[(6 * b + 3 + k, i)];
            }
        }
    }

    /// Adds Hᵀ kq H to `dq` and Hᵀ kv H to `dv` (kq, kv given as closures
    /// over (row, col) of the rows × rows matrices).
    fn project(
        &mut self,
        rows: usize,
        kq: impl Fn(usize, usize) -> f64,
        kv: impl Fn(usize, usize) -> f64,
    ) {
        let s = &mut *self.scratch;
        let m = s.cols.len();
        s.kh.clear();
        s.kh.resize(rows * m, 0.0);
        for (pass, out) in [(0, &mut *self.dq), (1, &mut *self.dv)] {
            let k = |r: usize, c: usize| if pass == 0 { kq(r, c) } else { kv(r, c) };
            let mut any = false;
            for r in 0..rows {
                for ci in 0..m {
                    let mut acc = 0.0;
                    for l in 0..rows {
                        acc += k(r, l) * s.h[l * m + ci];
                    }
                    s.kh[r * m + ci] = acc;
                    any |= acc != 0.0;
                }
            }
            if !any {
                continue;
            }
            for (ai, &a) in s.cols.iter().enumerate() {
                for (bi, &b) in s.cols.iter().enumerate() {
                    let mut acc = 0.0;
                    for r in 0..rows {
                        acc += s.h[r * m + ai] * s.kh[r * m + bi];
                    }
                    out[(a, b)] += acc;
                }
            }
        }
    }

    /// A force f₂ on `body2` at `p2` and −f₂ on `body1` at `p1` (points in
    /// SC0) depending on d = P₂ − P₁ and ḋ: adds Gᵀ kq G and Gᵀ kv G with
    /// kq = ∂f₂/∂d (N/m) and kv = ∂f₂/∂ḋ (N s/m).
    pub fn add_point_pair(
        &mut self,
        body1: Option<usize>,
        p1: &Vector3<f64>,
        body2: Option<usize>,
        p2: &Vector3<f64>,
        kq: &Matrix3<f64>,
        kv: &Matrix3<f64>,
    ) {
        if !self.begin_point_pair(body1, p1, body2, p2) {
            return;
        }
        self.project(3, |r, c| kq[(r, c)], |r, c| kv[(r, c)]);
    }

    /// Adds Hᵀ kq H and Hᵀ kv H with H = [Γ₁; Γ₂] (12 × n), the stacked body
    /// Jacobians of `body1` and `body2` (a ground side contributes zero rows):
    /// for elements that sum many point contributions between the same two
    /// bodies in twist coordinates first ([`point_twist_map`]).
    pub fn add_body_pair(
        &mut self,
        body1: Option<usize>,
        body2: Option<usize>,
        kq: &PairMatrix,
        kv: &PairMatrix,
    ) {
        if body1.is_none() && body2.is_none() {
            return;
        }
        self.begin(body1, body2, 12);
        let s = &mut *self.scratch;
        let m = s.cols.len();
        for (row0, body) in [(0, body1), (6, body2)] {
            let Some(b) = body else { continue };
            for (ci, &i) in s.cols.iter().enumerate() {
                for k in 0..6 {
                    s.h[(row0 + k) * m + ci] = self.gamma[(6 * b + k, i)];
                }
            }
        }
        self.project(12, |r, c| kq[(r, c)], |r, c| kv[(r, c)]);
    }

    /// The coupling of an element's first-order state with index `k` in the
    /// full coordinate vector to the relative position d = P₂ − P₁ of two
    /// points, with G = Γ_P₂ − Γ_P₁ (3 × n): adds Gᵀ`dq_column` to column k of
    /// `dq` (the force f₂ on P₂ depends on the state: `dq_column` = ∂f₂/∂z),
    /// `dq_row`ᵀG to row k of `dq` and `dv_row`ᵀG to row k of `dv` (the state
    /// residual depends on d and ḋ: `dq_row` = ∂r/∂d, `dv_row` = ∂r/∂ḋ).
    #[allow(clippy::too_many_arguments)]
    pub fn add_pair_state(
        &mut self,
        body1: Option<usize>,
        p1: &Vector3<f64>,
        body2: Option<usize>,
        p2: &Vector3<f64>,
        k: usize,
        dq_column: &Vector3<f64>,
        dq_row: &Vector3<f64>,
        dv_row: &Vector3<f64>,
    ) {
        if !self.begin_point_pair(body1, p1, body2, p2) {
            return;
        }
        let s = &*self.scratch;
        let m = s.cols.len();
        for (ci, &i) in s.cols.iter().enumerate() {
            let g = |u: &Vector3<f64>| (0..3).map(|r| u[r] * s.h[r * m + ci]).sum::<f64>();
            self.dq[(i, k)] += g(dq_column);
            self.dq[(k, i)] += g(dq_row);
            self.dv[(k, i)] += g(dv_row);
        }
    }

    /// Position of body `b`'s centre of mass (SC0), m.
    pub fn body_position(&self, b: usize) -> Vector3<f64> {
        self.bodies[b].position
    }

    /// A wrench w = (force, moment) expressed in a frame with direction cosines
    /// `a1` (SC0), acting on `body2` at the point `p` (SC0), and −w on `body1`
    /// at the same point, depending on the relative displacement δ and rate δ̇
    /// of body 2 with respect to body 1 (translation of the point and small
    /// rotation, in the same frame): adds Hᵀ kq H and Hᵀ kv H with
    /// H = diag(a1ᵀ, a1ᵀ)·[Γ_P⁽²⁾ − Γ_P⁽¹⁾; Γ_r⁽²⁾ − Γ_r⁽¹⁾], kq = ∂w/∂δ, kv = ∂w/∂δ̇.
    pub fn add_frame_pair(
        &mut self,
        body1: Option<usize>,
        body2: Option<usize>,
        p: &Vector3<f64>,
        a1: &Matrix3<f64>,
        kq: &Matrix6<f64>,
        kv: &Matrix6<f64>,
    ) {
        if body1.is_none() && body2.is_none() {
            return;
        }
        self.begin(body1, body2, 6);
        self.point_rows(0, body2, p, 1.0);
        self.point_rows(0, body1, p, -1.0);
        self.rotation_rows(3, body2, 1.0);
        self.rotation_rows(3, body1, -1.0);
        // Rotate the rows into the frame: H ← diag(a1ᵀ, a1ᵀ) H.
        let at = a1.transpose();
        let s = &mut *self.scratch;
        let m = s.cols.len();
        for ci in 0..m {
            for blk in [0, 3] {
                let x = Vector3::new(
                    s.h[blk * m + ci],
                    s.h[(blk + 1) * m + ci],
                    s.h[(blk + 2) * m + ci],
                );
                let y = at * x;
                for k in 0..3 {
                    s.h[(blk + k) * m + ci] = y[k];
                }
            }
        }
        self.project(6, |r, c| kq[(r, c)], |r, c| kv[(r, c)]);
    }
}

/// S = [E, −(ρ×)] (3 × 6): the velocity of a point at ρ from a body's centre
/// of mass from the body's twist (v, ω), v_P = v + ω × ρ.
pub fn point_twist_map(rho: &Vector3<f64>) -> SMatrix<f64, 3, 6> {
    let mut s = SMatrix::<f64, 3, 6>::zeros();
    s.fixed_view_mut::<3, 3>(0, 0)
        .copy_from(&Matrix3::identity());
    s.fixed_view_mut::<3, 3>(0, 3)
        .copy_from(&(-rho.cross_matrix()));
    s
}
