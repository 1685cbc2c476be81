//! The nonlinear critical speed, from time-domain runs (the linear one is
//! [`super::speed::critical_speed`]):
//!
//! - a **decelerating run** from a large lateral disturbance: the speed at
//!   which the lateral limit cycle (flange hunting) dies out, found by
//!   [`LimitCycleDetector`] (the one detection of the package: `umsim
//!   critical-speed` and the studies' `CriticalSpeed` reduction use it);
//! - a **bifurcation diagram** by continuation: constant-speed plateaus
//!   stepping the speed down from a hunting state, each started from the
//!   state the previous one ended in ([`Staircase`]: one run whose speed
//!   profile is a staircase, so the state, the force elements' states and
//!   the wheel spin carry over exactly), the limit-cycle amplitude measured
//!   at the end of each plateau after its transient ([`branch_amplitudes`]).
//!   This traces the stable branch (limit cycle or rest) down to the fold;
//!   the unstable branch of a subcritical Hopf bifurcation is not found by
//!   time integration.
//!
//! The amplitude of a signal x over a time window is half its range,
//! ½ (max x − min x): for a limit cycle x = c + a sin ωt sampled often
//! enough over at least a period it is a (to (ωh)²/8 at the sampling
//! interval h), independent of the offset c (a wheelset hunting about an
//! off-centre position).

use super::CoordinateInfo;
use super::CoordinateKind;
use crate::Equations;
use crate::run::{OutputSink, RunError, RunSummary, run_scenario_into};
use railmbs_models::{Axis, ForceKind, Model, Scenario};
use std::collections::VecDeque;

/// Thresholds of the limit-cycle detection.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct DetectionSettings {
    /// Length of the sliding window of the amplitude, s: longer than a
    /// period of the limit cycle (and shorter than the time in which the
    /// run's speed changes the amplitude much).
    pub window: f64,
    /// The amplitude below which a limit cycle has died out (the signal's
    /// unit, m for a lateral displacement).
    pub off: f64,
    /// The amplitude from which a limit cycle is established; above `off`
    /// (hysteresis: an amplitude wandering about one threshold cannot make
    /// the detection flicker).
    pub on: f64,
    /// A limit cycle has also died out when its amplitude falls below this
    /// fraction of the largest it had (0 for none): a flange-hunting cycle
    /// that collapses onto a small residual oscillation of the tread (as
    /// the wheelset on soft springs does, from 6.5 to about 2 mm) collapses
    /// there, whatever the absolute threshold.
    pub relative: f64,
}

impl DetectionSettings {
    /// A window of `window` s, dying out below `off`, established from
    /// twice `off`.
    pub fn new(window: f64, off: f64) -> Self {
        Self {
            window,
            off,
            on: 2.0 * off,
            relative: 0.0,
        }
    }

    /// Checks the settings: a positive window, 0 < off ≤ on, all finite,
    /// 0 ≤ relative < 1.
    ///
    /// # Errors
    /// What is wrong, naming the setting.
    pub fn check(&self) -> Result<(), String> {
        let positive = |name: &str, x: f64| {
            if x.is_finite() && x > 0.0 {
                Ok(())
            } else {
                Err(format!("{name} must be positive and finite, got {x}"))
            }
        };
        positive("window", self.window)?;
        positive("off threshold", self.off)?;
        positive("on threshold", self.on)?;
        if !(0.0..1.0).contains(&self.relative) {
            return Err(format!(
                "the relative threshold must be in [0, 1), got {}",
                self.relative
            ));
        }
        if self.on < self.off {
            return Err(format!(
                "the on threshold {} must not be below the off threshold {}",
                self.on, self.off
            ));
        }
        Ok(())
    }
}

/// Where a limit cycle died out.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Collapse {
    /// Time, s.
    pub t: f64,
    /// Running speed, m/s: the nonlinear critical speed of a decelerating run.
    pub speed: f64,
    /// Arc position on the track, m (None off a track).
    pub position: Option<f64>,
    /// The largest amplitude of the limit cycle that died out (the signal's unit).
    pub amplitude: f64,
}

/// What a run's limit-cycle detection found.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Detection {
    /// The amplitude never reached the on threshold: no limit cycle.
    NoLimitCycle {
        /// The largest amplitude seen.
        max_amplitude: f64,
    },
    /// A limit cycle was still going at the end of the run (it survives
    /// down to the lowest speed of the run).
    StillHunting {
        /// Running speed at the end, m/s.
        speed: f64,
        /// The amplitude at the end.
        amplitude: f64,
    },
    /// The (last) limit cycle died out.
    Collapsed(Collapse),
}

impl Detection {
    /// The collapse's speed, m/s (None without one).
    pub fn speed(&self) -> Option<f64> {
        match self {
            Self::Collapsed(c) => Some(c.speed),
            _ => None,
        }
    }
}

/// A row kept in the window: (t, v, s, the signals' values).
#[derive(Debug, Clone)]
struct Sample {
    t: f64,
    v: f64,
    s: Option<f64>,
    x: Vec<f64>,
}

/// Streaming detection of the end of a limit cycle in the rows of a run:
/// the amplitude at row time t is the largest over the signals of their
/// half ranges over the window [t − window, t]; with hysteresis, a limit
/// cycle is established when the amplitude reaches `on` and has died out
/// when it falls below `off` (or below `relative` times the largest
/// amplitude the cycle had).
///
/// The collapse is placed at the row that just left the window when the
/// amplitude fell below `off`: the window before still had an amplitude of
/// at least `off`, and only by that row, so it is the last extreme of the
/// limit cycle (within one row, independent of the window length).
#[derive(Debug, Clone)]
pub struct LimitCycleDetector {
    settings: DetectionSettings,
    recent: VecDeque<Sample>,
    /// The row that left the window last.
    dropped: Option<Sample>,
    hunting: bool,
    /// The largest amplitude of the present (or last) limit cycle.
    cycle_amplitude: f64,
    max_amplitude: f64,
    amplitude: f64,
    collapse: Option<Collapse>,
    last: Option<(f64, f64)>,
}

impl LimitCycleDetector {
    /// A detector with `settings` ([`DetectionSettings::check`]ed).
    ///
    /// # Errors
    /// Bad settings.
    pub fn new(settings: DetectionSettings) -> Result<Self, String> {
        settings.check()?;
        Ok(Self {
            settings,
            recent: VecDeque::new(),
            dropped: None,
            hunting: false,
            cycle_amplitude: 0.0,
            max_amplitude: 0.0,
            amplitude: 0.0,
            collapse: None,
            last: None,
        })
    }

    /// One row at time `t` (s, increasing), running speed `v` (m/s), arc
    /// position `s` (m), with the signals' values `x` (the same number
    /// every row). A non-finite value counts as no oscillation of its
    /// signal in this row's window (the run reports the failure itself).
    pub fn push(&mut self, t: f64, v: f64, s: Option<f64>, x: &[f64]) {
        self.recent.push_back(Sample {
            t,
            v,
            s,
            x: x.to_vec(),
        });
        while self
            .recent
            .front()
            .is_some_and(|r| r.t < t - self.settings.window)
        {
            self.dropped = self.recent.pop_front();
        }
        let amplitude = (0..x.len())
            .map(|k| {
                let (lo, hi) = self
                    .recent
                    .iter()
                    .map(|r| r.x[k])
                    .filter(|x| x.is_finite())
                    .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), x| {
                        (lo.min(x), hi.max(x))
                    });
                if hi >= lo { 0.5 * (hi - lo) } else { 0.0 }
            })
            .fold(0.0, f64::max);
        self.amplitude = amplitude;
        self.max_amplitude = self.max_amplitude.max(amplitude);
        self.last = Some((v, amplitude));
        if self.hunting {
            self.cycle_amplitude = self.cycle_amplitude.max(amplitude);
            let off = self
                .settings
                .off
                .max(self.settings.relative * self.cycle_amplitude);
            if amplitude < off {
                self.hunting = false;
                let at = self
                    .dropped
                    .as_ref()
                    .or(self.recent.front())
                    .expect("a row was pushed");
                self.collapse = Some(Collapse {
                    t: at.t,
                    speed: at.v,
                    position: at.s,
                    amplitude: self.cycle_amplitude,
                });
            }
        } else if amplitude >= self.settings.on {
            self.hunting = true;
            self.cycle_amplitude = amplitude;
            self.collapse = None;
        }
    }

    /// The amplitude at the last row.
    pub fn amplitude(&self) -> f64 {
        self.amplitude
    }

    /// Whether a limit cycle is established at the last row.
    pub fn hunting(&self) -> bool {
        self.hunting
    }

    /// What the rows so far show.
    pub fn detection(&self) -> Detection {
        match (self.hunting, self.collapse) {
            (true, _) => {
                let (speed, amplitude) = self.last.unwrap_or((f64::NAN, 0.0));
                Detection::StillHunting { speed, amplitude }
            }
            (false, Some(c)) => Detection::Collapsed(c),
            (false, None) => Detection::NoLimitCycle {
                max_amplitude: self.max_amplitude,
            },
        }
    }
}

/// The plan of a continuation in speed: a staircase speed profile of
/// plateaus at `speeds` (descending, m/s), the first held `first_hold` s
/// (for the disturbance to grow into the limit cycle), the others `hold`
/// s, joined by ramps of `ramp` s; the amplitude of each plateau is
/// measured over its last `measure` s.
#[derive(Debug, Clone, PartialEq)]
pub struct Staircase {
    /// Plateau speeds, m/s, descending.
    pub speeds: Vec<f64>,
    /// Length of the first plateau, s.
    pub first_hold: f64,
    /// Length of each other plateau, s.
    pub hold: f64,
    /// Length of the ramp from one plateau to the next, s.
    pub ramp: f64,
    /// The end of each plateau over which its amplitude is measured, s.
    pub measure: f64,
}

impl Staircase {
    /// Checks the plan: at least one speed, descending and non-negative;
    /// positive finite times, `measure` within every plateau.
    ///
    /// # Errors
    /// What is wrong, naming the setting.
    pub fn check(&self) -> Result<(), String> {
        if self.speeds.is_empty() {
            return Err("a continuation needs at least one speed".into());
        }
        if let Some(v) = self.speeds.iter().find(|v| !v.is_finite() || **v < 0.0) {
            return Err(format!(
                "speed {v} m/s of the continuation is not finite and ≥ 0"
            ));
        }
        if self.speeds.windows(2).any(|w| w[1] >= w[0]) {
            return Err("the continuation's speeds must be strictly descending".into());
        }
        for (name, x) in [
            ("first plateau", self.first_hold),
            ("plateau", self.hold),
            ("ramp", self.ramp),
            ("measuring window", self.measure),
        ] {
            if !(x.is_finite() && x > 0.0) {
                return Err(format!(
                    "the {name} length must be positive and finite, got {x} s"
                ));
            }
        }
        if self.measure > self.hold.min(self.first_hold) {
            return Err(format!(
                "the measuring window ({} s) must fit in a plateau ({} s)",
                self.measure,
                self.hold.min(self.first_hold)
            ));
        }
        Ok(())
    }

    /// (start, end) of each plateau, s.
    pub fn plateaus(&self) -> Vec<(f64, f64)> {
        let mut out = Vec::with_capacity(self.speeds.len());
        let mut t = 0.0;
        for k in 0..self.speeds.len() {
            let hold = if k == 0 { self.first_hold } else { self.hold };
            out.push((t, t + hold));
            t += hold + self.ramp;
        }
        out
    }

    /// The speed profile, knots (t s, v m/s): the speed constant on each
    /// plateau and linear on the ramps.
    pub fn profile(&self) -> Vec<(f64, f64)> {
        self.plateaus()
            .iter()
            .zip(&self.speeds)
            .flat_map(|(&(a, b), &v)| [(a, v), (b, v)])
            .collect()
    }

    /// The end of the last plateau, s.
    pub fn end_time(&self) -> f64 {
        self.plateaus().last().map_or(0.0, |p| p.1)
    }

    /// The distance run, m.
    pub fn distance(&self) -> f64 {
        let knots = self.profile();
        knots
            .windows(2)
            .map(|w| 0.5 * (w[0].1 + w[1].1) * (w[1].0 - w[0].0))
            .sum()
    }
}

/// One point of a bifurcation diagram.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BranchPoint {
    /// Running speed, m/s.
    pub speed: f64,
    /// Amplitude over the plateau's measuring window (largest over the
    /// signals; the signals' unit).
    pub amplitude: f64,
    /// Amplitude over the window's first half.
    pub early: f64,
    /// Amplitude over its second half.
    pub late: f64,
}

impl BranchPoint {
    /// Whether the transient has died out: the two halves' amplitudes
    /// agree within 5 % of the larger (or both are below `floor`).
    pub fn settled(&self, floor: f64) -> bool {
        let big = self.early.max(self.late);
        big < floor || (self.early - self.late).abs() <= 0.05 * big
    }
}

/// Half the range of `x` over the rows with time in [a, b] (0 without any).
fn half_range(t: &[f64], x: &[f64], a: f64, b: f64) -> f64 {
    let (lo, hi) = t
        .iter()
        .zip(x)
        .filter(|(t, x)| (a..=b).contains(*t) && x.is_finite())
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), (_, &x)| {
            (lo.min(x), hi.max(x))
        });
    if hi >= lo { 0.5 * (hi - lo) } else { 0.0 }
}

/// The bifurcation diagram of a run along `plan`: rows at times `t` (s)
/// with `signals` (each a column of the same length), the amplitude of
/// each plateau over its last `plan.measure` s.
pub fn branch_amplitudes(plan: &Staircase, t: &[f64], signals: &[&[f64]]) -> Vec<BranchPoint> {
    plan.plateaus()
        .iter()
        .zip(&plan.speeds)
        .map(|(&(_, end), &speed)| {
            let start = end - plan.measure;
            let mid = end - 0.5 * plan.measure;
            let amp = |a: f64, b: f64| {
                signals
                    .iter()
                    .map(|x| half_range(t, x, a, b))
                    .fold(0.0, f64::max)
            };
            BranchPoint {
                speed,
                amplitude: amp(start, end),
                early: amp(start, mid),
                late: amp(mid, end),
            }
        })
        .collect()
}

/// The lateral coordinates (in the wheelsets' track-following frames) of
/// the wheelsets of `model`'s wheel–rail elements: the signals of hunting.
pub fn wheelset_lateral_coordinates(model: &Model, coordinates: &[CoordinateInfo]) -> Vec<String> {
    let mut out = Vec::new();
    for f in &model.forces {
        if let ForceKind::WheelRail(w) = &f.kind {
            let body = &model.bodies[w.wheelset].name;
            for c in coordinates {
                if &c.owner == body
                    && c.kind == CoordinateKind::Translation(Axis::Y)
                    && !out.contains(&c.name)
                {
                    out.push(c.name.clone());
                }
            }
        }
    }
    out
}

/// Keeps the time, speed, position and `signals` columns of a run's rows
/// and passes every row on to `inner`.
struct Recorder<'a> {
    inner: &'a mut dyn OutputSink,
    signals: Vec<String>,
    /// (time, v, s, signals…) column indices.
    index: Vec<Option<usize>>,
    columns: Vec<Vec<f64>>,
}

impl OutputSink for Recorder<'_> {
    fn begin(&mut self, header: &[String]) -> Result<(), RunError> {
        let find = |n: &str| header.iter().position(|h| h == n);
        self.index = ["time", "v[m/s]", "s[m]"]
            .iter()
            .map(|n| find(n))
            .chain(self.signals.iter().map(|n| find(n)))
            .collect();
        if let Some(k) = self.signals.iter().position(|n| find(n).is_none()) {
            return Err(RunError::Sim(crate::SimError::Other(format!(
                "no output column \"{}\" (the limit-cycle signal); the columns are: {}",
                self.signals[k],
                header.join(", ")
            ))));
        }
        self.columns = vec![Vec::new(); self.index.len()];
        self.inner.begin(header)
    }

    fn row(&mut self, values: &[f64]) -> Result<(), RunError> {
        for (c, i) in self.columns.iter_mut().zip(&self.index) {
            c.push(i.map_or(f64::NAN, |i| values[i]));
        }
        self.inner.row(values)
    }

    fn accepted_loads(
        &mut self,
        samples: &[crate::run::LoadSample],
        name: &dyn Fn(usize) -> String,
    ) {
        self.inner.accepted_loads(samples, name);
    }

    fn finish(&mut self) -> Result<(), RunError> {
        self.inner.finish()
    }
}

/// A run of `scenario` whose rows are also kept: (summary, columns time,
/// v, s, then `signals`).
fn recorded_run(
    scenario: &Scenario,
    model: &Model,
    equations: Box<dyn Equations>,
    signals: &[String],
    sink: &mut dyn OutputSink,
    progress: impl FnMut(f64),
) -> Result<(RunSummary, Vec<Vec<f64>>), RunError> {
    let mut s = scenario.clone();
    // The signals are coordinates: make sure they are written.
    s.output.coordinates = true;
    let mut rec = Recorder {
        inner: sink,
        signals: signals.to_vec(),
        index: Vec::new(),
        columns: Vec::new(),
    };
    let summary = run_scenario_into(&s, model, equations, &mut rec, progress)?;
    Ok((summary, rec.columns))
}

/// The nonlinear critical speed of `scenario`, a decelerating run (its
/// `speed_profile`) from a large disturbance: the run (rows also written
/// to `sink`) and where the limit cycle of `signals` (coordinates, e.g.
/// [`wheelset_lateral_coordinates`]) died out.
///
/// # Errors
/// Bad settings, a scenario that cannot run, or a signal that is not a
/// coordinate. A run that fails part-way is not an error here: the summary
/// carries it, and the detection covers the rows written.
pub fn decelerating_run(
    scenario: &Scenario,
    model: &Model,
    equations: Box<dyn Equations>,
    signals: &[String],
    settings: DetectionSettings,
    sink: &mut dyn OutputSink,
    progress: impl FnMut(f64),
) -> Result<(RunSummary, Detection), RunError> {
    let setup = |message: String| RunError::Setup {
        file: scenario.source.clone(),
        message,
    };
    settings.check().map_err(setup)?;
    if signals.is_empty() {
        return Err(setup(
            "no signal for the limit cycle (the model has no wheelset on a wheel–rail element; \
             name a coordinate)"
                .into(),
        ));
    }
    let (summary, columns) = recorded_run(scenario, model, equations, signals, sink, progress)?;
    let mut detector = LimitCycleDetector::new(settings).map_err(setup)?;
    let mut x = vec![0.0; signals.len()];
    for k in 0..columns[0].len() {
        for (x, c) in x.iter_mut().zip(&columns[3..]) {
            *x = c[k];
        }
        let s = Some(columns[2][k]).filter(|s| s.is_finite());
        detector.push(columns[0][k], columns[1][k], s, &x);
    }
    Ok((summary, detector.detection()))
}

/// The bifurcation diagram of `scenario` by continuation along `plan`
/// (the scenario's track, start and initial state, its speed replaced by
/// the plan's staircase, the model parameter `v0` set to the first speed
/// when it has one, as [`super::speed::at_speed`]): the run (rows also
/// written to `sink`) and the amplitude of `signals` on each plateau.
///
/// # Errors
/// A bad plan, a scenario off a track or whose track is shorter than the
/// run, or one that cannot run.
pub fn bifurcation(
    scenario: &Scenario,
    model: &Model,
    equations: Box<dyn Equations>,
    signals: &[String],
    plan: &Staircase,
    sink: &mut dyn OutputSink,
    progress: impl FnMut(f64),
) -> Result<(RunSummary, Vec<BranchPoint>), RunError> {
    let setup = |message: String| RunError::Setup {
        file: scenario.source.clone(),
        message,
    };
    plan.check().map_err(setup)?;
    let mut s = scenario.clone();
    let Some(track) = &mut s.track else {
        return Err(setup(
            "a continuation in speed needs a scenario on a track".into(),
        ));
    };
    let distance = plan.distance();
    let room = track.track.length() - track.start;
    if distance > room {
        return Err(setup(format!(
            "the continuation runs {distance:.0} m but the track ({}) has {room:.0} m after the \
             start: use fewer or shorter plateaus, or a longer track",
            track.file.display()
        )));
    }
    track.speed = plan.speeds[0];
    track.speed_profile = plan.profile();
    s.end_time = plan.end_time();
    if model.parameter_index("v0").is_some() {
        s.set_parameter("v0", &format!("{:?}", plan.speeds[0]));
    }
    let (summary, columns) = recorded_run(&s, model, equations, signals, sink, progress)?;
    let signals: Vec<&[f64]> = columns[3..].iter().map(Vec::as_slice).collect();
    let points = branch_amplitudes(plan, &columns[0], &signals);
    // Plateaus the run did not reach (it failed) are left out.
    let reached = plan
        .plateaus()
        .iter()
        .take_while(|p| p.1 <= summary.t_end + 1e-9)
        .count();
    Ok((summary, points.into_iter().take(reached).collect()))
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The oscillator x'' − ε g(x; μ) x' + x = 0 with g = μ + x² − x⁴: by
    /// first-order averaging (x = a cos t, Krylov–Bogoliubov) its amplitude
    /// obeys da/dt = ε a (μ/2 + a²/8 − a⁴/16), a subcritical Hopf
    /// bifurcation at μ = 0 whose stable limit cycles have
    /// a² = 1 + √(1 + 8μ) down to the fold at μ = −1/8 (a = 1). The
    /// "speed" is v with μ = (v − 50)/80: Hopf at 50, fold at 40.
    fn mu(v: f64) -> f64 {
        (v - 50.0) / 80.0
    }

    const EPS: f64 = 0.1;

    /// The stable limit cycle's amplitude by averaging.
    fn averaged_amplitude(v: f64) -> f64 {
        (1.0 + (1.0 + 8.0 * mu(v)).sqrt()).sqrt()
    }

    /// Classical RK4 of the oscillator from (x, ẋ) over [t0, t1] with the
    /// speed law `speed(t)`, writing (t, v, x) every `every` steps.
    fn integrate(
        state: &mut [f64; 2],
        (t0, t1): (f64, f64),
        speed: &dyn Fn(f64) -> f64,
        mut row: impl FnMut(f64, f64, f64),
    ) {
        let h = 0.05;
        let f = |t: f64, y: [f64; 2]| {
            let g = mu(speed(t)) + y[0] * y[0] - y[0].powi(4);
            [y[1], EPS * g * y[1] - y[0]]
        };
        let n = ((t1 - t0) / h).round() as usize;
        for k in 0..n {
            let t = t0 + k as f64 * h;
            let y = *state;
            let k1 = f(t, y);
            let k2 = f(
                t + h / 2.0,
                [y[0] + h / 2.0 * k1[0], y[1] + h / 2.0 * k1[1]],
            );
            let k3 = f(
                t + h / 2.0,
                [y[0] + h / 2.0 * k2[0], y[1] + h / 2.0 * k2[1]],
            );
            let k4 = f(t + h, [y[0] + h * k3[0], y[1] + h * k3[1]]);
            for i in 0..2 {
                state[i] = y[i] + h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]);
            }
            if k % 4 == 3 {
                let t = t + h;
                row(t, speed(t), state[0]);
            }
        }
    }

    fn interpolate(knots: &[(f64, f64)], t: f64) -> f64 {
        if t <= knots[0].0 {
            return knots[0].1;
        }
        for w in knots.windows(2) {
            if t <= w[1].0 {
                return w[0].1 + (w[1].1 - w[0].1) * (t - w[0].0) / (w[1].0 - w[0].0);
            }
        }
        knots[knots.len() - 1].1
    }

    /// Continuation down the stable branch: each plateau's amplitude is the
    /// averaged one within 0.2 % (found 1e-5: the first-order averaging's
    /// amplitude error is O(ε²) for this damping, odd in ẋ; the slowest
    /// transient, at 41, decays as e^(−ε a²(a² − 1)/4 · t) = e^(−12) over
    /// a plateau of 1200); below the fold the oscillation dies out.
    #[test]
    fn continuation_follows_the_averaged_stable_branch_down_to_the_fold() {
        let plan = Staircase {
            speeds: vec![60.0, 55.0, 50.0, 46.0, 43.0, 41.0, 38.0],
            first_hold: 1500.0,
            hold: 1200.0,
            ramp: 20.0,
            measure: 100.0,
        };
        plan.check().unwrap();
        let knots = plan.profile();
        let (mut t, mut x) = (vec![], vec![]);
        let mut state = [0.5, 0.0];
        integrate(
            &mut state,
            (0.0, plan.end_time()),
            &|t| interpolate(&knots, t),
            |tt, _, xx| {
                t.push(tt);
                x.push(xx);
            },
        );
        let points = branch_amplitudes(&plan, &t, &[&x]);
        for p in &points {
            if p.speed >= 40.0 {
                let a = averaged_amplitude(p.speed);
                assert!(
                    (p.amplitude - a).abs() < 2e-3 * a,
                    "at {}: {} against {a}",
                    p.speed,
                    p.amplitude
                );
                assert!(p.settled(1e-3), "{p:?}");
            } else {
                assert!(p.amplitude < 0.01, "{p:?}");
            }
        }
    }

    /// Decelerating runs: the limit cycle survives the Hopf point (50) and
    /// dies out below the fold (40), after a delay: the slow passage
    /// through the saddle-node's bottleneck takes a time of order
    /// (ε² |dμ/dt|)^(−1/3) (the normal form ȧ = c₀ μ̇ t + c₁ a², with both
    /// coefficients ∝ ε), so the delay in speed scales as the deceleration
    /// to the power 2/3: 8 times slower, 4 times closer (checked within 25 %).
    #[test]
    fn a_decelerating_run_finds_the_fold_not_the_hopf_point() {
        let collapse = |rate: f64| {
            let speed = |t: f64| 50.0 - rate * t;
            let mut detector = LimitCycleDetector::new(DetectionSettings::new(20.0, 0.3)).unwrap();
            // Started on the limit cycle at the Hopf point.
            let mut state = [averaged_amplitude(50.0), 0.0];
            integrate(&mut state, (0.0, 15.0 / rate), &speed, |t, v, x| {
                detector.push(t, v, Some(10.0 * t), &[x]);
            });
            let Detection::Collapsed(c) = detector.detection() else {
                panic!("{:?}", detector.detection())
            };
            assert!((c.position.unwrap() - 10.0 * c.t).abs() < 1e-9);
            assert!(
                (c.amplitude - averaged_amplitude(50.0)).abs() < 0.01,
                "{c:?}"
            );
            c.speed
        };
        let (fast, slow) = (collapse(0.004), collapse(0.0005));
        println!("collapse at {fast} and {slow}");
        assert!(fast < 40.0 && slow < 40.0 && slow > fast, "{fast} {slow}");
        let ratio = (40.0 - slow) / (40.0 - fast);
        assert!((ratio - 0.25).abs() < 0.25 * 0.25, "delay ratio {ratio}");
    }

    /// The detector's hysteresis and the collapse's place: a signal of
    /// amplitude 1 that stops at a known row is placed there whatever the
    /// window; a signal wandering between off and on never counts twice.
    #[test]
    fn the_collapse_is_the_last_extreme_of_the_limit_cycle() {
        for window in [0.5, 1.0, 2.0] {
            let mut d = LimitCycleDetector::new(DetectionSettings::new(window, 0.2)).unwrap();
            for k in 0..1000 {
                let t = 0.01 * k as f64;
                let x = if k <= 499 {
                    if k % 2 == 0 { 1.0 } else { -1.0 }
                } else {
                    0.0
                };
                d.push(t, 60.0 - t, None, &[x]);
            }
            assert_eq!(
                d.detection(),
                Detection::Collapsed(Collapse {
                    t: 4.99,
                    speed: 60.0 - 4.99,
                    position: None,
                    amplitude: 1.0
                }),
                "window {window}"
            );
        }
        // Amplitude 0.3 (between off 0.2 and on 0.4): no limit cycle.
        let mut d = LimitCycleDetector::new(DetectionSettings::new(1.0, 0.2)).unwrap();
        for k in 0..500 {
            d.push(0.01 * k as f64, 1.0, None, &[0.3 * (0.5 * k as f64).sin()]);
        }
        assert!(matches!(d.detection(), Detection::NoLimitCycle { .. }));
        assert!(LimitCycleDetector::new(DetectionSettings::new(1.0, -1.0)).is_err());
    }
}
