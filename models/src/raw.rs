//! The RON syntax of model files as serde types, before resolution: names are
//! still strings and numeric fields are numbers or expression text.

use crate::model::{Axis, CreepLawSpec, Interpolation};
use serde::de::{self, Deserializer, MapAccess, Visitor};
use serde::{Deserialize, de::IgnoredAny};
use std::fmt;

/// A numeric field: a number or expression text.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum Value {
    Num(f64),
    Text(String),
}

impl Default for Value {
    fn default() -> Self {
        Value::Num(0.0)
    }
}

/// A number (the defaults of `CreepLawSpec`'s settings).
impl From<f64> for Value {
    fn from(x: f64) -> Self {
        Value::Num(x)
    }
}

impl Value {
    pub(crate) fn is_literal_zero(&self) -> bool {
        matches!(self, Value::Num(x) if *x == 0.0)
    }
}

struct ValueVisitor;

impl<'de> Visitor<'de> for ValueVisitor {
    type Value = Value;
    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("a number or an expression string")
    }
    fn visit_i64<E: de::Error>(self, v: i64) -> Result<Value, E> {
        Ok(Value::Num(v as f64))
    }
    fn visit_u64<E: de::Error>(self, v: u64) -> Result<Value, E> {
        Ok(Value::Num(v as f64))
    }
    fn visit_i128<E: de::Error>(self, v: i128) -> Result<Value, E> {
        Ok(Value::Num(v as f64))
    }
    fn visit_u128<E: de::Error>(self, v: u128) -> Result<Value, E> {
        Ok(Value::Num(v as f64))
    }
    fn visit_f64<E: de::Error>(self, v: f64) -> Result<Value, E> {
        Ok(Value::Num(v))
    }
    fn visit_str<E: de::Error>(self, v: &str) -> Result<Value, E> {
        Ok(Value::Text(v.to_string()))
    }
    fn visit_string<E: de::Error>(self, v: String) -> Result<Value, E> {
        Ok(Value::Text(v))
    }
}

impl<'de> Deserialize<'de> for Value {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        d.deserialize_any(ValueVisitor)
    }
}

/// A map kept in file order, duplicates included (reported by the resolver).
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct OrderedMap<T>(pub Vec<(String, T)>);

impl<T> Default for OrderedMap<T> {
    fn default() -> Self {
        OrderedMap(Vec::new())
    }
}

impl<'de, T: Deserialize<'de>> Deserialize<'de> for OrderedMap<T> {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V<T>(std::marker::PhantomData<T>);
        impl<'de, T: Deserialize<'de>> Visitor<'de> for V<T> {
            type Value = OrderedMap<T>;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a map { \"name\": value, ... }")
            }
            fn visit_map<A: MapAccess<'de>>(self, mut m: A) -> Result<Self::Value, A::Error> {
                let mut out = Vec::new();
                while let Some((k, v)) = m.next_entry::<String, T>()? {
                    out.push((k, v));
                }
                Ok(OrderedMap(out))
            }
        }
        d.deserialize_map(V(std::marker::PhantomData))
    }
}

/// A parameter's default: a value, or `(value: …, doc: "…")`.
#[derive(Debug, Clone, PartialEq)]
pub(crate) struct ParamValue {
    pub value: Value,
    pub doc: String,
}

impl<'de> Deserialize<'de> for ParamValue {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = ParamValue;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a number, an expression string or (value: …, doc: \"…\")")
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<ParamValue, E> {
                Ok(plain(ValueVisitor.visit_i64(v)?))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<ParamValue, E> {
                Ok(plain(ValueVisitor.visit_u64(v)?))
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> Result<ParamValue, E> {
                Ok(plain(Value::Num(v)))
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<ParamValue, E> {
                Ok(plain(Value::Text(v.to_string())))
            }
            fn visit_map<A: MapAccess<'de>>(self, mut m: A) -> Result<ParamValue, A::Error> {
                let mut value = None;
                let mut doc = String::new();
                while let Some(key) = m.next_key::<String>()? {
                    match key.as_str() {
                        "value" => value = Some(m.next_value::<Value>()?),
                        "doc" => doc = m.next_value::<String>()?,
                        other => {
                            m.next_value::<IgnoredAny>()?;
                            return Err(de::Error::unknown_field(other, &["value", "doc"]));
                        }
                    }
                }
                let value = value.ok_or_else(|| de::Error::missing_field("value"))?;
                Ok(ParamValue { value, doc })
            }
        }
        fn plain(value: Value) -> ParamValue {
            ParamValue {
                value,
                doc: String::new(),
            }
        }
        d.deserialize_any(V)
    }
}

pub(crate) type Vec3 = (Value, Value, Value);
pub(crate) type Vec6 = (Value, Value, Value, Value, Value, Value);

pub(crate) fn zero3() -> Vec3 {
    Default::default()
}

fn default_gravity() -> Vec3 {
    (Value::Num(0.0), Value::Num(0.0), Value::Num(-9.81))
}

/// An optional number or expression written plainly (no `Some(...)`).
fn some_value<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Option<Value>, D::Error> {
    Value::deserialize(d).map(Some)
}

fn ground_name() -> String {
    "ground".into()
}

pub(crate) fn unit_z() -> Vec3 {
    (Value::Num(0.0), Value::Num(0.0), Value::Num(1.0))
}

fn zero_matrix() -> RawMatrix6 {
    RawMatrix6::Diag(Default::default())
}

#[derive(Debug, Deserialize)]
#[serde(rename = "Model", deny_unknown_fields)]
pub(crate) struct RawModel {
    pub name: String,
    #[serde(default)]
    #[allow(dead_code)]
    pub description: String,
    #[serde(default)]
    pub parameters: OrderedMap<ParamValue>,
    #[serde(default)]
    pub macros: OrderedMap<OrderedMap<Value>>,
    #[serde(default = "default_gravity")]
    pub gravity: Vec3,
    pub bodies: Vec<RawBody>,
    #[serde(default)]
    pub cut_joints: Vec<RawCutJoint>,
    #[serde(default)]
    pub forces: Vec<RawForce>,
    #[serde(default)]
    pub subsystems: Vec<RawSubsystem>,
    #[serde(default)]
    pub connections: OrderedMap<RawConnection>,
}

/// An included subsystem: another model file under an instance name.
#[derive(Debug, Deserialize)]
#[serde(rename = "Subsystem", deny_unknown_fields)]
pub(crate) struct RawSubsystem {
    pub name: String,
    /// Relative to the including file.
    pub file: String,
    /// Overrides of the subsystem's parameters, in the includer's namespace.
    #[serde(default)]
    pub parameters: OrderedMap<Value>,
    /// Body of the includer that the subsystem's ground-attached bodies hang on.
    #[serde(default, deserialize_with = "some_string")]
    pub parent: Option<String>,
}

/// A named connection point: a point fixed to a body.
#[derive(Debug, Deserialize)]
#[serde(rename = "Connection", deny_unknown_fields)]
pub(crate) struct RawConnection {
    pub body: String,
    #[serde(default = "zero3")]
    pub point: Vec3,
}

/// An optional string written plainly (no `Some(...)`).
fn some_string<'de, D: serde::Deserializer<'de>>(d: D) -> Result<Option<String>, D::Error> {
    String::deserialize(d).map(Some)
}

#[derive(Debug, Deserialize)]
#[serde(rename = "Body", deny_unknown_fields)]
pub(crate) struct RawBody {
    pub name: String,
    pub mass: Value,
    pub inertia: RawInertia,
    pub joint: RawJoint,
}

#[derive(Debug, Deserialize)]
#[serde(rename = "Inertia", deny_unknown_fields)]
pub(crate) struct RawInertia {
    pub ixx: Value,
    pub iyy: Value,
    pub izz: Value,
    #[serde(default)]
    pub ixy: Value,
    #[serde(default)]
    pub ixz: Value,
    #[serde(default)]
    pub iyz: Value,
}

#[derive(Debug, Deserialize)]
#[serde(rename = "Joint", deny_unknown_fields)]
pub(crate) enum RawJoint {
    Revolute {
        parent: String,
        #[serde(default = "zero3")]
        at: Vec3,
        axis: Axis,
        #[serde(default)]
        coord: String,
        #[serde(default)]
        init: Value,
        #[serde(default)]
        vel: Value,
        #[serde(default = "zero3")]
        to_com: Vec3,
    },
    Prismatic {
        parent: String,
        #[serde(default = "zero3")]
        at: Vec3,
        axis: Axis,
        #[serde(default)]
        coord: String,
        #[serde(default)]
        init: Value,
        #[serde(default)]
        vel: Value,
        #[serde(default = "zero3")]
        to_com: Vec3,
    },
    SixDof {
        parent: String,
        #[serde(default = "zero3")]
        at: Vec3,
        #[serde(default = "default_order")]
        order: String,
        #[serde(default)]
        init: Vec6,
        #[serde(default)]
        vel: Vec6,
        /// Attach the body to a track-following frame at this arc offset (m):
        /// the joint then starts with the frame's six input transformations.
        #[serde(default)]
        track: Option<Value>,
    },
    Rigid {
        parent: String,
        #[serde(default = "zero3")]
        at: Vec3,
        #[serde(default = "zero3")]
        rotation: Vec3,
        /// Fix the body to a track-following frame at this arc offset (m).
        #[serde(default)]
        track: Option<Value>,
    },
    Joint {
        parent: String,
        transforms: Vec<RawTransform>,
    },
}

fn default_order() -> String {
    "xyz".to_string()
}

impl RawJoint {
    pub(crate) fn parent(&self) -> &str {
        match self {
            RawJoint::Revolute { parent, .. }
            | RawJoint::Prismatic { parent, .. }
            | RawJoint::SixDof { parent, .. }
            | RawJoint::Rigid { parent, .. }
            | RawJoint::Joint { parent, .. } => parent,
        }
    }
}

/// An elementary transformation's argument: a value (fixed, or rheonomic if it
/// uses `t`) or a generalized coordinate.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum TransformArg {
    Value(Value),
    Coord {
        coord: String,
        init: Value,
        vel: Value,
    },
}

impl<'de> Deserialize<'de> for TransformArg {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = TransformArg;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a number, an expression string or (coord: \"name\", init: …, vel: …)")
            }
            fn visit_i64<E: de::Error>(self, v: i64) -> Result<TransformArg, E> {
                Ok(TransformArg::Value(ValueVisitor.visit_i64(v)?))
            }
            fn visit_u64<E: de::Error>(self, v: u64) -> Result<TransformArg, E> {
                Ok(TransformArg::Value(ValueVisitor.visit_u64(v)?))
            }
            fn visit_f64<E: de::Error>(self, v: f64) -> Result<TransformArg, E> {
                Ok(TransformArg::Value(Value::Num(v)))
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<TransformArg, E> {
                Ok(TransformArg::Value(Value::Text(v.to_string())))
            }
            fn visit_map<A: MapAccess<'de>>(self, mut m: A) -> Result<TransformArg, A::Error> {
                let mut coord = None;
                let mut init = Value::default();
                let mut vel = Value::default();
                while let Some(key) = m.next_key::<String>()? {
                    match key.as_str() {
                        "coord" => coord = Some(m.next_value::<String>()?),
                        "init" => init = m.next_value::<Value>()?,
                        "vel" => vel = m.next_value::<Value>()?,
                        other => {
                            m.next_value::<IgnoredAny>()?;
                            return Err(de::Error::unknown_field(other, &["coord", "init", "vel"]));
                        }
                    }
                }
                let coord = coord.ok_or_else(|| de::Error::missing_field("coord"))?;
                Ok(TransformArg::Coord { coord, init, vel })
            }
        }
        d.deserialize_any(V)
    }
}

#[derive(Debug, Deserialize)]
#[serde(rename = "Transform")]
pub(crate) enum RawTransform {
    Tx(TransformArg),
    Ty(TransformArg),
    Tz(TransformArg),
    Rx(TransformArg),
    Ry(TransformArg),
    Rz(TransformArg),
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Deserialize)]
#[serde(rename = "Component")]
pub(crate) enum RawComponent {
    Tx,
    Ty,
    Tz,
    Rx,
    Ry,
    Rz,
}

#[derive(Debug, Deserialize)]
#[serde(rename = "CutJoint", deny_unknown_fields)]
pub(crate) struct RawCutJoint {
    pub name: String,
    pub body1: String,
    #[serde(default = "zero3")]
    pub point1: Vec3,
    #[serde(default = "zero3")]
    pub rotation1: Vec3,
    pub body2: String,
    #[serde(default = "zero3")]
    pub point2: Vec3,
    #[serde(default = "zero3")]
    pub rotation2: Vec3,
    pub constrain: Vec<RawComponent>,
}

#[derive(Debug, Deserialize)]
#[serde(rename = "Matrix6")]
pub(crate) enum RawMatrix6 {
    Diag(Vec6),
    Full(Vec<Value>),
    /// A coil spring between its lower and upper plates (frames at the lower
    /// plate): vertical, shear, bending and torsion stiffness (or damping)
    /// and the height.
    VerticalSpring {
        vertical: Value,
        shear: Value,
        bending: Value,
        torsion: Value,
        height: Value,
    },
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
#[serde(rename = "Frame")]
pub(crate) enum RawFrame {
    #[default]
    Global,
    Body,
}

// Raw syntax lives only while a file is resolved; size does not matter.
#[allow(clippy::large_enum_variant)]
#[derive(Debug, Deserialize)]
#[serde(rename = "Force", deny_unknown_fields)]
pub(crate) enum RawForce {
    Spring {
        name: String,
        body1: String,
        #[serde(default = "zero3")]
        point1: Vec3,
        body2: String,
        #[serde(default = "zero3")]
        point2: Vec3,
        c: Value,
        #[serde(default)]
        d: Value,
        #[serde(default)]
        f0: Value,
        #[serde(default)]
        x0: Value,
    },
    SeriesSpring {
        name: String,
        body1: String,
        #[serde(default = "zero3")]
        point1: Vec3,
        body2: String,
        #[serde(default = "zero3")]
        point2: Vec3,
        c: Value,
        d: Value,
        #[serde(default)]
        f0: Value,
    },
    Linear6 {
        name: String,
        body1: String,
        #[serde(default = "zero3")]
        point1: Vec3,
        #[serde(default = "zero3")]
        rotation1: Vec3,
        body2: String,
        #[serde(default = "zero3")]
        point2: Vec3,
        #[serde(default = "zero3")]
        rotation2: Vec3,
        stiffness: RawMatrix6,
        #[serde(default = "zero_matrix")]
        damping: RawMatrix6,
        #[serde(default)]
        preload: Vec6,
    },
    PointPlane {
        name: String,
        body: String,
        points: Vec<Vec3>,
        #[serde(default = "ground_name")]
        plane_body: String,
        #[serde(default = "zero3")]
        origin: Vec3,
        #[serde(default = "unit_z")]
        normal: Vec3,
        #[serde(default, deserialize_with = "some_value")]
        surface: Option<Value>,
        c: Value,
        #[serde(default)]
        d: Value,
        #[serde(default, deserialize_with = "some_value")]
        ct: Option<Value>,
        #[serde(default, deserialize_with = "some_value")]
        dt: Option<Value>,
        #[serde(default, deserialize_with = "some_value")]
        mu0: Option<Value>,
        #[serde(default)]
        mu: Value,
    },
    Coulomb {
        name: String,
        body1: String,
        #[serde(default = "zero3")]
        point1: Vec3,
        body2: String,
        #[serde(default = "zero3")]
        point2: Vec3,
        c: Value,
        #[serde(default)]
        d: Value,
        limit: Value,
        #[serde(default, deserialize_with = "some_value")]
        sliding: Option<Value>,
    },
    LoadFriction {
        name: String,
        body1: String,
        #[serde(default = "zero3")]
        point1: Vec3,
        body2: String,
        #[serde(default = "zero3")]
        point2: Vec3,
        c1: Value,
        c2: Value,
        #[serde(default, deserialize_with = "some_value")]
        mu0: Option<Value>,
        mu: Value,
        #[serde(default)]
        x0: Value,
    },
    Tabulated {
        name: String,
        body1: String,
        #[serde(default = "zero3")]
        point1: Vec3,
        body2: String,
        #[serde(default = "zero3")]
        point2: Vec3,
        table: Vec<(Value, Value)>,
        #[serde(default)]
        interpolation: Interpolation,
        #[serde(default)]
        d: Value,
        #[serde(default)]
        x0: Value,
    },
    WheelRail {
        name: String,
        wheelset: String,
        wheel_profile: String,
        #[serde(default)]
        wheel_profile_right: Option<String>,
        rail_profile: String,
        #[serde(default)]
        rail_profile_right: Option<String>,
        #[serde(default)]
        rail_profile_inclined: bool,
        radius: Value,
        #[serde(default = "default_back_to_back")]
        flange_back_distance: Value,
        #[serde(default = "default_taping_offset")]
        taping_offset: Value,
        #[serde(default = "default_mu")]
        mu: Value,
        #[serde(default = "default_young")]
        young: Value,
        #[serde(default = "default_poisson")]
        poisson: Value,
        #[serde(default)]
        normal_damping: Value,
        #[serde(default)]
        creep: CreepLawSpec<Value>,
        #[serde(default)]
        rail: RawRail,
        #[serde(default)]
        table: RawTable,
        /// Independently rotating wheels: the bodies (left, right) carrying
        /// each wheel's spin; `None` for a solid wheelset.
        #[serde(default)]
        wheels: Option<(String, String)>,
    },
    Applied {
        name: String,
        body: String,
        #[serde(default = "zero3")]
        point: Vec3,
        #[serde(default = "zero3")]
        force: Vec3,
        #[serde(default = "zero3")]
        torque: Vec3,
        #[serde(default)]
        frame: RawFrame,
    },
}

impl RawForce {
    pub(crate) fn name(&self) -> &str {
        match self {
            RawForce::Spring { name, .. }
            | RawForce::Linear6 { name, .. }
            | RawForce::Applied { name, .. }
            | RawForce::PointPlane { name, .. }
            | RawForce::Coulomb { name, .. }
            | RawForce::SeriesSpring { name, .. }
            | RawForce::LoadFriction { name, .. }
            | RawForce::Tabulated { name, .. }
            | RawForce::WheelRail { name, .. } => name,
        }
    }
}

fn default_back_to_back() -> Value {
    Value::Num(1.360)
}

fn default_taping_offset() -> Value {
    Value::Num(0.070)
}

fn default_mu() -> Value {
    Value::Num(0.4)
}

fn default_young() -> Value {
    Value::Num(2.1e11)
}

fn default_poisson() -> Value {
    Value::Num(0.28)
}

/// Rails of a `WheelRail` element.
#[derive(Debug, Default, Deserialize)]
#[serde(rename = "Rail")]
pub(crate) enum RawRail {
    #[default]
    Rigid,
    Elastic {
        ky: Value,
        #[serde(default)]
        cy: Value,
        kz: Value,
        #[serde(default)]
        cz: Value,
    },
}

/// Contact table grid of a `WheelRail` element (m, rad).
#[derive(Debug, Deserialize)]
#[serde(rename = "Table", deny_unknown_fields)]
pub(crate) struct RawTable {
    #[serde(default = "default_table_y_max")]
    pub y_max: f64,
    #[serde(default = "default_table_dy")]
    pub dy: f64,
    #[serde(default = "default_table_roll_max")]
    pub roll_max: f64,
    #[serde(default = "default_table_droll")]
    pub droll: f64,
}

impl Default for RawTable {
    fn default() -> Self {
        RawTable {
            y_max: default_table_y_max(),
            dy: default_table_dy(),
            roll_max: default_table_roll_max(),
            droll: default_table_droll(),
        }
    }
}

fn default_table_y_max() -> f64 {
    0.025
}

fn default_table_dy() -> f64 {
    0.1e-3
}

fn default_table_roll_max() -> f64 {
    0.03
}

fn default_table_droll() -> f64 {
    2e-3
}
