//! What `umsim bench` measures, as calls ready to time: the random states,
//! one (M, k) evaluation, one `ModelSystem::dynamics` call and one scenario
//! run. The criterion benchmarks (`cargo bench -p railmbs-cli --bench
//! equations`) time the same calls.

use super::timing::{Stopwatch, time_per_call};
use nalgebra::{DMatrix, DVector};
use railmbs_models::{Model, Scenario};
use railmbs_runtime::run::run_scenario;
use railmbs_runtime::{Equations, Evaluation, MechanicalSystem, ModelSystem, Parts};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// Seed of the states of [`random_states`].
const STATE_SEED: u64 = 20_260_422;
/// Seed of the track-frame inputs of [`MassAndBias`].
const INPUT_SEED: u64 = 7;

/// A state (t, q, q̇) to evaluate at.
#[derive(Debug, Clone)]
pub struct State {
    /// Time, s.
    pub t: f64,
    /// Generalized coordinates q (m or rad), model order.
    pub q: Vec<f64>,
    /// Generalized velocities q̇ (m/s or rad/s), model order.
    pub v: Vec<f64>,
}

/// `count` states near the model's initial state: q = q₀ + U(−0.5, 0.5)
/// (m or rad), q̇ = U(−1, 1) (m/s or rad/s), t = U(0, 1) s; the same on
/// every call (ChaCha8 with a fixed seed).
pub fn random_states(model: &Model, params: &[f64], count: usize) -> Vec<State> {
    let (q0, _) = model.initial_state(params);
    let mut rng = ChaCha8Rng::seed_from_u64(STATE_SEED);
    (0..count)
        .map(|_| State {
            t: rng.random_range(0.0..1.0),
            q: q0.iter().map(|x| x + rng.random_range(-0.5..0.5)).collect(),
            v: q0.iter().map(|_| rng.random_range(-1.0..1.0)).collect(),
        })
        .collect()
}

/// One evaluation of M and k (`Parts::MASS_AND_BIAS`) per [`call`](Self::call),
/// cycling through the states. A model on track-following frames gets fixed
/// random frame inputs, U(−1, 1).
pub struct MassAndBias<'a> {
    equations: Box<dyn Equations>,
    out: Evaluation,
    states: &'a [State],
    next: usize,
}

impl<'a> MassAndBias<'a> {
    /// `equations` at the parameter values `params`, on `states` (at least one).
    pub fn new(
        mut equations: Box<dyn Equations>,
        params: &[f64],
        states: &'a [State],
    ) -> Result<Self, String> {
        equations
            .set_parameters(params)
            .map_err(|e| e.to_string())?;
        if equations.input_count() > 0 {
            let mut rng = ChaCha8Rng::seed_from_u64(INPUT_SEED);
            let u: Vec<f64> = (0..3 * equations.input_count())
                .map(|_| rng.random_range(-1.0..1.0))
                .collect();
            equations.set_inputs(&u).map_err(|e| e.to_string())?;
        }
        let out = Evaluation::for_equations(equations.as_ref());
        Ok(Self {
            equations,
            out,
            states,
            next: 0,
        })
    }

    /// M of the last evaluation.
    pub fn mass(&self) -> &DMatrix<f64> {
        &self.out.mass
    }

    /// Evaluates at the next state.
    pub fn call(&mut self) -> Result<(), String> {
        let s = &self.states[self.next % self.states.len()];
        self.next += 1;
        self.equations
            .evaluate(s.t, &s.q, &s.v, Parts::MASS_AND_BIAS, &mut self.out)
            .map_err(|e| format!("evaluation of M and k failed: {e}"))?;
        std::hint::black_box(&self.out.mass);
        Ok(())
    }
}

/// One `ModelSystem::dynamics` call (M, k, gravity, body Jacobians and the
/// projection of the force elements' wrenches) per [`call`](Self::call),
/// cycling through the states. Not for models on track-following frames:
/// their wheel–rail forces need the scenario's track.
pub struct Dynamics<'a> {
    system: ModelSystem,
    /// M of the last call.
    pub mass: DMatrix<f64>,
    /// The generalized force of the last call.
    pub force: DVector<f64>,
    states: &'a [State],
    next: usize,
}

impl<'a> Dynamics<'a> {
    /// The system of `model` on `equations` at the parameter values
    /// `params`, on `states` (at least one).
    pub fn new(
        model: &Model,
        equations: Box<dyn Equations>,
        params: &[f64],
        states: &'a [State],
    ) -> Result<Self, String> {
        let system =
            ModelSystem::new(model, equations, params.to_vec()).map_err(|e| e.to_string())?;
        let dof = system.dof();
        Ok(Self {
            system,
            mass: DMatrix::zeros(dof, dof),
            force: DVector::zeros(dof),
            states,
            next: 0,
        })
    }

    /// `dynamics` at the next state.
    pub fn call(&mut self) -> Result<(), String> {
        let s = &self.states[self.next % self.states.len()];
        self.next += 1;
        self.system
            .dynamics(s.t, &s.q, &s.v, &mut self.mass, &mut self.force)
            .map_err(|e| format!("dynamics failed: {e}"))?;
        std::hint::black_box(&self.force);
        Ok(())
    }
}

/// One run of `scenario` by `run_scenario` with no CSV written: its CPU
/// seconds (the setup of the run, which is small, included) and steps.
pub fn run_scenario_once(
    scenario: &Scenario,
    model: &Model,
    equations: Box<dyn Equations>,
) -> Result<(f64, usize), String> {
    let watch = Stopwatch::start();
    let summary =
        run_scenario(scenario, model, equations, None, |_| {}).map_err(|e| e.to_string())?;
    // The runner's own timer is wall-clock; the stopwatch also counts the
    // setup (state, system) of the run.
    let seconds = watch.seconds();
    match summary.error {
        Some(e) => Err(format!("the scenario run failed: {e}")),
        None => Ok((seconds, summary.steps)),
    }
}

/// Builds an engine (a fresh one per call).
pub(crate) type MakeEngine<'a> = dyn Fn() -> Result<Box<dyn Equations>, String> + 'a;

/// Times (M, k) and `dynamics` of the engines from `make` on `states`, ns
/// per call. A model on track-following frames has no `dynamics` time
/// (`None`): it is measured by the scenario run instead.
pub(crate) fn time_engine(
    model: &Model,
    params: &[f64],
    states: &[State],
    make: &MakeEngine,
) -> Result<(f64, Option<f64>), String> {
    let mut eval = MassAndBias::new(make()?, params, states)?;
    let eval_ns = time_per_call(|_| eval.call())?;
    if !model.track_frames.is_empty() {
        return Ok((eval_ns, None));
    }
    let mut dynamics = Dynamics::new(model, make()?, params, states)?;
    let dynamics_ns = time_per_call(|_| dynamics.call())?;
    Ok((eval_ns, Some(dynamics_ns)))
}

/// The integrators' linear algebra on the model's mass matrices M at
/// `states` (evaluated once by `equations`), ns per call, in the order
/// (q̈ solve, LU factorization, LU solve): the Cholesky factorization of M
/// and its solve (RK4's q̈ per stage, `railmbs_integrate::linalg`), and the
/// dense LU factorization with partial pivoting and its solve, the kernels
/// of Park's Newton iterations (the iteration matrix M − βD − β²C has M's
/// order and pattern without constraints; here it is M itself, so the
/// pivots differ but not the work).
pub fn time_linear_solves(
    equations: Box<dyn Equations>,
    params: &[f64],
    states: &[State],
) -> Result<[f64; 3], String> {
    use railmbs_runtime::integrate::linalg::{DenseLu, cholesky_in_place, cholesky_solve};
    let mut eval = MassAndBias::new(equations, params, states)?;
    let mut masses = Vec::with_capacity(states.len());
    for _ in states {
        eval.call()?;
        masses.push(eval.mass().clone());
    }
    let n = masses[0].nrows();
    let rhs = DVector::from_element(n, 1.0);
    let mut work = masses[0].clone();
    let mut x = rhs.clone();
    let chol = time_per_call(|k| {
        work.copy_from(&masses[k % masses.len()]);
        x.copy_from(&rhs);
        if !cholesky_in_place(&mut work) {
            return Err("the mass matrix is not positive definite".to_string());
        }
        cholesky_solve(&work, x.as_mut_slice());
        std::hint::black_box(&x);
        Ok(())
    })?;
    let mut lu = DenseLu::new(n);
    let factor = time_per_call(|k| {
        lu.matrix_mut().copy_from(&masses[k % masses.len()]);
        lu.factorize()
            .map_err(|p| format!("the mass matrix is singular (column {})", p.column))?;
        std::hint::black_box(&lu);
        Ok::<(), String>(())
    })?;
    let solve = time_per_call(|_| {
        x.copy_from(&rhs);
        lu.solve_in_place(&mut x);
        std::hint::black_box(&x);
        Ok::<(), String>(())
    })?;
    Ok([chol, factor, solve])
}
