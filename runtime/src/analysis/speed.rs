//! A scenario's modes at its running speed and over a range of speeds (the
//! root locus), over a model parameter or the equivalent conicity (the
//! classical quasi-linear analysis), and the linear critical speed: at
//! each speed the steady state on the scenario's track ([`super::equilibrium`]), the
//! linearization there ([`super::linear`]) and its modes
//! ([`super::modes`]).

use super::CoordinateInfo;
use super::equilibrium::{Equilibrium, Role};
use super::linear::{Linearization, linearize};
use super::modes::{Modes, modes, zero_crossing};
use crate::Equations;
use crate::forces::ContactTableCache;
use crate::run::RunError;
use crate::run::scenario::{ScenarioSystem, scenario_system_sharing};
use railmbs_models::{InitialStateKind, Model, Scenario};
use std::time::Instant;

/// The modes of a scenario at one speed.
#[derive(Debug, Clone)]
pub struct SpeedModes {
    /// Running speed, m/s (0 off a track).
    pub speed: f64,
    /// The system's coordinates (names, units), in system order.
    pub coordinates: Vec<CoordinateInfo>,
    /// The steady state linearized about.
    pub equilibrium: Equilibrium,
    /// The linear system there.
    pub linearization: Linearization,
    /// Its modes.
    pub modes: Modes,
    /// Wall-clock seconds of the equilibrium solve, of the linearization
    /// and of the eigendecomposition (benchmark figures).
    pub seconds: [f64; 3],
}

/// The speeds FROM, FROM + STEP, … up to TO (m/s; TO included when it
/// falls on the grid, to a millionth of a step): the speed ranges of
/// `umsim modes --speed`, `umsim curving --speed` and the studies.
///
/// # Errors
/// Not 0 ≤ FROM ≤ TO and STEP > 0 (all finite), or more than 10 000 speeds.
pub fn speed_grid(from: f64, to: f64, step: f64) -> Result<Vec<f64>, String> {
    if !(from.is_finite() && to.is_finite() && step.is_finite())
        || step <= 0.0
        || to < from
        || from < 0.0
    {
        return Err(format!(
            "({from}, {to}, {step}): need 0 ≤ FROM ≤ TO and STEP > 0 (m/s)"
        ));
    }
    let count = ((to - from) / step + 1e-6).floor() as usize + 1;
    if count > 10_000 {
        return Err(format!(
            "({from}, {to}, {step}) asks for {count} speeds (at most 10000)"
        ));
    }
    Ok((0..count).map(|k| from + k as f64 * step).collect())
}

/// `scenario` run at the constant speed `speed` (m/s) from its steady state:
/// the track's speed set (a speed profile dropped), the model parameter
/// `v0` (the wheels' initial spin v0/r0 in the bundled vehicles: the guess
/// of their rolling rate) set to it when the model has one.
pub fn at_speed(scenario: &Scenario, model: &Model, speed: f64) -> Scenario {
    let mut s = scenario.clone();
    if let Some(track) = &mut s.track {
        track.speed = speed;
        track.speed_profile.clear();
    }
    if model.parameter_index("v0").is_some() {
        s.set_parameter("v0", &format!("{speed:?}"));
    }
    s.initial_kind = InitialStateKind::Equilibrium;
    s
}

/// The modes of `scenario` (at its steady state, see [`at_speed`] for the
/// speed) with the engine `equations`, sharing the contact tables `tables`.
///
/// # Errors
/// A bad scenario, no equilibrium, or a failed linearization or
/// eigendecomposition.
pub fn scenario_modes(
    scenario: &Scenario,
    model: &Model,
    equations: Box<dyn Equations>,
    tables: &ContactTableCache,
) -> Result<SpeedModes, RunError> {
    let mut s = scenario.clone();
    s.initial_kind = InitialStateKind::Equilibrium;
    let start = Instant::now();
    let ScenarioSystem {
        mut system,
        coordinates,
        equilibrium,
        ..
    } = scenario_system_sharing(&s, model, equations, tables)?;
    let setup = start.elapsed().as_secs_f64();
    let eq = equilibrium.expect("an equilibrium was asked for");
    let start = Instant::now();
    let left_out: Vec<usize> = (0..eq.roles.len())
        .filter(|&i| eq.roles[i] != Role::Position)
        .collect();
    let lin = linearize(
        &mut system,
        &coordinates,
        (eq.t, &eq.q, &eq.v),
        &eq.lambda,
        &left_out,
    )?;
    let linearized = start.elapsed().as_secs_f64();
    let start = Instant::now();
    let modes = modes(&lin, &coordinates)?;
    let decomposed = start.elapsed().as_secs_f64();
    Ok(SpeedModes {
        speed: s.track.as_ref().map_or(0.0, |t| t.speed),
        coordinates,
        equilibrium: eq,
        linearization: lin,
        modes,
        seconds: [setup, linearized, decomposed],
    })
}

/// The modes of `scenario` at each of `speeds` (m/s), each from its own
/// steady state; `engine` makes a fresh engine for each (the contact tables
/// are built once).
///
/// # Errors
/// As [`scenario_modes`], naming the speed.
pub fn root_locus(
    scenario: &Scenario,
    model: &Model,
    speeds: &[f64],
    engine: &mut dyn FnMut() -> Result<Box<dyn Equations>, RunError>,
) -> Result<Vec<SpeedModes>, RunError> {
    let tables = ContactTableCache::new();
    speeds
        .iter()
        .map(|&v| {
            let s = at_speed(scenario, model, v);
            scenario_modes(&s, model, engine()?, &tables).map_err(|e| RunError::Setup {
                file: scenario.source.clone(),
                message: format!("at {v} m/s: {e}"),
            })
        })
        .collect()
}

/// The modes of `scenario` (at its own speed) for each value of the model
/// parameter `name` in `values` (the parameter's unit), each from its own
/// steady state; `engine` makes a fresh engine for each (the contact
/// tables are shared: a parameter of the profiles or the track builds its
/// own).
///
/// # Errors
/// An unknown parameter, or as [`scenario_modes`], naming the value.
pub fn parameter_locus(
    scenario: &Scenario,
    model: &Model,
    name: &str,
    values: &[f64],
    engine: &mut dyn FnMut() -> Result<Box<dyn Equations>, RunError>,
) -> Result<Vec<SpeedModes>, RunError> {
    if model.parameter_index(name).is_none() {
        return Err(RunError::Setup {
            file: scenario.source.clone(),
            message: format!(
                "--sweep: model \"{}\" has no parameter \"{name}\" (`umsim info` lists them)",
                model.name
            ),
        });
    }
    locus_over(scenario, model, values, engine, &|s, x| {
        s.set_parameter(name, &format!("{x:?}"));
        format!("{name} = {x}")
    })
}

/// `scenario` with its wheel–rail contacts' equivalent conicity overridden
/// to `conicity` (–; [`railmbs_models::ScenarioTrack::conicity`], the
/// wheel–rail element's "Conicity override"), its steady state sought
/// from the model's reference state: the scenario's `initial` entries are
/// dropped, since the scaled geometry moves a given offset s = λ/λ₀ times
/// further across the profiles (a hunting scenario's 3 mm kick at s = 3
/// starts the solve on the flange); a scenario without a track is returned
/// as it is (it has no wheel–rail contact).
pub fn at_conicity(scenario: &Scenario, conicity: f64) -> Scenario {
    let mut s = scenario.clone();
    if let Some(track) = &mut s.track {
        track.conicity = Some(conicity);
        s.initial.clear();
    }
    s
}

/// The modes of `scenario` (at its own speed) for each equivalent conicity
/// of `conicities` (–, [`at_conicity`]): the classical quasi-linear
/// analysis over λ, each from its own steady state; `engine` makes a fresh
/// engine for each (the contact tables are built once: the override scales
/// the lookup, not the table).
///
/// # Errors
/// A scenario without a track, a conicity not positive, or as
/// [`scenario_modes`], naming the conicity.
pub fn conicity_locus(
    scenario: &Scenario,
    model: &Model,
    conicities: &[f64],
    engine: &mut dyn FnMut() -> Result<Box<dyn Equations>, RunError>,
) -> Result<Vec<SpeedModes>, RunError> {
    need_track(scenario)?;
    locus_over(scenario, model, conicities, engine, &|s, x| {
        *s = at_conicity(s, x);
        format!("equivalent conicity {x}")
    })
}

/// One equivalent conicity's (–) linear critical speed (m/s; `None` where
/// none is in the speed range) and root locus.
pub type CriticalAtConicity = (f64, Option<f64>, Vec<SpeedModes>);

/// The linear critical speed (m/s, [`critical_speed`]) of `scenario` at
/// each equivalent conicity of `conicities` (–): a root locus over
/// `speeds` (m/s, [`root_locus`]) per conicity; `None` where the least
/// damped lateral mode's damping ratio does not cross zero in `speeds`.
/// The loci come back with them.
///
/// # Errors
/// As [`conicity_locus`] and [`root_locus`].
pub fn critical_speed_over_conicity(
    scenario: &Scenario,
    model: &Model,
    conicities: &[f64],
    speeds: &[f64],
    engine: &mut dyn FnMut() -> Result<Box<dyn Equations>, RunError>,
) -> Result<Vec<CriticalAtConicity>, RunError> {
    need_track(scenario)?;
    conicities
        .iter()
        .map(|&x| {
            let locus =
                root_locus(&at_conicity(scenario, x), model, speeds, engine).map_err(|e| {
                    RunError::Setup {
                        file: scenario.source.clone(),
                        message: format!("at equivalent conicity {x}: {e}"),
                    }
                })?;
            Ok((x, critical_speed(&locus), locus))
        })
        .collect()
}

/// A scenario without a track as the error of a conicity analysis.
fn need_track(scenario: &Scenario) -> Result<(), RunError> {
    if scenario.track.is_none() {
        return Err(RunError::Setup {
            file: scenario.source.clone(),
            message: "--conicity: the scenario has no track, hence no wheel–rail contact whose \
                      conicity could be set"
                .into(),
        });
    }
    Ok(())
}

/// The one sweep of the loci over a variable: for each of `values`,
/// `apply` sets it on a copy of `scenario` (and names it for errors), and
/// its modes come from [`scenario_modes`] with a fresh engine from
/// `engine`, the contact tables shared.
fn locus_over(
    scenario: &Scenario,
    model: &Model,
    values: &[f64],
    engine: &mut dyn FnMut() -> Result<Box<dyn Equations>, RunError>,
    apply: &dyn Fn(&mut Scenario, f64) -> String,
) -> Result<Vec<SpeedModes>, RunError> {
    let tables = ContactTableCache::new();
    values
        .iter()
        .map(|&x| {
            let mut s = scenario.clone();
            let what = apply(&mut s, x);
            scenario_modes(&s, model, engine()?, &tables).map_err(|e| RunError::Setup {
                file: scenario.source.clone(),
                message: format!("at {what}: {e}"),
            })
        })
        .collect()
}

/// The linear critical speed of a root locus (sorted by speed), m/s: where
/// the damping ratio of the least damped lateral mode
/// ([`Modes::least_damped_lateral`]) first crosses zero, interpolated
/// linearly between the two speeds around it.
pub fn critical_speed(locus: &[SpeedModes]) -> Option<f64> {
    let samples: Vec<(f64, f64)> = locus
        .iter()
        .filter_map(|s| {
            s.modes
                .least_damped_lateral()
                .map(|m| (s.speed, m.damping_ratio))
        })
        .collect();
    zero_crossing(&samples)
}
