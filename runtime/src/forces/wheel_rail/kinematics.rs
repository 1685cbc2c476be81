//! Kinematics of the wheelset and its wheels at one state: the wheelset's
//! pose over the track and the rails' shifts by irregularities ([`Side`]),
//! the contact table's region contacts for a pose, and each contact's Hertz
//! shape, point, frame, approach and creepages ([`ContactKinematics`]) before
//! its normal force is known (Pogorelov 2005, Sect. 4).

use super::WheelRailContact;
use super::preparation::Bound;
use crate::forces::ForceContext;
use crate::system::SimError;
use nalgebra::{Matrix3, Vector3};
use railmbs_track::{SpeedLaw, TrackFrame};
use railmbs_wheelrail::creep::Creepages;
use railmbs_wheelrail::creepage::ContactFrame;
use railmbs_wheelrail::geometry::Contact;
use railmbs_wheelrail::hertz::{HertzShape, wheel_rail_curvatures};

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

/// One side (wheel and rail) of the wheelset at one state: what its contacts
/// share.
pub(super) struct Side<'a> {
    pub(super) ctx: &'a ForceContext<'a>,
    pub(super) b: &'a Bound,
    /// 0 left, 1 right.
    pub(super) side: usize,
    /// +1 left, −1 right.
    pub(super) sign: f64,
    /// Lateral shift of the wheelset over this rail (its irregularity taken
    /// off), m.
    pub(super) y: f64,
    /// Roll of the wheelset, rad.
    pub(super) roll: f64,
    /// Height of the axle above the nominal radius, less the rail's vertical
    /// irregularity, m.
    pub(super) z: f64,
    /// Yaw of the axle, rad.
    pub(super) yaw: f64,
    /// Longitudinal position of the axle in the track frame, m.
    pub(super) x_rel: f64,
    /// The rail's rigid shift by irregularities (lateral, vertical), m.
    pub(super) shift: (f64, f64),
    /// Track frame axes and origin, SC0.
    pub(super) axes: Matrix3<f64>,
    pub(super) origin: Vector3<f64>,
    /// Axle direction, SC0.
    pub(super) axle: Vector3<f64>,
    /// Rolling speed dividing the creepages, m/s.
    pub(super) speed: f64,
    /// Body carrying this wheel.
    pub(super) wheel: usize,
}

/// One contact before its normal force is known: its Hertz shape and
/// approach, and where it is ([`PointKinematics`]).
pub(super) struct ContactKinematics {
    pub(super) shape: HertzShape,
    /// Approach along the normal (load weight included), m.
    pub(super) approach: f64,
    pub(super) at: PointKinematics,
}

impl std::ops::Deref for ContactKinematics {
    type Target = PointKinematics;
    fn deref(&self) -> &PointKinematics {
        &self.at
    }
}

impl std::ops::DerefMut for ContactKinematics {
    fn deref_mut(&mut self) -> &mut PointKinematics {
        &mut self.at
    }
}

/// A contact's point, frame, approach rate and creepages, whatever its
/// normal problem (Hertz or a non-elliptic patch).
pub(super) struct PointKinematics {
    /// Normal (n_y, n_z) in the track cross-section.
    pub(super) normal_2d: [f64; 2],
    pub(super) cos_angle: f64,
    pub(super) point: Vector3<f64>,
    pub(super) ex: Vector3<f64>,
    pub(super) ey: Vector3<f64>,
    pub(super) n: Vector3<f64>,
    /// Rate of approach of the wheel surface along the normal, m/s.
    pub(super) approach_rate: f64,
    /// Creepages against a rail at rest.
    pub(super) creepages: Creepages,
    pub(super) speed: f64,
    pub(super) angle: f64,
    pub(super) rail_y: f64,
    pub(super) rolling_radius: f64,
}

impl WheelRailContact {
    /// Both sides (left, right) of the wheelset at the context's state, on
    /// the bound track: the wheelset's pose relative to the design track
    /// frame at its arc position, the rails' shifts by irregularities and
    /// gauge widening there, and the rolling speed.
    pub(super) fn sides<'a>(
        &self,
        ctx: &'a ForceContext<'a>,
        b: &'a Bound,
    ) -> Result<[Side<'a>; 2], SimError> {
        let t = ctx.t;
        let (s, frame) = self.design_frame(t, b)?;
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
            .gauge(s_ws)
            .map_err(|e| self.diverged(t, format!("track at s = {s_ws:.3} m: {e}")))?
            - b.track.nominal_gauge();
        let rail_shift = [
            (dev.left_lateral + 0.5 * widening, dev.left_vertical),
            (dev.right_lateral - 0.5 * widening, dev.right_vertical),
        ];
        let z_geom = rel.z - b.contact.nominal_radius;
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
        Ok(sides)
    }

    /// The arc position (m) of the wheelset's track-following frame at time
    /// `t` (s) and the design track frame there: a function of the time
    /// alone, kept for the last time asked (a step's Newton iterations, its
    /// Jacobian and its acceptance share one time), so the same numbers.
    fn design_frame(&self, t: f64, b: &Bound) -> Result<(f64, TrackFrame), SimError> {
        if let Ok(last) = self.frame_at.lock()
            && let Some((bits, s, frame)) = *last
            && bits == t.to_bits()
        {
            return Ok((s, frame));
        }
        let motion = b
            .speed
            .motion(t)
            .map_err(|e| self.diverged(t, format!("running speed: {e}")))?;
        let s = motion.s + b.offset;
        let frame = b
            .track
            .frame(s, motion.s_dot, motion.s_ddot)
            .map_err(|e| self.diverged(t, format!("track at s = {s:.3} m: {e}")))?;
        if let Ok(mut last) = self.frame_at.lock() {
            *last = Some((t.to_bits(), s, frame));
        }
        Ok((s, frame))
    }

    /// The contact table's region contacts (tread and flange slot) of a
    /// side's wheel at its wheelset position with its rail displaced
    /// laterally by `rail_dy` (m). With a conicity
    /// override the table is looked up at the lateral shift y' = s y
    /// (`shift_scale` s) and each contact's rail point is moved by y − y',
    /// so that it lies where the profiles' contact at y' lies relative to
    /// the wheelset (see the element's "Conicity override").
    pub(super) fn lookup(&self, s: &Side, rail_dy: f64) -> Result<[Contact; 2], SimError> {
        let y = s.y - rail_dy;
        let scale = s.b.shift_scale;
        if scale != 1.0 {
            let scaled = scale * y;
            let mut slots = self.lookup_at(s, scaled)?;
            for c in &mut slots {
                c.rail_y -= scaled - y;
            }
            return Ok(slots);
        }
        self.lookup_at(s, y)
    }

    /// The contact table's region contacts of the side's wheel at the
    /// lateral shift `y` (m) and the side's roll.
    fn lookup_at(&self, s: &Side, y: f64) -> Result<[Contact; 2], SimError> {
        s.b.contact
            .table
            .lookup_regions_of(s.side, y, s.roll)
            .map_err(|e| {
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

    /// One contact's geometry, frame and creepages with the rail displaced
    /// elastically by `d` = (d_y, d_z) (m, track frame; zero for rigid
    /// rails); `None` if it cannot carry load (open gap, or a region's
    /// boundary point that has lost its load).
    pub(super) fn kinematics(
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
        // (the cosine as `point_kinematics` takes it, bit for bit)
        let (_, cd) = c.contact_angle.sin_cos();
        // N ∝ approach^{3/2}: the load scales by `weight`. (Away from a
        // region boundary the weight is 1, and 1^(2/3) = 1 exactly: the
        // power is skipped there, bit for bit the same.)
        let scale = if weight == 1.0 {
            1.0
        } else {
            weight.powf(2.0 / 3.0)
        };
        let approach = penetration * scale * cd;
        // Hertz shape from the curvatures at the contact.
        let (curv_a, curv_b) = wheel_rail_curvatures(
            1.0 / c.wheel_longitudinal_curvature.max(1e-6),
            c.wheel_transverse_curvature,
            c.rail_transverse_curvature,
        );
        let curv_b = curv_b.max(MIN_CURVATURE_RATIO * curv_a);
        let shape = HertzShape::with_modulus(curv_a, curv_b, self.c.e_star)
            .map_err(|e| self.diverged(t, format!("Hertz: {e}")))?;
        let at = self.point_kinematics(s, c, d)?;
        Ok(Some(ContactKinematics {
            shape,
            approach,
            at,
        }))
    }

    /// A contact's point, frame, approach rate and creepages at the contact
    /// point `c` (its rail point, contact angle and rolling radius) with the
    /// rail displaced elastically by `d` = (d_y, d_z) (m, track frame).
    pub(super) fn point_kinematics(
        &self,
        s: &Side,
        c: &Contact,
        d: [f64; 2],
    ) -> Result<PointKinematics, SimError> {
        let t = s.ctx.t;
        let (sd, cd) = c.contact_angle.sin_cos();
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
        Ok(PointKinematics {
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
        })
    }
}
