//! Creepages and spin at a wheel–rail contact from the velocities of the two
//! bodies.
//!
//! Conventions (those of Kalker and CONTACT, body 1 = wheel, body 2 = rail):
//!
//! - the contact frame is right-handed `(eₓ, eᵧ, n)`: `eₓ` the rolling direction
//!   in the tangent plane, `n` the contact normal pointing from the rail into the
//!   wheel (upward on the tread), `eᵧ = n × eₓ` (to the left for `n` up and `eₓ`
//!   forward);
//! - creepages are the relative sliding velocity of the wheel's material point
//!   over the rail's at the contact point, divided by the rolling speed `V`:
//!   `ξ = (v_w − v_r)·eₓ / V`, `η = (v_w − v_r)·eᵧ / V`, and the spin
//!   `φ = (ω_w − ω_r)·n / V` (1/m);
//! - the creep forces computed from them ([`crate::creep`]) act **on the wheel**,
//!   opposing the sliding: `Fx < 0` for `ξ > 0` (linear theory
//!   `Fx = −G c² C11 ξ`).
//!
//! Example (hand calculation in the tests): a wheelset rolling at speed `V` with
//! wheel rolling radius `r` and nominal radius `r0` has `ξ ≈ 1 − r/r0`; yawed by
//! `ψ` it has `η = −sin ψ`, a lateral velocity `ẏ` adds `ẏ/V`; on a cone of
//! contact angle `δ` the left wheel (normal tilted inward, `n = (0, −sin δ, cos δ)`)
//! has spin `φ = −sin δ / r0 + ψ̇ cos δ / V`, the right wheel `+sin δ / r0 + ψ̇ cos δ / V`.

/// Creepages at one contact: longitudinal `xi` (–), lateral `eta` (–), spin
/// `phi` (1/m).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Creepages {
    /// Longitudinal creepage ξ, –.
    pub xi: f64,
    /// Lateral creepage η, –.
    pub eta: f64,
    /// Spin creepage φ, 1/m.
    pub phi: f64,
}

/// Orthonormal contact frame: rolling direction `ex`, lateral `ey = n × ex`,
/// normal `n` (rail → wheel), all unit vectors in one common frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ContactFrame {
    /// Rolling direction (unit).
    pub ex: [f64; 3],
    /// Lateral direction `n × ex` (unit).
    pub ey: [f64; 3],
    /// Normal from rail into wheel (unit).
    pub n: [f64; 3],
}

/// Errors of the creepage calculation.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum CreepageError {
    /// The rolling speed is not positive and finite (creepages are undefined at standstill).
    #[error("creepage: rolling speed must be positive and finite, got {0} m/s")]
    RollingSpeed(f64),
    /// A velocity or frame component is not finite.
    #[error("creepage: {0} has a non-finite component")]
    NotFinite(&'static str),
    /// The frame is not orthonormal and right-handed.
    #[error("creepage: contact frame is not orthonormal and right-handed (ey must equal n × ex)")]
    Frame,
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn cross(a: [f64; 3], b: [f64; 3]) -> [f64; 3] {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

impl ContactFrame {
    /// Frame from the normal `n` (rail → wheel) and an approximate rolling
    /// direction `forward` (projected into the tangent plane and normalised).
    /// `None` if either is zero/non-finite or they are parallel.
    pub fn from_normal_and_forward(n: [f64; 3], forward: [f64; 3]) -> Option<Self> {
        let nn = dot(n, n).sqrt();
        if !(nn.is_finite() && nn > 0.0) {
            return None;
        }
        let n = [n[0] / nn, n[1] / nn, n[2] / nn];
        let f = dot(forward, n);
        let t = [
            forward[0] - f * n[0],
            forward[1] - f * n[1],
            forward[2] - f * n[2],
        ];
        let tn = dot(t, t).sqrt();
        if !(tn.is_finite() && tn > 1e-12 * dot(forward, forward).sqrt()) {
            return None;
        }
        let ex = [t[0] / tn, t[1] / tn, t[2] / tn];
        Some(Self {
            ex,
            ey: cross(n, ex),
            n,
        })
    }
}

impl Creepages {
    /// Creepages from the velocities (m/s) of the wheel's and the rail's material
    /// points at the contact point, their angular velocities (rad/s), the contact
    /// frame and the rolling speed `v_roll` (m/s, positive), all vectors in one
    /// common frame.
    pub fn from_velocities(
        v_wheel: [f64; 3],
        v_rail: [f64; 3],
        omega_wheel: [f64; 3],
        omega_rail: [f64; 3],
        frame: &ContactFrame,
        v_roll: f64,
    ) -> Result<Self, CreepageError> {
        if !(v_roll.is_finite() && v_roll > 0.0) {
            return Err(CreepageError::RollingSpeed(v_roll));
        }
        for (name, v) in [
            ("wheel velocity", v_wheel),
            ("rail velocity", v_rail),
            ("wheel angular velocity", omega_wheel),
            ("rail angular velocity", omega_rail),
            ("contact frame ex", frame.ex),
            ("contact frame ey", frame.ey),
            ("contact frame n", frame.n),
        ] {
            if !v.iter().all(|c| c.is_finite()) {
                return Err(CreepageError::NotFinite(name));
            }
        }
        let c = cross(frame.n, frame.ex);
        let ortho = (dot(frame.ex, frame.ex) - 1.0).abs() < 1e-9
            && (dot(frame.n, frame.n) - 1.0).abs() < 1e-9
            && dot(frame.ex, frame.n).abs() < 1e-9
            && (0..3).all(|i| (c[i] - frame.ey[i]).abs() < 1e-9);
        if !ortho {
            return Err(CreepageError::Frame);
        }
        let dv = [
            v_wheel[0] - v_rail[0],
            v_wheel[1] - v_rail[1],
            v_wheel[2] - v_rail[2],
        ];
        let dw = [
            omega_wheel[0] - omega_rail[0],
            omega_wheel[1] - omega_rail[1],
            omega_wheel[2] - omega_rail[2],
        ];
        Ok(Self {
            xi: dot(dv, frame.ex) / v_roll,
            eta: dot(dv, frame.ey) / v_roll,
            phi: dot(dw, frame.n) / v_roll,
        })
    }
}
