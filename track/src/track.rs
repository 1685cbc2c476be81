//! The track: alignment, vertical profile, cant, gauge, rail inclination and
//! irregularities, and the track-following frame.

use crate::alignment::{Alignment, AlignmentPoint};
use crate::error::{TrackError, check_param, finite, invalid};
use crate::irregularity::{Irregularities, RailDeviation};
use crate::profile::{PiecewiseLinear, VerticalPoint, VerticalProfile};
use crate::speed::{ArcMotion, SpeedLaw};

/// Standard gravity, m/s² (CGPM 1901).
pub const STANDARD_GRAVITY: f64 = 9.806_65;
/// Standard gauge, m.
pub const STANDARD_GAUGE: f64 = 1.435;
/// Distance between the nominal contact points of standard-gauge track (2e0), m.
pub const STANDARD_RAIL_DISTANCE: f64 = 1.5;
/// The usual rail inclination 1:40 (tangent of the angle).
pub const RAIL_INCLINATION_1_40: f64 = 1.0 / 40.0;

/// A complete track.
#[derive(Debug, Clone, PartialEq)]
pub struct Track {
    alignment: Alignment,
    vertical: VerticalProfile,
    rail_distance: f64,
    nominal_gauge: f64,
    gauge_widening: PiecewiseLinear,
    rail_inclination: f64,
    irregularities: Irregularities,
}

/// Design geometry at one arc position (no irregularities).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct TrackPoint {
    /// Arc position, m.
    pub s: f64,
    /// Plan geometry (x, y, heading, curvature, signed cant).
    pub plan: AlignmentPoint,
    /// Height and grade.
    pub vertical: VerticalPoint,
    /// Pitch θ = −atan(g), rotation about the frame's y axis (right-hand rule:
    /// an up-grade gives θ < 0), rad.
    pub pitch: f64,
    /// dθ/ds, rad/m.
    pub pitch_rate: f64,
    /// d²θ/ds², rad/m².
    pub pitch_rate2: f64,
    /// Cant angle φ = asin(h/(2e0)), rotation about the frame's x axis
    /// (positive: left rail up), rad.
    pub roll: f64,
    /// dφ/ds, rad/m.
    pub roll_rate: f64,
    /// d²φ/ds², rad/m².
    pub roll_rate2: f64,
    /// Design gauge (nominal + design widening), m.
    pub gauge: f64,
}

/// Pose, velocities and accelerations of the track-following frame.
///
/// Origin on the centre line at rail-top level (cant rotates about the centre
/// line); orientation A = Rz(ψ)·Ry(θ)·Rx(φ) (heading, pitch, cant roll), so the
/// frame's x axis is the 3-D tangent, y points to the left rail, z up out of
/// the canted rail plane. `rotation[i][j]` is row i, column j of A; columns are
/// the frame axes in SC0 and v_SC0 = A·v_frame. Vectors named `*_local` are the
/// same vectors resolved in the frame (Aᵀ·v), not relative derivatives; for the
/// angular acceleration both coincide since ω × ω = 0.
///
/// The frame follows the design geometry; irregularities are deviations of the
/// rails from it, resolved in it ([`Track::deviation`]). For a model's
/// rheonomic joint use [`TrackFrame::rheonomic_inputs`] or [`Track::write_inputs`].
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct TrackFrame {
    /// Arc position s, m.
    pub s: f64,
    /// ṡ, m/s.
    pub s_dot: f64,
    /// s̈, m/s².
    pub s_ddot: f64,
    /// Origin in SC0, m.
    pub position: [f64; 3],
    /// Direction cosine matrix A (frame → SC0), row-major.
    pub rotation: [[f64; 3]; 3],
    /// Heading ψ, rad.
    pub heading: f64,
    /// Pitch θ, rad.
    pub pitch: f64,
    /// Cant roll φ, rad.
    pub roll: f64,
    /// Velocity of the origin in SC0, m/s.
    pub velocity: [f64; 3],
    /// Angular velocity in SC0, rad/s.
    pub angular_velocity: [f64; 3],
    /// Acceleration of the origin in SC0, m/s².
    pub acceleration: [f64; 3],
    /// Angular acceleration in SC0, rad/s².
    pub angular_acceleration: [f64; 3],
    /// Velocity resolved in the frame, m/s.
    pub velocity_local: [f64; 3],
    /// Angular velocity resolved in the frame, rad/s.
    pub angular_velocity_local: [f64; 3],
    /// Acceleration resolved in the frame, m/s².
    pub acceleration_local: [f64; 3],
    /// Angular acceleration resolved in the frame, rad/s².
    pub angular_acceleration_local: [f64; 3],
    /// Rates of the angles (ψ̇, θ̇, φ̇), rad/s.
    pub angle_rates: [f64; 3],
    /// Second derivatives of the angles (ψ̈, θ̈, φ̈), rad/s².
    pub angle_accelerations: [f64; 3],
}

/// Number of runtime inputs of one track-following frame: six pose components
/// (x, y, z, yaw, pitch, roll), each as value, rate and acceleration.
pub const FRAME_INPUTS: usize = 18;

impl TrackFrame {
    /// The rheonomic inputs of a model's track-following frame in the order the
    /// engines take them (`railmbs_models::TRACK_FRAME_COMPONENTS`: x, y, z in
    /// SC0, then yaw ψ, pitch θ, roll φ applied as Rz·Ry·Rx), each component as
    /// (value, rate, acceleration): m, m/s, m/s² and rad, rad/s, rad/s².
    pub fn rheonomic_inputs(&self) -> [f64; FRAME_INPUTS] {
        let mut u = [0.0; FRAME_INPUTS];
        for k in 0..3 {
            u[3 * k] = self.position[k];
            u[3 * k + 1] = self.velocity[k];
            u[3 * k + 2] = self.acceleration[k];
        }
        let angles = [self.heading, self.pitch, self.roll];
        for k in 0..3 {
            u[9 + 3 * k] = angles[k];
            u[9 + 3 * k + 1] = self.angle_rates[k];
            u[9 + 3 * k + 2] = self.angle_accelerations[k];
        }
        u
    }
}

impl Track {
    /// A level track on `alignment` with standard gauge, 2e0 = 1.5 m, rail
    /// inclination 1:40 and no irregularities. Fails if a cant reaches 2e0.
    pub fn new(alignment: Alignment) -> Result<Self, TrackError> {
        let t = Track {
            alignment,
            vertical: VerticalProfile::level(),
            rail_distance: STANDARD_RAIL_DISTANCE,
            nominal_gauge: STANDARD_GAUGE,
            gauge_widening: PiecewiseLinear::constant(0.0),
            rail_inclination: RAIL_INCLINATION_1_40,
            irregularities: Irregularities::default(),
        };
        t.check_cant()?;
        Ok(t)
    }

    fn check_cant(&self) -> Result<(), TrackError> {
        for (i, sec) in self.alignment.sections().iter().enumerate() {
            for h in [sec.cant_start, sec.cant_end] {
                if h.abs() >= self.rail_distance {
                    return Err(invalid(
                        format!("section {i} cant"),
                        format!(
                            "|{h}| m must be below the rail distance 2e0 = {} m",
                            self.rail_distance
                        ),
                    ));
                }
            }
        }
        Ok(())
    }

    /// Sets the vertical profile.
    pub fn with_vertical(mut self, vertical: VerticalProfile) -> Self {
        self.vertical = vertical;
        self
    }

    /// Sets the distance between the rails' nominal contact points 2e0 (m),
    /// over which the cant h is measured.
    pub fn with_rail_distance(mut self, rail_distance: f64) -> Result<Self, TrackError> {
        self.rail_distance = check_param("rail distance 2e0", rail_distance, true)?;
        self.check_cant()?;
        Ok(self)
    }

    /// Sets the nominal gauge (m).
    pub fn with_gauge(mut self, gauge: f64) -> Result<Self, TrackError> {
        self.nominal_gauge = check_param("nominal gauge", gauge, true)?;
        Ok(self)
    }

    /// Sets the design gauge widening as knots (s m, widening m), linear between
    /// them and constant beyond (e.g. widening in tight curves).
    pub fn with_gauge_widening(mut self, knots: &[(f64, f64)]) -> Result<Self, TrackError> {
        self.gauge_widening = PiecewiseLinear::new("gauge widening", knots)?;
        Ok(self)
    }

    /// Sets the rail inclination as the tangent of the angle (1/40, 1/20, 0).
    pub fn with_rail_inclination(mut self, inclination: f64) -> Result<Self, TrackError> {
        check_param("rail inclination", inclination, false)?;
        if !(0.0..0.5).contains(&inclination) {
            return Err(invalid(
                "rail inclination",
                format!("{inclination} must be in [0, 0.5) (a tangent, e.g. 1/40)"),
            ));
        }
        self.rail_inclination = inclination;
        Ok(self)
    }

    /// Sets the irregularities.
    pub fn with_irregularities(mut self, irregularities: Irregularities) -> Self {
        self.irregularities = irregularities;
        self
    }

    /// The alignment.
    pub fn alignment(&self) -> &Alignment {
        &self.alignment
    }
    /// The vertical profile.
    pub fn vertical(&self) -> &VerticalProfile {
        &self.vertical
    }
    /// Rail distance 2e0, m.
    pub fn rail_distance(&self) -> f64 {
        self.rail_distance
    }
    /// Nominal gauge, m.
    pub fn nominal_gauge(&self) -> f64 {
        self.nominal_gauge
    }
    /// Rail inclination (tangent).
    pub fn rail_inclination(&self) -> f64 {
        self.rail_inclination
    }
    /// The irregularities.
    pub fn irregularities(&self) -> &Irregularities {
        &self.irregularities
    }
    /// Plan length, m.
    pub fn length(&self) -> f64 {
        self.alignment.length()
    }

    /// Total per-rail deviation from the design geometry at `s`, m (see
    /// [`Irregularities::deviation`]).
    pub fn deviation(&self, s: f64) -> Result<RailDeviation, TrackError> {
        self.irregularities.deviation(s)
    }

    /// Design geometry at `s` (m). No allocation.
    pub fn point(&self, s: f64) -> Result<TrackPoint, TrackError> {
        let plan = self.alignment.point(s)?;
        let vertical = self.vertical.point(s)?;
        let (g, gp) = (vertical.grade, vertical.grade_rate);
        let q = 1.0 + g * g;
        // θ = −atan g: θ' = −g'/(1+g²), θ'' = 2 g g'²/(1+g²)² (g'' = 0 piecewise).
        let pitch = -g.atan();
        let pitch_rate = -gp / q;
        let pitch_rate2 = 2.0 * g * gp * gp / (q * q);
        // φ = asin u, u = h/(2e0): φ' = u'/√(1−u²), φ'' = u u'²/(1−u²)^{3/2} (u'' = 0).
        let u = plan.cant / self.rail_distance;
        let up = plan.cant_rate / self.rail_distance;
        let c2 = 1.0 - u * u;
        let c = c2.sqrt();
        let roll = u.asin();
        let roll_rate = up / c;
        let roll_rate2 = u * up * up / (c2 * c);
        let s = s.clamp(0.0, self.alignment.length());
        let gauge = self.gauge(s)?;
        Ok(TrackPoint {
            s,
            plan,
            vertical,
            pitch,
            pitch_rate,
            pitch_rate2,
            roll,
            roll_rate,
            roll_rate2,
            gauge,
        })
    }

    /// The gauge at arc position `s` (m), in m: [`TrackPoint::gauge`] of
    /// [`Track::point`] without the rest of the point (the contact asks for
    /// it at every wheelset and evaluation), with the same errors for an `s`
    /// off the track.
    pub fn gauge(&self, s: f64) -> Result<f64, TrackError> {
        let s = self.alignment.check_s(s)?;
        let (widening, _) = self.gauge_widening.value_slope(s);
        Ok(self.nominal_gauge + widening)
    }

    /// The track-following frame at arc position `s` (m) moving with `s_dot`
    /// (m/s) and `s_ddot` (m/s²). No allocation. `s` is the plan arc length, so
    /// on a grade g the frame's 3-D speed is ṡ·√(1 + g²).
    ///
    /// Derivation: r(s) = (x, y, z), r' = (cos ψ, sin ψ, g), r'' = (−κ sin ψ,
    /// κ cos ψ, g'); v = r' ṡ, a = r'' ṡ² + r' s̈. ω = ψ̇ e_z + θ̇ Rz e_y + φ̇ Rz Ry e_x
    /// and ω̇ its time derivative, with q̇ = q' ṡ and q̈ = q'' ṡ² + q' s̈ for
    /// q ∈ {ψ, θ, φ}.
    pub fn frame(&self, s: f64, s_dot: f64, s_ddot: f64) -> Result<TrackFrame, TrackError> {
        finite("running speed s_dot", s_dot)?;
        finite("running acceleration s_ddot", s_ddot)?;
        let p = self.point(s)?;
        let psi = p.plan.heading;
        let (th, ph) = (p.pitch, p.roll);
        let (sp, cp) = psi.sin_cos();
        let (st, ct) = th.sin_cos();
        let (sf, cf) = ph.sin_cos();
        // A = Rz(ψ) Ry(θ) Rx(φ).
        let rot = [
            [cp * ct, cp * st * sf - sp * cf, cp * st * cf + sp * sf],
            [sp * ct, sp * st * sf + cp * cf, sp * st * cf - cp * sf],
            [-st, ct * sf, ct * cf],
        ];
        let (v, a) = (s_dot, s_ddot);
        let v2 = v * v;
        let k = p.plan.curvature;
        let g = p.vertical.grade;
        let gp = p.vertical.grade_rate;
        let tangent = [cp, sp, g];
        let normal = [-k * sp, k * cp, gp];
        let velocity = [tangent[0] * v, tangent[1] * v, tangent[2] * v];
        let acceleration = [
            normal[0] * v2 + tangent[0] * a,
            normal[1] * v2 + tangent[1] * a,
            normal[2] * v2 + tangent[2] * a,
        ];
        let psi_d = k * v;
        let psi_dd = p.plan.curvature_rate * v2 + k * a;
        let th_d = p.pitch_rate * v;
        let th_dd = p.pitch_rate2 * v2 + p.pitch_rate * a;
        let ph_d = p.roll_rate * v;
        let ph_dd = p.roll_rate2 * v2 + p.roll_rate * a;
        // Axes: e_z, a_y = Rz e_y, b_x = Rz Ry e_x, and their time derivatives.
        let ay = [-sp, cp, 0.0];
        let ay_d = [-cp * psi_d, -sp * psi_d, 0.0];
        let bx = [cp * ct, sp * ct, -st];
        let bx_d = [
            -sp * ct * psi_d - cp * st * th_d,
            cp * ct * psi_d - sp * st * th_d,
            -ct * th_d,
        ];
        let mut omega = [0.0; 3];
        let mut omega_d = [0.0; 3];
        for i in 0..3 {
            let ez = if i == 2 { 1.0 } else { 0.0 };
            omega[i] = psi_d * ez + th_d * ay[i] + ph_d * bx[i];
            omega_d[i] =
                psi_dd * ez + th_dd * ay[i] + th_d * ay_d[i] + ph_dd * bx[i] + ph_d * bx_d[i];
        }
        let tr = |w: [f64; 3]| -> [f64; 3] {
            [
                rot[0][0] * w[0] + rot[1][0] * w[1] + rot[2][0] * w[2],
                rot[0][1] * w[0] + rot[1][1] * w[1] + rot[2][1] * w[2],
                rot[0][2] * w[0] + rot[1][2] * w[1] + rot[2][2] * w[2],
            ]
        };
        Ok(TrackFrame {
            s: p.s,
            s_dot: v,
            s_ddot: a,
            position: [p.plan.x, p.plan.y, p.vertical.z],
            rotation: rot,
            heading: psi,
            pitch: th,
            roll: ph,
            velocity,
            angular_velocity: omega,
            acceleration,
            angular_acceleration: omega_d,
            velocity_local: tr(velocity),
            angular_velocity_local: tr(omega),
            acceleration_local: tr(acceleration),
            angular_acceleration_local: tr(omega_d),
            angle_rates: [psi_d, th_d, ph_d],
            angle_accelerations: [psi_dd, th_dd, ph_dd],
        })
    }

    /// The track-following frame at time `t` (s) for a running-speed law.
    pub fn frame_at_time(&self, speed: &impl SpeedLaw, t: f64) -> Result<TrackFrame, TrackError> {
        let ArcMotion { s, s_dot, s_ddot } = speed.motion(t)?;
        self.frame(s, s_dot, s_ddot)
    }

    /// The frame `offset` m ahead of the speed law's arc position (a vehicle's
    /// frames sit at s(t) + offset, e.g. ± the bogie semi-spacing), at time `t`.
    pub fn frame_at_time_offset(
        &self,
        speed: &impl SpeedLaw,
        t: f64,
        offset: f64,
    ) -> Result<TrackFrame, TrackError> {
        finite("frame offset", offset)?;
        let ArcMotion { s, s_dot, s_ddot } = speed.motion(t)?;
        self.frame(s + offset, s_dot, s_ddot)
    }

    /// Writes the rheonomic inputs ([`TrackFrame::rheonomic_inputs`]) of
    /// frames at the given arc offsets (m) into `out` (length 18 × offsets), at
    /// time `t`: what a model's `set_inputs` takes. No allocation.
    pub fn write_inputs(
        &self,
        speed: &impl SpeedLaw,
        t: f64,
        offsets: &[f64],
        out: &mut [f64],
    ) -> Result<(), TrackError> {
        if out.len() != FRAME_INPUTS * offsets.len() {
            return Err(TrackError::InputLength {
                expected: FRAME_INPUTS * offsets.len(),
                got: out.len(),
            });
        }
        for (k, &off) in offsets.iter().enumerate() {
            let f = self.frame_at_time_offset(speed, t, off)?;
            out[FRAME_INPUTS * k..FRAME_INPUTS * (k + 1)].copy_from_slice(&f.rheonomic_inputs());
        }
        Ok(())
    }
}

/// Cant angle φ = asin(h/(2e0)) (rad) of a cant `cant` (m) over the rail
/// distance `rail_distance` = 2e0 (m). This crate uses asin throughout: the cant
/// is the height difference of two points 2e0 apart on the canted rail plane.
pub fn cant_angle(cant: f64, rail_distance: f64) -> Result<f64, TrackError> {
    check_param("cant", cant, false)?;
    check_param("rail distance 2e0", rail_distance, true)?;
    if cant.abs() >= rail_distance {
        return Err(invalid(
            "cant",
            format!("|{cant}| m must be below the rail distance {rail_distance} m"),
        ));
    }
    Ok((cant / rail_distance).asin())
}

/// Balancing (equilibrium) speed v_eq = √(g R tan φ) of a curve of radius
/// `radius` (m) with cant angle `cant_angle` (rad, its magnitude is used) under
/// gravity `g` (m/s²), m/s: the speed at which the resultant of gravity and the
/// centrifugal force is normal to the rail plane.
pub fn balancing_speed(radius: f64, cant_angle: f64, g: f64) -> Result<f64, TrackError> {
    check_param("radius", radius, true)?;
    check_param("gravity", g, true)?;
    check_param("cant angle", cant_angle, false)?;
    if cant_angle.abs() >= std::f64::consts::FRAC_PI_2 {
        return Err(invalid(
            "cant angle",
            format!("|{cant_angle}| rad must be < π/2"),
        ));
    }
    Ok((g * radius * cant_angle.abs().tan()).sqrt())
}

/// Uncompensated lateral acceleration a_q = v²/R − g·h/(2e0) (m/s²) at speed
/// `v` (m/s) in a curve of radius `radius` (m) with cant magnitude `cant` (m)
/// over the rail distance 2e0 (m), gravity `g` (m/s²). Positive: outward.
pub fn uncompensated_lateral_acceleration(
    v: f64,
    radius: f64,
    cant: f64,
    rail_distance: f64,
    g: f64,
) -> Result<f64, TrackError> {
    check_param("speed", v, false)?;
    check_param("radius", radius, true)?;
    check_param("cant", cant, false)?;
    check_param("rail distance 2e0", rail_distance, true)?;
    check_param("gravity", g, true)?;
    Ok(v * v / radius - g * cant.abs() / rail_distance)
}

/// Cant deficiency (m): the extra cant that would balance speed `v` (m/s) in a
/// curve of radius `radius` (m) with cant magnitude `cant` (m), i.e.
/// a_q · 2e0 / g = 2e0 v²/(g R) − h.
pub fn cant_deficiency(
    v: f64,
    radius: f64,
    cant: f64,
    rail_distance: f64,
    g: f64,
) -> Result<f64, TrackError> {
    Ok(uncompensated_lateral_acceleration(v, radius, cant, rail_distance, g)? * rail_distance / g)
}
