//! Running speed: the arc position s(t) of a track-following frame and its time
//! derivatives.

use crate::error::{TrackError, check_param, finite, invalid};

/// Arc position and its time derivatives at one instant.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct ArcMotion {
    /// Arc position s, m.
    pub s: f64,
    /// ṡ (running speed along the plan centre line), m/s.
    pub s_dot: f64,
    /// s̈, m/s².
    pub s_ddot: f64,
}

/// A law s(t). Implement it for custom speed profiles; it must not allocate.
pub trait SpeedLaw {
    /// s, ṡ, s̈ at time `t` (s).
    fn motion(&self, t: f64) -> Result<ArcMotion, TrackError>;
}

/// Constant speed: s(t) = s0 + v t.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ConstantSpeed {
    /// Arc position at t = 0, m.
    pub s0: f64,
    /// Speed, m/s.
    pub v: f64,
}

impl ConstantSpeed {
    /// Checks that both values are finite.
    pub fn new(s0: f64, v: f64) -> Result<Self, TrackError> {
        check_param("initial arc position s0", s0, false)?;
        check_param("speed v", v, false)?;
        Ok(ConstantSpeed { s0, v })
    }
}

impl SpeedLaw for ConstantSpeed {
    fn motion(&self, t: f64) -> Result<ArcMotion, TrackError> {
        finite("time t", t)?;
        Ok(ArcMotion {
            s: self.s0 + self.v * t,
            s_dot: self.v,
            s_ddot: 0.0,
        })
    }
}

/// Speed profile v(t) linear between knots (tᵢ, vᵢ), so s̈ is constant on each
/// interval and s(t) is its exact (quadratic) integral; before the first and
/// after the last knot the speed is held constant.
#[derive(Debug, Clone, PartialEq)]
pub struct SpeedTable {
    t: Vec<f64>,
    v: Vec<f64>,
    /// s at each knot, m.
    s: Vec<f64>,
}

impl SpeedTable {
    /// `s0` is the arc position at the first knot's time (m); knots are (t s,
    /// v m/s) with strictly increasing t.
    pub fn new(s0: f64, knots: &[(f64, f64)]) -> Result<Self, TrackError> {
        check_param("speed table s0", s0, false)?;
        if knots.is_empty() {
            return Err(invalid("speed table", "needs at least one knot"));
        }
        let mut t = Vec::with_capacity(knots.len());
        let mut v = Vec::with_capacity(knots.len());
        let mut s = Vec::with_capacity(knots.len());
        for (i, &(ti, vi)) in knots.iter().enumerate() {
            check_param(&format!("speed table knot {i} time"), ti, false)?;
            check_param(&format!("speed table knot {i} speed"), vi, false)?;
            if let Some(&prev) = t.last() {
                if ti <= prev {
                    return Err(invalid(
                        format!("speed table knot {i}"),
                        format!("time {ti} s is not greater than the previous {prev} s"),
                    ));
                }
                let last_s: f64 = *s.last().unwrap_or(&s0);
                let last_v: f64 = *v.last().unwrap_or(&vi);
                s.push(last_s + 0.5 * (last_v + vi) * (ti - prev));
            } else {
                s.push(s0);
            }
            t.push(ti);
            v.push(vi);
        }
        Ok(SpeedTable { t, v, s })
    }
}

impl SpeedTable {
    /// Knot times, s: where s̈ may jump.
    pub fn times(&self) -> &[f64] {
        &self.t
    }
}

impl SpeedLaw for SpeedTable {
    fn motion(&self, t: f64) -> Result<ArcMotion, TrackError> {
        finite("time t", t)?;
        let n = self.t.len();
        if t <= self.t[0] {
            return Ok(ArcMotion {
                s: self.s[0] + self.v[0] * (t - self.t[0]),
                s_dot: self.v[0],
                s_ddot: 0.0,
            });
        }
        if t >= self.t[n - 1] {
            return Ok(ArcMotion {
                s: self.s[n - 1] + self.v[n - 1] * (t - self.t[n - 1]),
                s_dot: self.v[n - 1],
                s_ddot: 0.0,
            });
        }
        let i = self.t.partition_point(|&k| k <= t) - 1;
        let a = (self.v[i + 1] - self.v[i]) / (self.t[i + 1] - self.t[i]);
        let dt = t - self.t[i];
        Ok(ArcMotion {
            s: self.s[i] + self.v[i] * dt + 0.5 * a * dt * dt,
            s_dot: self.v[i] + a * dt,
            s_ddot: a,
        })
    }
}
