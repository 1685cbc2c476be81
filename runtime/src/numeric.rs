//! The numeric-iterative engine: evaluates the recursive kinematics and the
//! equations of motion of a [`Model`] at every call, with no code generation.
//!
//! Kinematics (Pogorelov 2005, Sect. 2.1): every joint is a chain of elementary
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
//!
//! Performance: the joint transformations are compiled by `set_parameters`
//! into a flat list of steps (zero fixed transformations dropped, consecutive
//! fixed translations or rotations merged, elementary rotations applied to two
//! columns of A only); all work buffers live in the struct, so an evaluation
//! never allocates. M_ik is the scalar product of coordinate k's motion vector
//! (u_k, (p_k − o) × u_k) with the spatial momentum of body i's composite
//! subtree about the tree's root point o (two 3-vector dot products per entry).
//!
//! Formalisms ([`Formalism`]; Pogorelov 2005, Sect. 2.2 names the direct,
//! composite-body and articulated-body methods): the default composite-body
//! path forms M as above and leaves the solve M q̈ = Q − k to the integrator
//! (dense Cholesky, O(n³)). The articulated-body formalism (open trees only)
//! additionally solves M x = b in O(n) without forming M
//! ([`Equations::solve_mass`]) by the articulated-body recursion of
//! Featherstone (Rigid Body Dynamics Algorithms, 2008, Sect. 7.3) written in
//! absolute coordinates: spatial vectors in SC0 axes about each tree's root
//! point o, one scalar node per generalized coordinate (a body with several
//! coordinates is a chain of massless nodes ending in the body's inertia), so
//! no coordinate transforms between links are needed. The velocity-product
//! terms of the ABA are not repeated inside the recursion: k comes from the
//! engine's O(n) Newton–Euler pass above, and the recursion is run on
//! τ = Q − k with zero velocity terms, which gives q̈ = M⁻¹(Q − k) exactly as
//! the full ABA does (its passes 2 and 3 are linear in τ − k).

use crate::equations::{BodyKinematics, Equations, Evaluation, Parts};
use crate::system::SimError;
use nalgebra::{DMatrix, DVector, Matrix3, Matrix6, Vector3, Vector6};
use railmbs_models::{
    Axis, BodyRef, Component, CutJoint, ElementaryKind, Expr, Frame, Model, Motion,
};

/// What drives one elementary transformation, as read from the model.
#[derive(Debug, Clone)]
enum Source {
    /// A constant (evaluated from parameters by `set_parameters`).
    Fixed(Expr),
    /// Generalized coordinate index.
    Coordinate(usize),
    /// A function of time: index into `NumericEquations::time_motions`.
    Time(usize),
    /// Runtime input k (value, rate, acceleration in `NumericEquations::inputs[3k..]`).
    Input(usize),
}

#[derive(Debug, Clone)]
struct Op {
    rotation: bool,
    axis: usize,
    source: Source,
}

/// A rheonomic transformation s(t) with its first and second time derivatives.
#[derive(Debug, Clone)]
struct TimeMotion {
    value: Expr,
    rate: Expr,
    acceleration: Expr,
}

/// One compiled step of the forward pass (built by `set_parameters`).
#[derive(Debug, Clone, Copy)]
enum Step {
    /// Fixed translation by `value` (m) along axis `axis` of the current frame.
    AxisShift { axis: usize, value: f64 },
    /// Fixed translation by `d` (m), given in the current frame (consecutive
    /// fixed translations merged).
    Shift { d: Vector3<f64> },
    /// Fixed rotation A' = A R (consecutive fixed rotations merged).
    Turn { r: Matrix3<f64> },
    /// Rotation about axis `axis` of the current frame by coordinate `coord`.
    CoordRotation { axis: usize, coord: usize },
    /// Translation along axis `axis` of the current frame by coordinate `coord`.
    CoordTranslation { axis: usize, coord: usize },
    /// Rheonomic rotation or translation (`NumericEquations::time_motions[motion]`).
    Time {
        rotation: bool,
        axis: usize,
        motion: usize,
    },
    /// Rotation or translation driven by runtime input `input`.
    Input {
        rotation: bool,
        axis: usize,
        input: usize,
    },
}

#[derive(Debug, Clone)]
struct BodyData {
    parent: Option<usize>,
    /// First body of this body's tree (the one whose parent is SC0).
    root: usize,
    ops: Vec<Op>,
    mass_expr: Expr,
    inertia_expr: [Expr; 6],
    mass: f64,
    /// Inertia about the centre of mass in the body frame, kg m².
    inertia: Matrix3<f64>,
    /// Principal moments (ixx, iyy, izz) when the products of inertia are
    /// zero (the usual case), for a cheaper A I Aᵀ.
    principal: Option<Vector3<f64>>,
    /// Coordinates on the path from SC0 to this body (inclusive), in order.
    chain: Vec<usize>,
    /// Where this body's own coordinates start in `chain`.
    own_start: usize,
    /// Range of this body's compiled steps in `NumericEquations::steps`.
    steps: (usize, usize),
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

/// How the numeric engine obtains q̈ (Pogorelov 2005, Sect. 2.2).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Formalism {
    /// Composite-body method: M (O(n²)) for the integrator's Cholesky solve.
    /// The default, and the only one for closed loops and Park's method.
    #[default]
    CompositeBody,
    /// Articulated-body method (Featherstone 2008, Sect. 7.3): M x = b solved
    /// in O(n) without M ([`Equations::solve_mass`]); open trees only. M is
    /// still computed (by composite bodies) whenever it is asked for.
    ArticulatedBody,
}

impl Formalism {
    /// Coordinates from which the articulated-body q̈ beats composite-body M
    /// plus its Cholesky solve: on planar chains (`cargo bench -p
    /// railmbs-runtime --bench formalisms`, one run each, opt-level 1) ABA
    /// took 19.2 against 23.4 µs at 40 links and 66.6 against 96.7 µs at
    /// 100 (an earlier session: 29.3 against 31.4 µs at 40), at 30 links
    /// the two were within the machine's noise of each other across runs.
    pub const ARTICULATED_BODY_FROM: usize = 40;

    /// The faster formalism for explicit integration (RK4 needs q̈ only,
    /// never M): articulated-body for open trees (no cut joints) of at least
    /// [`Formalism::ARTICULATED_BODY_FROM`] coordinates, composite-body
    /// otherwise. Both give q̈ to rounding (tests/aba.rs); implicit
    /// integration and the analyses need M and use composite bodies.
    pub fn for_explicit_integration(model: &Model) -> Formalism {
        if model.cut_joints.is_empty() && model.coordinates.len() >= Self::ARTICULATED_BODY_FROM {
            Formalism::ArticulatedBody
        } else {
            Formalism::CompositeBody
        }
    }
}

/// The numeric-iterative engine of one model.
#[derive(Debug, Clone)]
pub struct NumericEquations {
    formalism: Formalism,
    /// Body names (for messages).
    body_names: Vec<String>,
    /// Whether the last forward pass filled `inertia_global` and `axes`
    /// (what [`Equations::solve_mass`] works on).
    inertia_current: bool,
    /// Articulated-body work buffers: per body the articulated inertia (6×6,
    /// spatial, about the tree's root point, SC0 axes) and bias force it
    /// passes to its parent, and its spatial acceleration; per coordinate
    /// U = I^A s, D = sᵀ U and u = τ − sᵀ p^A (Featherstone 2008, Sect. 7.3).
    art_inertia: Vec<Matrix6<f64>>,
    art_bias: Vec<Vector6<f64>>,
    art_acc: Vec<Vector6<f64>>,
    node_u: Vec<Vector6<f64>>,
    node_d: Vec<f64>,
    node_tau: Vec<f64>,
    bodies: Vec<BodyData>,
    children: Vec<Vec<usize>>,
    coordinate_count: usize,
    /// Body whose joint holds each coordinate.
    coordinate_body: Vec<usize>,
    parameter_count: usize,
    gravity_expr: [Expr; 3],
    gravity: Vector3<f64>,
    cuts: Vec<CutData>,
    constraint_count: usize,
    time_motions: Vec<TimeMotion>,
    /// Runtime inputs: value, rate, acceleration of each (m or rad, per s, per s²).
    inputs: Vec<f64>,
    steps: Vec<Step>,
    params: Vec<f64>,
    parameters_set: bool,
    // Work buffers, sized once by `new`.
    states: Vec<FrameState>,
    axes: Vec<Axis6>,
    inertia_global: Vec<Matrix3<f64>>,
    /// Composite bodies: mass (kg), centre of mass (m), inertia about it (kg m², SC0 axes).
    composite_mass: Vec<f64>,
    composite_center: Vec<Vector3<f64>>,
    composite_inertia: Vec<Matrix3<f64>>,
    /// Motion vector of each coordinate about its tree's root point o:
    /// angular part (u or 0) then linear part ((p − o) × u or u).
    motion: Vec<[f64; 6]>,
    /// Subtree wrenches of the backward pass: force (N), moment about the
    /// body's centre of mass (N m).
    subtree_force: Vec<Vector3<f64>>,
    subtree_moment: Vec<Vector3<f64>>,
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

/// A' = A R_k(s) without the full product: with (i, j) the axes following k
/// cyclically, column i becomes c a_i + s a_j and column j becomes
/// c a_j − s a_i (column k is unchanged).
#[inline(always)]
fn rotate_columns(a: &mut Matrix3<f64>, axis: usize, s: f64) {
    let (sn, c) = s.sin_cos();
    let i = (axis + 1) % 3;
    let j = (axis + 2) % 3;
    let ai = a.column(i).into_owned();
    let aj = a.column(j).into_owned();
    a.set_column(i, &(ai * c + aj * sn));
    a.set_column(j, &(aj * c - ai * sn));
}

/// A rheonomic rotation or translation along axis `axis` of the current frame
/// with prescribed value, rate and acceleration.
#[allow(clippy::too_many_arguments)]
#[inline]
fn rheonomic(
    s: &mut FrameState,
    rotation: bool,
    axis: usize,
    val: f64,
    rate: f64,
    acc: f64,
    with_acc: bool,
) {
    let u = s.a.column(axis).into_owned();
    if rotation {
        rotate(s, axis, &u, val, rate, acc, with_acc);
    } else {
        let d = u * val;
        let v_rel = u * rate;
        let a_rel = u * acc;
        translate(s, &d, Some((&v_rel, &a_rel)), with_acc);
    }
}

/// Translation of the frame by `d` (SC0) moving with relative velocity
/// `v_rel` and acceleration `a_rel` along it:
/// v' = v + ω×d + v_rel, a⁰' = a⁰ + α⁰×d + ω×(ω×d) + 2 ω×v_rel + a_rel.
#[inline(always)]
fn translate(
    s: &mut FrameState,
    d: &Vector3<f64>,
    v_rel: Option<(&Vector3<f64>, &Vector3<f64>)>,
    with_acc: bool,
) {
    let wd = s.w.cross(d);
    if with_acc {
        s.acc0 += s.alpha0.cross(d) + s.w.cross(&wd);
    }
    s.v += wd;
    if let Some((vr, ar)) = v_rel {
        if with_acc {
            s.acc0 += 2.0 * s.w.cross(vr) + ar;
        }
        s.v += vr;
    }
    s.r += d;
}

/// Rotation of the frame about its axis `axis` (u in SC0) by angle `val` with
/// rate `rate` and prescribed acceleration `acc`:
/// ω' = ω + u ṡ, α⁰' = α⁰ + ω×(u ṡ) + u s̈, A' = A R_axis(val).
#[inline(always)]
fn rotate(
    s: &mut FrameState,
    axis: usize,
    u: &Vector3<f64>,
    val: f64,
    rate: f64,
    acc: f64,
    with_acc: bool,
) {
    let w_rel = u * rate;
    if with_acc {
        s.alpha0 += s.w.cross(&w_rel);
        if acc != 0.0 {
            s.alpha0 += u * acc;
        }
    }
    s.w += w_rel;
    rotate_columns(&mut s.a, axis, val);
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

/// Backward accumulation of body wrenches `(f_j, n_j)` (about each centre of
/// mass) over subtrees: `f_sub[j]`, `n_sub[j]` (moment about r_j).
fn accumulate_wrenches(
    states: &[FrameState],
    children: &[Vec<usize>],
    wrench: impl Fn(usize) -> (Vector3<f64>, Vector3<f64>),
    f_sub: &mut [Vector3<f64>],
    n_sub: &mut [Vector3<f64>],
) {
    for j in (0..states.len()).rev() {
        let (mut f, mut n) = wrench(j);
        let rj = states[j].r;
        for &c in &children[j] {
            f += f_sub[c];
            n += n_sub[c] + (states[c].r - rj).cross(&f_sub[c]);
        }
        f_sub[j] = f;
        n_sub[j] = n;
    }
}

impl NumericEquations {
    /// Prepares the engine for `model`. Call [`Equations::set_parameters`] before evaluating.
    pub fn new(model: &Model) -> Self {
        let n = model.coordinates.len();
        let mut bodies: Vec<BodyData> = Vec::with_capacity(model.bodies.len());
        let mut children = vec![Vec::new(); model.bodies.len()];
        let mut coordinate_body = vec![0; n];
        let mut time_motions = Vec::new();
        for (j, b) in model.bodies.iter().enumerate() {
            let parent = body_option(b.parent);
            if let Some(p) = parent {
                children[p].push(j);
            }
            let root = parent.map_or(j, |p| bodies[p].root);
            let mut chain = parent.map(|p| bodies[p].chain.clone()).unwrap_or_default();
            let own_start = chain.len();
            let mut ops = Vec::with_capacity(b.joint.len());
            for e in &b.joint {
                let (rotation, axis) = match e.kind {
                    ElementaryKind::Translation(a) => (false, axis_index(a)),
                    ElementaryKind::Rotation(a) => (true, axis_index(a)),
                };
                let source = match &e.motion {
                    Motion::Fixed(x) => Source::Fixed(x.clone()),
                    Motion::Coordinate(i) => {
                        chain.push(*i);
                        if let Some(cb) = coordinate_body.get_mut(*i) {
                            *cb = j;
                        }
                        Source::Coordinate(*i)
                    }
                    Motion::Time(x) => {
                        let rate = x.time_derivative();
                        let acceleration = rate.time_derivative();
                        time_motions.push(TimeMotion {
                            value: x.clone(),
                            rate,
                            acceleration,
                        });
                        Source::Time(time_motions.len() - 1)
                    }
                    Motion::Input(k) => Source::Input(*k),
                };
                ops.push(Op {
                    rotation,
                    axis,
                    source,
                });
            }
            bodies.push(BodyData {
                parent,
                root,
                ops,
                mass_expr: b.mass.clone(),
                inertia_expr: b.inertia.clone(),
                mass: 0.0,
                inertia: Matrix3::zeros(),
                principal: None,
                chain,
                own_start,
                steps: (0, 0),
            });
        }
        let cuts: Vec<CutData> = model.cut_joints.iter().map(cut_data).collect();
        let constraint_count = cuts.iter().map(|c| c.components.len()).sum();
        let nb = bodies.len();
        Self {
            formalism: Formalism::CompositeBody,
            body_names: model.bodies.iter().map(|b| b.name.clone()).collect(),
            inertia_current: false,
            art_inertia: vec![Matrix6::zeros(); nb],
            art_bias: vec![Vector6::zeros(); nb],
            art_acc: vec![Vector6::zeros(); nb],
            node_u: vec![Vector6::zeros(); n],
            node_d: vec![0.0; n],
            node_tau: vec![0.0; n],
            bodies,
            children,
            coordinate_count: n,
            coordinate_body,
            parameter_count: model.parameters.len(),
            gravity_expr: model.gravity.clone(),
            gravity: Vector3::zeros(),
            cuts,
            constraint_count,
            time_motions,
            inputs: vec![0.0; 18 * model.track_frames.len()],
            steps: Vec::new(),
            params: Vec::new(),
            parameters_set: false,
            states: vec![FrameState::default(); nb],
            axes: vec![Axis6::default(); n],
            inertia_global: vec![Matrix3::zeros(); nb],
            composite_mass: vec![0.0; nb],
            composite_center: vec![Vector3::zeros(); nb],
            composite_inertia: vec![Matrix3::zeros(); nb],
            motion: vec![[0.0; 6]; n],
            subtree_force: vec![Vector3::zeros(); nb],
            subtree_moment: vec![Vector3::zeros(); nb],
        }
    }

    /// [`NumericEquations::new`] with the given formalism. The
    /// articulated-body method needs an open tree: a model with cut joints
    /// (closed loops) is refused with an error naming the model and its cut
    /// joints (no silent fallback: the user asked for O(n) and would not get
    /// it; the composite-body formalism handles loops).
    pub fn with_formalism(model: &Model, formalism: Formalism) -> Result<Self, SimError> {
        if formalism == Formalism::ArticulatedBody && !model.cut_joints.is_empty() {
            let names: Vec<&str> = model.cut_joints.iter().map(|c| c.name.as_str()).collect();
            return Err(SimError::Other(format!(
                "model \"{}\" has closed loops (cut joints {}): the articulated-body \
                 method needs an open tree; use the composite-body formalism \
                 (--engine numeric)",
                model.name,
                names.join(", ")
            )));
        }
        let mut e = Self::new(model);
        e.formalism = formalism;
        Ok(e)
    }

    /// The formalism this engine uses for q̈.
    pub fn formalism(&self) -> Formalism {
        self.formalism
    }

    /// Motion vector (angular, linear) of every coordinate about its tree's
    /// root point o (a point of the mechanism, so no digits are lost far
    /// from SC0): (u, (p − o) × u) for a rotation, (0, u) for a translation.
    fn motion_vectors(&mut self) {
        for ((m, ax), &body) in self
            .motion
            .iter_mut()
            .zip(&self.axes)
            .zip(&self.coordinate_body)
        {
            let o = self.states[self.bodies[body].root].r;
            let (a, b) = if ax.rotation {
                (ax.u, (ax.p - o).cross(&ax.u))
            } else {
                (Vector3::zeros(), ax.u)
            };
            *m = [a.x, a.y, a.z, b.x, b.y, b.z];
        }
    }

    /// Spatial inertia of body `j` about its tree's root point o in SC0 axes
    /// (motion vectors (ω, v_o), force vectors (n_o, f)): with d = c − o,
    /// `[[I_c + m d̃ d̃ᵀ, m d̃], [m d̃ᵀ, m E]]` (Featherstone 2008, ch. 2: the rigid-body inertia
    /// about a point other than the centre of mass).
    fn spatial_inertia(&self, j: usize) -> Matrix6<f64> {
        let m = self.bodies[j].mass;
        let d = self.states[j].r - self.states[self.bodies[j].root].r;
        let md = m * d;
        // m d̃ (cross-product matrix of m d).
        let c = Matrix3::new(0.0, -md.z, md.y, md.z, 0.0, -md.x, -md.y, md.x, 0.0);
        let rot = self.inertia_global[j] + steiner(m, &d);
        let mut out = Matrix6::zeros();
        out.fixed_view_mut::<3, 3>(0, 0).copy_from(&rot);
        out.fixed_view_mut::<3, 3>(0, 3).copy_from(&c);
        out.fixed_view_mut::<3, 3>(3, 0).copy_from(&c.transpose());
        out.fixed_view_mut::<3, 3>(3, 3)
            .copy_from(&Matrix3::from_diagonal_element(m));
        out
    }

    /// Solves M x = b in place (b: generalized forces, N or N m; x: q̈, m/s²
    /// or rad/s²) by the articulated-body recursion (Featherstone 2008,
    /// Sect. 7.3, passes 2 and 3 with zero velocity terms, in absolute
    /// coordinates), O(n), at the kinematics of the last forward pass.
    ///
    /// Backward, per body (children first), then per own coordinate from the
    /// last to the first: I^A = I_j + Σ_children I^a, p^A = Σ_children p^a;
    /// U = I^A s, D = sᵀ U, u = b_k − sᵀ p^A; I^a = I^A − U Uᵀ / D,
    /// p^a = p^A + U u / D. Forward: a = a_parent; x_k = (u − Uᵀ a) / D;
    /// a += s x_k. A body without coordinates passes I^A, p^A on unchanged
    /// (it moves rigidly with its parent as far as q̈ is concerned).
    fn articulated_solve(&mut self, b: &mut [f64]) -> Result<(), SimError> {
        self.motion_vectors();
        let nb = self.bodies.len();
        for j in (0..nb).rev() {
            let mut ia = self.spatial_inertia(j);
            let mut pa = Vector6::zeros();
            for &c in &self.children[j] {
                ia += self.art_inertia[c];
                pa += self.art_bias[c];
            }
            let body = &self.bodies[j];
            for &k in body.chain[body.own_start..].iter().rev() {
                let s = Vector6::from_column_slice(&self.motion[k]);
                let u = ia * s;
                let d = s.dot(&u);
                if !(d > 0.0 && d.is_finite()) {
                    return Err(SimError::Other(format!(
                        "articulated-body method: the articulated inertia of coordinate {k} \
                         (body \"{}\") about its axis is {d}, not positive (a massless \
                         subtree or a singular joint axis)",
                        self.body_names[j]
                    )));
                }
                let tau = b[k] - s.dot(&pa);
                ia -= u * (u.transpose() / d);
                pa += u * (tau / d);
                self.node_u[k] = u;
                self.node_d[k] = d;
                self.node_tau[k] = tau;
            }
            self.art_inertia[j] = ia;
            self.art_bias[j] = pa;
        }
        for j in 0..nb {
            let body = &self.bodies[j];
            let mut a = match body.parent {
                Some(p) => self.art_acc[p],
                None => Vector6::zeros(),
            };
            for &k in &body.chain[body.own_start..] {
                let x = (self.node_tau[k] - self.node_u[k].dot(&a)) / self.node_d[k];
                a += Vector6::from_column_slice(&self.motion[k]) * x;
                b[k] = x;
            }
            self.art_acc[j] = a;
        }
        Ok(())
    }

    /// Compiles the joint transformations of every body into `steps` with the
    /// current parameter values: fixed transformations of value zero vanish,
    /// runs of fixed translations become one shift and runs of fixed
    /// rotations one matrix.
    fn compile_steps(&mut self) -> Result<(), SimError> {
        let p = &self.params;
        let mut steps = Vec::new();
        for (j, body) in self.bodies.iter_mut().enumerate() {
            let start = steps.len();
            for op in &body.ops {
                let step = match &op.source {
                    Source::Fixed(expr) => {
                        let value = finite(expr.eval(p, 0.0), || format!("joint of body #{j}"))?;
                        if value == 0.0 {
                            continue;
                        }
                        let last = if steps.len() > start {
                            steps.last_mut()
                        } else {
                            None
                        };
                        if let Some(last) = last {
                            match (op.rotation, &mut *last) {
                                (false, Step::AxisShift { axis, value: v }) => {
                                    let mut d = Vector3::zeros();
                                    d[*axis] = *v;
                                    d[op.axis] += value;
                                    *last = Step::Shift { d };
                                    continue;
                                }
                                (false, Step::Shift { d }) => {
                                    d[op.axis] += value;
                                    continue;
                                }
                                (true, Step::Turn { r }) => {
                                    *r *= elementary_rotation(op.axis, value);
                                    continue;
                                }
                                _ => {}
                            }
                        }
                        if op.rotation {
                            Step::Turn {
                                r: elementary_rotation(op.axis, value),
                            }
                        } else {
                            Step::AxisShift {
                                axis: op.axis,
                                value,
                            }
                        }
                    }
                    Source::Coordinate(i) => {
                        if op.rotation {
                            Step::CoordRotation {
                                axis: op.axis,
                                coord: *i,
                            }
                        } else {
                            Step::CoordTranslation {
                                axis: op.axis,
                                coord: *i,
                            }
                        }
                    }
                    Source::Time(k) => Step::Time {
                        rotation: op.rotation,
                        axis: op.axis,
                        motion: *k,
                    },
                    Source::Input(k) => Step::Input {
                        rotation: op.rotation,
                        axis: op.axis,
                        input: *k,
                    },
                };
                steps.push(step);
            }
            body.steps = (start, steps.len());
        }
        self.steps = steps;
        Ok(())
    }

    /// Forward pass: kinematics of all frames and partial velocities; the bias
    /// accelerations only `with_acc`, the inertia tensors in SC0 only
    /// `with_inertia`.
    fn forward(&mut self, t: f64, q: &[f64], qd: &[f64], with_acc: bool, with_inertia: bool) {
        let root_state = FrameState {
            a: Matrix3::identity(),
            ..FrameState::default()
        };
        for j in 0..self.bodies.len() {
            let body = &self.bodies[j];
            // Start from the parent's frame, in place (field by field: no
            // memcpy call for the whole state).
            let (done, rest) = self.states.split_at_mut(j);
            let s = &mut rest[0];
            let from = match body.parent {
                Some(p) => &done[p],
                None => &root_state,
            };
            s.r = from.r;
            s.a = from.a;
            s.v = from.v;
            s.w = from.w;
            if with_acc {
                s.acc0 = from.acc0;
                s.alpha0 = from.alpha0;
            }
            for step in &self.steps[body.steps.0..body.steps.1] {
                match *step {
                    Step::AxisShift { axis, value } => {
                        let d = s.a.column(axis) * value;
                        translate(s, &d, None, with_acc);
                    }
                    Step::Shift { d } => {
                        let d = s.a * d;
                        translate(s, &d, None, with_acc);
                    }
                    Step::Turn { r } => s.a *= r,
                    Step::CoordRotation { axis, coord } => {
                        let u = s.a.column(axis).into_owned();
                        self.axes[coord] = Axis6 {
                            rotation: true,
                            u,
                            p: s.r,
                        };
                        rotate(s, axis, &u, q[coord], qd[coord], 0.0, with_acc);
                    }
                    Step::CoordTranslation { axis, coord } => {
                        let u = s.a.column(axis).into_owned();
                        self.axes[coord] = Axis6 {
                            rotation: false,
                            u,
                            p: s.r,
                        };
                        let d = u * q[coord];
                        let v_rel = u * qd[coord];
                        translate(s, &d, Some((&v_rel, &Vector3::zeros())), with_acc);
                    }
                    Step::Time {
                        rotation,
                        axis,
                        motion,
                    } => {
                        let m = &self.time_motions[motion];
                        let val = m.value.eval(&self.params, t);
                        let rate = m.rate.eval(&self.params, t);
                        let acc = m.acceleration.eval(&self.params, t);
                        rheonomic(s, rotation, axis, val, rate, acc, with_acc);
                    }
                    Step::Input {
                        rotation,
                        axis,
                        input,
                    } => {
                        let u = &self.inputs[3 * input..3 * input + 3];
                        rheonomic(s, rotation, axis, u[0], u[1], u[2], with_acc);
                    }
                }
            }
            if with_inertia {
                self.inertia_global[j] = match &body.principal {
                    Some(d) => rotate_principal(&s.a, d),
                    None => rotate_tensor(&s.a, &body.inertia),
                };
            }
        }
    }

    /// Partial velocity of body `j`'s centre of mass and its angular velocity
    /// with respect to coordinate `i` (which must be on the body's chain).
    fn partial(&self, i: usize, j: usize) -> (Vector3<f64>, Vector3<f64>) {
        self.partial_at(i, &self.states[j].r)
    }

    /// Partial velocity of the point `x` (SC0, moving with a body whose chain
    /// holds coordinate `i`) and the partial angular velocity.
    fn partial_at(&self, i: usize, x: &Vector3<f64>) -> (Vector3<f64>, Vector3<f64>) {
        let ax = &self.axes[i];
        if ax.rotation {
            (ax.u.cross(&(x - ax.p)), ax.u)
        } else {
            (ax.u, Vector3::zeros())
        }
    }

    /// Generalized force of a subtree wrench (force `f`, moment `n` about the
    /// subtree's reference point `c`) on coordinate `i`.
    fn project_wrench(
        &self,
        i: usize,
        f: &Vector3<f64>,
        n: &Vector3<f64>,
        c: &Vector3<f64>,
    ) -> f64 {
        let ax = &self.axes[i];
        if ax.rotation {
            ax.u.dot(&(n + (c - ax.p).cross(f)))
        } else {
            ax.u.dot(f)
        }
    }

    /// M by composite bodies; with `bias` (needs the bias accelerations of
    /// the forward pass) k and with `gravity` Q_g in the same passes.
    fn mass_matrix(
        &mut self,
        mass: &mut DMatrix<f64>,
        mut bias: Option<&mut DVector<f64>>,
        mut gravity: Option<&mut DVector<f64>>,
    ) {
        let nb = self.bodies.len();
        // Composite bodies: mass, centre of mass, inertia about it (SC0 axes);
        // with `bias` also the subtree inertia wrenches.
        for j in (0..nb).rev() {
            if bias.is_some() {
                self.inertia_wrench(j);
            }
            let body = &self.bodies[j];
            let children = &self.children[j];
            let mut m = body.mass;
            let mut first = Vector3::zeros(); // Σ m_k (c_k − r_j)
            let rj = self.states[j].r;
            for &c in children {
                m += self.composite_mass[c];
                first += self.composite_mass[c] * (self.composite_center[c] - rj);
            }
            let dc = if m > 0.0 { first / m } else { Vector3::zeros() };
            // Parallel-axis theorem about the composite centre.
            let mut inertia = self.inertia_global[j] + steiner(body.mass, &dc);
            for &c in children {
                inertia += self.composite_inertia[c]
                    + steiner(
                        self.composite_mass[c],
                        &(self.composite_center[c] - rj - dc),
                    );
            }
            self.composite_mass[j] = m;
            self.composite_center[j] = rj + dc;
            self.composite_inertia[j] = inertia;
        }
        self.motion_vectors();
        let n = mass.nrows();
        let ms = mass.as_mut_slice(); // column-major: (r, c) at r + c n
        for (b, body) in self.bodies.iter().enumerate() {
            let o = self.states[body.root].r;
            let cm = self.composite_mass[b];
            let cc = self.composite_center[b];
            let ci = &self.composite_inertia[b];
            for pos in body.own_start..body.chain.len() {
                let i = body.chain[pos];
                let ax = &self.axes[i];
                // Momentum of the composite subtree moving with unit rate of
                // q_i: linear, and angular about its centre cc; then about o.
                let (lin, ang) = if ax.rotation {
                    (cm * ax.u.cross(&(cc - ax.p)), ci * ax.u)
                } else {
                    (cm * ax.u, Vector3::zeros())
                };
                let h = ang + (cc - o).cross(&lin);
                let f = [h.x, h.y, h.z, lin.x, lin.y, lin.z];
                // M_ik = S_k · (h, lin): the generalized force of the momentum
                // on coordinate k, u_k·(h − (p_k − o)×lin) for a rotation.
                for &k in &body.chain[..=pos] {
                    let m = &self.motion[k];
                    let value = m[0] * f[0]
                        + m[1] * f[1]
                        + m[2] * f[2]
                        + (m[3] * f[3] + m[4] * f[4] + m[5] * f[5]);
                    ms[k + i * n] = value;
                    ms[i + k * n] = value;
                }
                if let Some(bias) = bias.as_deref_mut() {
                    let (f, t) = (&self.subtree_force[b], &self.subtree_moment[b]);
                    bias[i] = self.project_wrench(i, f, t, &self.states[b].r);
                }
                if let Some(gravity) = gravity.as_deref_mut() {
                    // The weight of the subtree acts at its centre of mass.
                    let weight = cm * self.gravity;
                    gravity[i] = self.project_wrench(i, &weight, &Vector3::zeros(), &cc);
                }
            }
        }
    }

    /// Subtree inertia wrench of body `j` at q̈ = 0 (its children's already
    /// accumulated): force Σ m a⁰ and moment about r_j of the Newton–Euler
    /// terms (m a⁰, I α⁰ + ω × I ω).
    #[inline(always)]
    fn inertia_wrench(&mut self, j: usize) {
        let s = &self.states[j];
        let i = &self.inertia_global[j];
        let mut f = self.bodies[j].mass * s.acc0;
        let mut n = i * s.alpha0 + s.w.cross(&(i * s.w));
        for &c in &self.children[j] {
            let fc = self.subtree_force[c];
            f += fc;
            n += self.subtree_moment[c] + (self.states[c].r - s.r).cross(&fc);
        }
        self.subtree_force[j] = f;
        self.subtree_moment[j] = n;
    }

    /// Projection of the subtree wrenches (about each body's centre of mass)
    /// on the coordinates: `out_i = Σ_j Γ_jᵀ (f_j, n_j)` per coordinate.
    fn project_subtree_wrenches(&self, out: &mut DVector<f64>) {
        for (b, body) in self.bodies.iter().enumerate() {
            let r = &self.states[b].r;
            let (f, n) = (&self.subtree_force[b], &self.subtree_moment[b]);
            for &i in &body.chain[body.own_start..] {
                out[i] = self.project_wrench(i, f, n, r);
            }
        }
    }

    /// Pose (position, direction cosines) of a cut-joint frame in SC0.
    fn frame_pose(&self, f: &FrameData) -> (Vector3<f64>, Matrix3<f64>) {
        match f.body {
            Some(b) => {
                let s = &self.states[b];
                (s.r + s.a * f.origin, s.a * f.rotation)
            }
            None => (f.origin, f.rotation),
        }
    }

    fn frame_chain(&self, f: &FrameData) -> &[usize] {
        match f.body {
            Some(b) => &self.bodies[b].chain,
            None => &[],
        }
    }

    fn constraints(&self, out: &mut Evaluation) {
        let n = self.coordinate_count;
        let mut row = 0;
        for cut in &self.cuts {
            let [f1, f2] = &cut.frames;
            let (p1, a1) = self.frame_pose(f1);
            let (p2, a2) = self.frame_pose(f2);
            let d = p2 - p1;
            for comp in &cut.components {
                let jac = &mut out.constraint_jacobian;
                for i in 0..n {
                    jac[(row, i)] = 0.0;
                }
                let g;
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
                        let exd = e.cross(&d);
                        for &i in self.frame_chain(f1) {
                            let (dp1, dt1) = self.partial_at(i, &p1);
                            jac[(row, i)] += dt1.dot(&exd) - dp1.dot(&e);
                        }
                        for &i in self.frame_chain(f2) {
                            let (dp2, _) = self.partial_at(i, &p2);
                            jac[(row, i)] += dp2.dot(&e);
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
                        let c = 0.5 * (a_k2.cross(&b_k1) - a_k1.cross(&b_k2));
                        for &i in self.frame_chain(f1) {
                            let (_, dt1) = self.partial_at(i, &p1);
                            jac[(row, i)] += dt1.dot(&c);
                        }
                        for &i in self.frame_chain(f2) {
                            let (_, dt2) = self.partial_at(i, &p2);
                            jac[(row, i)] -= dt2.dot(&c);
                        }
                    }
                }
                out.constraints[row] = g;
                row += 1;
            }
        }
    }

    /// Checks that `out` has the sizes of this engine for the requested parts.
    fn check_buffers(&self, parts: Parts, out: &Evaluation) -> Result<(), SimError> {
        let n = self.coordinate_count;
        let nb = self.bodies.len();
        let nc = self.constraint_count;
        let bad = |what: &str, got: String, want: String| {
            Err(SimError::Other(format!(
                "evaluation buffer {what} is {got}, the numeric engine needs {want} \
                 (create it with Evaluation::for_equations)"
            )))
        };
        if parts.mass && out.mass.shape() != (n, n) {
            return bad(
                "mass",
                format!("{:?}", out.mass.shape()),
                format!("({n}, {n})"),
            );
        }
        if parts.bias && out.bias.len() != n {
            return bad("bias", out.bias.len().to_string(), n.to_string());
        }
        if parts.gravity && out.gravity.len() != n {
            return bad("gravity", out.gravity.len().to_string(), n.to_string());
        }
        if parts.kinematics && out.bodies.len() != nb {
            return bad("bodies", out.bodies.len().to_string(), nb.to_string());
        }
        if parts.jacobians && out.jacobians.shape() != (6 * nb, n) {
            return bad(
                "jacobians",
                format!("{:?}", out.jacobians.shape()),
                format!("({}, {n})", 6 * nb),
            );
        }
        if parts.constraints
            && nc > 0
            && (out.constraints.len() != nc || out.constraint_jacobian.shape() != (nc, n))
        {
            return bad(
                "constraints",
                format!(
                    "{} and {:?}",
                    out.constraints.len(),
                    out.constraint_jacobian.shape()
                ),
                format!("{nc} and ({nc}, {n})"),
            );
        }
        Ok(())
    }
}

fn cut_data(c: &CutJoint) -> CutData {
    CutData {
        frames: [
            frame_data(c.body1, &c.frame1),
            frame_data(c.body2, &c.frame2),
        ],
        components: c.constrained.clone(),
    }
}

/// Parallel-axis term m(|d|² E − d dᵀ) (the sign of d does not matter).
#[inline(always)]
fn steiner(m: f64, d: &Vector3<f64>) -> Matrix3<f64> {
    let (x, y, z) = (d.x, d.y, d.z);
    let (xx, yy, zz) = (m * x * x, m * y * y, m * z * z);
    let (xy, xz, yz) = (m * x * y, m * x * z, m * y * z);
    Matrix3::new(yy + zz, -xy, -xz, -xy, xx + zz, -yz, -xz, -yz, xx + yy)
}

/// A I Aᵀ for a symmetric I: B = A I, then the six distinct entries of B Aᵀ.
#[inline(always)]
fn rotate_tensor(a: &Matrix3<f64>, i: &Matrix3<f64>) -> Matrix3<f64> {
    let b = a * i;
    let e =
        |r: usize, c: usize| b[(r, 0)] * a[(c, 0)] + b[(r, 1)] * a[(c, 1)] + b[(r, 2)] * a[(c, 2)];
    let (xx, yy, zz) = (e(0, 0), e(1, 1), e(2, 2));
    let (xy, xz, yz) = (e(0, 1), e(0, 2), e(1, 2));
    Matrix3::new(xx, xy, xz, xy, yy, yz, xz, yz, zz)
}

/// A diag(d) Aᵀ: entry (r, c) is Σ_k d_k A_rk A_ck.
#[inline(always)]
fn rotate_principal(a: &Matrix3<f64>, d: &Vector3<f64>) -> Matrix3<f64> {
    let e = |r: usize, c: usize| {
        d.x * a[(r, 0)] * a[(c, 0)] + d.y * a[(r, 1)] * a[(c, 1)] + d.z * a[(r, 2)] * a[(c, 2)]
    };
    let (xx, yy, zz) = (e(0, 0), e(1, 1), e(2, 2));
    let (xy, xz, yz) = (e(0, 1), e(0, 2), e(1, 2));
    Matrix3::new(xx, xy, xz, xy, yy, yz, xz, yz, zz)
}

impl Equations for NumericEquations {
    fn engine_name(&self) -> &str {
        match self.formalism {
            Formalism::CompositeBody => "numeric",
            Formalism::ArticulatedBody => "numeric-aba",
        }
    }
    fn solves_mass(&self) -> bool {
        self.formalism == Formalism::ArticulatedBody
    }
    fn solve_mass(&mut self, b: &mut [f64]) -> Result<bool, SimError> {
        if self.formalism != Formalism::ArticulatedBody {
            return Ok(false);
        }
        if b.len() != self.coordinate_count {
            return Err(SimError::Other(format!(
                "solve_mass: right-hand side has {} entries, the model has {} coordinates",
                b.len(),
                self.coordinate_count
            )));
        }
        if !self.inertia_current {
            return Err(SimError::Other(
                "solve_mass called before an evaluation of the bias terms or the mass matrix"
                    .into(),
            ));
        }
        self.articulated_solve(b)?;
        Ok(true)
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
    fn input_count(&self) -> usize {
        self.inputs.len() / 3
    }
    fn set_inputs(&mut self, u: &[f64]) -> Result<(), SimError> {
        if u.len() != self.inputs.len() {
            return Err(SimError::Other(format!(
                "the numeric engine takes {} input values (3 per input), got {}",
                self.inputs.len(),
                u.len()
            )));
        }
        self.inputs.copy_from_slice(u);
        Ok(())
    }

    fn set_parameters(&mut self, params: &[f64]) -> Result<(), SimError> {
        if params.len() != self.parameter_count {
            return Err(SimError::Other(format!(
                "expected {} parameter values, got {}",
                self.parameter_count,
                params.len()
            )));
        }
        self.parameters_set = false;
        self.params = params.to_vec();
        let p = &self.params;
        for (j, body) in self.bodies.iter_mut().enumerate() {
            body.mass = finite(body.mass_expr.eval(p, 0.0), || format!("mass of body #{j}"))?;
            let mut i = [0.0; 6];
            for (k, e) in body.inertia_expr.iter().enumerate() {
                i[k] = finite(e.eval(p, 0.0), || format!("inertia of body #{j}"))?;
            }
            body.inertia = Matrix3::new(i[0], i[3], i[4], i[3], i[1], i[5], i[4], i[5], i[2]);
            body.principal =
                (i[3] == 0.0 && i[4] == 0.0 && i[5] == 0.0).then(|| Vector3::new(i[0], i[1], i[2]));
        }
        self.compile_steps()?;
        let p = &self.params;
        for (k, g) in self.gravity_expr.iter().enumerate() {
            self.gravity[k] = finite(g.eval(p, 0.0), || "gravity".into())?;
        }
        for cut in &mut self.cuts {
            for f in &mut cut.frames {
                for k in 0..3 {
                    f.origin[k] =
                        finite(f.origin_expr[k].eval(p, 0.0), || "cut joint frame".into())?;
                }
                let mut angles = [0.0; 3];
                for (k, a) in angles.iter_mut().enumerate() {
                    *a = finite(f.rotation_expr[k].eval(p, 0.0), || {
                        "cut joint frame rotation".into()
                    })?;
                }
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
        self.check_buffers(parts, out)?;
        self.forward(t, q, v, parts.bias, parts.mass || parts.bias);
        self.inertia_current = parts.mass || parts.bias;
        if parts.kinematics {
            for (k, s) in out.bodies.iter_mut().zip(&self.states) {
                let BodyKinematics {
                    position,
                    rotation,
                    velocity,
                    angular_velocity,
                } = k;
                *position = s.r;
                *rotation = s.a;
                *velocity = s.v;
                *angular_velocity = s.w;
            }
        }
        if parts.mass {
            // k and Q_g come with M from the same composite-body passes.
            self.mass_matrix(
                &mut out.mass,
                parts.bias.then_some(&mut out.bias),
                parts.gravity.then_some(&mut out.gravity),
            );
        } else {
            if parts.bias {
                for j in (0..self.bodies.len()).rev() {
                    self.inertia_wrench(j);
                }
                self.project_subtree_wrenches(&mut out.bias);
            }
            if parts.gravity {
                let (bodies, g) = (&self.bodies, self.gravity);
                accumulate_wrenches(
                    &self.states,
                    &self.children,
                    |j| (bodies[j].mass * g, Vector3::zeros()),
                    &mut self.subtree_force,
                    &mut self.subtree_moment,
                );
                self.project_subtree_wrenches(&mut out.gravity);
            }
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
