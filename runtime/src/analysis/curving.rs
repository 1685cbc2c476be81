//! Quasi-static curving: the steady state of a vehicle in a constant curve
//! at constant speed, solved directly.
//!
//! The vehicle's coordinates are relative to track-following frames; on a
//! circular curve of constant cant run at constant speed the frames' rates
//! and accelerations (the centripetal acceleration V²/R, the yaw rate V/R,
//! the cant's gravity component) are the same at every arc position, so the
//! steady curving state is an equilibrium in those frames
//! ([`super::equilibrium`]): the suspension and contact coordinates at rest
//! relative to their frames, the wheels' spin rates solved, the
//! longitudinal position held. The scenario's vehicle is put on a circular
//! curve of [`CURVE_LENGTH`] m (its own track replaced), at the middle of
//! it, and solved there with every force element and the wheel–rail contact
//! of its model, exactly as a run would see them.

use super::CoordinateInfo;
use super::equilibrium::{Equilibrium, EquilibriumSettings};
use super::speed::at_speed;
use super::{CoordinateKind, wheel_loads};
use crate::Equations;
use crate::equations::Parts;
use crate::forces::ContactTableCache;
use crate::run::RunError;
use crate::run::scenario::{ScenarioSystem, scenario_system_with};
use railmbs_models::{Axis, ForceKind, InitialOverride, Model, Scenario};
use railmbs_track::{Alignment, Direction, Section, Track};
use std::sync::Arc;
use std::time::Instant;

/// Length of the circular curve the vehicle is put on, m (its reference
/// point at the middle): long enough for any vehicle's track frames.
pub const CURVE_LENGTH: f64 = 2000.0;

/// A constant curve run at constant speed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Curve {
    /// Radius, m, signed: positive for a left curve, negative for a right one.
    pub radius: f64,
    /// Cant (height of the outer rail above the inner), m, ≥ 0.
    pub cant: f64,
    /// Running speed, m/s.
    pub speed: f64,
}

impl Curve {
    /// Uncompensated lateral acceleration V²/R − g h/(2 e0) in the track
    /// plane, m/s² (2 e0 = 1.5 m the rail distance, g = 9.81 m/s²).
    pub fn cant_deficiency_acceleration(&self) -> f64 {
        self.speed * self.speed / self.radius.abs()
            - 9.81 * self.cant / railmbs_track::track::STANDARD_RAIL_DISTANCE
    }

    /// The circular curve as a track of [`CURVE_LENGTH`] m.
    ///
    /// # Errors
    /// A radius that is zero or not finite, or a negative cant.
    pub fn track(&self) -> Result<Track, String> {
        if !(self.radius.is_finite() && self.radius != 0.0) {
            return Err(format!(
                "curve radius {} m: must be finite and non-zero (positive left, negative right)",
                self.radius
            ));
        }
        if !(self.cant.is_finite() && self.cant >= 0.0) {
            return Err(format!("cant {} m: must be finite and ≥ 0", self.cant));
        }
        if !(self.speed.is_finite() && self.speed > 0.0) {
            return Err(format!("speed {} m/s: must be finite and > 0", self.speed));
        }
        let direction = if self.radius > 0.0 {
            Direction::Left
        } else {
            Direction::Right
        };
        let section = Section::curve(CURVE_LENGTH, self.radius.abs(), direction)
            .with_cant(self.cant, self.cant);
        Alignment::new(vec![section])
            .and_then(Track::new)
            .map_err(|e| format!("curve of radius {} m: {e}", self.radius))
    }
}

/// One wheelset in the curve.
#[derive(Debug, Clone, PartialEq)]
pub struct WheelsetCurving {
    /// The wheel–rail element's long name (`Bogie1.WS1.contact`).
    pub element: String,
    /// The wheelset body's long name (`Bogie1.WS1.ws`).
    pub wheelset: String,
    /// Lateral position relative to the track centre line, m (positive to
    /// the left), if the wheelset has a lateral coordinate.
    pub lateral: Option<f64>,
    /// Angle of attack, its yaw relative to the track, rad (positive to the
    /// left), if it has a yaw coordinate.
    pub yaw: Option<f64>,
    /// The element's outputs at the steady state, as the columns of a run's
    /// CSV (`L.Q [N]`, `L.Y [N]`, `L.Fx [N]`, …, `SumY [N]`).
    pub outputs: Vec<(String, f64)>,
}

impl WheelsetCurving {
    /// The output `name` (as in [`WheelsetCurving::outputs`]).
    pub fn output(&self, name: &str) -> Option<f64> {
        self.outputs.iter().find(|(n, _)| n == name).map(|x| x.1)
    }
}

/// The quasi-static curving solution.
#[derive(Debug, Clone)]
pub struct Curving {
    /// The curve.
    pub curve: Curve,
    /// The system's coordinates, in system order.
    pub coordinates: Vec<CoordinateInfo>,
    /// The steady state.
    pub equilibrium: Equilibrium,
    /// Every wheelset, in the model's order of its wheel–rail elements.
    pub wheelsets: Vec<WheelsetCurving>,
    /// Wall-clock seconds of everything before the final solve (model,
    /// contact tables, track; a failed direct solve and the continuation's
    /// steps, if any) and of the final solve (benchmark figures).
    pub seconds: [f64; 2],
}

/// `scenario` on the circular `curve` at its speed (the track replaced,
/// see [`at_speed`] for the speed), the vehicle's reference point at the
/// curve's middle, starting from its steady state.
///
/// # Errors
/// A bad curve (named) or a scenario without a track.
pub fn curve_scenario(
    scenario: &Scenario,
    model: &Model,
    curve: &Curve,
) -> Result<Scenario, RunError> {
    let setup = |message: String| RunError::Setup {
        file: scenario.source.clone(),
        message,
    };
    let track = curve.track().map_err(setup)?;
    let mut s = at_speed(scenario, model, curve.speed);
    let Some(spec) = s.track.as_mut() else {
        return Err(setup(
            "quasi-static curving needs a vehicle on a track: the scenario has no `track`".into(),
        ));
    };
    spec.track = Arc::new(track);
    spec.start = 0.5 * CURVE_LENGTH;
    Ok(s)
}

/// Curvature steps of the continuation: each solve starts from the one
/// before, at curvatures growing geometrically by this factor from
/// [`CONTINUATION_START`] (1/m).
pub const CONTINUATION_FACTOR: f64 = 1.5;

/// The curvature the continuation starts at, 1/m (a 5 km curve: near the
/// straight track's state, which the model's initial state approximates).
pub const CONTINUATION_START: f64 = 2e-4;

/// Newton iterations of the direct solve before it gives up for the
/// continuation in curvature: Vehicle 1 converges in 3–7 iterations from a
/// nearby curve or speed and in 6–21 from its initial state where it
/// converges at all (21: the 600 m curve with 100 mm cant at 40 m/s); a
/// failing attempt costs no more than about twice a converging one.
pub const DIRECT_ITERATIONS: usize = 30;

/// Largest change of a position in one Newton step of the direct solve, m
/// or rad ([`EquilibriumSettings::max_step`]): a third of the flangeway
/// clearance of a standard wheelset (about 6–7 mm each side for S1002 or
/// P8 on 1435 mm), so that no step carries a wheelset from one flange
/// across to the other. With the default 0.1 m, Newton's method from the
/// centred guess sent Vehicle 1's rear wheelset to the inner flange in the
/// 600 m curve at 40 m/s and stalled there (≈ 400 N left), while the run in
/// time settles with every wheelset towards the outer rail (the steady
/// state this step finds).
pub const DIRECT_MAX_STEP: f64 = 2e-3;

/// Settings of the direct solve (from the model's initial state or from a
/// guess): [`DIRECT_ITERATIONS`], [`DIRECT_MAX_STEP`].
pub fn direct_settings() -> EquilibriumSettings {
    EquilibriumSettings {
        max_iterations: DIRECT_ITERATIONS,
        max_step: DIRECT_MAX_STEP,
        ..EquilibriumSettings::default()
    }
}

/// The quasi-static curving solution of `scenario`'s vehicle in `curve`
/// with engines from `engine` (one per solve), sharing the contact tables
/// `tables`.
///
/// Newton's method from the model's initial state (wheelsets centred),
/// with steps of at most [`DIRECT_MAX_STEP`] and giving up after
/// [`DIRECT_ITERATIONS`] ([`direct_settings`]), converges in wide curves
/// and in moderate ones at high cant deficiency; in a tight one (Vehicle 1
/// in the 150 m curve, where the leading wheelsets run on their flanges)
/// the solve then follows the curvature from [`CONTINUATION_START`] up in
/// steps of [`CONTINUATION_FACTOR`], each from the state before
/// (coordinates and rates), at the same cant and speed, with the default
/// [`EquilibriumSettings`].
///
/// # Errors
/// As [`curve_scenario`], a bad scenario, or no steady state (the
/// equilibrium's error at the curvature where the continuation stopped:
/// the residual and the coordinates carrying it).
pub fn curving(
    scenario: &Scenario,
    model: &Model,
    engine: &mut dyn FnMut() -> Result<Box<dyn Equations>, RunError>,
    tables: &ContactTableCache,
    curve: &Curve,
) -> Result<Curving, RunError> {
    curving_from(scenario, model, engine, tables, curve, None)
}

/// As [`curving`], starting from the solution `guess` of a nearby curve or
/// speed (a sweep's previous point) instead of the model's initial state;
/// the continuation in curvature, if needed, starts from the model's.
///
/// # Errors
/// As [`curving`].
pub fn curving_from(
    scenario: &Scenario,
    model: &Model,
    engine: &mut dyn FnMut() -> Result<Box<dyn Equations>, RunError>,
    tables: &ContactTableCache,
    curve: &Curve,
    guess: Option<&Curving>,
) -> Result<Curving, RunError> {
    let start = Instant::now();
    let solve = |engine: &mut dyn FnMut() -> Result<Box<dyn Equations>, RunError>,
                 c: &Curve,
                 guess: Option<(&[CoordinateInfo], &Equilibrium, f64)>,
                 settings: &EquilibriumSettings| {
        let mut s = curve_scenario(scenario, model, c)?;
        if let Some((coordinates, eq, speed)) = guess {
            // The rolling rates scale with the speed.
            let rates = c.speed / speed;
            let n = model.coordinates.len();
            s.initial = coordinates[..n]
                .iter()
                .enumerate()
                .map(|(i, info)| InitialOverride {
                    coordinate: info.name.clone(),
                    value: Some(eq.q[i]),
                    velocity: Some(eq.v[i] * rates),
                })
                .collect();
        }
        scenario_system_with(&s, model, engine()?, tables, settings)
    };
    let first = guess.map(|g| (g.coordinates.as_slice(), &g.equilibrium, g.curve.speed));
    let solved = match solve(engine, curve, first, &direct_settings()) {
        Ok(s) => s,
        Err(direct) => {
            let target = 1.0 / curve.radius.abs();
            if target <= CONTINUATION_START {
                return Err(direct);
            }
            let mut kappa = CONTINUATION_START;
            let mut last: Option<ScenarioSystem> = None;
            loop {
                let c = Curve {
                    radius: curve.radius.signum() / kappa,
                    ..*curve
                };
                let from = last.as_ref().map(|l: &ScenarioSystem| {
                    (
                        l.coordinates.as_slice(),
                        l.equilibrium
                            .as_ref()
                            .expect("an equilibrium was asked for"),
                        curve.speed,
                    )
                });
                let s = solve(engine, &c, from, &EquilibriumSettings::default()).map_err(|e| {
                    RunError::Setup {
                        file: scenario.source.clone(),
                        message: format!(
                            "curving: no steady state directly ({direct}), nor by continuation in \
                         curvature, which stopped at R = {:.1} m: {e}",
                            1.0 / kappa
                        ),
                    }
                })?;
                if kappa == target {
                    break s;
                }
                last = Some(s);
                kappa = (kappa * CONTINUATION_FACTOR).min(target);
            }
        }
    };
    let ScenarioSystem {
        mut system,
        coordinates,
        equilibrium,
        ..
    } = solved;
    let total = start.elapsed().as_secs_f64();
    let eq = equilibrium.expect("an equilibrium was asked for");
    let failed = |e: crate::system::SimError| RunError::Setup {
        file: scenario.source.clone(),
        message: format!("curving: the steady state's outputs: {e}"),
    };
    // The accepted state sets the elements' states (as at a run's start),
    // then the outputs as a run writes them.
    wheel_loads(&mut system, eq.t, &eq.q, &eq.v).map_err(failed)?;
    system
        .evaluate(eq.t, &eq.q, &eq.v, Parts::KINEMATICS)
        .map_err(failed)?;
    let mut values = Vec::new();
    system.force_outputs(eq.t, &mut values);
    let mut wheelsets = Vec::new();
    let mut offset = 0;
    for (element, f) in system.forces().iter().enumerate() {
        let names = f.output_names();
        if let ForceKind::WheelRail(w) = &model.forces[element].kind {
            let wheelset = model.bodies[w.wheelset].name.clone();
            let find = |kind: CoordinateKind| {
                coordinates
                    .iter()
                    .position(|c| c.owner == wheelset && c.kind == kind)
                    .map(|i| eq.q[i])
            };
            wheelsets.push(WheelsetCurving {
                element: f.name().to_string(),
                lateral: find(CoordinateKind::Translation(Axis::Y)),
                yaw: find(CoordinateKind::Rotation(Axis::Z)),
                wheelset,
                outputs: names
                    .iter()
                    .cloned()
                    .zip(values[offset..offset + names.len()].iter().copied())
                    .collect(),
            });
        }
        offset += names.len();
    }
    Ok(Curving {
        curve: *curve,
        coordinates,
        seconds: [total - eq.seconds, eq.seconds],
        equilibrium: eq,
        wheelsets,
    })
}
