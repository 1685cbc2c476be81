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
use railmbs_models::{Axis, ForceKind, InitialOverride, InitialStateKind, Model, Scenario};
use railmbs_track::{Alignment, Direction, Section, Track};
use railmbs_wheelrail::geometry::RigidContact;
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

/// Settings of the direct solve from [`first_guess`]: [`DIRECT_ITERATIONS`],
/// the wheelsets' lateral shifts limited to [`DIRECT_MAX_STEP`] per step
/// (no step across a flangeway), the other positions to the default 0.1 m
/// (the car body's lean in the cant and its lateral and vertical
/// suspension deflections, 10–40 mm for Vehicle 1, which the guess leaves
/// out, in a step or two), and chord steps
/// ([`EquilibriumSettings::chord_steps`]: Vehicle 1 in the 150 m curve
/// takes 11 iterations with 6 fresh Jacobians instead of 9 with 9, about
/// 7 % less time in one criterion run).
pub fn guessed_settings(model: &Model, coordinates: &[CoordinateInfo]) -> EquilibriumSettings {
    let step_limits = model
        .forces
        .iter()
        .filter_map(|f| match &f.kind {
            ForceKind::WheelRail(w) => coordinates.iter().position(|c| {
                c.owner == model.bodies[w.wheelset].name
                    && c.kind == CoordinateKind::Translation(Axis::Y)
            }),
            _ => None,
        })
        .map(|i| (i, DIRECT_MAX_STEP))
        .collect();
    EquilibriumSettings {
        max_iterations: DIRECT_ITERATIONS,
        step_limits,
        chord_steps: true,
        ..EquilibriumSettings::default()
    }
}

/// The quasi-static curving solution of `scenario`'s vehicle in `curve`
/// with engines from `engine` (one per solve), sharing the contact tables
/// `tables`.
///
/// Newton's method from the rigid vehicle's position in the curve
/// ([`first_guess`]: the classical quasi-static estimate, each wheelset at
/// its rigid bogie's rolling line or flange, the bodies on their chords),
/// the wheelsets' lateral steps capped at [`DIRECT_MAX_STEP`] and giving
/// up after [`DIRECT_ITERATIONS`] ([`guessed_settings`]): Vehicle 1
/// converges in 5–10 iterations in curves of 120–3000 m. Where that fails
/// (Vehicle 1 in the 600 m curve at 2.0 m/s² cant deficiency), Newton's
/// method from the model's initial state (wheelsets centred) with every
/// step capped at [`DIRECT_MAX_STEP`] ([`direct_settings`]), and where that
/// fails too, the continuation in curvature ([`curving_by_continuation`]).
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
/// speed (a sweep's previous point) instead of [`first_guess`], with
/// [`direct_settings`]; if that fails, the continuation in curvature from
/// the model's initial state.
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
                 initial: Option<Vec<InitialOverride>>,
                 settings: &EquilibriumSettings| {
        solve_at(scenario, model, engine, tables, curve, initial, settings)
    };
    let solved = match guess {
        Some(g) => {
            let initial = restart(
                model,
                &g.coordinates,
                &g.equilibrium,
                curve.speed / g.curve.speed,
            );
            solve(engine, Some(initial), &direct_settings())
        }
        None => {
            // The model's initial state with the rigid vehicle's positions
            // in the curve ([`first_guess`]).
            let mut s = curve_scenario(scenario, model, curve)?;
            s.initial_kind = InitialStateKind::Given;
            let built = scenario_system_with(&s, model, engine()?, tables, &direct_settings())?;
            let mut initial = scenario.initial.clone();
            let guessed = first_guess(model, &built, curve);
            initial.retain(|o| guessed.iter().all(|g| g.coordinate != o.coordinate));
            initial.extend(guessed);
            let settings = guessed_settings(model, &built.coordinates);
            solve(engine, Some(initial), &settings)
                .or_else(|_| solve(engine, None, &direct_settings()))
        }
    };
    let solved = match solved {
        Ok(s) => s,
        Err(direct) => continuation(scenario, model, engine, tables, curve, Some(direct))?,
    };
    outputs(scenario, model, curve, solved, start)
}

/// The quasi-static curving solution by continuation in curvature only:
/// from the model's initial state at the curvature [`CONTINUATION_START`]
/// up in steps of [`CONTINUATION_FACTOR`], each solve from the state
/// before (coordinates and rates), at the same cant and speed, with the
/// default [`EquilibriumSettings`]. Slower than [`curving`] (Vehicle 1 in
/// the 150 m curve: 10 solves) but needing no guess: the reference the
/// direct solves are tested against.
///
/// # Errors
/// As [`curving`].
pub fn curving_by_continuation(
    scenario: &Scenario,
    model: &Model,
    engine: &mut dyn FnMut() -> Result<Box<dyn Equations>, RunError>,
    tables: &ContactTableCache,
    curve: &Curve,
) -> Result<Curving, RunError> {
    let start = Instant::now();
    let solved = continuation(scenario, model, engine, tables, curve, None)?;
    outputs(scenario, model, curve, solved, start)
}

/// The initial coordinates and rates of a solution (`coordinates`, `eq`),
/// its rolling rates scaled by `rates` (the ratio of the speeds).
fn restart(
    model: &Model,
    coordinates: &[CoordinateInfo],
    eq: &Equilibrium,
    rates: f64,
) -> Vec<InitialOverride> {
    coordinates[..model.coordinates.len()]
        .iter()
        .enumerate()
        .map(|(i, info)| InitialOverride {
            coordinate: info.name.clone(),
            value: Some(eq.q[i]),
            velocity: Some(eq.v[i] * rates),
        })
        .collect()
}

/// The steady state of `scenario` in curve `c` from `initial` (the
/// scenario's own initial overrides if `None`) with `settings`.
fn solve_at(
    scenario: &Scenario,
    model: &Model,
    engine: &mut dyn FnMut() -> Result<Box<dyn Equations>, RunError>,
    tables: &ContactTableCache,
    c: &Curve,
    initial: Option<Vec<InitialOverride>>,
    settings: &EquilibriumSettings,
) -> Result<ScenarioSystem, RunError> {
    let mut s = curve_scenario(scenario, model, c)?;
    if let Some(initial) = initial {
        s.initial = initial;
    }
    scenario_system_with(&s, model, engine()?, tables, settings)
}

/// The continuation in curvature ([`curving_by_continuation`]); `direct`,
/// the error of a direct solve that failed before it, for the message.
fn continuation(
    scenario: &Scenario,
    model: &Model,
    engine: &mut dyn FnMut() -> Result<Box<dyn Equations>, RunError>,
    tables: &ContactTableCache,
    curve: &Curve,
    direct: Option<RunError>,
) -> Result<ScenarioSystem, RunError> {
    let target = 1.0 / curve.radius.abs();
    if target <= CONTINUATION_START {
        if let Some(direct) = direct {
            return Err(direct);
        }
        return solve_at(
            scenario,
            model,
            engine,
            tables,
            curve,
            None,
            &EquilibriumSettings::default(),
        );
    }
    let tried = direct.map_or(String::new(), |e| {
        format!("no steady state directly ({e}), nor ")
    });
    let mut kappa = CONTINUATION_START;
    let mut last: Option<ScenarioSystem> = None;
    loop {
        let c = Curve {
            radius: curve.radius.signum() / kappa,
            ..*curve
        };
        let from = last.as_ref().map(|l| {
            let eq = l
                .equilibrium
                .as_ref()
                .expect("an equilibrium was asked for");
            restart(model, &l.coordinates, eq, 1.0)
        });
        let s = solve_at(
            scenario,
            model,
            engine,
            tables,
            &c,
            from,
            &EquilibriumSettings::default(),
        )
        .map_err(|e| RunError::Setup {
            file: scenario.source.clone(),
            message: format!(
                "curving: {tried}by continuation in curvature, which stopped at R = {:.1} m: {e}",
                1.0 / kappa
            ),
        })?;
        if kappa == target {
            return Ok(s);
        }
        last = Some(s);
        kappa = (kappa * CONTINUATION_FACTOR).min(target);
    }
}

/// The curving solution's outputs at the state `solved` reached (`start`:
/// when the solve began, for [`Curving::seconds`]).
fn outputs(
    scenario: &Scenario,
    model: &Model,
    curve: &Curve,
    solved: ScenarioSystem,
    start: Instant,
) -> Result<Curving, RunError> {
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

/// Half the distance between the two wheels' contact points assumed by
/// [`first_guess`], m: half the standard rail distance 2 e₀ = 1.5 m (as in
/// [`Curve::cant_deficiency_acceleration`]).
const HALF_CONTACT_BASE: f64 = 0.5 * railmbs_track::track::STANDARD_RAIL_DISTANCE;

/// The lateral shift y (m, positive left) at which the rigid contact
/// geometry `table` ((y, Δr) in increasing y, Δr = r_left − r_right) gives
/// the rolling-radius difference `target` (m), by linear interpolation from
/// the centre outwards on the side `target` asks for, capped at the flange:
/// the start of the steepest rise of |Δr| on that side (the jump from tread
/// to flange contact; 6.1 mm for S1002 on UIC60 1:40 at 1435 mm, where Δr
/// jumps from 5.0 to 17.5 mm within the table's 0.5 mm). With whether it
/// was capped (the wheelset at its flange).
fn pure_rolling_shift(table: &[(f64, f64)], target: f64) -> (f64, bool) {
    let Some(centre) = table
        .iter()
        .enumerate()
        .min_by(|a, b| a.1.0.abs().total_cmp(&b.1.0.abs()))
        .map(|(i, _)| i)
    else {
        return (0.0, false);
    };
    let side: Vec<(f64, f64)> = if target >= 0.0 {
        table[centre..].to_vec()
    } else {
        table[..=centre].iter().rev().copied().collect()
    };
    // The flange: the steepest rise of |Δr| over |y|.
    let flange = side
        .windows(2)
        .map(|p| (p[0].0, (p[1].1 - p[0].1).abs() / (p[1].0 - p[0].0).abs()))
        .max_by(|a, b| a.1.total_cmp(&b.1))
        .map_or(0.0, |(y, _)| y);
    for p in side.windows(2) {
        let ((y0, d0), (y1, d1)) = (p[0], p[1]);
        if y0.abs() >= flange.abs() {
            break;
        }
        if (d1 - target) * (d0 - target) <= 0.0 && d1 != d0 {
            let y = y0 + (target - d0) / (d1 - d0) * (y1 - y0);
            return if y.abs() < flange.abs() {
                (y, false)
            } else {
                (flange, true)
            };
        }
    }
    (flange, true)
}

/// The first guess of the direct solve in `curve` for the system `built`
/// of `model` (its model's initial state, not solved): the lateral
/// positions, yaw angles and heights of a rigid vehicle following the
/// curve, as overrides of the model's initial coordinates (the rest stay
/// as the model gives them).
///
/// The classical quasi-static estimate, in the track-following frames of
/// the bodies (each at its own arc offset: a frame at arc distance d
/// ahead is turned by κ d, and the straight line tangent at d = 0 lies
/// −κ d²/2 to the left of it; κ = 1/R signed, positive left):
///
/// - the wheelsets of a rigid bogie of semi-wheelbase a in free curving
///   (no flange force; linear creep with f₁₁ = f₂₂, no gravitational
///   stiffness: the lateral balance gives the bogie no yaw against its
///   frame, the yaw balance 2 b (Δr/2r₀ − b κ) = 2 a² κ of the
///   longitudinal creep moments against the lateral creep forces' of
///   the angles of attack ±a κ) all at the shift where
///   Δr(y) = −2 r₀ b κ (1 + a²/b²) (Redtenbacher's pure rolling
///   Δr = 2 r₀ b / R for a = 0; the rigid bogie as in Boocock 1969, J.
///   Mech. Eng. Sci. 11), from the contact table's rigid functions
///   ([`ForceElement::rigid_contact`](crate::forces::ForceElement::rigid_contact),
///   b = 0.75 m), capped at the flange (the start of the steepest rise of
///   |Δr| on that side: 6.1 mm for S1002 on UIC60 1:40);
/// - where that caps the leading wheelset at its flange (Vehicle 1 below
///   about 540 m), the trailing ones at the inner rail's flange: the rigid
///   bogie yawed across its flangeway, as Vehicle 1 runs in the 150 m
///   curve (tests/integration/curving.rs);
/// - each wheelset's height and roll on its rails at its shift (the
///   table's rigid functions), its carrier raised by their mean;
/// - the body carrying wheelsets (tied to a wheelset by a force element,
///   the one of nearest track offset: a bogie frame) on the least-squares
///   line through its wheelsets' positions, the wheelsets parallel to it
///   (ψ_w = ψ_c − κ d);
/// - the body carrying those (the car body) on the line through their
///   centres, the chord: −κ d₁ d₂ / 2 to the left of its frame for
///   carriers at d₁, d₂, turned by κ (d₁ + d₂)/2.
///
/// Simplified: cant deficiency, creep saturation and the suspension's
/// deflections are left to Newton's method. The guess only has to put
/// every wheelset on the right side of its flangeway and every body near
/// its chord (the car body of Vehicle 1 in the 150 m curve lies 0.30 m
/// inside its frame, 150 steps of [`DIRECT_MAX_STEP`] from a centred
/// guess; its wheelsets rise by 0.4 mm at their flanges, which a centred
/// guess leaves as 1.2 MN of contact force).
pub fn first_guess(model: &Model, built: &ScenarioSystem, curve: &Curve) -> Vec<InitialOverride> {
    let kappa = 1.0 / curve.radius;
    let params = built.system.params();
    let n = model.bodies.len();
    let mut offset: Vec<Option<f64>> = vec![None; n];
    for f in &model.track_frames {
        offset[f.body] = Some(f.offset.eval(params, 0.0));
    }
    // The lateral and yaw coordinate of each body, if it has both.
    let coordinate = |b: usize, kind: CoordinateKind| {
        built
            .coordinates
            .iter()
            .position(|c| c.owner == model.bodies[b].name && c.kind == kind)
    };
    let placeable: Vec<Option<(usize, usize)>> = (0..n)
        .map(|b| {
            offset[b]?;
            Some((
                coordinate(b, CoordinateKind::Translation(Axis::Y))?,
                coordinate(b, CoordinateKind::Rotation(Axis::Z))?,
            ))
        })
        .collect();
    // Which bodies the force elements tie together.
    let mut ties: Vec<Vec<usize>> = vec![Vec::new(); n];
    let mut wheelsets: Vec<(usize, usize)> = Vec::new();
    for (element, f) in model.forces.iter().enumerate() {
        if let ForceKind::WheelRail(w) = &f.kind {
            wheelsets.push((w.wheelset, element));
            continue;
        }
        let mut bodies = Vec::new();
        f.kind.clone().bodies_mut(&mut |b| bodies.push(*b));
        for &a in &bodies {
            for &b in &bodies {
                if a != b && !ties[a].contains(&b) {
                    ties[a].push(b);
                }
            }
        }
    }
    let is_wheelset = |b: usize| wheelsets.iter().any(|&(w, _)| w == b);
    // The nearest tied body (by track offset) among `candidates`.
    let carrier = |b: usize, excluded: &dyn Fn(usize) -> bool| {
        let s = offset[b]?;
        ties[b]
            .iter()
            .copied()
            .filter(|&c| placeable[c].is_some() && !excluded(c))
            .min_by(|&c1, &c2| {
                let d = |c: usize| (offset[c].unwrap_or(f64::INFINITY) - s).abs();
                d(c1).total_cmp(&d(c2))
            })
    };
    // Units: a carrier and its wheelsets (with their rigid contact functions).
    let mut units: Vec<(usize, Vec<UnitWheelset>)> = Vec::new();
    for &(w, element) in &wheelsets {
        if placeable[w].is_none() {
            continue;
        }
        let Some((r0, table)) = built.system.forces()[element].rigid_contact() else {
            continue;
        };
        let Some(c) = carrier(w, &is_wheelset) else {
            continue;
        };
        match units.iter_mut().find(|u| u.0 == c) {
            Some(u) => u.1.push((w, r0, table)),
            None => units.push((c, vec![(w, r0, table)])),
        }
    }
    let mut overrides = Vec::new();
    // (body, lateral, yaw) relative to its own frame.
    let mut placed: Vec<(usize, f64, f64)> = Vec::new();
    // (body, rise of its height, roll): wheelsets on the rails, the bodies
    // above them raised with them.
    let mut lifted: Vec<(usize, f64, Option<f64>)> = Vec::new();
    let mut centres: Vec<(usize, f64)> = Vec::new();
    for (c, unit) in &mut units {
        let sc = offset[*c].unwrap_or(0.0);
        let d = |w: usize| offset[w].unwrap_or(sc) - sc;
        unit.sort_by(|a, b| d(b.0).total_cmp(&d(a.0)));
        // The rigid bogie in free curving (linear creep, f₁₁ = f₂₂): its
        // wheelsets at the same shift, where Δr = 2 r₀ b κ (1 + a²/b²).
        let a = 0.5 * (d(unit[0].0) - d(unit[unit.len() - 1].0));
        let b = HALF_CONTACT_BASE;
        let dr = |rigid: &[RigidContact]| -> Vec<(f64, f64)> {
            rigid
                .iter()
                .map(|r| (r.y, r.rolling_radius_difference()))
                .collect()
        };
        let (lead, flange) = pure_rolling_shift(
            &dr(&unit[0].2),
            -2.0 * unit[0].1 * b * kappa * (1.0 + a * a / (b * b)),
        );
        let mut rise = 0.0;
        let members: Vec<(usize, f64)> = unit
            .iter()
            .enumerate()
            .map(|(k, (w, _, rigid))| {
                // Where the leading wheelset flanges, the trailing ones run
                // towards the inner rail, to its flange.
                let y = if k > 0 && flange {
                    pure_rolling_shift(&dr(rigid), -lead.signum() * f64::INFINITY).0
                } else {
                    lead
                };
                // The axle's height and roll on the rails at that shift.
                let (z, roll) = rigid_at(rigid, y);
                let (z0, _) = rigid_at(rigid, 0.0);
                rise += (z - z0) / unit.len() as f64;
                lifted.push((*w, z - z0, Some(roll)));
                (*w, y)
            })
            .collect();
        lifted.push((*c, rise, None));
        // Points (d, y + κ d²/2) in the carrier's frame; line y_c + ψ_c d.
        let pts: Vec<(f64, f64)> = members
            .iter()
            .map(|&(w, y)| {
                let d = d(w);
                (d, y + 0.5 * kappa * d * d)
            })
            .collect();
        let (yc, psi) = line_through(&pts);
        for (&(w, y), &(d, _)) in members.iter().zip(&pts) {
            placed.push((w, y, psi - kappa * d));
        }
        placed.push((*c, yc, psi));
        centres.push((*c, yc));
    }
    // The bodies carrying the carriers (car bodies), on the chords.
    let is_unit = |b: usize| is_wheelset(b) || units.iter().any(|u| u.0 == b);
    let mut tops: Vec<(usize, Vec<(usize, f64)>)> = Vec::new();
    for &(c, yc) in &centres {
        if let Some(top) = carrier(c, &is_unit) {
            match tops.iter_mut().find(|t| t.0 == top) {
                Some(t) => t.1.push((c, yc)),
                None => tops.push((top, vec![(c, yc)])),
            }
        }
    }
    for (top, members) in &tops {
        let st = offset[*top].unwrap_or(0.0);
        let pts: Vec<(f64, f64)> = members
            .iter()
            .map(|&(c, y)| {
                let d = offset[c].unwrap_or(st) - st;
                (d, y + 0.5 * kappa * d * d)
            })
            .collect();
        let (y, psi) = line_through(&pts);
        placed.push((*top, y, psi));
        let rise: f64 = members
            .iter()
            .filter_map(|&(c, _)| lifted.iter().find(|l| l.0 == c).map(|l| l.1))
            .sum::<f64>()
            / members.len() as f64;
        lifted.push((*top, rise, None));
    }
    for (b, dz, roll) in lifted {
        let shifts = [
            (CoordinateKind::Translation(Axis::Z), Some(dz)),
            (CoordinateKind::Rotation(Axis::X), roll),
        ];
        for (kind, value) in shifts {
            if let (Some(i), Some(x)) = (coordinate(b, kind), value) {
                let x = if kind == CoordinateKind::Rotation(Axis::X) {
                    x
                } else {
                    built.q0[i] + x
                };
                overrides.push(InitialOverride {
                    coordinate: built.coordinates[i].name.clone(),
                    value: Some(x),
                    velocity: None,
                });
            }
        }
    }
    for (b, y, psi) in placed {
        if let Some((iy, iz)) = placeable[b] {
            for (i, x) in [(iy, y), (iz, psi)] {
                overrides.push(InitialOverride {
                    coordinate: built.coordinates[i].name.clone(),
                    value: Some(x),
                    velocity: None,
                });
            }
        }
    }
    overrides
}

/// A wheelset of a unit in [`first_guess`]: its body, nominal rolling
/// radius (m) and rigid contact functions.
type UnitWheelset = (usize, f64, Vec<RigidContact>);

/// The axle height above nominal (m) and roll (rad) of the rigid contact
/// functions `rigid` at the shift `y` (m), interpolated linearly (held at
/// the table's ends).
fn rigid_at(rigid: &[RigidContact], y: f64) -> (f64, f64) {
    let k = rigid.partition_point(|r| r.y < y);
    match (k.checked_sub(1).and_then(|i| rigid.get(i)), rigid.get(k)) {
        (Some(a), Some(b)) if b.y > a.y => {
            let t = (y - a.y) / (b.y - a.y);
            (a.z + t * (b.z - a.z), a.roll + t * (b.roll - a.roll))
        }
        (_, Some(r)) | (Some(r), None) => (r.z, r.roll),
        (None, None) => (0.0, 0.0),
    }
}

/// The least-squares line y = a + b d through `pts` (d, y): (a, b); a
/// single point gives b = 0.
fn line_through(pts: &[(f64, f64)]) -> (f64, f64) {
    let k = pts.len() as f64;
    if pts.is_empty() {
        return (0.0, 0.0);
    }
    let (md, my) = pts
        .iter()
        .fold((0.0, 0.0), |(a, b), &(d, y)| (a + d / k, b + y / k));
    let sdd: f64 = pts.iter().map(|&(d, _)| (d - md) * (d - md)).sum();
    if sdd <= 0.0 {
        return (my, 0.0);
    }
    let b = pts.iter().map(|&(d, y)| (d - md) * (y - my)).sum::<f64>() / sdd;
    (my - b * md, b)
}

#[cfg(test)]
mod tests {
    use super::{line_through, pure_rolling_shift};

    /// A conical tread (Δr = 2 λ y, λ = 0.2) to a flange at |y| = 6 mm,
    /// where Δr jumps by 12 mm within a 0.5 mm step of the table.
    fn coned(y: f64) -> f64 {
        let tread = 2.0 * 0.2 * y;
        if y.abs() > 6e-3 {
            tread + y.signum() * 12e-3
        } else {
            tread
        }
    }

    #[test]
    fn the_pure_rolling_shift_is_where_the_tread_gives_the_radius_difference() {
        let table: Vec<(f64, f64)> = (-40..=40)
            .map(|k| {
                let y = f64::from(k) * 5e-4;
                (y, coned(y))
            })
            .collect();
        // On the tread: y = Δr / (2 λ), both sides.
        for target in [1e-3, -1e-3, 2e-3] {
            let (y, flange) = pure_rolling_shift(&table, target);
            assert!((y - target / 0.4).abs() < 1e-12, "{target}: {y}");
            assert!(!flange);
        }
        // Beyond the tread's 2.4 mm: capped at the flange's start.
        for (target, edge) in [(5e-3, 6e-3), (-0.1, -6e-3)] {
            let (y, flange) = pure_rolling_shift(&table, target);
            assert!((y - edge).abs() < 1e-12, "{target}: {y}");
            assert!(flange);
        }
    }

    #[test]
    fn the_line_through_points_on_a_line_is_that_line() {
        let (a, b) = line_through(&[(-1.28, 0.3 - 1.28 * 0.01), (1.28, 0.3 + 1.28 * 0.01)]);
        assert!(
            (a - 0.3).abs() < 1e-15 && (b - 0.01).abs() < 1e-15,
            "{a} {b}"
        );
        assert_eq!(line_through(&[(2.0, 0.5)]), (0.5, 0.0));
        assert_eq!(line_through(&[]), (0.0, 0.0));
    }
}
