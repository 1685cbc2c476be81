//! Wheel–rail contact of one wheelset on the scenario's track (Pogorelov 2005,
//! Sect. 4; docs/design.md "Wheel–rail contact").
//!
//! Per evaluation, for a wheelset body whose track-following frame sits at arc
//! position s:
//!
//! 1. the wheelset's pose relative to the design track frame at s: lateral
//!    shift y, height z, yaw ψ (of the axle about the frame's z) and roll φ
//!    (positive lifts the left wheel); the spin never enters;
//! 2. the rails' deviations at s (irregularities, gauge widening): each rail is
//!    shifted rigidly, laterally by Δyₖ and vertically by Δzₖ, so wheel k sees
//!    the wheelset at lateral shift y − Δyₖ over a nominal rail and its gap
//!    grows by z − r₀ − Δzₖ;
//! 3. the contacts of each wheel from the contact table: the deepest point of
//!    the tread region and of the flange region of the wheel profile
//!    ([`railmbs_wheelrail::geometry::ContactTable::lookup_regions`]), so one-
//!    and two-point contact come out of one continuous description (the
//!    single deepest point jumps at the flange root of S1002 on UIC60, which
//!    would make the forces jump and the integration chatter); the contact
//!    angle is the gap's lateral slope. Vertical penetration p = −gap,
//!    normal approach δ = p cos δ_c (δ_c the contact angle), Hertzian normal
//!    force N = (δ/δ₁)^{3/2} (plus optional damping along the normal, never
//!    pulling);
//! 4. the contact frame: normal n in the track's cross-section plane tilted
//!    by δ_c towards the track centre, rolling direction eₓ = a × n (a the axle
//!    direction), eᵧ = n × eₓ; creepages from the material velocity of the
//!    wheel at the contact point (the rails are at rest) divided by the rolling
//!    speed V = |v·eₓ| of the wheelset centre;
//! 5. the Hertz ellipse and the creep forces by the chosen law; on the wheel:
//!    N n + Fx eₓ + Fy eᵧ at the contact point and the spin moment Mz n.
//!
//! **Elastic rails** (`rail: Elastic(ky, cy, kz, cz)`, Pogorelov 2005, Sect. 4.2):
//! each rail head is massless and moves laterally and vertically, by
//! d = (d_y, d_z) in the track's cross-section, against a spring–damper to
//! ground. At every force evaluation and for each rail,
//! [`railmbs_wheelrail::elastic_rail::solve`] finds d in equilibrium with
//! that wheel's contacts (inner Newton iterations on d for the normal forces,
//! outer iterations for the creep forces; one- and two-point contact): the
//! contacts come from the same table with the wheelset shifted by −d_y over
//! the rail and the gap closed by d_z, and the rail's velocity enters the
//! lateral creepage. The damper's rate is backward Euler,
//! ḋ = (d − d_prev)/(t − t_prev), from the rail displacement d_prev of the
//! latest accepted step before t (the element's state, changed only in
//! [`ForceElement::accept_step`], never inside Newton iterations or by
//! rejected steps); without an accepted step before t (the start of a run)
//! the rails are in static equilibrium. The outer iterations start from the
//! creep forces of that same accepted step
//! ([`railmbs_wheelrail::elastic_rail::solve_from`]), which halves their
//! number without changing the solution. The contact has no damper of its own
//! along the normal then (`normal_damping` must be 0: the rail dampers act
//! in series with the Hertz spring). The Jacobian uses the Hertz stiffness in
//! series with the support's K + C/h along the normal. Outputs per rail:
//! `L.rail_dy`, `L.rail_dz` (m, track frame, +y left, +z up).
//!
//! **Independently rotating wheels** (`wheels: Some(("WheelL", "WheelR"))`):
//! each wheel is its own body turning on the axle (the `wheelset` body, which
//! then has no spin). The contact geometry still follows the axle's pose;
//! each wheel's contact forces act on its own body and its creepages come
//! from that body's velocity and angular velocity, so each wheel rolls at its
//! own speed and no longitudinal creep couples the two.
//!
//! The rails' reactions go to ground (the track is not a body of the model).
//! Outputs per wheel follow the usual assessment conventions: Q the vertical
//! wheel load and Y the lateral force of the wheel on the rail, positive
//! towards the field side, both in the track frame; ΣY the track-shifting force
//! of the wheelset (lateral force on the track, positive to the left).

use super::{
    ForceContext, ForceElement, ForceJacobian, Wrench, add_force, add_moment, eval_scalar,
};
use crate::equations::BodyKinematics;
use crate::system::SimError;
use crate::track_inputs::RunningSpeed;
use nalgebra::{Matrix3, Vector3};
use railmbs_models::{RailKind, WheelRail};
use railmbs_track::{SpeedLaw, Track};
use railmbs_wheelrail::creep::{ContactPatch, CreepForces, CreepLaw, CreepLawSpec, Creepages};
use railmbs_wheelrail::creepage::ContactFrame;
use railmbs_wheelrail::elastic_rail::{
    self, ContactMaterial, CreepStart, ElasticRailError, ElasticRailSettings, RailContact,
    RailContactGeometry, RailSupport,
};
use railmbs_wheelrail::geometry::{self, Contact, ContactTable, SearchSettings, TableSettings};
use railmbs_wheelrail::hertz::{HertzShape, effective_modulus, wheel_rail_curvatures};
use railmbs_wheelrail::kalker::KalkerCoefficients;
use railmbs_wheelrail::profile::{Profile, ProfileKind, ProfileSettings};
use std::collections::HashMap;
use std::path::PathBuf;
use std::sync::{Arc, Mutex};

/// Below this wheelset speed (m/s) the creepages are divided by it instead of
/// the actual speed (creepages are undefined at standstill); the creep forces
/// then act as a stiff viscous regularisation of friction.
pub const MIN_ROLLING_SPEED: f64 = 0.1;

/// The transverse relative curvature B is kept at least A/25 (axis ratio
/// ≤ 25): conformal contact in a worn wheel throat would otherwise give B ≤ 0,
/// where Hertz's theory does not apply.
const MIN_CURVATURE_RATIO: f64 = 1.0 / 25.0;

/// Slope of the wheel–rail distance along the profile (–) at which a
/// region's boundary point has lost its load entirely.
const BOUNDARY_SLOPE: f64 = 0.05;

/// 0 at 0, 1 from 1 on, C¹ between.
fn smoothstep(x: f64) -> f64 {
    let x = x.clamp(0.0, 1.0);
    x * x * (3.0 - 2.0 * x)
}

/// Largest tan δ used for the contact's lead ahead of the axle plane (75°).
const MAX_LEAD_TAN: f64 = 3.73;

/// The scenario's track, as the wheel–rail elements see it.
pub struct TrackBinding {
    /// The track.
    pub track: Arc<Track>,
    /// The running speed law s(t) of the reference point.
    pub speed: RunningSpeed,
    /// Arc offset of each body's track-following frame (its own, or its
    /// nearest ancestor's), m; `None` for bodies not on a track frame.
    pub body_offsets: Vec<Option<f64>>,
    /// Contact tables already built in this run, shared between wheelsets
    /// with the same profiles and dimensions.
    pub tables: Mutex<HashMap<String, Arc<PreparedContact>>>,
}

/// Profiles on the track: the contact table and what is derived from it.
#[derive(Debug)]
pub struct PreparedContact {
    table: ContactTable,
    /// Mean nominal rolling radius r₀, m.
    nominal_radius: f64,
    /// Largest contact angle found in the table (the flange angle), rad.
    flange_angle: f64,
}

/// Material and law constants from the parameters.
#[derive(Debug, Clone, Copy, Default)]
struct Constants {
    radius: f64,
    flange_back_distance: f64,
    taping_offset: f64,
    mu: f64,
    /// Effective modulus E*, Pa.
    e_star: f64,
    /// Combined shear modulus G = E/(2(1 + ν)), Pa.
    shear: f64,
    poisson: f64,
    normal_damping: f64,
    /// The creep law, its settings evaluated.
    creep: CreepLawSpec,
    /// Elastic rails' support (per rail), or `None` for rigid rails.
    rail: Option<RailSupport>,
}

/// Where the element is on the track (after [`ForceElement::bind_track`]).
struct Bound {
    track: Arc<Track>,
    speed: RunningSpeed,
    offset: f64,
    contact: Arc<PreparedContact>,
    law: Box<dyn CreepLaw + Send + Sync>,
    /// Nadal's limit of Y/Q for the flange angle and μ.
    nadal: f64,
}

/// One solved contact.
#[derive(Debug, Clone, Copy, Default)]
struct ContactState {
    /// Point of application (on the rail surface), SC0, m.
    point: Vector3<f64>,
    /// Contact frame in SC0.
    ex: Vector3<f64>,
    ey: Vector3<f64>,
    n: Vector3<f64>,
    /// Normal force, N.
    normal: f64,
    /// dN/dδ, N/m.
    normal_stiffness: f64,
    creepages: Creepages,
    forces: CreepForces,
    /// Linear creep coefficients f11 = G a b C11, f22 = G a b C22 (N), times the
    /// saturation ratio (|F| / linear |F|, ≤ 1), for the Jacobian.
    f11: f64,
    f22: f64,
    /// Rolling speed, m/s.
    speed: f64,
    /// Contact angle, rad; lateral position of the contact on the rail (track
    /// frame, m).
    angle: f64,
    rail_y: f64,
    /// Rolling radius of the wheel at the contact, m.
    rolling_radius: f64,
    /// Power dissipated at the contact, W: the creep forces against the
    /// creepages, −V (F_x ξ + F_y η + M_z φ) (the forces act on the wheel and
    /// oppose the slip), plus the normal damper's force times the approach
    /// rate (rigid rails).
    dissipation: f64,
    /// Elastic energy of the Hertz contact, (2/5) N δ (N ∝ δ^{3/2}), J.
    elastic_energy: f64,
}

impl ContactState {
    /// Total force on the wheel, SC0, N.
    fn force(&self) -> Vector3<f64> {
        self.n * self.normal + self.ex * self.forces.fx + self.ey * self.forces.fy
    }
}

/// Both wheels at one state.
#[derive(Debug, Clone, Copy, Default)]
struct WheelsetState {
    /// Per side (left, right): contacts (up to two) and how many.
    contacts: [[ContactState; 2]; 2],
    count: [usize; 2],
    /// Track frame axes in SC0 (columns x, y, z).
    track_axes: Matrix3<f64>,
    /// Elastic rails: per rail (left, right) the displacement (d_y, d_z), m,
    /// in the track frame; zero for rigid rails.
    rail_d: [[f64; 2]; 2],
    /// Elastic rails: per rail the creep forces the rail's outer iterations
    /// converged to (where the next step's iterations start).
    rail_creep: [CreepStart; 2],
}

impl WheelsetState {
    /// The contacts of side 0 (left) or 1 (right).
    fn side(&self, side: usize) -> &[ContactState] {
        &self.contacts[side][..self.count[side]]
    }

    /// Adds a loaded contact to side 0 (left) or 1 (right).
    fn push(&mut self, side: usize, contact: ContactState) {
        self.contacts[side][self.count[side]] = contact;
        self.count[side] += 1;
    }
}

/// One side (wheel and rail) of the wheelset at one state: what its contacts
/// share.
struct Side<'a> {
    ctx: &'a ForceContext<'a>,
    b: &'a Bound,
    /// 0 left, 1 right.
    side: usize,
    /// +1 left, −1 right.
    sign: f64,
    /// Lateral shift of the wheelset over this rail (its irregularity taken
    /// off), m.
    y: f64,
    /// Roll of the wheelset, rad.
    roll: f64,
    /// Height of the axle above the nominal radius, less the rail's vertical
    /// irregularity, m.
    z: f64,
    /// Yaw of the axle, rad.
    yaw: f64,
    /// Longitudinal position of the axle in the track frame, m.
    x_rel: f64,
    /// The rail's rigid shift by irregularities (lateral, vertical), m.
    shift: (f64, f64),
    /// Track frame axes and origin, SC0.
    axes: Matrix3<f64>,
    origin: Vector3<f64>,
    /// Axle direction, SC0.
    axle: Vector3<f64>,
    /// Rolling speed dividing the creepages, m/s.
    speed: f64,
    /// Body carrying this wheel.
    wheel: usize,
}

/// One contact before its normal force is known.
struct ContactKinematics {
    shape: HertzShape,
    /// Approach along the normal (load weight included), m.
    approach: f64,
    /// Normal (n_y, n_z) in the track cross-section.
    normal_2d: [f64; 2],
    cos_angle: f64,
    point: Vector3<f64>,
    ex: Vector3<f64>,
    ey: Vector3<f64>,
    n: Vector3<f64>,
    /// Rate of approach of the wheel surface along the normal, m/s.
    approach_rate: f64,
    /// Creepages against a rail at rest.
    creepages: Creepages,
    speed: f64,
    angle: f64,
    rail_y: f64,
    rolling_radius: f64,
}

/// The contact geometry of one wheel on its elastic rail for
/// [`elastic_rail::solve`]: the table's region contacts with the wheelset
/// shifted by −d_y over the rail and the gap closed by d_z.
struct TableRail<'a> {
    el: &'a WheelRailContact,
    s: &'a Side<'a>,
}

impl RailContactGeometry for TableRail<'_> {
    fn contacts_at(
        &self,
        d: [f64; 2],
        out: &mut [RailContact; elastic_rail::MAX_CONTACTS],
    ) -> Result<usize, ElasticRailError> {
        let geo = |e: SimError| ElasticRailError::Geometry {
            index: 0,
            what: e.to_string(),
        };
        let sets = self.el.lookup(self.s, d[0]).map_err(geo)?;
        for (o, c) in out.iter_mut().zip(&sets[self.s.side]) {
            *o = match self.el.kinematics(self.s, c, d).map_err(geo)? {
                Some(k) => RailContact {
                    approach: k.approach,
                    normal: k.normal_2d,
                    hertz: k.shape,
                    creepages: k.creepages,
                },
                // Open (or a boundary point without load): no force; any
                // valid shape will do.
                None => {
                    let (sd, cd) = c.contact_angle.sin_cos();
                    RailContact {
                        approach: 0.0,
                        normal: [-self.s.sign * sd, cd],
                        hertz: self.el.placeholder_shape.ok_or_else(|| {
                            ElasticRailError::Parameter("no Hertz shape for an open contact".into())
                        })?,
                        creepages: Creepages::default(),
                    }
                }
            };
        }
        Ok(2)
    }
}

/// The elastic rails at an accepted step: time (s), displacements (left,
/// right; (d_y, d_z) each, m) and creep forces.
type RailRecord = (f64, [[f64; 2]; 2], [CreepStart; 2]);

/// The wheel–rail element of one wheelset.
pub struct WheelRailContact {
    name: String,
    spec: WheelRail,
    c: Constants,
    bound: Option<Bound>,
    /// The last solved state and what it was solved for (time and the
    /// wheelset's kinematics): the accept-step hook, the outputs and the
    /// Jacobian usually ask again for the state the last force evaluation
    /// saw, and the contact solution is the costly part of a step.
    /// The kinematics are the wheelset's and each wheel's body's (the same
    /// body thrice for a solid wheelset).
    last: std::sync::Mutex<Option<(f64, [BodyKinematics; 3], WheelsetState)>>,
    /// Elastic rails: the rails at the last accepted step. Only
    /// [`ForceElement::accept_step`] changes it; every evaluation until the
    /// next accepted step (Newton iterations, Jacobians, the output rows of
    /// the step, which the runner evaluates before accepting it) starts from
    /// it.
    rail_accepted: Option<RailRecord>,
    /// A valid Hertz shape for contacts without load (elastic rails).
    placeholder_shape: Option<HertzShape>,
}

impl std::fmt::Debug for WheelRailContact {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("WheelRailContact")
            .field("name", &self.name)
            .field("wheelset", &self.spec.wheelset)
            .field("bound", &self.bound.is_some())
            .finish()
    }
}

impl WheelRailContact {
    /// The element named `name` from the model's wheel–rail spec. Nothing
    /// is evaluated or checked here: the constants come with
    /// [`ForceElement::set_parameters`] and the profiles and contact table
    /// with [`ForceElement::bind_track`], which report errors.
    pub fn new(name: String, spec: &WheelRail) -> Self {
        Self {
            name,
            spec: spec.clone(),
            c: Constants::default(),
            bound: None,
            last: std::sync::Mutex::new(None),
            rail_accepted: None,
            placeholder_shape: HertzShape::with_modulus(1.0, 1.0, 1.0).ok(),
        }
    }

    fn err(&self, message: impl std::fmt::Display) -> SimError {
        SimError::Other(format!("wheel–rail element \"{}\": {message}", self.name))
    }

    fn diverged(&self, t: f64, message: impl std::fmt::Display) -> SimError {
        SimError::Diverged {
            t,
            reason: format!("wheel–rail element \"{}\": {message}", self.name),
        }
    }

    /// Reads the profiles and builds (or reuses) the contact table.
    fn prepare(&self, binding: &TrackBinding) -> Result<Arc<PreparedContact>, SimError> {
        let track = &binding.track;
        let t = &self.spec.table;
        let key = format!(
            "{:?}|{:?}|{}|{}|{}|{}|{}|{}|{}|{}|{}|{}",
            self.spec.wheel_profiles,
            self.spec.rail_profiles,
            self.spec.rail_profiles_inclined,
            self.c.radius,
            self.c.flange_back_distance,
            self.c.taping_offset,
            track.nominal_gauge(),
            track.rail_inclination(),
            t.y_max,
            t.dy,
            t.roll_max,
            t.droll
        );
        let mut tables = binding
            .tables
            .lock()
            .map_err(|_| self.err("contact table cache poisoned"))?;
        if let Some(p) = tables.get(&key) {
            return Ok(p.clone());
        }
        let read = |path: &PathBuf, kind: ProfileKind, inclination: f64| {
            let settings = ProfileSettings {
                rail_inclination: inclination,
                ..ProfileSettings::default()
            };
            Profile::read(path, kind, &settings)
                .map_err(|e| self.err(format!("{}: {e}", path.display())))
        };
        let inclination = if self.spec.rail_profiles_inclined {
            0.0
        } else {
            track.rail_inclination().atan()
        };
        let wheelset = geometry::Wheelset::new(
            read(&self.spec.wheel_profiles[0], ProfileKind::Wheel, 0.0)?,
            read(&self.spec.wheel_profiles[1], ProfileKind::Wheel, 0.0)?,
            self.c.radius,
            self.c.flange_back_distance,
        );
        let wheelset = geometry::Wheelset {
            taping_line_offset: self.c.taping_offset,
            ..wheelset
        };
        let rails = geometry::Track::new(
            read(&self.spec.rail_profiles[0], ProfileKind::Rail, inclination)?,
            read(&self.spec.rail_profiles[1], ProfileKind::Rail, inclination)?,
            track.nominal_gauge(),
        );
        let table = ContactTable::new(
            &wheelset,
            &rails,
            SearchSettings::default(),
            TableSettings {
                y_max: t.y_max,
                dy: t.dy,
                roll_max: t.roll_max,
                droll: t.droll,
            },
        )
        .map_err(|e| self.err(format!("contact table: {e}")))?;
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
        tables.insert(key, prepared.clone());
        Ok(prepared)
    }

    /// [`Self::solve_new`], or the stored result for the same time and
    /// wheelset kinematics (the axle's and, for independently rotating wheels,
    /// the wheels', whose spin alone changes the creep forces).
    fn solve(&self, ctx: &ForceContext) -> Result<WheelsetState, SimError> {
        let body = [
            ctx.bodies[self.spec.wheelset],
            ctx.bodies[self.wheel_body(0)],
            ctx.bodies[self.wheel_body(1)],
        ];
        if let Ok(last) = self.last.lock()
            && let Some((t, k, state)) = last.as_ref()
            && *t == ctx.t
            && *k == body
        {
            return Ok(*state);
        }
        let state = self.solve_new(ctx)?;
        if let Ok(mut last) = self.last.lock() {
            *last = Some((ctx.t, body, state));
        }
        Ok(state)
    }

    /// Solves both wheels' contacts at the context's state.
    fn solve_new(&self, ctx: &ForceContext) -> Result<WheelsetState, SimError> {
        let Some(b) = &self.bound else {
            return Err(self.err(
                "no track: a wheel–rail element needs the scenario's track (`track: (file: …)`)",
            ));
        };
        let t = ctx.t;
        let motion = b
            .speed
            .motion(t)
            .map_err(|e| self.diverged(t, format!("running speed: {e}")))?;
        let s = motion.s + b.offset;
        let frame = b
            .track
            .frame(s, motion.s_dot, motion.s_ddot)
            .map_err(|e| self.diverged(t, format!("track at s = {s:.3} m: {e}")))?;
        let r = &frame.rotation;
        let axes = Matrix3::new(
            r[0][0], r[0][1], r[0][2], r[1][0], r[1][1], r[1][2], r[2][0], r[2][1], r[2][2],
        );
        let origin = Vector3::from(frame.position);
        let body = &ctx.bodies[self.spec.wheelset];
        // Pose relative to the design track frame.
        let rel = axes.transpose() * (body.position - origin);
        let axle = body.rotation.column(1).into_owned();
        let axle_t = axes.transpose() * axle;
        let roll = axle_t.z.clamp(-1.0, 1.0).asin();
        let yaw = (-axle_t.x).atan2(axle_t.y);
        // Rails: irregularities at the wheelset's own arc position, plus the
        // design gauge widening shared equally by both rails.
        let s_ws = s + rel.x;
        let dev = b
            .track
            .deviation(s_ws)
            .map_err(|e| self.diverged(t, format!("track irregularity at s = {s_ws:.3} m: {e}")))?;
        let widening = b
            .track
            .point(s_ws)
            .map_err(|e| self.diverged(t, format!("track at s = {s_ws:.3} m: {e}")))?
            .gauge
            - b.track.nominal_gauge();
        let rail_shift = [
            (dev.left_lateral + 0.5 * widening, dev.left_vertical),
            (dev.right_lateral - 0.5 * widening, dev.right_vertical),
        ];
        let z_geom = rel.z - b.contact.nominal_radius;
        let mut state = WheelsetState {
            track_axes: axes,
            ..WheelsetState::default()
        };
        let forward = axes.column(0).into_owned();
        let speed = body.velocity.dot(&forward).abs().max(MIN_ROLLING_SPEED);
        let sides = [0, 1].map(|side| Side {
            ctx,
            b,
            side,
            sign: if side == 0 { 1.0 } else { -1.0 },
            y: rel.y - rail_shift[side].0,
            roll,
            z: z_geom - rail_shift[side].1,
            yaw,
            x_rel: rel.x,
            shift: rail_shift[side],
            axes,
            origin,
            axle,
            speed,
            wheel: self.wheel_body(side),
        });
        match self.c.rail {
            None => {
                let left = self.lookup(&sides[0], 0.0)?;
                let right = if sides[1].y == sides[0].y {
                    left
                } else {
                    self.lookup(&sides[1], 0.0)?
                };
                let sets: [&[Contact; 2]; 2] = [&left[0], &right[1]];
                for (side, geo) in sides.iter().enumerate() {
                    for c in sets[side] {
                        let Some(k) = self.kinematics(geo, c, [0.0; 2])? else {
                            continue;
                        };
                        let elastic = k
                            .shape
                            .normal_force(k.approach)
                            .map_err(|e| self.diverged(t, format!("Hertz: {e}")))?;
                        let normal = (elastic + self.c.normal_damping * k.approach_rate).max(0.0);
                        if normal == 0.0 {
                            continue;
                        }
                        let stiffness = if elastic > 0.0 {
                            k.shape.stiffness(k.approach)
                        } else {
                            0.0
                        };
                        let hertz = k
                            .shape
                            .contact(normal)
                            .map_err(|e| self.diverged(t, format!("Hertz: {e}")))?;
                        let patch = self.patch(hertz.a, hertz.b, normal);
                        let forces = b
                            .law
                            .forces_at_speed(&patch, &k.creepages, k.speed)
                            .map_err(|e| self.diverged(t, format!("creep forces: {e}")))?;
                        let damper_power = (normal - elastic) * k.approach_rate;
                        let st = self.contact_state(
                            &k,
                            &patch,
                            (normal, stiffness),
                            forces,
                            (damper_power, 0.4 * elastic * k.approach),
                        )?;
                        state.push(side, st);
                    }
                }
            }
            Some(support) => {
                let (h, d_prev, creep) = self.rail_reference(t);
                for (side, geo) in sides.iter().enumerate() {
                    let start = (h, d_prev[side], &creep[side]);
                    self.solve_elastic_side(geo, &support, start, &mut state)?;
                }
            }
        }
        Ok(state)
    }

    /// The contact table's region contacts for a side's wheelset position
    /// with its rail displaced laterally by `rail_dy` (m).
    fn lookup(&self, s: &Side, rail_dy: f64) -> Result<[[Contact; 2]; 2], SimError> {
        let y = s.y - rail_dy;
        s.b.contact.table.lookup_regions(y, s.roll).map_err(|e| {
            self.diverged(
                s.ctx.t,
                format!(
                    "wheelset out of the contact table ({e}); lateral shift {:.2} mm, roll \
                     {:.4} rad: derailment, or enlarge `table`",
                    y * 1e3,
                    s.roll
                ),
            )
        })
    }

    /// The body carrying wheel `side` (0 left, 1 right): the wheel's own body
    /// for independently rotating wheels, else the wheelset.
    fn wheel_body(&self, side: usize) -> usize {
        self.spec.wheels.map_or(self.spec.wheelset, |w| w[side])
    }

    /// Where the backward-Euler rate of the elastic rails starts from at time
    /// `t` (s): (h, d_prev, creep) with d_prev the rails' displacements (left,
    /// right; (d_y, d_z) each, m) at the last accepted step, h the time since
    /// it (s) and the creep forces there (where the outer iterations start).
    /// At the accepted time itself or before any accepted step (the start of
    /// a run) the rails are in static equilibrium: h = ∞.
    fn rail_reference(&self, t: f64) -> (f64, [[f64; 2]; 2], [CreepStart; 2]) {
        match self.rail_accepted {
            Some((tr, d, creep)) if tr < t => (t - tr, d, creep),
            accepted => {
                let (_, d, creep) = accepted.unwrap_or_default();
                (f64::INFINITY, d, creep)
            }
        }
    }

    /// One side on its massless elastic rail (Pogorelov 2005, Sect. 4.2, via
    /// [`elastic_rail::solve_from`]): the rail displacement and the normal
    /// and creep forces in equilibrium, written into `state`; `start` is
    /// (h, d_prev, creep) of [`Self::rail_reference`] for this rail.
    fn solve_elastic_side(
        &self,
        s: &Side,
        support: &RailSupport,
        start: (f64, [f64; 2], &CreepStart),
        state: &mut WheelsetState,
    ) -> Result<(), SimError> {
        let (h, d_prev, creep_start) = start;
        let t = s.ctx.t;
        let material = ContactMaterial {
            g: self.c.shear,
            nu: self.c.poisson,
            mu: self.c.mu,
        };
        // The support's effective stiffness over the step, K + C/h (the
        // backward-Euler damper).
        let keff = if h.is_finite() {
            [support.ky + support.cy / h, support.kz + support.cz / h]
        } else {
            [support.ky, support.kz]
        };
        let settings = ElasticRailSettings {
            h,
            v_roll: s.speed,
            // 1 µN against wheel loads of tens of kN: what the integrator
            // resolves at tolerances down to 1e-14 m against the 1e8 N/m
            // support (the solver raises it to the rounding of its terms on
            // tiny steps).
            force_tol: 1e-6,
            rel_tol: 1e-8,
            max_inner: 50,
            max_outer: 200,
        };
        let side_name = ["left", "right"][s.side];
        let sol = elastic_rail::solve_from(
            support,
            &material,
            &TableRail { el: self, s },
            s.b.law.as_ref(),
            d_prev,
            creep_start,
            &settings,
        )
        .map_err(|e| self.diverged(t, format!("{side_name} rail: {e}")))?;
        let d = sol.displacement;
        state.rail_d[s.side] = d;
        state.rail_creep[s.side] = CreepStart {
            forces: sol.contacts.map(|c| c.creep),
            slope: sol.contacts.map(|c| c.lateral_slope),
        };
        let sets = self.lookup(s, d[0])?;
        for (i, c) in sets[s.side].iter().enumerate().take(sol.n_contacts) {
            let r = &sol.contacts[i];
            if r.normal_force <= 0.0 {
                continue;
            }
            let Some(mut k) = self.kinematics(s, c, d)? else {
                continue;
            };
            // The rail's own velocity in the lateral creepage, as the solver
            // used it: Δη = −(ḋ·t)/V, t = (n_z, −n_y) in the cross-section.
            let [ny, nz] = r.normal;
            k.creepages.eta -= (sol.velocity[0] * nz - sol.velocity[1] * ny) / s.speed;
            // Hertz spring in series with the rail support along the normal:
            // 1/k = 1/k_H + nᵀ K_eff⁻¹ n.
            let k_hertz = k.shape.stiffness(r.approach);
            let compliance = ny * ny / keff[0] + nz * nz / keff[1];
            let stiffness = if k_hertz > 0.0 {
                k_hertz / (1.0 + k_hertz * compliance)
            } else {
                0.0
            };
            let patch = self.patch(r.a, r.b, r.normal_force);
            // The rail supports' dampers are not counted in the contact's
            // dissipation (they act between rail and ground).
            let st = self.contact_state(
                &k,
                &patch,
                (r.normal_force, stiffness),
                r.creep,
                (0.0, 0.4 * r.normal_force * r.approach),
            )?;
            state.push(s.side, st);
        }
        Ok(())
    }

    /// One contact's geometry, frame and creepages with the rail displaced
    /// elastically by `d` = (d_y, d_z) (m, track frame; zero for rigid
    /// rails); `None` if it cannot carry load (open gap, or a region's
    /// boundary point that has lost its load).
    fn kinematics(
        &self,
        s: &Side,
        c: &Contact,
        d: [f64; 2],
    ) -> Result<Option<ContactKinematics>, SimError> {
        let t = s.ctx.t;
        let penetration = -(c.gap + s.z - d[1]);
        // A region's deepest point on the region boundary, where the
        // surfaces still close towards the other region (distance slope ≠ 0),
        // is not a contact of its own: the other region's slot holds it. Its
        // load fades out with the slope; a true minimum born on the boundary
        // has zero slope, so the load is continuous.
        let weight = 1.0 - smoothstep(c.distance_slope.abs() / BOUNDARY_SLOPE);
        if penetration <= 0.0 || weight == 0.0 {
            return Ok(None);
        }
        let (sd, cd) = c.contact_angle.sin_cos();
        // N ∝ approach^{3/2}: the load scales by `weight`.
        let approach = penetration * weight.powf(2.0 / 3.0) * cd;
        // Hertz shape from the curvatures at the contact.
        let (curv_a, curv_b) = wheel_rail_curvatures(
            1.0 / c.wheel_longitudinal_curvature.max(1e-6),
            c.wheel_transverse_curvature,
            c.rail_transverse_curvature,
        );
        let curv_b = curv_b.max(MIN_CURVATURE_RATIO * curv_a);
        let shape = HertzShape::with_modulus(curv_a, curv_b, self.c.e_star)
            .map_err(|e| self.diverged(t, format!("Hertz: {e}")))?;
        // Contact point on the (displaced) rail, in the track frame then SC0,
        // first in the axle's plane.
        let mut local = Vector3::new(
            s.x_rel,
            c.rail_y + s.shift.0 + d[0],
            c.rail_z + s.shift.1 + d[1],
        );
        // The wheel: the wheelset, or its own body for independently
        // rotating wheels.
        let wheel = &s.ctx.bodies[s.wheel];
        let n = s.axes * Vector3::new(0.0, -s.sign * sd, cd);
        // Overswing: a yawed wheel touches the rail ahead of (or behind) its
        // axle plane, where its surface normal — in the wheel's meridian
        // plane, a body of revolution's normals lie there — is the rail's
        // normal n: the circumferential direction u = axle × ρ is then
        // orthogonal to n, so the rolling does no work against the normal
        // force. Solved for the shift x along the track: (axle × (ρ₀ + x eₓ))·n
        // = 0, x ≈ r tan δ ψ for small yaw ψ; bounded by the steepest real
        // flange (tan δ ≤ 3.73), as a region's deepest point on the region
        // boundary can carry a near-vertical slope.
        let track_x = s.axes.column(0).into_owned();
        let rho0 = s.origin + s.axes * local - wheel.position;
        let denominator = s.axle.cross(&track_x).dot(&n);
        if denominator.abs() > 1e-12 {
            let bound = MAX_LEAD_TAN * c.rolling_radius * s.yaw.abs();
            local.x += (-s.axle.cross(&rho0).dot(&n) / denominator).clamp(-bound, bound);
        }
        let point = s.origin + s.axes * local;
        let rho = point - wheel.position;
        let ex = s.axle.cross(&n).normalize();
        let ey = n.cross(&ex);
        let v_wheel = wheel.velocity + wheel.angular_velocity.cross(&rho);
        // Approach rate: the wheel's surface moving against the normal at the
        // contact point. The spin about the axle only rolls the surface
        // through the contact: with the overswing above its velocity there is
        // orthogonal to n, except where the overswing bound cuts in; the
        // approach uses the non-spinning motion, so that a bounded overswing
        // does not feed the spin into the normal damper.
        let omega_frame = wheel.angular_velocity - s.axle * wheel.angular_velocity.dot(&s.axle);
        let approach_rate = -(wheel.velocity + omega_frame.cross(&rho)).dot(&n);
        // Against a rail at rest (the elastic rail's velocity is added by
        // its solve).
        let frame = ContactFrame {
            ex: ex.into(),
            ey: ey.into(),
            n: n.into(),
        };
        let omega = wheel.angular_velocity.into();
        let creepages =
            Creepages::from_velocities(v_wheel.into(), [0.0; 3], omega, [0.0; 3], &frame, s.speed)
                .map_err(|e| self.diverged(t, e.to_string()))?;
        Ok(Some(ContactKinematics {
            shape,
            approach,
            normal_2d: [-s.sign * sd, cd],
            cos_angle: cd,
            point,
            ex,
            ey,
            n,
            approach_rate,
            creepages,
            speed: s.speed,
            angle: c.contact_angle,
            rail_y: local.y,
            rolling_radius: c.rolling_radius,
        }))
    }

    /// The contact patch for the creep law: semi-axes `a`, `b` (m), normal
    /// force `n` (N).
    fn patch(&self, a: f64, b: f64, n: f64) -> ContactPatch {
        ContactPatch {
            a,
            b,
            g: self.c.shear,
            nu: self.c.poisson,
            mu: self.c.mu,
            n,
        }
    }

    /// The solved contact: normal force `normal` (N) with dN/dδ `stiffness`
    /// (N/m) and the creep forces.
    fn contact_state(
        &self,
        k: &ContactKinematics,
        patch: &ContactPatch,
        (normal, stiffness): (f64, f64),
        forces: CreepForces,
        (damper_power, elastic_energy): (f64, f64),
    ) -> Result<ContactState, SimError> {
        // Linear creep coefficients (Kalker), scaled by the saturation of the
        // actual forces, for the approximate Jacobian (Pogorelov 2005, Sect. 6).
        let (f11, f22) = KalkerCoefficients::saturated_slopes(
            patch.a,
            patch.b,
            self.c.shear,
            self.c.poisson,
            k.creepages.xi,
            k.creepages.eta,
            forces.fx,
            forces.fy,
        )
        .ok_or_else(|| self.err("Poisson ratio outside Kalker's table"))?;
        Ok(ContactState {
            point: k.point,
            ex: k.ex,
            ey: k.ey,
            n: k.n,
            normal,
            normal_stiffness: stiffness * k.cos_angle,
            creepages: k.creepages,
            forces,
            f11,
            f22,
            speed: k.speed,
            angle: k.angle,
            rail_y: k.rail_y,
            rolling_radius: k.rolling_radius,
            dissipation: -k.speed
                * (forces.fx * k.creepages.xi
                    + forces.fy * k.creepages.eta
                    + forces.mz * k.creepages.phi)
                + damper_power,
            elastic_energy,
        })
    }

    /// Per-side sums in the track frame: (Q, Y) with Q the vertical wheel load
    /// and Y the lateral force on the rail towards the field side, N.
    fn wheel_loads(state: &WheelsetState) -> [(f64, f64); 2] {
        [0, 1].map(|side| {
            let sign = if side == 0 { 1.0 } else { -1.0 };
            let f: Vector3<f64> = state.side(side).iter().map(|c| c.force()).sum();
            let local = state.track_axes.transpose() * f;
            // Force on the rail is −f; field side is +y on the left, −y on the right.
            (local.z, -sign * local.y)
        })
    }
}

/// Nadal's limit of Y/Q for flange angle `beta` (rad) and friction `mu`:
/// (tan β − μ)/(1 + μ tan β) (Nadal 1908).
pub fn nadal_limit(beta: f64, mu: f64) -> f64 {
    let t = beta.tan();
    (t - mu) / (1.0 + mu * t)
}

/// Prud'homme's limit of the track-shifting force ΣY (N) for axle load `p`
/// (N): α (10 kN + P/3), α = 0.85 (Prud'homme 1970, the usual factor for
/// track in service).
pub fn prudhomme_limit(p: f64) -> f64 {
    0.85 * (10e3 + p / 3.0)
}

impl ForceElement for WheelRailContact {
    fn name(&self) -> &str {
        &self.name
    }

    fn set_parameters(&mut self, params: &[f64]) -> Result<(), SimError> {
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
                RailKind::Elastic { ky, cy, kz, cz } => Some(RailSupport {
                    ky: ev(ky, "rail.ky")?,
                    cy: ev(cy, "rail.cy")?,
                    kz: ev(kz, "rail.kz")?,
                    cz: ev(cz, "rail.cz")?,
                }),
            },
        };
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
        // The contact table is built from these when the track is bound.
        let geometry = |c: &Constants| (c.radius, c.flange_back_distance, c.taping_offset);
        if self.bound.is_some() && geometry(&c) != geometry(&self.c) {
            return Err(self.err(
                "the wheel radius, back-to-back distance and taping line are fixed once the \
                 contact table is built (at the start of the run)",
            ));
        }
        self.c = c;
        *self.last.get_mut().unwrap_or_else(|e| e.into_inner()) = None;
        self.rail_accepted = None;
        Ok(())
    }

    fn needs_track(&self) -> bool {
        true
    }

    fn bind_track(&mut self, binding: &TrackBinding) -> Result<(), SimError> {
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
        self.bound = Some(Bound {
            track: binding.track.clone(),
            speed: binding.speed.clone(),
            offset,
            contact,
            law,
            nadal,
        });
        Ok(())
    }

    fn apply(&self, ctx: &ForceContext, wrenches: &mut [Wrench]) -> Result<(), SimError> {
        let state = self.solve(ctx)?;
        for side in 0..2 {
            let body = Some(self.wheel_body(side));
            for c in state.side(side) {
                add_force(wrenches, ctx, body, &c.point, &c.force());
                add_moment(wrenches, body, &(c.n * c.forces.mz));
            }
        }
        Ok(())
    }

    fn output_names(&self) -> Vec<String> {
        let mut names = Vec::new();
        for side in ["L", "R"] {
            for n in [
                "Q [N]",
                "Y [N]",
                "Y/Q [-]",
                "N [N]",
                "Fx [N]",
                "Fy [N]",
                "xi [-]",
                "eta [-]",
                "spin [1/m]",
                "Tgamma [N]",
                "P [W]",
                "Eel [J]",
                "contact_angle [rad]",
                "contact_y [m]",
                "contacts [-]",
                "rolling_radius [m]",
            ] {
                names.push(format!("{side}.{n}"));
            }
        }
        names.push("SumY [N]".into());
        names.push("Nadal [-]".into());
        if self.c.rail.is_some() {
            for side in ["L", "R"] {
                for n in ["rail_dy [m]", "rail_dz [m]"] {
                    names.push(format!("{side}.{n}"));
                }
            }
        }
        names
    }

    fn outputs(&self, ctx: &ForceContext, out: &mut Vec<f64>) {
        let Ok(state) = self.solve(ctx) else {
            // Only at an interpolated output state the steps never visited
            // (the step states themselves were solved): NaN marks the gap.
            out.extend(std::iter::repeat_n(f64::NAN, self.output_names().len()));
            return;
        };
        let loads = Self::wheel_loads(&state);
        for (side, &(q, y)) in loads.iter().enumerate() {
            let contacts = state.side(side);
            let sum = |f: &dyn Fn(&ContactState) -> f64| contacts.iter().map(f).sum::<f64>();
            // The contact carrying the largest normal force describes the wheel.
            let main = contacts
                .iter()
                .max_by(|a, b| a.normal.total_cmp(&b.normal))
                .copied()
                .unwrap_or_default();
            out.extend([
                q,
                y,
                if q > 0.0 { y / q } else { 0.0 },
                sum(&|c| c.normal),
                sum(&|c| c.forces.fx),
                sum(&|c| c.forces.fy),
                main.creepages.xi,
                main.creepages.eta,
                main.creepages.phi,
                // Wear number Tγ = |Fx ξ| + |Fy η| (N), per contact, summed.
                sum(&|c| {
                    (c.forces.fx * c.creepages.xi).abs() + (c.forces.fy * c.creepages.eta).abs()
                }),
                sum(&|c| c.dissipation),
                sum(&|c| c.elastic_energy),
                main.angle,
                main.rail_y,
                contacts.len() as f64,
                main.rolling_radius,
            ]);
        }
        // Track-shifting force: lateral force on the track, positive left =
        // Y_left − Y_right in field-side terms.
        out.push(loads[0].1 - loads[1].1);
        out.push(self.bound.as_ref().map_or(f64::NAN, |b| b.nadal));
        if self.c.rail.is_some() {
            out.extend(state.rail_d.iter().flatten());
        }
    }

    fn assessment_loads(&self, ctx: &ForceContext) -> Option<super::WheelLoads> {
        let state = self.solve(ctx).ok()?;
        // The distance s of the wheelset along the track.
        let distance = self
            .bound
            .as_ref()
            .and_then(|b| b.speed.motion(ctx.t).ok().map(|m| m.s + b.offset));
        Some(super::WheelLoads {
            distance,
            loads: Self::wheel_loads(&state),
            nadal: self.bound.as_ref().map(|b| b.nadal),
        })
    }

    fn remembers_accepted_steps(&self) -> bool {
        // Elastic rails start their damper rate from the accepted step.
        self.c.rail.is_some()
    }

    fn accept_step(&mut self, ctx: &ForceContext) -> Result<(), SimError> {
        let state = self.solve(ctx)?;
        // Elastic rails: this step's rail displacements become the start of
        // the next step's damper rate (never changed inside Newton
        // iterations or by rejected steps).
        if self.c.rail.is_some() {
            self.rail_accepted = Some((ctx.t, state.rail_d, state.rail_creep));
        }
        Ok(())
    }

    fn add_jacobian(&self, ctx: &ForceContext, jac: &mut ForceJacobian) -> Result<(), SimError> {
        let state = self.solve(ctx)?;
        for side in 0..2 {
            for c in state.side(side) {
                // f = N n + Fx eₓ + Fy eᵧ on the wheel at the contact point;
                // d = wheel point − rail point (at rest): ∂N/∂d = −k n,
                // ∂F/∂ḋ ≈ −(f11/V) eₓeₓᵀ − (f22/V) eᵧeᵧᵀ − c_n nnᵀ.
                let nn = c.n * c.n.transpose();
                let kq = -c.normal_stiffness * nn;
                let kv = -(c.f11 / c.speed) * (c.ex * c.ex.transpose())
                    - (c.f22 / c.speed) * (c.ey * c.ey.transpose())
                    - self.c.normal_damping * nn;
                jac.add_point_pair(
                    None,
                    &c.point,
                    Some(self.wheel_body(side)),
                    &c.point,
                    &kq,
                    &kv,
                );
            }
        }
        Ok(())
    }
}
