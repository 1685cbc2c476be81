//! The track as the input provider of a model's track-following frames.

use crate::inputs::InputProvider;
use crate::system::SimError;
use railmbs_models::Model;
use railmbs_track::{ArcMotion, ConstantSpeed, SpeedLaw, SpeedTable, Track, TrackError};
use std::sync::Arc;

/// Drives every track-following frame of a model along a track: frame k sits
/// at arc position s(t) + offset_k, with s(t) from the speed law. Implemented
/// as an input provider for constant speed (what scenarios give), where the
/// times at which frames pass the track's kinks are known in closed form.
pub struct TrackInputs<S: SpeedLaw + Send> {
    track: Arc<Track>,
    speed: S,
    /// Arc offsets of the frames, m.
    offsets: Vec<f64>,
    /// The inputs last written and the time they are for: a step's Newton
    /// iterations, its finite-difference Jacobian and its acceptance all
    /// evaluate at one time, and the inputs depend on the time alone, so
    /// they are copied, not recomputed (the same numbers: a pure function
    /// of `t`'s bits).
    last: (Option<u64>, Vec<f64>),
}

impl<S: SpeedLaw + Send> TrackInputs<S> {
    /// The frames of `model` (offsets evaluated with `params`) on `track`.
    pub fn for_model(
        model: &Model,
        params: &[f64],
        track: Arc<Track>,
        speed: S,
    ) -> Result<Self, SimError> {
        let offsets = model
            .track_frames
            .iter()
            .map(|f| {
                let x = f.offset.eval(params, 0.0);
                if x.is_finite() {
                    Ok(x)
                } else {
                    Err(SimError::Other(format!(
                        "model \"{}\": the track offset of body \"{}\" is not finite ({x})",
                        model.name, model.bodies[f.body].name
                    )))
                }
            })
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Self {
            track,
            speed,
            offsets,
            last: (None, Vec::new()),
        })
    }
}

/// Arc positions where the track's design geometry has kinks: section joints
/// (curvature rate and cant rate change there).
fn kinks(track: &Track) -> Vec<f64> {
    let a = track.alignment();
    (1..a.sections().len())
        .filter_map(|i| a.section_start(i))
        .collect()
}

/// The running speed of a scenario: constant, or a profile of knots (t, v).
#[derive(Debug, Clone, PartialEq)]
pub enum RunningSpeed {
    /// Constant speed: s(t) = s0 + v t (m, m/s).
    Constant(ConstantSpeed),
    /// Speed linear between knots (t, v) (s, m/s), held constant outside.
    Profile(SpeedTable),
}

impl SpeedLaw for RunningSpeed {
    fn motion(&self, t: f64) -> Result<ArcMotion, TrackError> {
        match self {
            RunningSpeed::Constant(c) => c.motion(t),
            RunningSpeed::Profile(p) => p.motion(t),
        }
    }
}

impl RunningSpeed {
    /// Times where s̈ jumps (knots of a profile), s.
    fn knots(&self) -> &[f64] {
        match self {
            RunningSpeed::Constant(_) => &[],
            RunningSpeed::Profile(p) => p.times(),
        }
    }

    /// The time in (t0, t1) at which s(t) = `target`, if s passes it there
    /// (s is non-decreasing: the speed is never negative). Closed form at
    /// constant speed, bisection to rounding otherwise.
    fn time_at(&self, target: f64, t0: f64, t1: f64) -> Option<f64> {
        if let RunningSpeed::Constant(c) = self {
            if c.v == 0.0 {
                return None;
            }
            let t = (target - c.s0) / c.v;
            return (t > t0 && t < t1).then_some(t);
        }
        let s = |t: f64| self.motion(t).map(|m| m.s).ok();
        let (mut a, mut b) = (t0, t1);
        if !(s(a)? < target && s(b)? > target) {
            return None;
        }
        for _ in 0..200 {
            let m = 0.5 * (a + b);
            if m <= a || m >= b {
                break;
            }
            if s(m)? < target {
                a = m;
            } else {
                b = m;
            }
        }
        Some(0.5 * (a + b))
    }
}

impl InputProvider for TrackInputs<RunningSpeed> {
    fn input_count(&self) -> usize {
        6 * self.offsets.len()
    }

    fn inputs(&mut self, t: f64, out: &mut [f64]) -> Result<(), SimError> {
        let (time, values) = &mut self.last;
        if *time == Some(t.to_bits()) && values.len() == out.len() {
            out.copy_from_slice(values);
            return Ok(());
        }
        *time = None;
        self.track
            .write_inputs(&self.speed, t, &self.offsets, out)
            .map_err(|e| SimError::Diverged {
                t,
                reason: format!("track-following frame: {e}"),
            })?;
        values.clear();
        values.extend_from_slice(out);
        *time = Some(t.to_bits());
        Ok(())
    }

    /// Frame k passes the kink at s_b when s(t) + offset_k = s_b; a speed
    /// profile's knots are breakpoints too (the frames' accelerations jump).
    fn breakpoints(&self, t0: f64, t1: f64) -> Vec<f64> {
        let mut times: Vec<f64> = kinks(&self.track)
            .iter()
            .flat_map(|&sb| {
                self.offsets
                    .iter()
                    .filter_map(move |off| self.speed.time_at(sb - off, t0, t1))
            })
            .chain(
                self.speed
                    .knots()
                    .iter()
                    .copied()
                    .filter(|&t| t > t0 && t < t1),
            )
            .collect();
        times.sort_by(f64::total_cmp);
        times.dedup_by(|a, b| (*a - *b).abs() < 1e-9);
        times
    }
}

impl<S: SpeedLaw + Send> TrackInputs<S> {
    /// The frames' arc offsets, m.
    pub fn offsets(&self) -> &[f64] {
        &self.offsets
    }
}
