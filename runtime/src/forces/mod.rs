//! Force elements (seed paper Sect. 3). Each element computes the wrenches it
//! applies to bodies from their kinematics; the system projects them on the
//! generalized coordinates with the body Jacobians (Q = Σ Γ_jᵀ F_j).
//!
//! Adding an element: write its model syntax and spec in
//! `railmbs_models::forces`, its module here with a type implementing
//! [`ForceElement`] built from that spec, and add one arm to [`build`].

mod applied;
mod bipolar;
pub mod contact;
mod linear6;
pub mod nonlinear;
mod series;
pub mod sliding_mean;
pub mod torsion;
pub mod wheel_rail;

pub use applied::AppliedForce;
pub use bipolar::LinearBipolar;
pub use contact::{PointPlane, contact_stiffness_damping};
pub use linear6::Linear6;
pub use nonlinear::{Characteristic, CoulombFriction, LoadFriction, Tabulated};
pub use series::SeriesSpringDamper;
pub use wheel_rail::{TrackBinding, WheelRailContact};

use crate::equations::BodyKinematics;
use crate::system::SimError;
use nalgebra::{DMatrix, Matrix3, Matrix6, SMatrix, Vector3};

/// 12×12 matrix over the twists (v, ω) of two bodies (body 1 first).
pub type PairMatrix = SMatrix<f64, 12, 12>;
use railmbs_models::{BodyRef, Expr, ForceKind, Frame, Model};

/// Force (N) and moment about the centre of mass (N m) on one body, in SC0.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct Wrench {
    pub force: Vector3<f64>,
    pub moment: Vector3<f64>,
}

/// One row of the end-of-run assessment table: the largest value of a
/// quantity over the run, when it occurred, and its limit if there is one.
#[derive(Debug, Clone, PartialEq)]
pub struct Assessment {
    /// Long name of the element.
    pub element: String,
    /// What is measured (e.g. `Y/Q left`).
    pub quantity: String,
    /// Largest value over the accepted steps.
    pub max: f64,
    /// Time of the largest value, s.
    pub time: f64,
    /// The limit it is judged against, same unit.
    pub limit: Option<f64>,
    /// Name of the limit (e.g. `Nadal`).
    pub limit_name: &'static str,
    /// Unit of `max` and `limit`.
    pub unit: &'static str,
}

/// What a force element sees: time, body kinematics (model order), parameters,
/// and the first-order state variables of all elements with their rates.
#[derive(Debug, Clone, Copy)]
pub struct ForceContext<'a> {
    /// s.
    pub t: f64,
    pub bodies: &'a [BodyKinematics],
    pub params: &'a [f64],
    /// First-order element states z of the whole system (see
    /// [`ForceElement::state_count`]); each element reads its own slice.
    pub states: &'a [f64],
    /// Their rates ż, same layout.
    pub state_rates: &'a [f64],
}

/// A force element of the runtime.
pub trait ForceElement: std::fmt::Debug + Send {
    /// Long name (as in the model).
    fn name(&self) -> &str;
    /// Re-evaluates parameter-dependent constants.
    fn set_parameters(&mut self, params: &[f64]) -> Result<(), SimError>;
    /// Adds the element's wrenches to `wrenches` (one per body; forces on the
    /// ground are dropped).
    fn apply(&self, ctx: &ForceContext, wrenches: &mut [Wrench]) -> Result<(), SimError>;
    /// Names of the element's output variables, without the element's name
    /// (e.g. `F`, `x`); the writer prefixes `<element>.`. Units in brackets.
    fn output_names(&self) -> Vec<String>;
    /// Values of the outputs, appended to `out`, same order as the names.
    fn outputs(&self, ctx: &ForceContext, out: &mut Vec<f64>);
    /// Called once per accepted step (elements with state update here only).
    fn accept_step(&mut self, _ctx: &ForceContext) {}
    /// Connects the element to the scenario's track (wheel–rail contact);
    /// elements that do not need the track ignore it.
    fn bind_track(&mut self, _binding: &TrackBinding) -> Result<(), SimError> {
        Ok(())
    }
    /// Whether the element cannot work without a track (see
    /// [`ForceElement::bind_track`]).
    fn needs_track(&self) -> bool {
        false
    }
    /// Safety and loading maxima over the accepted steps so far, for the
    /// end-of-run summary.
    fn assessment(&self) -> Vec<Assessment> {
        Vec::new()
    }
    /// Number of first-order state variables the element adds to the system
    /// (a spring in series with a damper: its spring extension). They are
    /// appended to the generalized coordinates with zero mass-matrix rows; the
    /// element's state equations r(q, q̇, z, ż) = 0 take those rows of the
    /// force vector, so an implicit integrator solves them together with the
    /// equations of motion (Park's method treats them with the same
    /// derivative formula as q).
    fn state_count(&self) -> usize {
        0
    }
    /// Names of the states (without the element's name), units in brackets.
    fn state_names(&self) -> Vec<String> {
        Vec::new()
    }
    /// Tells the element where its states start in [`ForceContext::states`].
    fn set_state_offset(&mut self, _offset: usize) {}
    /// Initial states and rates consistent with the state equations at the
    /// initial kinematics, written to the element's own slices (`z`, `zdot`
    /// have `state_count` entries).
    fn initial_states(&self, _ctx: &ForceContext, _z: &mut [f64], _zdot: &mut [f64]) {}
    /// Residuals of the element's state equations (in force units, so that
    /// the rows scale like the equations of motion), `state_count` entries.
    fn state_residuals(&self, _ctx: &ForceContext, _out: &mut [f64]) {}
    /// Adds the element's approximate contribution to ∂Q/∂q and ∂Q/∂q̇ (paper
    /// Sect. 6, Eq. 31): its local stiffness and damping matrices mapped by the
    /// Jacobians of its attachment points, neglecting the derivatives of the
    /// body Jacobians Γ themselves. Uses the element's current state (mode,
    /// anchors) like [`ForceElement::apply`].
    fn add_jacobian(&self, ctx: &ForceContext, jac: &mut ForceJacobian) -> Result<(), SimError>;
}

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
/// with ∂Γ/∂q (proportional to the force itself) being neglected as in the
/// seed paper, Sect. 6. Only the columns where the two bodies' Jacobians are
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

/// Builds the runtime force elements of a model: the registry, one line per
/// element, each built from its own model spec.
pub fn build(model: &Model) -> Vec<Box<dyn ForceElement>> {
    model
        .forces
        .iter()
        .map(|f| -> Box<dyn ForceElement> {
            let name = f.name.clone();
            match &f.kind {
                ForceKind::Bipolar(spec) => Box::new(LinearBipolar::new(name, spec)),
                ForceKind::SeriesSpringDamper(spec) => {
                    Box::new(SeriesSpringDamper::new(name, spec))
                }
                ForceKind::Linear6(spec) => Box::new(Linear6::new(name, spec)),
                ForceKind::PointPlane(spec) => Box::new(PointPlane::new(name, spec)),
                ForceKind::Coulomb(spec) => Box::new(CoulombFriction::new(name, spec)),
                ForceKind::LoadFriction(spec) => Box::new(LoadFriction::new(name, spec)),
                ForceKind::Tabulated(spec) => Box::new(Tabulated::new(name, spec)),
                ForceKind::WheelRail(spec) => Box::new(WheelRailContact::new(name, spec)),
                ForceKind::Applied(spec) => Box::new(AppliedForce::new(name, spec)),
                ForceKind::TorsionSpring(spec) => Box::new(torsion::TorsionSpring::new(name, spec)),
            }
        })
        .collect()
}

/// A point fixed to a body (or to SC0), with its parameter expressions.
#[derive(Debug, Clone)]
pub(crate) struct Attachment {
    pub body: Option<usize>,
    expr: [Expr; 3],
    /// Body coordinates (or SC0 for the ground), m.
    pub local: Vector3<f64>,
}

impl Attachment {
    pub fn new(body: BodyRef, point: &[Expr; 3]) -> Self {
        Self {
            body: match body {
                BodyRef::Ground => None,
                BodyRef::Body(i) => Some(i),
            },
            expr: point.clone(),
            local: Vector3::zeros(),
        }
    }
    pub fn set_parameters(&mut self, params: &[f64], owner: &str) -> Result<(), SimError> {
        self.local = eval_vector(&self.expr, params, 0.0, owner)?;
        Ok(())
    }
    /// Position in SC0, m.
    pub fn position(&self, ctx: &ForceContext) -> Vector3<f64> {
        match self.body {
            Some(b) => ctx.bodies[b].point_position(&self.local),
            None => self.local,
        }
    }
    /// Velocity in SC0, m/s.
    pub fn velocity(&self, ctx: &ForceContext) -> Vector3<f64> {
        match self.body {
            Some(b) => ctx.bodies[b].point_velocity(&self.local),
            None => Vector3::zeros(),
        }
    }
}

/// A frame fixed to a body (or SC0): an attachment point plus an orientation.
#[derive(Debug, Clone)]
pub(crate) struct FrameAttachment {
    pub point: Attachment,
    angles: [Expr; 3],
    /// Orientation relative to the body frame.
    pub rotation: Matrix3<f64>,
}

impl FrameAttachment {
    pub fn new(body: BodyRef, frame: &Frame) -> Self {
        Self {
            point: Attachment::new(body, &frame.origin),
            angles: frame.rotation_xyz.clone(),
            rotation: Matrix3::identity(),
        }
    }
    pub fn set_parameters(&mut self, params: &[f64], owner: &str) -> Result<(), SimError> {
        self.point.set_parameters(params, owner)?;
        let a = eval_vector(&self.angles, params, 0.0, owner)?;
        self.rotation = crate::numeric::xyz_rotation([a[0], a[1], a[2]]);
        Ok(())
    }
    /// Direction cosines of the frame in SC0 and its angular velocity.
    pub fn orientation(&self, ctx: &ForceContext) -> (Matrix3<f64>, Vector3<f64>) {
        match self.point.body {
            Some(b) => (
                ctx.bodies[b].rotation * self.rotation,
                ctx.bodies[b].angular_velocity,
            ),
            None => (self.rotation, Vector3::zeros()),
        }
    }
}

/// Evaluates three expressions, refusing non-finite results.
pub(crate) fn eval_vector(
    e: &[Expr; 3],
    params: &[f64],
    t: f64,
    owner: &str,
) -> Result<Vector3<f64>, SimError> {
    let v = Vector3::new(
        e[0].eval(params, t),
        e[1].eval(params, t),
        e[2].eval(params, t),
    );
    if v.iter().all(|x| x.is_finite()) {
        Ok(v)
    } else {
        Err(SimError::NonFinite {
            t,
            what: format!("force element \"{owner}\": a vector component is not finite: {v:?}"),
        })
    }
}

/// Evaluates one parameter expression, refusing non-finite results.
pub(crate) fn eval_scalar(
    e: &Expr,
    params: &[f64],
    owner: &str,
    field: &str,
) -> Result<f64, SimError> {
    let v = e.eval(params, 0.0);
    if v.is_finite() {
        Ok(v)
    } else {
        Err(SimError::Other(format!(
            "force element \"{owner}\": {field} is not finite ({v})"
        )))
    }
}

/// Adds the generalized force Γ_bᵀ w of the wrench `w` on body `b` to `out`:
/// `gamma` holds the stacked body Jacobians (rows 6b..6b+6 of body b, one
/// column per coordinate); entries of `out` beyond its columns (first-order
/// element states) take nothing.
pub(crate) fn add_generalized_force(gamma: &DMatrix<f64>, b: usize, w: &Wrench, out: &mut [f64]) {
    let comps = [
        w.force.x, w.force.y, w.force.z, w.moment.x, w.moment.y, w.moment.z,
    ];
    if comps.iter().all(|c| *c == 0.0) {
        return;
    }
    for (i, qi) in out.iter_mut().take(gamma.ncols()).enumerate() {
        let mut s = 0.0;
        for (k, c) in comps.iter().enumerate() {
            s += gamma[(6 * b + k, i)] * c;
        }
        *qi += s;
    }
}

/// Adds force `f` acting at the SC0 point `p` to the wrench of `body`.
pub(crate) fn add_force(
    wrenches: &mut [Wrench],
    ctx: &ForceContext,
    body: Option<usize>,
    p: &Vector3<f64>,
    f: &Vector3<f64>,
) {
    if let Some(b) = body {
        let w = &mut wrenches[b];
        w.force += f;
        w.moment += (p - ctx.bodies[b].position).cross(f);
    }
}

/// Adds a pure moment to the wrench of `body`.
pub(crate) fn add_moment(wrenches: &mut [Wrench], body: Option<usize>, m: &Vector3<f64>) {
    if let Some(b) = body {
        wrenches[b].moment += m;
    }
}
