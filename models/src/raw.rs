//! The RON syntax of model files as serde types, before resolution: names are
//! still strings and numeric fields are numbers or expression text.

use crate::forces::RawForce;
use crate::model::Axis;
use serde::de::{self, Deserializer, MapAccess, Visitor};
use serde::{Deserialize, de::IgnoredAny};
use std::fmt;

/// A numeric field: a number or expression text.
#[derive(Debug, Clone, PartialEq)]
pub enum Value {
    /// A number.
    Num(f64),
    /// Expression text.
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
pub struct OrderedMap<T>(pub Vec<(String, T)>);

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
pub(crate) fn some_value<'de, D: serde::Deserializer<'de>>(
    d: D,
) -> Result<Option<Value>, D::Error> {
    Value::deserialize(d).map(Some)
}

pub(crate) fn ground_name() -> String {
    "ground".into()
}

pub(crate) fn unit_z() -> Vec3 {
    (Value::Num(0.0), Value::Num(0.0), Value::Num(1.0))
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
