//! Force elements of the model language (Pogorelov 2005, Sect. 3), one module
//! per element. A module owns its element's model syntax (a raw struct read
//! from RON), its resolution into a spec (names resolved, fields turned into
//! [`Expr`]s), its value checks (run with the file's default parameters when
//! it is resolved, and again with an including file's parameters after
//! subsystem overrides) and the traversal of its expressions and bodies.
//!
//! Adding an element: write its module with a raw type implementing
//! `ForceSyntax` and a spec type implementing `ForceSpec`, and add one line
//! to the registry below (which declares the module and re-exports its public
//! types here). The runtime builds its behaviour from the spec
//! (`railmbs_runtime::forces::build`, one line there too).

use crate::expr::Expr;
use crate::load::{Cx, Lookup, Where};
pub(crate) use crate::visit::body_ref;
use serde::de::{self, Deserialize, Deserializer, EnumAccess, MapAccess, VariantAccess, Visitor};
use std::fmt;

pub mod point_pair;
pub use point_pair::PointPair;

/// The model syntax of a force element: what a RON constructor
/// `Name(name: "…", …)` in a model's `forces` list deserializes to.
pub(crate) trait ForceSyntax {
    /// What the element resolves to.
    type Spec;
    /// The element's name as written.
    fn name(&self) -> &str;
    /// Resolves names and expressions, reporting problems through `cx` at `w`
    /// (value checks included: [`ForceSpec::check`] runs with the file's
    /// default parameters).
    fn resolve(&self, cx: &mut Cx, w: &Where, lookup: &Lookup) -> Self::Spec;
}

/// A resolved force element: its expressions and bodies, and the range
/// checks of its values.
pub(crate) trait ForceSpec {
    /// Calls `f` on every expression of the element.
    fn exprs_mut(&mut self, f: &mut dyn FnMut(&mut Expr));
    /// Calls `f` on every body index the element refers to (ground is not a
    /// body and is not visited).
    fn bodies_mut(&mut self, f: &mut dyn FnMut(&mut usize));
    /// The range checks of the element's values (a stiffness positive, a
    /// static friction not below the sliding one...) with the parameter
    /// values `c.params`: written once, used when the element is resolved and
    /// again after a subsystem's parameters are overridden.
    fn check(&self, c: &mut Checks);
}

impl<T: ForceSpec> ForceSpec for Box<T> {
    fn exprs_mut(&mut self, f: &mut dyn FnMut(&mut Expr)) {
        (**self).exprs_mut(f);
    }
    fn bodies_mut(&mut self, f: &mut dyn FnMut(&mut usize)) {
        (**self).bodies_mut(f);
    }
    fn check(&self, c: &mut Checks) {
        (**self).check(c);
    }
}

/// Collects the range problems of an element's values, each with the RON key
/// of the field it concerns.
pub(crate) struct Checks<'a> {
    params: &'a [f64],
    /// (RON key, message), in the order found.
    pub problems: Vec<(&'static str, String)>,
}

impl<'a> Checks<'a> {
    /// Checks with the parameter values `params`.
    pub fn new(params: &'a [f64]) -> Self {
        Self {
            params,
            problems: Vec::new(),
        }
    }

    /// The value of `e` at t = 0.
    pub fn value(&self, e: &Expr) -> f64 {
        e.eval(self.params, 0.0)
    }

    /// Records a problem with the field at `key`.
    pub fn push(&mut self, key: &'static str, message: String) {
        self.problems.push((key, message));
    }

    /// `e` > 0 (a stiffness), if it is finite.
    pub fn positive(&mut self, key: &'static str, e: &Expr) {
        let x = self.value(e);
        if x.is_finite() && x <= 0.0 {
            self.push(key, format!("{key} must be positive, got {x}"));
        }
    }

    /// `e` ≥ 0 (a damping), if it is finite.
    pub fn non_negative(&mut self, key: &'static str, e: &Expr) {
        let x = self.value(e);
        if x.is_finite() && x < 0.0 {
            self.push(key, format!("{key} must not be negative, got {x}"));
        }
    }

    /// 0 ≤ sliding ≤ static (friction coefficients or forces), where finite.
    pub fn friction(&mut self, key: &'static str, sliding: &Expr, key0: &str, stat: &Expr) {
        let (s, s0) = (self.value(sliding), self.value(stat));
        if s.is_finite() && s < 0.0 {
            self.push(key, format!("{key} must not be negative, got {s}"));
        } else if s.is_finite() && s0.is_finite() && s > s0 {
            self.push(key, format!("{key} = {s} must not exceed {key0} = {s0}"));
        }
    }
}

/// The registry: one line per element,
/// `mod module: Constructor => Variant(Spec) from Raw;`.
/// It defines [`ForceKind`], the raw enum read from RON and the list of
/// constructor names the locator uses, so that they cannot drift apart.
macro_rules! force_elements {
    ($( $(#[$doc:meta])* mod $module:ident: $ctor:ident => $variant:ident($spec:ty) from $raw:ident; )*) => {
        $(
            pub mod $module;
            pub use $module::*;
        )*

        /// Force elements of the model. The runtime computes their forces; the
        /// model only describes them. Each variant's fields are expressions
        /// over parameters (and `t` where stated).
        // The variants' sizes differ, but a model holds few force elements and
        // the layout is a contract shared by both engines.
        #[allow(clippy::large_enum_variant)]
        #[derive(Debug, Clone, PartialEq)]
        pub enum ForceKind {
            $( $(#[$doc])* $variant($spec), )*
        }

        impl ForceKind {
            /// The element's constructor name in model files (`Spring`, `WheelRail`…).
            pub fn constructor(&self) -> &'static str {
                match self {
                    $( ForceKind::$variant(_) => stringify!($ctor), )*
                }
            }

            /// Every expression of the force element.
            pub fn exprs_mut(&mut self, f: &mut dyn FnMut(&mut Expr)) {
                match self {
                    $( ForceKind::$variant(s) => s.exprs_mut(f), )*
                }
            }

            /// Every body index the element refers to (ground is not visited).
            pub fn bodies_mut(&mut self, f: &mut dyn FnMut(&mut usize)) {
                match self {
                    $( ForceKind::$variant(s) => s.bodies_mut(f), )*
                }
            }

            /// The body indices the element refers to, in visiting order
            /// (ground is not a body and is not listed).
            pub fn bodies(&self) -> Vec<usize> {
                let mut out = Vec::new();
                self.clone().bodies_mut(&mut |b| out.push(*b));
                out
            }
        }

        impl ForceSpec for ForceKind {
            fn exprs_mut(&mut self, f: &mut dyn FnMut(&mut Expr)) {
                ForceKind::exprs_mut(self, f);
            }
            fn bodies_mut(&mut self, f: &mut dyn FnMut(&mut usize)) {
                ForceKind::bodies_mut(self, f);
            }
            fn check(&self, c: &mut Checks) {
                match self {
                    $( ForceKind::$variant(s) => s.check(c), )*
                }
            }
        }

        /// A force element as written in a model file, before resolution.
        // Raw syntax lives only while a file is resolved; size does not matter.
        #[allow(clippy::large_enum_variant)]
        #[derive(Debug)]
        pub(crate) enum RawForce {
            $( $ctor($raw), )*
        }

        /// The RON constructor names of the force elements (for the locator
        /// and for "expected one of" messages).
        pub(crate) const CONSTRUCTORS: &[&str] = &[$( stringify!($ctor) ),*];

        impl RawForce {
            /// The element's name as written.
            pub(crate) fn name(&self) -> &str {
                match self {
                    $( RawForce::$ctor(r) => r.name(), )*
                }
            }

            /// Resolves the element (see [`ForceSyntax::resolve`]).
            pub(crate) fn resolve(&self, cx: &mut Cx, w: &Where, lookup: &Lookup) -> ForceKind {
                match self {
                    $( RawForce::$ctor(r) => ForceKind::$variant(r.resolve(cx, w, lookup)), )*
                }
            }

            /// Reads the fields of the element with constructor `ctor` from a
            /// RON enum variant (model files, and the couplers of train
            /// files); an unknown constructor is an error listing `expected`.
            pub(crate) fn from_variant<'de, A: VariantAccess<'de>>(
                ctor: &str,
                variant: A,
                expected: &'static [&'static str],
            ) -> Result<RawForce, A::Error> {
                match ctor {
                    $( stringify!($ctor) => variant
                        .struct_variant(&[], StructOf::<$raw>::default())
                        .map(RawForce::$ctor), )*
                    other => Err(de::Error::unknown_variant(other, expected)),
                }
            }
        }

        impl<'de> Deserialize<'de> for RawForce {
            fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
                struct V;
                impl<'de> Visitor<'de> for V {
                    type Value = RawForce;
                    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                        f.write_str("a force element")
                    }
                    fn visit_enum<A: EnumAccess<'de>>(self, data: A) -> Result<RawForce, A::Error> {
                        let (Constructor(ctor), variant) = data.variant()?;
                        RawForce::from_variant(&ctor, variant, CONSTRUCTORS)
                    }
                }
                d.deserialize_enum("Force", CONSTRUCTORS, V)
            }
        }
    };
}

force_elements! {
    /// Linear bipolar spring–damper between two points (Pogorelov 2005,
    /// Sect. 3.1), see [`Bipolar`].
    mod bipolar: Spring => Bipolar(Bipolar) from RawSpring;
    /// Spring in series with a damper between two points (Pogorelov 2005,
    /// Sect. 3.1), see [`SeriesSpringDamper`].
    mod series_spring: SeriesSpring => SeriesSpringDamper(SeriesSpringDamper) from RawSeriesSpring;
    /// Generalized linear 6×6 element (Pogorelov 2005, Sect. 3.2), see [`Linear6`].
    mod linear6: Linear6 => Linear6(Linear6) from RawLinear6;
    /// Point–plane contact (Pogorelov 2005, Sect. 3.3), see [`PointPlane`].
    mod point_plane: PointPlane => PointPlane(PointPlane) from RawPointPlane;
    /// Bipolar Coulomb friction (Pogorelov 2005, Sect. 3.1), see [`Coulomb`].
    mod coulomb: Coulomb => Coulomb(Coulomb) from RawCoulomb;
    /// Load-dependent friction (Pogorelov 2005, Sect. 3.1, Fig. 3), see
    /// [`LoadFriction`].
    mod load_friction: LoadFriction => LoadFriction(LoadFriction) from RawLoadFriction;
    /// Tabulated force–deflection characteristic, see [`Tabulated`].
    mod tabulated: Tabulated => Tabulated(Tabulated) from RawTabulated;
    /// Wheel–rail contact of a wheelset on the scenario's track (Pogorelov
    /// 2005, Sect. 4), see [`WheelRail`].
    mod wheel_rail: WheelRail => WheelRail(Box<WheelRail>) from RawWheelRail;
    /// An applied force and torque on one body, see [`Applied`].
    mod applied: Applied => Applied(Applied) from RawApplied;
    /// Torsion spring–damper about an axis, see [`TorsionSpring`].
    mod torsion_spring: TorsionSpring => TorsionSpring(TorsionSpring) from RawTorsionSpring;
}

/// A RON constructor name (an identifier, so that RON records it for its
/// error messages).
pub(crate) struct Constructor(pub(crate) String);

impl<'de> Deserialize<'de> for Constructor {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        struct V;
        impl Visitor<'_> for V {
            type Value = Constructor;
            fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
                f.write_str("a force element's constructor name")
            }
            fn visit_str<E: de::Error>(self, v: &str) -> Result<Constructor, E> {
                Ok(Constructor(v.to_string()))
            }
        }
        d.deserialize_identifier(V)
    }
}

/// Reads a struct variant's fields into the raw struct `T` (which carries the
/// field list, defaults and `deny_unknown_fields` itself).
pub(crate) struct StructOf<T>(std::marker::PhantomData<T>);

impl<T> Default for StructOf<T> {
    fn default() -> Self {
        StructOf(std::marker::PhantomData)
    }
}

impl<'de, T: Deserialize<'de>> Visitor<'de> for StructOf<T> {
    type Value = T;
    fn expecting(&self, f: &mut fmt::Formatter) -> fmt::Result {
        f.write_str("the fields of a force element")
    }
    fn visit_map<A: MapAccess<'de>>(self, map: A) -> Result<T, A::Error> {
        T::deserialize(de::value::MapAccessDeserializer::new(map))
    }
}
