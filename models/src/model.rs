//! The resolved, validated model: what the numeric engine (`runtime`) and the
//! symbolic engine (`codegen`) consume. Produced by [`crate::load_model`] from a
//! RON file; every name is resolved to an index and every numeric field is an
//! [`Expr`] over the model's identifiers (parameters) and, where allowed, time.
//!
//! Conventions (see DESIGN.md): SI units; a body frame has its origin at the
//! body's centre of mass; a joint is an ordered list of elementary
//! transformations from the parent's body frame to the child's body frame.

use crate::expr::Expr;
use std::path::PathBuf;

/// Axis of an elementary transformation or a vector component.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
pub enum Axis {
    X,
    Y,
    Z,
}

impl Axis {
    /// 0, 1, 2 for x, y, z.
    pub fn index(self) -> usize {
        match self {
            Axis::X => 0,
            Axis::Y => 1,
            Axis::Z => 2,
        }
    }
}

/// Kind of an elementary transformation: translation along or rotation about an
/// axis of the current (moving) frame.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum ElementaryKind {
    Translation(Axis),
    Rotation(Axis),
}

/// What drives an elementary transformation.
#[derive(Debug, Clone, PartialEq)]
pub enum Motion {
    /// A constant over parameters only (no `t`). Metres or radians.
    Fixed(Expr),
    /// A generalized coordinate: index into [`Model::coordinates`].
    Coordinate(usize),
    /// A function of time `t` (and parameters): rheonomic. Metres or radians.
    Time(Expr),
    /// Runtime input `k` (rheonomic): the runtime supplies its value, first and
    /// second time derivatives at every evaluation. Inputs are the pose
    /// components of the track-following frames, [`Model::track_frames`]
    /// `[k / 6]`, component `k % 6` in the order x, y, z (m), yaw, pitch, roll (rad).
    Input(usize),
}

/// One elementary transformation `tx ty tz rx ry rz`.
#[derive(Debug, Clone, PartialEq)]
pub struct Elementary {
    pub kind: ElementaryKind,
    pub motion: Motion,
}

/// Which body a joint, force or cut joint refers to.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum BodyRef {
    /// The inertial frame SC0 (body 0).
    Ground,
    /// Index into [`Model::bodies`].
    Body(usize),
}

/// A rigid body with its joint to its parent.
#[derive(Debug, Clone, PartialEq)]
pub struct Body {
    /// Long name (with subsystem prefix, e.g. `Bogie1.WS2`).
    pub name: String,
    /// kg.
    pub mass: Expr,
    /// Inertia tensor about the centre of mass in the body frame, kg m²:
    /// `[ixx, iyy, izz, ixy, ixz, iyz]` (the tensor is `[[ixx, ixy, ixz], [ixy, iyy, iyz], [ixz, iyz, izz]]`;
    /// products of inertia are the tensor's off-diagonal entries, i.e. −∫xy dm).
    pub inertia: [Expr; 6],
    /// The parent. Parents always come before their children in `Model::bodies`
    /// (the loader sorts topologically), so a forward pass over bodies is a tree traversal.
    pub parent: BodyRef,
    /// Elementary transformations from the parent body frame to this body frame.
    pub joint: Vec<Elementary>,
}

/// A generalized coordinate.
#[derive(Debug, Clone, PartialEq)]
pub struct Coordinate {
    /// Long name, used as the CSV column name.
    pub name: String,
    /// Index of the body whose joint holds it.
    pub body: usize,
    /// Index of the elementary transformation within that joint.
    pub elementary: usize,
    /// Initial value (m or rad), expression over parameters.
    pub initial: Expr,
    /// Initial velocity (m/s or rad/s), expression over parameters.
    pub initial_velocity: Expr,
}

/// A frame fixed to a body: origin in the body frame (m) and orientation by
/// rotations about x, then y, then z of the moving frame (rad).
#[derive(Debug, Clone, PartialEq)]
pub struct Frame {
    pub origin: [Expr; 3],
    pub rotation_xyz: [Expr; 3],
}

/// A relative-pose component that a cut joint constrains, measured in frame 1.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Component {
    Tx,
    Ty,
    Tz,
    Rx,
    Ry,
    Rz,
}

/// A cut joint closing a kinematic loop: the constrained components of the
/// pose of `frame2` on `body2` relative to `frame1` on `body1` are zero.
/// Translational components: (r₂ − r₁)·e_k(frame 1). Rotational components:
/// the antisymmetric part of R = A₁ᵀA₂, g_x = (R_zy − R_yz)/2 etc. (equal to the
/// small relative rotation angle).
#[derive(Debug, Clone, PartialEq)]
pub struct CutJoint {
    pub name: String,
    pub body1: BodyRef,
    pub frame1: Frame,
    pub body2: BodyRef,
    pub frame2: Frame,
    pub constrained: Vec<Component>,
}

/// The frame in which a vector given in a model is expressed.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum VectorFrame {
    /// The inertial frame SC0.
    Global,
    /// The body frame of the body the element acts on.
    Body,
}

/// How a tabulated characteristic is interpolated between its rows.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Deserialize)]
pub enum Interpolation {
    /// Straight lines between the rows (kinks at the rows).
    #[default]
    Linear,
    /// Piecewise cubic Hermite with Fritsch–Carlson slopes (Fritsch &
    /// Carlson 1980, SIAM J. Numer. Anal. 17): continuous slope, through every
    /// row, and monotone wherever the rows are (no overshoot in a bump stop's
    /// clearance, as a C² interpolating spline would give).
    Spline,
}

/// Force elements of the model. The runtime computes their forces; the model
/// only describes them. Each variant's fields are expressions over parameters
/// (and `t` where stated).
// The variants' sizes differ, but a model holds few force elements and the
// layout is a contract shared by both engines.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Clone, PartialEq)]
pub enum ForceKind {
    /// Linear bipolar spring–damper between two points (paper Sect. 3.1):
    /// F = c (x − x0) + d ẋ + f0 along the line of the points, x the distance (m).
    /// Positive force pulls the points together (tension).
    Bipolar {
        body1: BodyRef,
        point1: [Expr; 3],
        body2: BodyRef,
        point2: [Expr; 3],
        /// N/m.
        stiffness: Expr,
        /// N s/m.
        damping: Expr,
        /// N.
        preload: Expr,
        /// Free length, m.
        free_length: Expr,
    },
    /// Spring c in series with damper d between two points (paper Sect. 3.1),
    /// with a preload f0 in parallel: the spring's extension s is a
    /// first-order state variable integrated with q, and the tension is
    /// F = c s + f0 = d (ẋ − ṡ) + f0, x the distance of the points (m). No
    /// free length: the damper takes up any static length change, so the
    /// force depends on the motion only. Positive F pulls the points together.
    SeriesSpringDamper {
        body1: BodyRef,
        point1: [Expr; 3],
        body2: BodyRef,
        point2: [Expr; 3],
        /// N/m.
        stiffness: Expr,
        /// N s/m.
        damping: Expr,
        /// N.
        preload: Expr,
    },
    /// Generalized linear 6×6 elastic and dissipative element (paper Sect. 3.2)
    /// between frame 1 on body 1 and frame 2 on body 2. The relative displacement
    /// (three translations, three small rotations, in frame 1) is
    /// δ = (A₁ᵀ(r₂ − r₁), g_rot) and the wrench on body 2, in frame 1, is
    /// −(C δ + D δ̇ + preload); body 1 gets the reaction.
    Linear6 {
        body1: BodyRef,
        frame1: Frame,
        body2: BodyRef,
        frame2: Frame,
        /// Row-major 6×6, N/m, N/rad, N m/m, N m/rad.
        stiffness: Box<[Expr; 36]>,
        /// Row-major 6×6, damping units as stiffness per second.
        damping: Box<[Expr; 36]>,
        /// Static preload wrench (N, N m), in frame 1.
        preload: [Expr; 6],
    },
    /// Point–plane contact (paper Sect. 3.3): points fixed to `body` against
    /// the plane through `origin` with outward `normal` fixed to `plane_body`
    /// (both in that body's frame). Penetration δ ≥ 0 gives the normal force
    /// N = max(0, c δ + d δ̇) (no adhesion); the tangential force is Coulomb
    /// friction with sticking (the point tied to an anchor by ct, dt) up to
    /// μ0 N, and sliding at μ N.
    PointPlane {
        body: BodyRef,
        /// Contact points in the frame of `body`, m.
        points: Vec<[Expr; 3]>,
        plane_body: BodyRef,
        /// A point of the plane, m.
        origin: [Expr; 3],
        /// Normal pointing out of the plane's solid side (any length > 0).
        normal: [Expr; 3],
        /// Point–Z-surface variant: instead of the plane, the surface
        /// z = f(x, y) in the frame of `plane_body` shifted to `origin` (x, y
        /// are the local variables `Var(0)`, `Var(1)`, m), solid below it; the
        /// normal is the surface's upward normal (−f_x, −f_y, 1).
        surface: Option<Expr>,
        /// Normal stiffness per point, N/m.
        stiffness: Expr,
        /// Normal damping per point, N s/m.
        damping: Expr,
        /// Tangential stiffness of the sticking anchor, N/m.
        tangential_stiffness: Expr,
        /// Tangential damping of the sticking anchor, N s/m.
        tangential_damping: Expr,
        /// Static friction coefficient μ0 (≥ μ).
        mu_static: Expr,
        /// Sliding friction coefficient μ (≥ 0).
        mu: Expr,
    },
    /// Bipolar Coulomb friction (paper Sect. 3.1) between two points: sticking,
    /// F = f0 + c (x − x0) + d ẋ with f0, x0 stored when sticking begins,
    /// until |F| reaches the static limit; then sliding, F = F_s sign(ẋ).
    /// Positive F pulls the points together.
    Coulomb {
        body1: BodyRef,
        point1: [Expr; 3],
        body2: BodyRef,
        point2: [Expr; 3],
        /// Sticking stiffness, N/m.
        stiffness: Expr,
        /// Sticking damping, N s/m.
        damping: Expr,
        /// Static limit F0, N.
        static_limit: Expr,
        /// Sliding force F_s (≤ F0), N.
        sliding_force: Expr,
    },
    /// Load-dependent friction (paper Sect. 3.1, Fig. 3): spring c1 in series
    /// with spring c2 in parallel with friction proportional to the force in
    /// c2 (static μ0, sliding μ). x is the distance minus `free_length`.
    LoadFriction {
        body1: BodyRef,
        point1: [Expr; 3],
        body2: BodyRef,
        point2: [Expr; 3],
        /// N/m.
        c1: Expr,
        /// N/m.
        c2: Expr,
        mu_static: Expr,
        mu: Expr,
        /// m.
        free_length: Expr,
    },
    /// Tabulated force–deflection characteristic (bump stops):
    /// F = f(x − x0) + d ẋ, with f piecewise linear through the rows
    /// (deflection m, force N) and extended linearly beyond the end rows.
    Tabulated {
        body1: BodyRef,
        point1: [Expr; 3],
        body2: BodyRef,
        point2: [Expr; 3],
        /// (deflection m, force N), deflection increasing.
        table: Vec<(Expr, Expr)>,
        /// Between the rows: straight lines, or a monotone cubic.
        interpolation: Interpolation,
        /// N s/m.
        damping: Expr,
        /// m.
        free_length: Expr,
    },
    /// Wheel–rail contact of a wheelset on the scenario's track (seed paper
    /// Sect. 4): left and right wheel against their rails, contact geometry
    /// from a table over lateral shift and roll, Hertzian normal force, creep
    /// forces by the chosen law. The wheelset body's frame has its origin at
    /// the axle centre and its y axis along the axle (to the left); its spin
    /// about y may be a coordinate or not (then the wheels' rolling speed is
    /// that of the body's angular velocity anyway).
    WheelRail(Box<WheelRail>),
    /// An applied force and torque on one body; expressions may depend on `t`.
    Applied {
        body: usize,
        /// Point of application in the body frame, m.
        point: [Expr; 3],
        /// N.
        force: [Expr; 3],
        /// N m.
        torque: [Expr; 3],
        frame: VectorFrame,
    },
}

/// Data of a wheel–rail contact element ([`ForceKind::WheelRail`]).
#[derive(Debug, Clone, PartialEq)]
pub struct WheelRail {
    /// The wheelset body.
    pub wheelset: usize,
    /// Wheel profiles (left, right; the right one mirrored when placed),
    /// absolute paths.
    pub wheel_profiles: [PathBuf; 2],
    /// Rail profiles (left, right), absolute paths. The track's rail
    /// inclination is applied when they are read, unless
    /// `rail_profiles_inclined`.
    pub rail_profiles: [PathBuf; 2],
    /// The rail profile files are already drawn inclined (as the Manchester
    /// benchmark's UIC60 files are): the track's rail inclination is not
    /// applied again.
    pub rail_profiles_inclined: bool,
    /// Nominal rolling radius at the taping line, m.
    pub radius: Expr,
    /// Distance between the flange backs, m.
    pub flange_back_distance: Expr,
    /// Distance from a flange back to the taping line, m.
    pub taping_offset: Expr,
    /// Coefficient of friction, –.
    pub mu: Expr,
    /// Young's modulus of wheel and rail, Pa.
    pub young: Expr,
    /// Poisson's ratio of wheel and rail, –.
    pub poisson: Expr,
    /// Damping along the contact normal, N s/m (0: none).
    pub normal_damping: Expr,
    /// The creep-force law.
    pub creep: CreepLawSpec<Expr>,
    /// Rigid rails, or massless elastic rails (seed paper Sect. 4.2).
    pub rail: RailKind,
    /// Contact table ranges and steps.
    pub table: ContactTableSpec,
    /// Independently rotating wheels: the bodies (left, right) that carry
    /// each wheel's spin, usually on revolute joints about the axle's y axis.
    /// Each wheel's contact forces act on its own body and its creepages come
    /// from that body's velocity and angular velocity; the contact geometry
    /// still follows the `wheelset` (axle) body's pose. `None`: a solid
    /// wheelset, both wheels on the `wheelset` body.
    pub wheels: Option<[usize; 2]>,
}

/// Creep-force law of a wheel–rail element: the wheelrail crate's spec, its
/// real-valued settings as expressions over the parameters.
pub use railmbs_wheelrail::creep::{CreepLawSpec, SlidingZone};

/// The rails of a wheel–rail element.
#[derive(Debug, Clone, PartialEq)]
pub enum RailKind {
    /// Rails fixed to the track.
    Rigid,
    /// Massless rail heads on lateral and vertical spring–dampers (per rail):
    /// N/m, N s/m.
    Elastic {
        ky: Expr,
        cy: Expr,
        kz: Expr,
        cz: Expr,
    },
}

/// Contact table grid: lateral shift in [−y_max, y_max] by dy, roll in
/// [−roll_max, roll_max] by droll (m, rad).
#[derive(Debug, Clone, PartialEq)]
pub struct ContactTableSpec {
    pub y_max: f64,
    pub dy: f64,
    pub roll_max: f64,
    pub droll: f64,
}

/// A named force element.
#[derive(Debug, Clone, PartialEq)]
pub struct ForceElement {
    /// Long name, used in output variable names.
    pub name: String,
    pub kind: ForceKind,
}

/// An identifier of the model: a runtime input of both engines.
#[derive(Debug, Clone, PartialEq)]
pub struct Parameter {
    pub name: String,
    /// Default: an expression over other parameters (never `t`).
    pub default: Expr,
    /// Free text (units, meaning).
    pub doc: String,
}

/// A named set of assignments applied at once ("loaded", a wedge type...).
#[derive(Debug, Clone, PartialEq)]
pub struct Macro {
    pub name: String,
    /// (parameter index, new value expression).
    pub assignments: Vec<(usize, Expr)>,
}

/// A track-following frame (DESIGN.md): a frame moving along the track with
/// the vehicle, at arc position s(t) + `offset`. Its pose enters the equations as
/// six runtime inputs (x, y, z in SC0, then yaw, pitch, roll applied in that
/// order: Rz·Ry·Rx), so curves, transitions and cant add the right centrifugal and
/// gyroscopic terms in both engines without special cases.
#[derive(Debug, Clone, PartialEq)]
pub struct TrackFrame {
    /// The body whose joint starts with this frame.
    pub body: usize,
    /// Arc-length offset from the vehicle's reference position, m (positive
    /// ahead), expression over parameters.
    pub offset: Expr,
}

/// Pose components of a track-following frame, in input order.
pub const TRACK_FRAME_COMPONENTS: [&str; 6] = ["x", "y", "z", "yaw", "pitch", "roll"];

/// A resolved, validated model.
#[derive(Debug, Clone, PartialEq)]
pub struct Model {
    pub name: String,
    /// The file it was loaded from, when it came from a file.
    pub source: Option<PathBuf>,
    pub parameters: Vec<Parameter>,
    pub macros: Vec<Macro>,
    /// m/s², expressions over parameters. Default (0, 0, −9.81).
    pub gravity: [Expr; 3],
    /// Topologically sorted: a parent precedes its children.
    pub bodies: Vec<Body>,
    /// In order of appearance (body order, then elementary order).
    pub coordinates: Vec<Coordinate>,
    pub cut_joints: Vec<CutJoint>,
    pub forces: Vec<ForceElement>,
    /// Track-following frames; each supplies six runtime inputs.
    pub track_frames: Vec<TrackFrame>,
}
