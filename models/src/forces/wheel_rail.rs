//! `WheelRail`: wheel–rail contact of a wheelset on the scenario's track
//! (Pogorelov 2005, Sect. 4).

use super::{Checks, ForceSpec, ForceSyntax};
use crate::expr::Expr;
use crate::load::{Cx, Lookup, Where};
use crate::model::BodyRef;
use crate::raw::Value;
use railmbs_wheelrail::creep::CreepLawSpec;
use railmbs_wheelrail::elastic_rail::LateralDamping;
use railmbs_wheelrail::profile::{Profile, ProfileKind, ProfilePoints, ProfileSettings, read_points};
use serde::Deserialize;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// Wheel–rail contact of a wheelset on the scenario's track (Pogorelov 2005,
/// Sect. 4): left and right wheel against their rails, contact geometry
/// from a table over lateral shift and roll, Hertzian normal force, creep
/// forces by the chosen law. The wheelset body's frame has its origin at
/// the axle centre and its y axis along the axle (to the left); its spin
/// about y may be a coordinate or not (then the wheels' rolling speed is
/// that of the body's angular velocity anyway).
#[derive(Clone, PartialEq)]
pub struct WheelRail {
    /// The wheelset body.
    pub wheelset: usize,
    /// Wheel profiles (left, right; the right one mirrored when placed),
    /// read when the model is loaded.
    pub wheel_profiles: [ProfileFile; 2],
    /// Rail profiles (left, right), read when the model is loaded. The
    /// track's rail inclination is applied when they are placed on the
    /// scenario's track, unless `rail_profiles_inclined`.
    pub rail_profiles: [ProfileFile; 2],
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
    /// The creep-force law and its settings (expressions over parameters);
    /// used by the Hertz contact only (see [`ContactModel`]).
    pub creep: CreepLawSpec<Expr>,
    /// The contact model: Hertz (default) or non-elliptic Kik–Piotrowski.
    pub contact: ContactModel,
    /// Rigid rails, or massless elastic rails (Pogorelov 2005, Sect. 4.2).
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

/// The field list of the derived form, with `contact` only where it is not
/// the default Hertz: the model's structural text
/// ([`crate::Model::canonical_structure`], the compiled plugin's key) of the
/// models written before the contact model could be chosen stays the same
/// (the plugin does not depend on it: the runtime evaluates the contact).
impl std::fmt::Debug for WheelRail {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let mut d = f.debug_struct("WheelRail");
        d.field("wheelset", &self.wheelset)
            .field("wheel_profiles", &self.wheel_profiles)
            .field("rail_profiles", &self.rail_profiles)
            .field("rail_profiles_inclined", &self.rail_profiles_inclined)
            .field("radius", &self.radius)
            .field("flange_back_distance", &self.flange_back_distance)
            .field("taping_offset", &self.taping_offset)
            .field("mu", &self.mu)
            .field("young", &self.young)
            .field("poisson", &self.poisson)
            .field("normal_damping", &self.normal_damping)
            .field("creep", &self.creep);
        if self.contact != ContactModel::Hertz {
            d.field("contact", &self.contact);
        }
        d.field("rail", &self.rail)
            .field("table", &self.table)
            .field("wheels", &self.wheels)
            .finish()
    }
}

/// The contact model of a wheel–rail element (`contact:`).
#[derive(Debug, Clone, PartialEq)]
pub enum ContactModel {
    /// Hertz: per contact point an elliptic patch from the curvatures there,
    /// the normal force from the approach, the creep forces by `creep`
    /// (default).
    Hertz,
    /// Non-elliptic patches by the modified Kik–Piotrowski method
    /// ([`railmbs_wheelrail::kik_piotrowski`]): from the virtual penetration
    /// of the profiles, any number per wheel, the normal force from the
    /// approach over the patch (Boussinesq), the tangential forces by strips
    /// on the patch (the `creep` law is not used).
    KikPiotrowski {
        /// Penetration-reduction factor ε (–), in (0, 1] (default 0.55).
        penetration_reduction: Expr,
        /// Width of the patches' strips, the sampling step of the gap
        /// across the wheel profile (m; default 1e-4, at most 1e-3).
        strip_width: f64,
    },
}

/// A wheel or rail profile file of a wheel–rail element, read, parsed and
/// validated when the model is loaded: its points, and their smoothing with
/// the default settings, are known to be valid. Elements naming the same file
/// share the points (a file included several times is loaded once).
#[derive(Clone, PartialEq)]
pub struct ProfileFile {
    /// The file, canonical (absolute): the resolved model does not depend on
    /// the working directory, nor on which file included the element.
    pub path: PathBuf,
    /// Its points as read (library convention, m; see
    /// [`railmbs_wheelrail::profile`]), before smoothing and before a rail
    /// inclination is applied.
    pub points: Arc<ProfilePoints>,
}

impl ProfileFile {
    /// Reads and validates the `kind` profile at `path` (canonical): the
    /// points, and their smoothing with the default settings (the wheels'
    /// profile as the contact uses it; a rail's before its inclination).
    pub fn read(path: PathBuf, kind: ProfileKind) -> Result<Self, String> {
        let points = read_points(&path, kind).map_err(|e| e.to_string())?;
        Profile::from_points(&points, &ProfileSettings::default()).map_err(|e| e.to_string())?;
        Ok(ProfileFile {
            path,
            points: Arc::new(points),
        })
    }

    /// A file that could not be read: no points (stands in for it while the
    /// other problems of the model are collected; never in a loaded model).
    fn missing(path: PathBuf, kind: ProfileKind) -> Self {
        let points = ProfilePoints {
            kind,
            name: path.display().to_string(),
            points: Vec::new(),
        };
        ProfileFile {
            path,
            points: Arc::new(points),
        }
    }
}

/// The path alone: the model's structural text
/// ([`crate::Model::canonical_structure`]) names profiles by file, as the
/// compiled plugin does not depend on their content (the wheel–rail forces
/// are evaluated by the runtime).
impl std::fmt::Debug for ProfileFile {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        self.path.fmt(f)
    }
}

/// The rails of a wheel–rail element.
#[derive(Debug, Clone, PartialEq)]
pub enum RailKind {
    /// Rails fixed to the track.
    Rigid,
    /// Massless rail heads on lateral and vertical spring–dampers (per rail):
    /// N/m, N s/m.
    Elastic {
        /// Lateral stiffness, N/m (positive).
        ky: Expr,
        /// Lateral damping, N s/m (default 0).
        cy: Expr,
        /// Vertical stiffness, N/m (positive).
        kz: Expr,
        /// Vertical damping, N s/m (default 0).
        cz: Expr,
        /// When the lateral damping acts: `Always` (default) or
        /// `TwoPointContact` (Pogorelov 2005, Sect. 4.2).
        lateral_damping: LateralDamping,
    },
}

/// Contact table grid: lateral shift in [−y_max, y_max] by dy, roll in
/// [−roll_max, roll_max] by droll (m, rad).
#[derive(Debug, Clone, PartialEq)]
pub struct ContactTableSpec {
    /// Largest lateral shift of the wheelset, m (default 0.025).
    pub y_max: f64,
    /// Lateral step, m (default 1e-4).
    pub dy: f64,
    /// Largest roll, rad (default 0.03; 0 allowed).
    pub roll_max: f64,
    /// Roll step, rad (default 2e-3).
    pub droll: f64,
}

/// `WheelRail(name, wheelset, wheel_profile, …, creep, rail, table, wheels)`.
#[derive(Debug, Deserialize)]
#[serde(rename = "WheelRail", deny_unknown_fields)]
pub(crate) struct RawWheelRail {
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
    /// `None` where not given (the Hertz contact's default law); with
    /// `contact: KikPiotrowski(..)` it must not be given.
    #[serde(default, deserialize_with = "given")]
    creep: Option<CreepLawSpec<Value>>,
    #[serde(default)]
    contact: RawContact,
    #[serde(default)]
    rail: RawRail,
    #[serde(default)]
    table: RawTable,
    /// Independently rotating wheels: the bodies (left, right) carrying
    /// each wheel's spin; `None` for a solid wheelset.
    #[serde(default)]
    wheels: Option<(String, String)>,
}

impl ForceSyntax for RawWheelRail {
    type Spec = Box<WheelRail>;
    fn name(&self) -> &str {
        &self.name
    }
    fn resolve(&self, cx: &mut Cx, w: &Where, lookup: &Lookup) -> Box<WheelRail> {
        wheel_rail(
            cx,
            w,
            lookup,
            WheelRailRaw {
                wheelset: &self.wheelset,
                profiles: [
                    ("wheel_profile", Some(&self.wheel_profile)),
                    ("wheel_profile_right", self.wheel_profile_right.as_ref()),
                    ("rail_profile", Some(&self.rail_profile)),
                    ("rail_profile_right", self.rail_profile_right.as_ref()),
                ],
                values: [
                    ("radius", &self.radius),
                    ("flange_back_distance", &self.flange_back_distance),
                    ("taping_offset", &self.taping_offset),
                    ("mu", &self.mu),
                    ("young", &self.young),
                    ("poisson", &self.poisson),
                    ("normal_damping", &self.normal_damping),
                ],
                rail_profile_inclined: self.rail_profile_inclined,
                creep: self.creep.as_ref(),
                contact: &self.contact,
                rail: &self.rail,
                table: &self.table,
                wheels: self.wheels.as_ref(),
            },
        )
    }
}

/// A field written as its value (`creep: Strip(..)`, not `Some(..)`),
/// `None` only where it is left out.
fn given<'de, D, T>(d: D) -> Result<Option<T>, D::Error>
where
    D: serde::Deserializer<'de>,
    T: Deserialize<'de>,
{
    T::deserialize(d).map(Some)
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

/// Contact model of a `WheelRail` element.
#[derive(Debug, Default, Deserialize)]
#[serde(rename = "Contact")]
pub(crate) enum RawContact {
    #[default]
    Hertz,
    KikPiotrowski {
        #[serde(default = "default_penetration_reduction")]
        penetration_reduction: Value,
        #[serde(default = "default_strip_width")]
        strip_width: f64,
    },
}

fn default_penetration_reduction() -> Value {
    Value::Num(railmbs_wheelrail::kik_piotrowski::PENETRATION_REDUCTION)
}

fn default_strip_width() -> f64 {
    1e-4
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
        #[serde(default)]
        lateral_damping: LateralDamping,
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

/// The fields of a raw `WheelRail` element, borrowed for resolution.
struct WheelRailRaw<'r> {
    wheelset: &'r str,
    /// (key, path text): wheel left/right, rail left/right.
    profiles: [(&'static str, Option<&'r String>); 4],
    /// (key, value): radius, flange_back_distance, taping_offset, mu, young,
    /// poisson, normal_damping.
    values: [(&'static str, &'r Value); 7],
    rail_profile_inclined: bool,
    creep: Option<&'r CreepLawSpec<Value>>,
    contact: &'r RawContact,
    rail: &'r RawRail,
    table: &'r RawTable,
    /// Independently rotating wheels' bodies (left, right), if any.
    wheels: Option<&'r (String, String)>,
}

/// Resolves a wheel–rail element: the wheelset body, profile files (paths
/// relative to the model file; read and validated here, each error at its
/// field), material and friction values (checked with the defaults), the
/// creep law, rails and table grid.
fn wheel_rail(cx: &mut Cx, w: &Where, lookup: &Lookup, raw: WheelRailRaw) -> Box<WheelRail> {
    let wheelset = match cx.body_ref(w, "wheelset", raw.wheelset, lookup) {
        BodyRef::Body(k) => k,
        BodyRef::Ground => {
            if raw.wheelset == "ground" {
                cx.err(
                    w,
                    Some("wheelset"),
                    None,
                    "the wheelset must be a body, not ground".into(),
                );
            }
            0
        }
    };
    let base = cx.file.parent().unwrap_or(Path::new("."));
    let mut files: Vec<ProfileFile> = Vec::with_capacity(4);
    for (k, (key, text)) in raw.profiles.iter().enumerate() {
        let kind = if k < 2 {
            ProfileKind::Wheel
        } else {
            ProfileKind::Rail
        };
        // A missing right-hand profile is the left one (mirrored when placed).
        let Some(text) = text else {
            let left = files[k - 1].clone();
            files.push(left);
            continue;
        };
        let path = base.join(text);
        if text.is_empty() || !path.is_file() {
            cx.err(
                w,
                Some(key),
                Some(text),
                format!("profile file not found: {}", path.display()),
            );
            files.push(ProfileFile::missing(path, kind));
            continue;
        }
        let path = std::fs::canonicalize(&path).unwrap_or(path);
        files.push(match ProfileFile::read(path.clone(), kind) {
            Ok(file) => file,
            Err(e) => {
                cx.err(w, Some(key), Some(text), format!("{kind} profile {e}"));
                ProfileFile::missing(path, kind)
            }
        });
    }
    let e: Vec<Expr> = raw
        .values
        .iter()
        .map(|(key, v)| cx.expr(w, key, key, v, false))
        .collect();
    let default_law = CreepLawSpec::default();
    let creep = raw
        .creep
        .unwrap_or(&default_law)
        .map(|key, v| cx.expr(w, &format!("creep.{key}"), key, v, false));
    let contact = match raw.contact {
        RawContact::Hertz => ContactModel::Hertz,
        RawContact::KikPiotrowski {
            penetration_reduction,
            strip_width,
        } => {
            let strip_width = *strip_width;
            if raw.creep.is_some() {
                cx.err(
                    w,
                    Some("creep"),
                    None,
                    "`creep` is not used with `contact: KikPiotrowski(..)`: its tangential \
                     forces come from the strips of its own patches; remove `creep`"
                        .into(),
                );
            }
            if !(strip_width.is_finite() && strip_width > 0.0 && strip_width <= 1e-3) {
                cx.err(
                    w,
                    Some("strip_width"),
                    None,
                    format!("strip_width must be in (0, 1e-3] m, got {strip_width}"),
                );
            }
            ContactModel::KikPiotrowski {
                penetration_reduction: cx.expr(
                    w,
                    "contact.penetration_reduction",
                    "penetration_reduction",
                    penetration_reduction,
                    false,
                ),
                strip_width,
            }
        }
    };
    let rail = match raw.rail {
        RawRail::Rigid => RailKind::Rigid,
        RawRail::Elastic {
            ky,
            cy,
            kz,
            cz,
            lateral_damping,
        } => {
            let ky = cx.expr(w, "rail.ky", "ky", ky, false);
            let cy = cx.expr(w, "rail.cy", "cy", cy, false);
            let kz = cx.expr(w, "rail.kz", "kz", kz, false);
            let cz = cx.expr(w, "rail.cz", "cz", cz, false);
            RailKind::Elastic {
                ky,
                cy,
                kz,
                cz,
                lateral_damping: *lateral_damping,
            }
        }
    };
    let t = raw.table;
    for (key, v, zero_ok) in [
        ("y_max", t.y_max, false),
        ("dy", t.dy, false),
        ("roll_max", t.roll_max, true),
        ("droll", t.droll, false),
    ] {
        if !(v.is_finite() && (v > 0.0 || (zero_ok && v == 0.0))) {
            cx.err(
                w,
                Some(key),
                None,
                format!("table {key} must be positive and finite, got {v}"),
            );
        }
    }
    let wheels = raw.wheels.map(|(left, right)| {
        let mut ids = [0; 2];
        for (k, name) in [left, right].into_iter().enumerate() {
            ids[k] = match cx.body_ref(w, "wheels", name, lookup) {
                BodyRef::Body(b) => b,
                BodyRef::Ground => {
                    if name == "ground" {
                        cx.err(
                            w,
                            Some("wheels"),
                            Some(name),
                            "a wheel must be a body, not ground".into(),
                        );
                    }
                    0
                }
            };
        }
        if ids[0] == ids[1] || ids.contains(&wheelset) {
            cx.err(
                w,
                Some("wheels"),
                None,
                format!(
                    "the two wheels (\"{left}\", \"{right}\") must be two different bodies, \
                     neither of them the wheelset \"{}\" (that is a solid wheelset: omit \
                     `wheels`)",
                    raw.wheelset
                ),
            );
        }
        ids
    });
    let mut e = e.into_iter();
    let mut next = || e.next().expect("seven values");
    Box::new(WheelRail {
        wheelset,
        wheel_profiles: [files[0].clone(), files[1].clone()],
        rail_profiles: [files[2].clone(), files[3].clone()],
        rail_profiles_inclined: raw.rail_profile_inclined,
        radius: next(),
        flange_back_distance: next(),
        taping_offset: next(),
        mu: next(),
        young: next(),
        poisson: next(),
        normal_damping: next(),
        creep,
        contact,
        rail,
        table: ContactTableSpec {
            y_max: t.y_max,
            dy: t.dy,
            roll_max: t.roll_max,
            droll: t.droll,
        },
        wheels,
    })
}

impl ForceSpec for WheelRail {
    fn exprs_mut(&mut self, f: &mut dyn FnMut(&mut Expr)) {
        let WheelRail {
            radius,
            flange_back_distance,
            taping_offset,
            mu,
            young,
            poisson,
            normal_damping,
            creep,
            contact,
            rail,
            ..
        } = self;
        for e in [
            radius,
            flange_back_distance,
            taping_offset,
            mu,
            young,
            poisson,
            normal_damping,
        ] {
            f(e);
        }
        creep.for_each_value_mut(|_, e| f(e));
        if let ContactModel::KikPiotrowski {
            penetration_reduction,
            ..
        } = contact
        {
            f(penetration_reduction);
        }
        match rail {
            RailKind::Elastic { ky, cy, kz, cz, .. } => {
                for e in [ky, cy, kz, cz] {
                    f(e);
                }
            }
            RailKind::Rigid => {}
        }
    }
    fn bodies_mut(&mut self, f: &mut dyn FnMut(&mut usize)) {
        f(&mut self.wheelset);
        if let Some(wheels) = &mut self.wheels {
            wheels.iter_mut().for_each(&mut *f);
        }
    }
    fn check(&self, c: &mut Checks) {
        c.positive("radius", &self.radius);
        c.positive("flange_back_distance", &self.flange_back_distance);
        c.positive("young", &self.young);
        c.non_negative("taping_offset", &self.taping_offset);
        c.non_negative("mu", &self.mu);
        c.non_negative("normal_damping", &self.normal_damping);
        let nu = c.value(&self.poisson);
        if nu.is_finite() && !(0.0..=0.5).contains(&nu) {
            c.push("poisson", format!("poisson must be in [0, 0.5], got {nu}"));
        }
        // The law's own checks, its settings at these parameter values (1 where
        // not finite: counts and ranges are checked all the same).
        let law = self.creep.map(|_, e| Some(c.value(e)).filter(|x| x.is_finite()).unwrap_or(1.0));
        if let Err(e) = law.validate() {
            c.push("creep", e.to_string());
        }
        if let ContactModel::KikPiotrowski {
            penetration_reduction,
            ..
        } = &self.contact
        {
            let e = c.value(penetration_reduction);
            if e.is_finite() && !(e > 0.0 && e <= 1.0) {
                c.push(
                    "penetration_reduction",
                    format!("penetration_reduction must be in (0, 1], got {e}"),
                );
            }
        }
        if let RailKind::Elastic { ky, cy, kz, cz, .. } = &self.rail {
            c.positive("ky", ky);
            c.positive("kz", kz);
            c.non_negative("cy", cy);
            c.non_negative("cz", cz);
        }
    }
}
