//! From a scenario to a system ready to integrate: parameter values and
//! initial state, the engine driven along the track, the restart velocities
//! at the track's kinks, and the integrator check.

use super::RunError;
use crate::Equations;
use crate::analysis::{
    self, CoordinateInfo, equilibrium::Equilibrium, equilibrium::EquilibriumSettings,
};
use crate::equations::Parts;
use crate::forces::{ContactTableCache, TrackBinding};
use crate::inputs::{DrivenEquations, InputProvider};
use crate::model_system::ModelSystem;
use crate::system::MechanicalSystem;
use crate::system::SimError;
use crate::track_inputs::{RunningSpeed, TrackInputs};
use railmbs_models::{InitialStateKind, IntegratorSpec, Model, Scenario};

/// Parameter values and initial state of a run.
#[derive(Debug, Clone, PartialEq)]
pub struct InitialState {
    /// In `Model::parameters` order.
    pub params: Vec<f64>,
    /// Generalized coordinates (m, rad).
    pub q: Vec<f64>,
    /// Generalized velocities (m/s, rad/s).
    pub v: Vec<f64>,
}

/// The parameter values and initial state a scenario asks for (errors name the
/// scenario file, with line and column).
pub fn scenario_state(scenario: &Scenario, model: &Model) -> Result<InitialState, RunError> {
    let setup = |message: String| RunError::Setup {
        file: scenario.source.clone(),
        message,
    };
    let params = scenario.parameter_values(model)?;
    model.check_body_values(&params).map_err(|problems| {
        setup(format!(
            "with the scenario's parameters, {}",
            problems.join("; ")
        ))
    })?;
    let (q, v) = scenario.initial_state(model, &params)?;
    if let Some(i) = q.iter().chain(&v).position(|x| !x.is_finite()) {
        return Err(setup(format!(
            "initial state of model \"{}\" is not finite (entry {i}); check the init/vel expressions",
            model.name
        )));
    }
    Ok(InitialState { params, q, v })
}

/// An engine driven along the track: the wrapped equations, the times at
/// which the frames pass kinks of the track, and the track for the force
/// elements that need it.
pub(crate) type DrivenModel = (Box<dyn Equations>, Vec<f64>, Option<TrackBinding>);

/// Wraps the engine of a model with track-following frames so that the
/// scenario's track drives them; other models pass through.
/// Contact tables come from (and go to) `tables`.
pub(crate) fn drive_track_frames(
    scenario: &Scenario,
    model: &Model,
    params: &[f64],
    equations: Box<dyn Equations>,
    tables: &ContactTableCache,
) -> Result<DrivenModel, RunError> {
    if model.track_frames.is_empty() {
        return Ok((equations, Vec::new(), None));
    }
    let setup = |message: String| RunError::Setup {
        file: scenario.source.clone(),
        message,
    };
    let Some(spec) = &scenario.track else {
        return Err(setup(format!(
            "model \"{}\" has {} track-following frame(s): the scenario must say which track \
             and how fast, e.g. `track: (file: \"../tracks/tc1.ron\", start: 11.0, speed: 4.4)`",
            model.name,
            model.track_frames.len()
        )));
    };
    let speed = if spec.speed_profile.is_empty() {
        railmbs_track::ConstantSpeed::new(spec.start, spec.speed).map(RunningSpeed::Constant)
    } else {
        railmbs_track::SpeedTable::new(spec.start, &spec.speed_profile).map(RunningSpeed::Profile)
    }
    .map_err(|e| setup(format!("track: {e}")))?;
    // The track was read and built when the scenario was loaded.
    let track = spec.track.clone();
    let inputs = TrackInputs::for_model(model, params, track.clone(), speed.clone())?;
    let breakpoints = inputs.breakpoints(0.0, scenario.end_time);
    // Each body's track frame: its own or its nearest ancestor's.
    let mut body_offsets: Vec<Option<f64>> = vec![None; model.bodies.len()];
    for (b, body) in model.bodies.iter().enumerate() {
        body_offsets[b] = match body.parent {
            railmbs_models::BodyRef::Body(p) => body_offsets[p],
            railmbs_models::BodyRef::Ground => None,
        };
        if let Some(k) = model.track_frames.iter().position(|f| f.body == b) {
            body_offsets[b] = Some(inputs.offsets()[k]);
        }
    }
    let binding = TrackBinding {
        track,
        speed,
        body_offsets,
        tables: tables.clone(),
        conicity: spec.conicity,
    };
    Ok((
        Box::new(DrivenEquations::new(equations, Box::new(inputs))?),
        breakpoints,
        Some(binding),
    ))
}

/// A scenario's system at its initial state, before any output.
pub struct ScenarioSystem {
    /// The model's engine (driven along the track) with its force elements.
    pub system: ModelSystem,
    /// Its coordinates, in system order (names, units).
    pub coordinates: Vec<CoordinateInfo>,
    /// Initial system coordinates (coordinates, then element states).
    pub q0: Vec<f64>,
    /// Their rates.
    pub v0: Vec<f64>,
    /// Times of the kinks of the track-following frames, s.
    pub breakpoints: Vec<f64>,
    /// The running speed law on a track.
    pub arc: Option<RunningSpeed>,
    /// The equilibrium the run starts from (`initial_state: Equilibrium`),
    /// with the roles of the coordinates.
    pub equilibrium: Option<Equilibrium>,
}

/// Builds the system of `scenario` on `model` with the engine `equations`:
/// parameters and initial state, the track, and, when the scenario asks for
/// it (`initial_state: Equilibrium`), the equilibrium at t = 0 from that
/// state, solved with the force elements' states as built (frictionless:
/// [`ModelSystem::keep_initial_force_states`]) and then accepted there.
///
/// # Errors
/// A bad scenario, or no equilibrium (the message names the scenario file).
pub fn scenario_system(
    scenario: &Scenario,
    model: &Model,
    equations: Box<dyn Equations>,
) -> Result<ScenarioSystem, RunError> {
    scenario_system_sharing(scenario, model, equations, &ContactTableCache::new())
}

/// [`scenario_system`] with the wheel–rail contact tables of `tables`
/// (those built here are added): the systems of a sweep over speed or
/// parameters build each table once.
pub fn scenario_system_sharing(
    scenario: &Scenario,
    model: &Model,
    equations: Box<dyn Equations>,
    tables: &ContactTableCache,
) -> Result<ScenarioSystem, RunError> {
    scenario_system_with(
        scenario,
        model,
        equations,
        tables,
        &EquilibriumSettings::default(),
    )
}

/// [`scenario_system_sharing`] solving the equilibrium (when the scenario
/// asks for one) with `settings` instead of the defaults: an analysis that
/// has a second way to the solution (quasi-static curving's continuation)
/// lets a direct attempt give up early.
pub fn scenario_system_with(
    scenario: &Scenario,
    model: &Model,
    equations: Box<dyn Equations>,
    tables: &ContactTableCache,
    settings: &EquilibriumSettings,
) -> Result<ScenarioSystem, RunError> {
    let setup = |message: String| RunError::Setup {
        file: scenario.source.clone(),
        message,
    };
    let InitialState {
        params,
        q: q0,
        v: v0,
    } = scenario_state(scenario, model)?;
    let (equations, breakpoints, binding) =
        drive_track_frames(scenario, model, &params, equations, tables)?;
    let mut system = ModelSystem::new(model, equations, params)?;
    check_integrator(&system, &scenario.integrator).map_err(setup)?;
    let (mut q0, mut v0) = system.initial_state(0.0, &q0, &v0)?;
    match &binding {
        Some(b) => system.bind_track(b)?,
        None => {
            if let Some(f) = system.forces().iter().find(|f| f.needs_track()) {
                return Err(setup(format!(
                    "force element \"{}\" needs a track: put its wheelset on a \
                     track-following frame and give the scenario a `track`",
                    f.name()
                )));
            }
        }
    }
    let coordinates = analysis::coordinates(model, &system);
    let equilibrium = match scenario.initial_kind {
        InitialStateKind::Given => None,
        InitialStateKind::Equilibrium => {
            // Frictionless: no element state is accepted at the guess.
            system.keep_initial_force_states();
            let eq =
                analysis::equilibrium::solve(&mut system, &coordinates, 0.0, &q0, &v0, settings)
                    .map_err(|e| setup(format!("initial_state: Equilibrium: {e}")))?;
            // The force elements' states (anchors, modes) start there.
            system.accept_step(eq.t, &eq.q, &eq.v)?;
            q0.clone_from(&eq.q);
            v0.clone_from(&eq.v);
            Some(eq)
        }
    };
    Ok(ScenarioSystem {
        system,
        coordinates,
        q0,
        v0,
        breakpoints,
        arc: binding.as_ref().map(|b| b.speed.clone()),
        equilibrium,
    })
}

/// One body velocity vector (v, ω) per body, stacked.
fn body_velocities(e: &crate::equations::Evaluation) -> nalgebra::DVector<f64> {
    nalgebra::DVector::from_iterator(
        6 * e.bodies.len(),
        e.bodies
            .iter()
            .flat_map(|b| b.velocity.iter().chain(b.angular_velocity.iter()).copied()),
    )
}

/// Half-width (s) of the gap left around a breakpoint at `t`: segments end
/// this much before a kink of the track and restart this much after it, so
/// that no step ever ends exactly on the kink (where the inputs are one-sided).
/// At 100 m/s it moves a frame by 1e-8 m per second of simulated time.
pub(crate) fn breakpoint_gap(t: f64) -> f64 {
    1e-10 * t.abs().max(1.0)
}

/// Velocities after a kink of the track-following frames (segment ended at
/// `t_before`, restarts at `t_after`): the frames' rates jump there, the
/// bodies' absolute velocities do not. Solves Γ(t⁺) q̇⁺ + γ(t⁺) = V(t⁻) for all
/// bodies in the least-squares sense (exact for bodies with six coordinates
/// relative to their frame), γ being the rheonomic part of the body velocities.
pub(crate) fn continuous_velocities(
    system: &mut ModelSystem,
    t_before: f64,
    t_after: f64,
    q: &[f64],
    v: &[f64],
) -> Result<Vec<f64>, SimError> {
    let t = t_before;
    let parts = Parts {
        jacobians: true,
        ..Parts::KINEMATICS
    };
    let before = body_velocities(system.evaluate(t_before, q, v, parts)?);
    let zero = vec![0.0; q.len()];
    let e = system.evaluate(t_after, q, &zero, parts)?;
    let rhs = before - body_velocities(e);
    let solution = e
        .jacobians
        .clone()
        .svd(true, true)
        .solve(&rhs, 1e-12)
        .map_err(|e| SimError::Other(format!("velocity re-initialization at t = {t} s: {e}")))?;
    // Element states keep their rates (their equations hold at the next step).
    let n = solution.len();
    Ok(solution.iter().chain(&v[n..]).copied().collect())
}

/// Refuses an explicit integrator for a system with first-order element
/// states (their rows of the mass matrix are zero).
pub(crate) fn check_integrator(system: &ModelSystem, spec: &IntegratorSpec) -> Result<(), String> {
    if matches!(spec, IntegratorSpec::Rk4 { .. }) && system.state_count() > 0 {
        return Err(format!(
            "the model has first-order element states ({}) which the explicit RK4 integrator \
             cannot solve; use `integrator: Park(..)`",
            system.state_names().join(", ")
        ));
    }
    Ok(())
}
