//! The numeric-iterative engine: evaluates the recursive kinematics and the
//! equations of motion of a [`Model`] at every call, with no code generation.
//!
//! Kinematics (seed paper Sect. 2.1): every joint is a chain of elementary
//! transformations; walking them from SC0 outwards gives each frame's position
//! r, direction cosines A, velocity v, angular velocity ω and the "bias"
//! accelerations a⁰, α⁰ (the accelerations at q̈ = 0). For a translation d = A e s
//! along the current axis e:
//!
//! ```text
//!   r' = r + d,  v' = v + ω×d + A e ṡ,  a⁰' = a⁰ + α⁰×d + ω×(ω×d) + 2 ω×(A e ṡ) + A e s̈
//! ```
//!
//! and for a rotation about u = A e:  A' = A R_e(s), ω' = ω + u ṡ,
//! α⁰' = α⁰ + ω×(u ṡ) + u s̈ — where s̈ is the prescribed acceleration of a
//! rheonomic transformation and zero for a generalized coordinate.
//!
//! The partial velocities of coordinate i (axis u through point p) are
//! (u×(r_j − p), u) for a rotation and (u, 0) for a translation; they form the
//! body Jacobians Γ_j. The mass matrix comes from the composite-body method
//! (O(n²)): M_ij = S_jᵀ (I^c_{sub(i)} S_i) for coordinate j on the path to i,
//! with all spatial quantities taken about points of the mechanism (never the
//! distant SC0 origin) so that a vehicle 10 km down the track loses no digits.
//! k and Q_g come from one backward accumulation of body wrenches (O(n)).

use crate::equations::{BodyKinematics, Equations, Evaluation, Parts};
use crate::system::SimError;
use nalgebra::{Matrix3, Vector3};
use railmbs_models::{
    Axis, BodyRef, Component, CutJoint, ElementaryKind, Expr, Frame, Model, Motion,
};

/// What drives one elementary transformation, resolved for fast evaluation.
#[derive(Debug, Clone)]
enum Source {
    /// A constant (evaluated from parameters by `set_parameters`).
    Fixed { expr: Expr, value: f64 },
    /// Generalized coordinate index.
    Coordinate(usize),
    /// A function of time with its first and second time derivatives.
    Time {
        value: Expr,
        rate: Expr,
        acceleration: Expr,
    },
}

#[derive(Debug, Clone)]
struct Op {
    rotation: bool,
    axis: usize,
    source: Source,
}

#[derive(Debug, Clone)]
struct BodyData {
    parent: Option<usize>,
    ops: Vec<Op>,
    mass_expr: Expr,
    inertia_expr: [Expr; 6],
    mass: f64,
    /// Inertia about the centre of mass in the body frame, kg m².
    inertia: Matrix3<f64>,
    /// Coordinates on the path from SC0 to this body (inclusive), in order.
    chain: Vec<usize>,
}

/// A fixed frame on a body, evaluated.
#[derive(Debug, Clone)]
struct FrameData {
    body: Option<usize>,
    origin_expr: [Expr; 3],
    rotation_expr: [Expr; 3],
    origin: Vector3<f64>,
    rotation: Matrix3<f64>,
}

#[derive(Debug, Clone)]
struct CutData {
    frames: [FrameData; 2],
    components: Vec<Component>,
}

/// Per-coordinate partial velocity, filled during the forward pass.
#[derive(Debug, Clone, Copy, Default)]
struct Axis6 {
    rotation: bool,
    /// Unit axis in SC0.
    u: Vector3<f64>,
    /// A point on a rotation axis (origin of the frame the rotation acts in), m.
    p: Vector3<f64>,
}

/// Per-body state of the forward pass.
#[derive(Debug, Clone, Copy, Default)]
struct FrameState {
    r: Vector3<f64>,
    a: Matrix3<f64>,
    v: Vector3<f64>,
    w: Vector3<f64>,
    acc0: Vector3<f64>,
    alpha0: Vector3<f64>,
}

/// The numeric-iterative engine of one model.
#[derive(Debug, Clone)]
pub struct NumericEquations {
    bodies: Vec<BodyData>,
    children: Vec<Vec<usize>>,
    coordinate_count: usize,
    parameter_count: usize,
    gravity_expr: [Expr; 3],
    gravity: Vector3<f64>,
    cuts: Vec<CutData>,
    constraint_count: usize,
    params: Vec<f64>,
    parameters_set: bool,
    // Work buffers.
    states: Vec<FrameState>,
    axes: Vec<Axis6>,
    inertia_global: Vec<Matrix3<f64>>,
}

/// Elementary rotation matrix about axis `k` by angle `s`.
pub fn elementary_rotation(axis: usize, s: f64) -> Matrix3<f64> {
    let (sn, c) = s.sin_cos();
    match axis {
        0 => Matrix3::new(1.0, 0.0, 0.0, 0.0, c, -sn, 0.0, sn, c),
        1 => Matrix3::new(c, 0.0, sn, 0.0, 1.0, 0.0, -sn, 0.0, c),
        _ => Matrix3::new(c, -sn, 0.0, sn, c, 0.0, 0.0, 0.0, 1.0),
    }
}

/// Rotation matrix of a fixed frame: rotations about x, then y, then z of the
/// moving frame.
pub fn xyz_rotation(angles: [f64; 3]) -> Matrix3<f64> {
    elementary_rotation(0, angles[0])
        * elementary_rotation(1, angles[1])
        * elementary_rotation(2, angles[2])
}

fn axis_index(a: Axis) -> usize {
    a.index()
}

fn body_option(r: BodyRef) -> Option<usize> {
    match r {
        BodyRef::Ground => None,
        BodyRef::Body(i) => Some(i),
    }
}

fn frame_data(body: BodyRef, frame: &Frame) -> FrameData {
    FrameData {
        body: body_option(body),
        origin_expr: frame.origin.clone(),
        rotation_expr: frame.rotation_xyz.clone(),
        origin: Vector3::zeros(),
        rotation: Matrix3::identity(),
    }
}

fn finite(value: f64, what: impl FnOnce() -> String) -> Result<f64, SimError> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(SimError::Other(format!(
            "parameter-dependent value is not finite: {}",
            what()
        )))
    }
}

impl NumericEquations {
    /// Prepares the engine for `model`. Call [`Equations::set_parameters`] before evaluating.
    pub fn new(model: &Model) -> Self {
        let n = model.coordinates.len();
        let mut bodies: Vec<BodyData> = Vec::with_capacity(model.bodies.len());
        let mut children = vec![Vec::new(); model.bodies.len()];
        for (j, b) in model.bodies.iter().enumerate() {
            let parent = body_option(b.parent);
            if let Some(p) = parent {
                children[p].push(j);
            }
            let mut chain = parent.map(|p| bodies[p].chain.clone()).unwrap_or_default();
            let ops = b
                .joint
                .iter()
                .map(|e| {
                    let (rotation, axis) = match e.kind {
                        ElementaryKind::Translation(a) => (false, axis_index(a)),
                        ElementaryKind::Rotation(a) => (true, axis_index(a)),
                    };
                    let source = match &e.motion {
                        Motion::Fixed(x) => Source::Fixed {
                            expr: x.clone(),
                            value: 0.0,
                        },
                        Motion::Coordinate(i) => {
                            chain.push(*i);
                            Source::Coordinate(*i)
                        }
                        Motion::Time(x) => {
                            let rate = x.time_derivative();
                            let acceleration = rate.time_derivative();
                            Source::Time {
                                value: x.clone(),
                                rate,
                                acceleration,
                            }
                        }
                    };
                    Op {
                        rotation,
                        axis,
                        source,
                    }
                })
                .collect();
            bodies.push(BodyData {
                parent,
                ops,
                mass_expr: b.mass.clone(),
                inertia_expr: b.inertia.clone(),
                mass: 0.0,
                inertia: Matrix3::zeros(),
                chain,
            });
        }
        let cuts: Vec<CutData> = model.cut_joints.iter().map(cut_data).collect();
        let constraint_count = cuts.iter().map(|c| c.components.len()).sum();
        let nb = bodies.len();
        Self {
            bodies,
            children,
            coordinate_count: n,
            parameter_count: model.parameters.len(),
            gravity_expr: model.gravity.clone(),
            gravity: Vector3::zeros(),
            cuts,
            constraint_count,
            params: Vec::new(),
            parameters_set: false,
            states: vec![FrameState::default(); nb],
            axes: vec![Axis6::default(); n],
            inertia_global: vec![Matrix3::zeros(); nb],
        }
    }

    /// Forward pass: kinematics of all frames and partial velocities.
    fn forward(&mut self, t: f64, q: &[f64], qd: &[f64]) {
        for j in 0..self.bodies.len() {
            let body = &self.bodies[j];
            let mut s = match body.parent {
                Some(p) => self.states[p],
                None => FrameState {
                    a: Matrix3::identity(),
                    ..FrameState::default()
                },
            };
            for op in &body.ops {
                let (val, rate, acc, coord) = match &op.source {
                    Source::Fixed { value, .. } => (*value, 0.0, 0.0, None),
                    Source::Coordinate(i) => (q[*i], qd[*i], 0.0, Some(*i)),
                    Source::Time {
                        value,
                        rate,
                        acceleration,
                    } => (
                        value.eval(&self.params, t),
                        rate.eval(&self.params, t),
                        acceleration.eval(&self.params, t),
                        None,
                    ),
                };
                let u = s.a.column(op.axis).into_owned();
                if let Some(i) = coord {
                    self.axes[i] = Axis6 {
                        rotation: op.rotation,
                        u,
                        p: s.r,
                    };
                }
                if op.rotation {
                    let w_rel = u * rate;
                    s.alpha0 += s.w.cross(&w_rel) + u * acc;
                    s.w += w_rel;
                    s.a *= elementary_rotation(op.axis, val);
                } else {
                    let d = u * val;
                    let v_rel = u * rate;
                    s.acc0 += s.alpha0.cross(&d)
                        + s.w.cross(&s.w.cross(&d))
                        + 2.0 * s.w.cross(&v_rel)
                        + u * acc;
                    s.v += s.w.cross(&d) + v_rel;
                    s.r += d;
                }
            }
            self.states[j] = s;
            self.inertia_global[j] = s.a * body.inertia * s.a.transpose();
        }
    }

    /// Partial velocity of body `j`'s centre of mass and its angular velocity
    /// with respect to coordinate `i` (which must be on the body's chain).
    fn partial(&self, i: usize, j: usize) -> (Vector3<f64>, Vector3<f64>) {
        let ax = &self.axes[i];
        if ax.rotation {
            (ax.u.cross(&(self.states[j].r - ax.p)), ax.u)
        } else {
            (ax.u, Vector3::zeros())
        }
    }

    /// Generalized force of a subtree wrench (force `f`, moment `n` about the
    /// subtree's reference point `c`) on coordinate `i`.
    fn project_wrench(&self, i: usize, f: &Vector3<f64>, n: &Vector3<f64>, c: &Vector3<f64>) -> f64 {
        let ax = &self.axes[i];
        if ax.rotation {
            ax.u.dot(&(n + (c - ax.p).cross(f)))
        } else {
            ax.u.dot(f)
        }
    }

    fn mass_matrix(&self, out: &mut Evaluation) {
        let nb = self.bodies.len();
        // Composite bodies: mass, centre of mass, inertia about it (SC0 axes).
        let mut cm = vec![0.0; nb];
        let mut cc = vec![Vector3::zeros(); nb];
        let mut ci = vec![Matrix3::zeros(); nb];
        for j in (0..nb).rev() {
            let mut m = self.bodies[j].mass;
            let mut first = Vector3::zeros(); // Σ m_k (c_k − r_j)
            let rj = self.states[j].r;
            for &c in &self.children[j] {
                m += cm[c];
                first += cm[c] * (cc[c] - rj);
            }
            let dc = if m > 0.0 { first / m } else { Vector3::zeros() };
            let center = rj + dc;
            // Parallel-axis theorem about the composite centre.
            let mut inertia = self.inertia_global[j] + steiner(self.bodies[j].mass, &(-dc));
            for &c in &self.children[j] {
                inertia += ci[c] + steiner(cm[c], &(cc[c] - rj - dc));
            }
            cm[j] = m;
            cc[j] = center;
            ci[j] = inertia;
        }
        let mass = &mut out.mass;
        for (b, body) in self.bodies.iter().enumerate() {
            // Coordinates of this body's own joint: the tail of its chain.
            let parent_len = body.parent.map_or(0, |p| self.bodies[p].chain.len());
            for (pos, &i) in body.chain.iter().enumerate().skip(parent_len) {
                let ax = &self.axes[i];
                // Momentum of the composite subtree moving with unit rate of q_i.
                let (lin, ang) = if ax.rotation {
                    (cm[b] * ax.u.cross(&(cc[b] - ax.p)), ci[b] * ax.u)
                } else {
                    (cm[b] * ax.u, Vector3::zeros())
                };
                for &k in &body.chain[..=pos] {
                    let value = self.project_wrench(k, &lin, &ang, &cc[b]);
                    mass[(i, k)] = value;
                    mass[(k, i)] = value;
                }
            }
        }
    }

    /// Backward accumulation of body wrenches `(f_j, n_j)` (about each centre of
    /// mass) and projection on the coordinates: returns Σ_j Γ_jᵀ (f_j, n_j).
    fn project_body_wrenches(
        &self,
        wrench: impl Fn(usize) -> (Vector3<f64>, Vector3<f64>),
        out: &mut nalgebra::DVector<f64>,
    ) {
        let nb = self.bodies.len();
        let mut f_sub = vec![Vector3::zeros(); nb];
        let mut n_sub = vec![Vector3::zeros(); nb];
        for j in (0..nb).rev() {
            let (mut f, mut n) = wrench(j);
            let rj = self.states[j].r;
            for &c in &self.children[j] {
                f += f_sub[c];
                n += n_sub[c] + (self.states[c].r - rj).cross(&f_sub[c]);
            }
            f_sub[j] = f;
            n_sub[j] = n;
        }
        for (b, body) in self.bodies.iter().enumerate() {
            let parent_len = body.parent.map_or(0, |p| self.bodies[p].chain.len());
            for &i in &body.chain[parent_len..] {
                out[i] = self.project_wrench(i, &f_sub[b], &n_sub[b], &self.states[b].r);
            }
        }
    }

    fn constraints(&self, out: &mut Evaluation) {
        let n = self.coordinate_count;
        let mut row = 0;
        for cut in &self.cuts {
            // Frame positions, axes, and per-coordinate partials of both frames.
            let pose = |f: &FrameData| -> (Vector3<f64>, Matrix3<f64>) {
                match f.body {
                    Some(b) => {
                        let s = &self.states[b];
                        (s.r + s.a * f.origin, s.a * f.rotation)
                    }
                    None => (f.origin, f.rotation),
                }
            };
            let (p1, a1) = pose(&cut.frames[0]);
            let (p2, a2) = pose(&cut.frames[1]);
            let d = p2 - p1;
            // Partial (δP, δθ) of a frame w.r.t. coordinate i.
            let partial = |f: &FrameData, p: &Vector3<f64>, i: usize| -> (Vector3<f64>, Vector3<f64>) {
                match f.body {
                    Some(b) if self.bodies[b].chain.contains(&i) => {
                        let ax = &self.axes[i];
                        if ax.rotation {
                            (ax.u.cross(&(p - ax.p)), ax.u)
                        } else {
                            (ax.u, Vector3::zeros())
                        }
                    }
                    _ => (Vector3::zeros(), Vector3::zeros()),
                }
            };
            for comp in &cut.components {
                let g;
                let mut grad = vec![0.0; n];
                match comp {
                    Component::Tx | Component::Ty | Component::Tz => {
                        let k = match comp {
                            Component::Tx => 0,
                            Component::Ty => 1,
                            _ => 2,
                        };
                        let e = a1.column(k).into_owned();
                        g = d.dot(&e);
                        // δg = (δP2 − δP1)·e + δθ1·(e × d)
                        for (i, gi) in grad.iter_mut().enumerate() {
                            let (dp1, dt1) = partial(&cut.frames[0], &p1, i);
                            let (dp2, _) = partial(&cut.frames[1], &p2, i);
                            *gi = (dp2 - dp1).dot(&e) + dt1.dot(&e.cross(&d));
                        }
                    }
                    Component::Rx | Component::Ry | Component::Rz => {
                        // g_x = (e_z1·e_y2 − e_y1·e_z2)/2 and cyclic.
                        let (k1, k2) = match comp {
                            Component::Rx => (1, 2),
                            Component::Ry => (2, 0),
                            _ => (0, 1),
                        };
                        let a_k2 = a1.column(k2).into_owned();
                        let b_k1 = a2.column(k1).into_owned();
                        let a_k1 = a1.column(k1).into_owned();
                        let b_k2 = a2.column(k2).into_owned();
                        g = 0.5 * (a_k2.dot(&b_k1) - a_k1.dot(&b_k2));
                        // δ(a·b) = (δθ1 − δθ2)·(a × b)
                        let c1 = a_k2.cross(&b_k1);
                        let c2 = a_k1.cross(&b_k2);
                        for (i, gi) in grad.iter_mut().enumerate() {
                            let (_, dt1) = partial(&cut.frames[0], &p1, i);
                            let (_, dt2) = partial(&cut.frames[1], &p2, i);
                            let dt = dt1 - dt2;
                            *gi = 0.5 * (dt.dot(&c1) - dt.dot(&c2));
                        }
                    }
                }
                out.constraints[row] = g;
                for (i, gi) in grad.iter().enumerate() {
                    out.constraint_jacobian[(row, i)] = *gi;
                }
                row += 1;
            }
        }
    }
}

fn cut_data(c: &CutJoint) -> CutData {
    CutData {
        frames: [frame_data(c.body1, &c.frame1), frame_data(c.body2, &c.frame2)],
        components: c.constrained.clone(),
    }
}

/// Parallel-axis term m(|d|² E − d dᵀ).
fn steiner(m: f64, d: &Vector3<f64>) -> Matrix3<f64> {
    m * (Matrix3::identity() * d.norm_squared() - d * d.transpose())
}

impl Equations for NumericEquations {
    fn engine_name(&self) -> &str {
        "numeric"
    }
    fn dof(&self) -> usize {
        self.coordinate_count
    }
    fn body_count(&self) -> usize {
        self.bodies.len()
    }
    fn constraint_count(&self) -> usize {
        self.constraint_count
    }
    fn parameter_count(&self) -> usize {
        self.parameter_count
    }

    fn set_parameters(&mut self, params: &[f64]) -> Result<(), SimError> {
        if params.len() != self.parameter_count {
            return Err(SimError::Other(format!(
                "expected {} parameter values, got {}",
                self.parameter_count,
                params.len()
            )));
        }
        self.params = params.to_vec();
        let p = &self.params;
        for (j, body) in self.bodies.iter_mut().enumerate() {
            body.mass = finite(body.mass_expr.eval(p, 0.0), || format!("mass of body #{j}"))?;
            let i: Vec<f64> = body.inertia_expr.iter().map(|e| e.eval(p, 0.0)).collect();
            for v in &i {
                finite(*v, || format!("inertia of body #{j}"))?;
            }
            body.inertia = Matrix3::new(i[0], i[3], i[4], i[3], i[1], i[5], i[4], i[5], i[2]);
            for op in &mut body.ops {
                if let Source::Fixed { expr, value } = &mut op.source {
                    *value = finite(expr.eval(p, 0.0), || format!("joint of body #{j}"))?;
                }
            }
        }
        for (k, g) in self.gravity_expr.iter().enumerate() {
            self.gravity[k] = finite(g.eval(p, 0.0), || "gravity".into())?;
        }
        for cut in &mut self.cuts {
            for f in &mut cut.frames {
                for k in 0..3 {
                    f.origin[k] = finite(f.origin_expr[k].eval(p, 0.0), || "cut joint frame".into())?;
                }
                let angles = [
                    f.rotation_expr[0].eval(p, 0.0),
                    f.rotation_expr[1].eval(p, 0.0),
                    f.rotation_expr[2].eval(p, 0.0),
                ];
                f.rotation = xyz_rotation(angles);
            }
        }
        self.parameters_set = true;
        Ok(())
    }

    fn evaluate(
        &mut self,
        t: f64,
        q: &[f64],
        v: &[f64],
        parts: Parts,
        out: &mut Evaluation,
    ) -> Result<(), SimError> {
        if !self.parameters_set {
            return Err(SimError::Other(
                "numeric engine evaluated before its parameters were set".into(),
            ));
        }
        let n = self.coordinate_count;
        if q.len() != n || v.len() != n {
            return Err(SimError::Other(format!(
                "state has {} coordinates and {} velocities, the model has {n}",
                q.len(),
                v.len()
            )));
        }
        self.forward(t, q, v);
        if parts.kinematics {
            for (j, s) in self.states.iter().enumerate() {
                out.bodies[j] = BodyKinematics {
                    position: s.r,
                    rotation: s.a,
                    velocity: s.v,
                    angular_velocity: s.w,
                };
            }
        }
        if parts.mass {
            self.mass_matrix(out);
        }
        if parts.bias {
            let mut bias = std::mem::take(&mut out.bias);
            self.project_body_wrenches(
                |j| {
                    let s = &self.states[j];
                    let i = &self.inertia_global[j];
                    (
                        self.bodies[j].mass * s.acc0,
                        i * s.alpha0 + s.w.cross(&(i * s.w)),
                    )
                },
                &mut bias,
            );
            out.bias = bias;
        }
        if parts.gravity {
            let mut gravity = std::mem::take(&mut out.gravity);
            self.project_body_wrenches(
                |j| (self.bodies[j].mass * self.gravity, Vector3::zeros()),
                &mut gravity,
            );
            out.gravity = gravity;
        }
        if parts.jacobians {
            out.jacobians.fill(0.0);
            for (j, body) in self.bodies.iter().enumerate() {
                for &i in &body.chain {
                    let (lin, ang) = self.partial(i, j);
                    for k in 0..3 {
                        out.jacobians[(6 * j + k, i)] = lin[k];
                        out.jacobians[(6 * j + 3 + k, i)] = ang[k];
                    }
                }
            }
        }
        if parts.constraints && self.constraint_count > 0 {
            self.constraints(out);
        }
        Ok(())
    }
}
