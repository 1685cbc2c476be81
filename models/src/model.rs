//! The resolved, validated model: what the numeric engine (`runtime`) and the
//! symbolic engine (`codegen`) consume. Produced by [`crate::load_model`] from a
//! RON file; every name is resolved to an index and every numeric field is an
//! [`Expr`] over the model's identifiers (parameters) and, where allowed, time.
//!
//! Conventions (see docs/design.md): SI units; a body frame has its origin at the
//! body's centre of mass; a joint is an ordered list of elementary
//! transformations from the parent's body frame to the child's body frame.

use crate::expr::Expr;
pub use crate::forces::{
    ContactModel, ContactTableSpec, ForceKind, ProfileFile, RailKind, WheelRail,
};
pub use railmbs_wheelrail::creep::{CreepLawSpec, SlidingZone};
use std::path::PathBuf;

/// Axis of an elementary transformation or a vector component.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash, serde::Serialize, serde::Deserialize)]
pub enum Axis {
    /// The x axis (component 0).
    X,
    /// The y axis (component 1).
    Y,
    /// The z axis (component 2).
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
    /// `Tx`, `Ty`, `Tz`: translation along the axis (m).
    Translation(Axis),
    /// `Rx`, `Ry`, `Rz`: rotation about the axis (rad, right-handed).
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
    /// Translation or rotation, and along or about which axis.
    pub kind: ElementaryKind,
    /// Its amount (m or rad): fixed, a coordinate, a function of time or a
    /// runtime input.
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
    /// Origin in the body frame (SC0 for ground), m.
    pub origin: [Expr; 3],
    /// Rotation angles about x, then y, then z of the moving frame, rad.
    pub rotation_xyz: [Expr; 3],
}

/// A relative-pose component that a cut joint constrains, measured in frame 1.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Hash)]
pub enum Component {
    /// Translation along x of frame 1, m.
    Tx,
    /// Translation along y of frame 1, m.
    Ty,
    /// Translation along z of frame 1, m.
    Tz,
    /// Small rotation about x of frame 1, rad.
    Rx,
    /// Small rotation about y of frame 1, rad.
    Ry,
    /// Small rotation about z of frame 1, rad.
    Rz,
}

/// A cut joint closing a kinematic loop: the constrained components of the
/// pose of `frame2` on `body2` relative to `frame1` on `body1` are zero.
/// Translational components: (r₂ − r₁)·e_k(frame 1). Rotational components:
/// the antisymmetric part of R = A₁ᵀA₂, g_x = (R_zy − R_yz)/2 etc. (equal to the
/// small relative rotation angle).
#[derive(Debug, Clone, PartialEq)]
pub struct CutJoint {
    /// Long name (with subsystem prefix).
    pub name: String,
    /// The first body (or ground).
    pub body1: BodyRef,
    /// Frame 1, fixed to `body1` (`point1`, `rotation1`); the components are
    /// measured in its axes.
    pub frame1: Frame,
    /// The second body (or ground).
    pub body2: BodyRef,
    /// Frame 2, fixed to `body2` (`point2`, `rotation2`).
    pub frame2: Frame,
    /// The constrained components (`constrain`), in file order, each once
    /// and at least one.
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

/// A named force element.
#[derive(Debug, Clone, PartialEq)]
pub struct ForceElement {
    /// Long name, used in output variable names.
    pub name: String,
    /// The element type and its resolved fields.
    pub kind: ForceKind,
}

/// An identifier of the model: a runtime input of both engines.
#[derive(Debug, Clone, PartialEq)]
pub struct Parameter {
    /// Long name (with subsystem prefix, e.g. `Bogie1.WS2.m`), as used in
    /// expressions and scenario overrides.
    pub name: String,
    /// Default: an expression over other parameters (never `t`).
    pub default: Expr,
    /// Free text (meaning, then the unit after the last comma: "car body
    /// mass, kg"; see [`Parameter::unit`]).
    pub doc: String,
}

impl Parameter {
    /// The unit the doc text gives after a `", "` (the last such that is a
    /// unit), before an optional remark (`" (…"`, `": …"` or `", …"`): "N
    /// s/m" of "primary lateral damping, N s/m (choice)", "m" of "initial
    /// sinking, m: the static position …, so runs start near equilibrium";
    /// a doc of a unit alone is that unit. Only SI-style symbols are taken for units
    /// (`kg m2`, `N/m`, `m/s2`, `N m/rad`, `1/m`, …; see [`is_unit`]); `None`
    /// if the doc gives none (a dimensionless parameter, or no doc).
    pub fn unit(&self) -> Option<&str> {
        let doc = self.doc.as_str();
        // After a ", ", the last first; then the whole doc.
        let mut starts: Vec<usize> = doc.match_indices(", ").map(|(i, _)| i + 2).collect();
        starts.reverse();
        starts.push(0);
        starts.into_iter().find_map(|start| {
            let tail = &doc[start..];
            let end = [tail.find(" ("), tail.find(':'), tail.find(',')]
                .into_iter()
                .flatten()
                .min()
                .unwrap_or(tail.len());
            let unit = tail[..end].trim();
            is_unit(unit).then_some(unit)
        })
    }
}

/// Whether `text` is a unit written with SI symbols: words separated by
/// spaces (a product), each a `/`-separated chain of symbols (`m`, `kg`,
/// `s`, `N`, `rad`, `Pa`, …) with an optional power (`2`, `3`, `²`, `³`), or
/// `1` before a `/` (`1/m`).
pub fn is_unit(text: &str) -> bool {
    const SYMBOLS: [&str; 20] = [
        "m", "mm", "km", "kg", "t", "g", "s", "h", "min", "N", "kN", "rad", "deg", "Pa", "MPa",
        "GPa", "Hz", "W", "J", "K",
    ];
    let atom = |a: &str| {
        let base = a.trim_end_matches(['2', '3', '4', '²', '³', '⁴']);
        SYMBOLS.contains(&base)
    };
    !text.is_empty()
        && text.split(' ').all(|word| {
            let mut parts = word.split('/');
            let first = parts.next().unwrap_or("");
            (atom(first) || (first == "1" && word.contains('/'))) && parts.all(atom)
        })
}

/// A named set of assignments applied at once ("loaded", a wedge type...).
#[derive(Debug, Clone, PartialEq)]
pub struct Macro {
    /// Long name (with subsystem prefix, e.g. `Bogie1.WS2.worn`).
    pub name: String,
    /// (parameter index, new value expression).
    pub assignments: Vec<(usize, Expr)>,
}

/// A track-following frame (docs/design.md): a frame moving along the track with
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
    /// The `name` of the top model file (included files' names are ignored).
    pub name: String,
    /// The file it was loaded from, when it came from a file.
    pub source: Option<PathBuf>,
    /// The identifiers, indexed by [`Expr::Param`]: the file's own in file
    /// order, then each subsystem's (recursively) in the order of `subsystems`.
    pub parameters: Vec<Parameter>,
    /// Named sets of assignments, the file's own, then the subsystems'.
    pub macros: Vec<Macro>,
    /// m/s², expressions over parameters. Default (0, 0, −9.81).
    pub gravity: [Expr; 3],
    /// Topologically sorted: a parent precedes its children.
    pub bodies: Vec<Body>,
    /// In order of appearance (body order, then elementary order).
    pub coordinates: Vec<Coordinate>,
    /// Loop-closing constraints, the file's own, then the subsystems'.
    pub cut_joints: Vec<CutJoint>,
    /// Force elements, the file's own, then the subsystems'.
    pub forces: Vec<ForceElement>,
    /// Track-following frames; each supplies six runtime inputs.
    pub track_frames: Vec<TrackFrame>,
}
