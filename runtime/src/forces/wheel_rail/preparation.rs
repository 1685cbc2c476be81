//! What the element needs before it runs: its constants, evaluated and
//! checked from the parameters, and its binding to the scenario's track
//! ([`TrackBinding`]): the wheel and rail profiles (read when the model was
//! loaded) smoothed and placed on the track, the
//! contact table built from them (or reused from another wheelset of the run
//! with the same profiles and dimensions) and the creep law.

use super::table_cache::{TableCache, TableInputs, TableKey};
use super::{WheelRailContact, nadal_limit};
use crate::forces::eval_scalar;
use crate::system::SimError;
use crate::track_inputs::RunningSpeed;
use railmbs_models::{ContactModel, ProfileFile, RailKind};
use railmbs_track::Track;
use railmbs_wheelrail::creep::{CreepLaw, CreepLawSpec};
use railmbs_wheelrail::elastic_rail::RailSupport;
use railmbs_wheelrail::geometry::{
    self, ContactGeometry, ContactTable, SearchSettings, TableSettings,
};
use railmbs_wheelrail::hertz::effective_modulus;
use railmbs_wheelrail::kik_piotrowski::KikPiotrowski;
use railmbs_wheelrail::profile::{Profile, ProfileSettings};
use std::collections::HashMap;
use std::sync::{Arc, Mutex};

/// The scenario's track, as the wheel–rail elements see it.
pub struct TrackBinding {
    /// The track.
    pub track: Arc<Track>,
    /// The running speed law s(t) of the reference point.
    pub speed: RunningSpeed,
    /// Arc offset of each body's track-following frame (its own, or its
    /// nearest ancestor's), m; `None` for bodies not on a track frame.
    pub body_offsets: Vec<Option<f64>>,
    /// Contact tables already built, shared between wheelsets with the
    /// same profiles and dimensions (of this run, or of every run given the
    /// same cache).
    pub tables: ContactTableCache,
    /// The equivalent conicity override of the quasi-linear analyses (–),
    /// or `None` for the profiles' own geometry: see
    /// [`WheelRailContact`](super::WheelRailContact)'s "Conicity override".
    pub conicity: Option<f64>,
}

/// Contact tables in memory by the content hash of what they are built from
/// (the profiles' points, wheel radius, flange back distance, taping-line
/// offset, the track's gauge and rail inclination, the table's grid; see
/// `table_cache`, which also keeps them on disk): the wheelsets of one run
/// share them, and so do the runs given the same cache
/// ([`run_scenario_with`](crate::run::run_scenario_with): the cases of a
/// study, whose model and track are the same). A clone shares the tables.
///
/// Each table has its own slot: a run that needs a table another thread is
/// building waits for it (and then shares it), while tables of other keys
/// (a study over the flange back distance, say) are built at the same time
/// on other threads.
#[derive(Debug, Clone, Default)]
pub struct ContactTableCache(Arc<Mutex<HashMap<TableKey, TableSlot>>>);

/// The slot of one table: empty until its first builder has built it (a
/// build that failed leaves it empty for the next run to try again).
type TableSlot = Arc<Mutex<Option<Arc<PreparedContact>>>>;

impl ContactTableCache {
    /// An empty cache.
    pub fn new() -> Self {
        Self::default()
    }

    /// Number of tables built into it (waits for the builds under way).
    pub fn len(&self) -> usize {
        let Ok(slots) = self.0.lock() else { return 0 };
        slots
            .values()
            .filter(|slot| slot.lock().is_ok_and(|t| t.is_some()))
            .count()
    }

    /// Whether no table was built into it.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// Profiles on the track: the contact table and what is derived from it.
#[derive(Debug)]
pub struct PreparedContact {
    pub(super) table: ContactTable,
    /// Mean nominal rolling radius r₀, m.
    pub(super) nominal_radius: f64,
    /// Largest contact angle found in the table (the flange angle), rad.
    pub(super) flange_angle: f64,
}

/// The profile settings with the rail inclination `rail_inclination` (rad).
fn profile_settings(rail_inclination: f64) -> ProfileSettings {
    ProfileSettings {
        rail_inclination,
        ..ProfileSettings::default()
    }
}

/// Material and law constants from the parameters.
#[derive(Debug, Clone, Copy, Default)]
pub(super) struct Constants {
    pub(super) radius: f64,
    pub(super) flange_back_distance: f64,
    pub(super) taping_offset: f64,
    pub(super) mu: f64,
    /// Effective modulus E*, Pa.
    pub(super) e_star: f64,
    /// Combined shear modulus G = E/(2(1 + ν)), Pa.
    pub(super) shear: f64,
    pub(super) poisson: f64,
    pub(super) normal_damping: f64,
    /// The creep law, its settings evaluated.
    pub(super) creep: CreepLawSpec,
    /// Elastic rails' support (per rail), or `None` for rigid rails.
    pub(super) rail: Option<RailSupport>,
    /// The non-elliptic contact (Kik–Piotrowski) and its strip width (m),
    /// or `None` for Hertz.
    pub(super) non_elliptic: Option<(KikPiotrowski, f64)>,
}

/// Where the element is on the track (after [`ForceElement::bind_track`]).
pub(super) struct Bound {
    pub(super) track: Arc<Track>,
    pub(super) speed: RunningSpeed,
    pub(super) offset: f64,
    pub(super) contact: Arc<PreparedContact>,
    pub(super) law: Box<dyn CreepLaw + Send + Sync>,
    /// Nadal's limit of Y/Q for the flange angle and μ.
    pub(super) nadal: f64,
    /// The factor s on the lateral shift at which the contact table is
    /// looked up (1 without a conicity override): s = λ / λ₀, λ the
    /// override, λ₀ the table's own central conicity.
    pub(super) shift_scale: f64,
    /// The non-elliptic contact's profiles on the track, where its gap is
    /// sampled at every evaluation (`None` for Hertz).
    pub(super) geometry: Option<ContactGeometry>,
}

impl WheelRailContact {
    /// The element on the scenario's track: its track-following frame's arc
    /// offset, the contact table of its profiles (see [`Self::prepare`]), the
    /// creep law and Nadal's limit for the table's flange angle.
    pub(super) fn bind(&self, binding: &TrackBinding) -> Result<Bound, SimError> {
        let Some(offset) = binding
            .body_offsets
            .get(self.spec.wheelset)
            .copied()
            .flatten()
        else {
            return Err(self.err(
                "the wheelset is not on a track-following frame: give its joint (or an \
                 ancestor's) `SixDof(..., track: Some(offset))`",
            ));
        };
        let contact = self.prepare(binding)?;
        let law = self.c.creep.build().map_err(|e| self.err(e))?;
        let nadal = nadal_limit(contact.flange_angle, self.c.mu);
        let shift_scale = match binding.conicity {
            None => 1.0,
            Some(lambda) if self.c.non_elliptic.is_none() => self.shift_scale(&contact, lambda)?,
            Some(_) => {
                return Err(self.err(
                    "the equivalent conicity override scales the contact table's geometry, \
                     which the Kik–Piotrowski contact does not use: run it with `contact: Hertz`",
                ));
            }
        };
        let geometry = match self.c.non_elliptic {
            None => None,
            Some(_) => {
                let (wheelset, rails) = self.placed_profiles(binding)?;
                Some(
                    ContactGeometry::new(&wheelset, &rails, SearchSettings::default())
                        .map_err(|e| self.err(format!("contact geometry: {e}")))?,
                )
            }
        };
        Ok(Bound {
            track: binding.track.clone(),
            speed: binding.speed.clone(),
            offset,
            contact,
            law,
            nadal,
            shift_scale,
            geometry,
        })
    }

    /// The factor s = λ / λ₀ on the lateral shift of the conicity override
    /// `lambda` (–), λ₀ the profiles' central conicity
    /// ([`ContactTable::central_conicity`]: the exact rigid contact's
    /// ½ dΔr/dy over the table's nodes at ±dy).
    fn shift_scale(&self, contact: &PreparedContact, lambda: f64) -> Result<f64, SimError> {
        if !(lambda.is_finite() && lambda > 0.0) {
            return Err(self.err(format!(
                "the equivalent conicity override must be positive and finite, got {lambda}"
            )));
        }
        let own = contact.table.central_conicity().map_err(|e| {
            self.err(format!(
                "conicity override: the profiles' own central conicity: {e}"
            ))
        })?;
        if !(own.is_finite() && own > 1e-6) {
            return Err(self.err(format!(
                "conicity override: the profiles' own central conicity is {own}, not positive: \
                 their rolling radius difference does not restore the wheelset, and cannot be \
                 scaled to {lambda}"
            )));
        }
        Ok(lambda / own)
    }

    /// Places the profiles (read and validated when the model was loaded) on
    /// the track, the rails inclined by the track's rail inclination unless
    /// their files are drawn inclined, and builds (or reuses) the contact
    /// table.
    pub(super) fn prepare(&self, binding: &TrackBinding) -> Result<Arc<PreparedContact>, SimError> {
        let track = &binding.track;
        let t = &self.spec.table;
        let inclination = self.rail_inclination(binding);
        let settings = profile_settings;
        let [wheel_left, wheel_right] = &self.spec.wheel_profiles;
        let [rail_left, rail_right] = &self.spec.rail_profiles;
        let inputs = TableInputs {
            wheels: [
                (&wheel_left.points, settings(0.0)),
                (&wheel_right.points, settings(0.0)),
            ],
            rails: [
                (&rail_left.points, settings(inclination)),
                (&rail_right.points, settings(inclination)),
            ],
            radius: self.c.radius,
            flange_back_distance: self.c.flange_back_distance,
            taping_offset: self.c.taping_offset,
            gauge: track.nominal_gauge(),
            search: SearchSettings::default(),
            table: TableSettings {
                y_max: t.y_max,
                dy: t.dy,
                roll_max: t.roll_max,
                droll: t.droll,
            },
        };
        let key = inputs.key();
        // The map is locked only to find (or make) the table's slot; the
        // slot stays locked while its table is built.
        let slot = binding
            .tables
            .0
            .lock()
            .map_err(|_| self.err("contact table cache poisoned"))?
            .entry(key.clone())
            .or_default()
            .clone();
        let mut slot = slot
            .lock()
            .map_err(|_| self.err("contact table cache poisoned"))?;
        if let Some(p) = slot.as_ref() {
            return Ok(p.clone());
        }
        let build = || {
            let (wheelset, rails) = self.placed_profiles(binding)?;
            ContactTable::new(&wheelset, &rails, inputs.search, inputs.table)
                .map_err(|e| self.err(format!("contact table: {e}")))
        };
        let table = match TableCache::default_location() {
            Some(cache) => cache.get_or_build(&key, build)?,
            None => build()?,
        };
        let flange_angle = table
            .rigid_functions()
            .iter()
            .flat_map(|r| r.sides.iter().flat_map(|s| s.as_slice().iter()))
            .map(|c| c.contact_angle)
            .fold(0.0, f64::max);
        let prepared = Arc::new(PreparedContact {
            nominal_radius: self.c.radius,
            table,
            flange_angle,
        });
        *slot = Some(prepared.clone());
        Ok(prepared)
    }

    /// The rails' inclination (rad) the profiles are placed with: the
    /// track's, unless the rail files are drawn inclined.
    fn rail_inclination(&self, binding: &TrackBinding) -> f64 {
        if self.spec.rail_profiles_inclined {
            0.0
        } else {
            binding.track.rail_inclination().atan()
        }
    }

    /// The wheelset and rails of the element's profiles (read and validated
    /// when the model was loaded) on the track: smoothed, the rails inclined
    /// as [`Self::rail_inclination`] says.
    fn placed_profiles(
        &self,
        binding: &TrackBinding,
    ) -> Result<(geometry::Wheelset, geometry::Track), SimError> {
        let read = |file: &ProfileFile, rail_inclination: f64| {
            Profile::from_points(&file.points, &profile_settings(rail_inclination))
                .map_err(|e| self.err(format!("{}: {e}", file.path.display())))
        };
        let inclination = self.rail_inclination(binding);
        let [wheel_left, wheel_right] = &self.spec.wheel_profiles;
        let [rail_left, rail_right] = &self.spec.rail_profiles;
        let wheelset = geometry::Wheelset::new(
            read(wheel_left, 0.0)?,
            read(wheel_right, 0.0)?,
            self.c.radius,
            self.c.flange_back_distance,
        );
        let wheelset = geometry::Wheelset {
            taping_line_offset: self.c.taping_offset,
            ..wheelset
        };
        let rails = geometry::Track::new(
            read(rail_left, inclination)?,
            read(rail_right, inclination)?,
            binding.track.nominal_gauge(),
        );
        Ok((wheelset, rails))
    }

    /// The constants at the parameter values `params` (in
    /// `Model::parameters` order), checked: dimensions and moduli positive,
    /// Poisson's ratio in [0, 0.5), the elastic rails' supports valid.
    pub(super) fn constants(&self, params: &[f64]) -> Result<Constants, SimError> {
        let name = self.name.clone();
        let ev = |e, field| eval_scalar(e, params, &name, field);
        let s = &self.spec;
        let young = ev(&s.young, "young")?;
        let poisson = ev(&s.poisson, "poisson")?;
        let c = Constants {
            radius: ev(&s.radius, "radius")?,
            flange_back_distance: ev(&s.flange_back_distance, "flange_back_distance")?,
            taping_offset: ev(&s.taping_offset, "taping_offset")?,
            mu: ev(&s.mu, "mu")?,
            e_star: effective_modulus(young, poisson),
            shear: young / (2.0 * (1.0 + poisson)),
            poisson,
            normal_damping: ev(&s.normal_damping, "normal_damping")?,
            creep: s
                .creep
                .try_map(|key, e| eval_scalar(e, params, &name, key))?,
            rail: match &s.rail {
                RailKind::Rigid => None,
                RailKind::Elastic {
                    ky,
                    cy,
                    kz,
                    cz,
                    lateral_damping,
                } => Some(RailSupport {
                    ky: ev(ky, "rail.ky")?,
                    cy: ev(cy, "rail.cy")?,
                    kz: ev(kz, "rail.kz")?,
                    cz: ev(cz, "rail.cz")?,
                    lateral_damping: *lateral_damping,
                }),
            },
            non_elliptic: match &s.contact {
                ContactModel::Hertz => None,
                ContactModel::KikPiotrowski {
                    penetration_reduction,
                    strip_width,
                } => Some((
                    KikPiotrowski {
                        penetration_reduction: ev(penetration_reduction, "penetration_reduction")?,
                        young,
                        poisson,
                    },
                    *strip_width,
                )),
            },
        };
        if let Some((kp, width)) = &c.non_elliptic {
            let e = kp.penetration_reduction;
            if !(e.is_finite() && e > 0.0 && e <= 1.0) {
                return Err(self.err(format!(
                    "contact: KikPiotrowski: penetration_reduction must be in (0, 1], got {e}"
                )));
            }
            if !(width.is_finite() && *width > 0.0 && *width <= 1e-3) {
                return Err(self.err(format!(
                    "contact: KikPiotrowski: strip_width must be in (0, 1e-3] m, got {width} m"
                )));
            }
            if c.rail.is_some() {
                return Err(self.err(
                    "contact: KikPiotrowski is not available with elastic rails (their \
                     equilibrium is solved for Hertz contacts): use `rail: Rigid`",
                ));
            }
        }
        for (field, v) in [
            ("radius", c.radius),
            ("flange_back_distance", c.flange_back_distance),
            ("young", young),
        ] {
            if v <= 0.0 {
                return Err(self.err(format!("{field} must be positive, got {v}")));
            }
        }
        if !(0.0..0.5).contains(&poisson) {
            return Err(self.err(format!("poisson must be in [0, 0.5), got {poisson}")));
        }
        if c.mu < 0.0 || c.normal_damping < 0.0 || c.taping_offset < 0.0 {
            return Err(self.err("mu, normal_damping and taping_offset must not be negative"));
        }
        if let Some(r) = &c.rail {
            if !(r.ky.is_finite() && r.ky > 0.0 && r.kz.is_finite() && r.kz > 0.0) {
                return Err(self.err(format!(
                    "rail stiffnesses ky, kz must be positive and finite, got {} and {} N/m",
                    r.ky, r.kz
                )));
            }
            if !(r.cy.is_finite() && r.cy >= 0.0 && r.cz.is_finite() && r.cz >= 0.0) {
                return Err(self.err(format!(
                    "rail damping cy, cz must not be negative, got {} and {} N s/m",
                    r.cy, r.cz
                )));
            }
            // The elastic rail's equilibrium (Pogorelov 2005, Sect. 4.2) balances
            // the Hertz force against the rail support: a damper along the
            // contact normal has no place in it (the rail's dampers cy, cz
            // act in series with the Hertz spring instead).
            if c.normal_damping != 0.0 {
                return Err(self.err(format!(
                    "normal_damping must be 0 with elastic rails (the rail dampers cy, cz \
                     damp the contact), got {} N s/m",
                    c.normal_damping
                )));
            }
        }
        Ok(c)
    }
}
