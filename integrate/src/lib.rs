//! # railmbs-integrate
//!
//! Integrators for mechanical systems: Park's implicit method (variable
//! step, Newton iterations, Lagrange multipliers for cut joints) and the
//! classical fixed-step RK4. Both integrate a [`MechanicalSystem`]
//!
//! ```text
//!     M(q, t) q̈ = f(t, q, q̇) + Gᵀ λ,      g(q, t) = 0
//! ```
//!
//! (Pogorelov 2005, Sect. 6) and know nothing else about the model.
//!
//! # Stepping
//!
//! A solver is built from a system, its settings and an initial state
//! ([`Park::new`], [`Rk4::new`]); for constrained systems the initial state
//! is made consistent there. The caller owns the loop: [`Stepper::step`]
//! advances one accepted step and returns a [`StepView`] of the state at its
//! end (t, h, q, q̇, q̈, λ); [`Stepper::set_stop_time`] makes the steps end
//! exactly at a given time (the next steps shorten to reach it and no step
//! passes it); the caller may stop after any step (an event) and build a new
//! solver to restart from a state of its choosing. [`Stepper::stats`] counts
//! steps, rejections, Newton iterations and evaluations so far.
//!
//! A step ends with [`MechanicalSystem::accept_step`], where force elements
//! with state (friction modes, stick anchors) move on. Output evaluated after
//! that sees the next step's element states; [`Stepper::step_observed`]
//! instead calls an observer with the end state of the step before accepting
//! it, which is where a runner evaluates the output rows of the step.
//!
//! ```no_run
//! # use railmbs_integrate::{MechanicalSystem, Park, ParkSettings, SimError, Stepper};
//! # fn run(system: &mut impl MechanicalSystem, q0: &[f64], v0: &[f64]) -> Result<(), SimError> {
//! let mut solver = Park::new(system, ParkSettings::default(), 0.0, q0, v0)?;
//! solver.set_stop_time(2.0)?;
//! while solver.t() < 2.0 {
//!     let state = solver.step()?;
//!     println!("{} {:?}", state.t, state.q);
//! }
//! # Ok(()) }
//! ```
//!
//! [`integrate_park`], [`integrate_park_steps`] and [`integrate_rk4`] are thin loops over `step()`
//! with an observer, for tests and short studies.
//!
//! * [`park`]: Park's stiffly stable implicit method, the production solver.
//! * [`rk4`]: classical explicit Runge–Kutta of order 4 with fixed step, for
//!   verification and comparison, unconstrained systems only.

use nalgebra::DVector;

pub mod block;
pub mod linalg;
pub mod park;
pub mod rk4;
pub mod system;

pub use block::{BlockMatrix, BlockPattern, BorderedLu};
pub use park::{
    JacobianKind, LinearSolver, Park, ParkSettings, integrate_park, integrate_park_steps,
};
pub use rk4::{Rk4, Rk4Settings, integrate_rk4};
pub use system::{MechanicalSystem, SimError};

/// A solver that the caller steps: one accepted step per [`Stepper::step`].
///
/// Implemented by [`Park`] and [`Rk4`]; the system is owned by the solver
/// (pass `&mut system` to keep it, [`MechanicalSystem`] is implemented for
/// mutable references).
pub trait Stepper {
    /// The system integrated.
    type System: MechanicalSystem;

    /// Time of the current state, s.
    fn t(&self) -> f64;

    /// The current state: the initial state before the first step, else the
    /// end of the last accepted step.
    fn state(&self) -> StepView<'_>;

    /// Makes the steps end exactly at `t_stop` (s): the step that would pass
    /// it is shortened (Park approaches it in at most five equal steps), and
    /// [`Stepper::step`] fails once it is reached. Infinite by default; set it
    /// before the first step of Park without `initial_step` (the first step
    /// is chosen from the span to the stop time).
    ///
    /// # Errors
    /// [`SimError::Other`] when `t_stop` is NaN or before [`Stepper::t`].
    fn set_stop_time(&mut self, t_stop: f64) -> Result<(), SimError>;

    /// The stop time, s (infinite when none was set).
    fn stop_time(&self) -> f64;

    /// Advances one accepted step (calling
    /// [`MechanicalSystem::accept_step`] with its final state) and returns
    /// the state at its end.
    ///
    /// # Errors
    /// The solver's errors (see [`Park::new`], [`Rk4::new`]), any error of
    /// the system (including those of `accept_step`), and
    /// [`SimError::Other`] when the stop time has been reached.
    fn step(&mut self) -> Result<StepView<'_>, SimError> {
        self.step_observed(&mut |_, _| Ok(()))
    }

    /// As [`Stepper::step`], and calls `before_accept` with the system and
    /// the state at the end of the step once the step has passed its tests
    /// and before [`MechanicalSystem::accept_step`]: the system's element
    /// states are still those the step was integrated with, so outputs
    /// evaluated there (at the end state or at states interpolated within
    /// the step) agree with the accelerations of the step. An error of
    /// `before_accept` ends the step with that error (nothing accepted).
    ///
    /// # Errors
    /// As [`Stepper::step`], and the errors of `before_accept`.
    fn step_observed(
        &mut self,
        before_accept: BeforeAccept<'_, Self::System>,
    ) -> Result<StepView<'_>, SimError>;

    /// Steps until `t` (s), reached exactly (sets the stop time), and returns
    /// the state there.
    ///
    /// # Errors
    /// As [`Stepper::set_stop_time`] and [`Stepper::step`].
    fn step_until(&mut self, t: f64) -> Result<StepView<'_>, SimError> {
        self.set_stop_time(t)?;
        while self.t() < t {
            self.step()?;
        }
        Ok(self.state())
    }

    /// Counters so far and the current state.
    fn stats(&self) -> &IntegrationStats;

    /// The system.
    fn system(&self) -> &Self::System;

    /// The system, mutable (to evaluate outputs at the current state between
    /// steps; evaluations must not change what the next step sees).
    fn system_mut(&mut self) -> &mut Self::System;
}

/// The observer of [`Stepper::step_observed`]: called with the system and
/// the end state of a step before the step is accepted.
pub type BeforeAccept<'a, S> = &'a mut dyn FnMut(&mut S, StepView<'_>) -> Result<(), SimError>;

/// One reported state: the end of an accepted step (or the initial state).
#[derive(Debug, Clone, Copy)]
pub struct StepView<'a> {
    /// Time at the end of the step, s.
    pub t: f64,
    /// Length of the step that led here, s (0 for the initial state).
    pub h: f64,
    /// Generalized coordinates q (n).
    pub q: &'a [f64],
    /// Generalized velocities q̇ (n).
    pub v: &'a [f64],
    /// Generalized accelerations q̈ (n).
    pub accel: &'a [f64],
    /// Lagrange multipliers λ (nc; empty without constraints). The constraint
    /// reaction in generalized forces is Gᵀλ.
    pub lambda: &'a [f64],
}

/// What a solver did so far, and where it is.
#[derive(Debug, Clone, PartialEq)]
pub struct IntegrationStats {
    /// Accepted steps.
    pub steps: usize,
    /// Rejected step attempts (error test failures and Newton failures).
    pub rejected_steps: usize,
    /// Of the rejected attempts, those rejected because Newton did not converge.
    pub newton_failures: usize,
    /// Newton iterations (each one evaluation of the residual), all attempts.
    pub newton_iterations: usize,
    /// Evaluations of the Jacobians ∂f/∂q, ∂f/∂q̇ (analytic or by differences).
    pub jacobian_evaluations: usize,
    /// LU factorizations of the iteration matrix.
    pub lu_factorizations: usize,
    /// Calls of [`MechanicalSystem::dynamics`],
    /// including those for finite-difference Jacobians.
    pub dynamics_evaluations: usize,
    /// Whether the observer of [`integrate_park`] or [`integrate_rk4`]
    /// stopped the run before `t_end` (always `false` while stepping).
    pub stopped_by_observer: bool,
    /// Time reached, s.
    pub t: f64,
    /// Coordinates q reached.
    pub q: DVector<f64>,
    /// Velocities q̇ reached.
    pub v: DVector<f64>,
    /// Accelerations q̈ reached.
    pub accel: DVector<f64>,
    /// Lagrange multipliers λ reached (empty without constraints).
    pub lambda: DVector<f64>,
}

impl IntegrationStats {
    pub(crate) fn new(t: f64, n: usize, nc: usize) -> Self {
        Self {
            steps: 0,
            rejected_steps: 0,
            newton_failures: 0,
            newton_iterations: 0,
            jacobian_evaluations: 0,
            lu_factorizations: 0,
            dynamics_evaluations: 0,
            stopped_by_observer: false,
            t,
            q: DVector::zeros(n),
            v: DVector::zeros(n),
            accel: DVector::zeros(n),
            lambda: DVector::zeros(nc),
        }
    }
}

/// Fails with [`SimError::NonFinite`] naming the time, the quantity and the
/// first offending index when `data` holds a NaN or an infinity.
pub(crate) fn check_finite(t: f64, what: &str, data: &[f64]) -> Result<(), SimError> {
    if all_finite(data) {
        return Ok(());
    }
    match data.iter().position(|x| !x.is_finite()) {
        None => Ok(()),
        Some(i) => Err(SimError::NonFinite {
            t,
            what: format!("{what}[{i}] = {}", data[i]),
        }),
    }
}

/// Whether every value of `data` is finite, in one pass that vectorizes:
/// x · 0 is ±0 for a finite x and NaN for ±∞ or NaN, summed in eight
/// independent lanes (an early-exit search such as `position` does not
/// vectorize; the mass matrix and Jacobians are checked at every
/// evaluation).
pub(crate) fn all_finite(data: &[f64]) -> bool {
    let mut lanes = [0.0f64; 8];
    let chunks = data.chunks_exact(8);
    let tail: f64 = chunks.remainder().iter().map(|x| x * 0.0).sum();
    for chunk in chunks {
        for (lane, x) in lanes.iter_mut().zip(chunk) {
            *lane += x * 0.0;
        }
    }
    lanes.iter().sum::<f64>() + tail == 0.0
}

/// Checks the system size and initial state of a new solver.
pub(crate) fn check_initial_state(
    n: usize,
    t0: f64,
    q0: &[f64],
    v0: &[f64],
) -> Result<(), SimError> {
    if n == 0 {
        return Err(SimError::Other(
            "the system has no degrees of freedom (dof() = 0)".into(),
        ));
    }
    if q0.len() != n || v0.len() != n {
        return Err(SimError::Other(format!(
            "initial state has {} coordinates and {} velocities, the system has {n} degrees of freedom",
            q0.len(),
            v0.len()
        )));
    }
    if !t0.is_finite() {
        return Err(SimError::Other(format!("start time {t0} s must be finite")));
    }
    check_finite(t0, "initial coordinate q0", q0)?;
    check_finite(t0, "initial velocity v0", v0)?;
    Ok(())
}

/// Checks the end time of [`integrate_park`] and [`integrate_rk4`].
pub(crate) fn check_end_time(t0: f64, t_end: f64) -> Result<(), SimError> {
    if !t0.is_finite() || !t_end.is_finite() {
        return Err(SimError::Other(format!(
            "start time {t0} s and end time {t_end} s must be finite"
        )));
    }
    check_stop_time(t0, t_end)
}

/// Checks a stop time `t_stop` (s) for a solver at time `t` (s).
pub(crate) fn check_stop_time(t: f64, t_stop: f64) -> Result<(), SimError> {
    if t_stop.is_nan() {
        return Err(SimError::Other("the stop time is NaN".into()));
    }
    if t_stop < t {
        return Err(SimError::Other(format!(
            "end time {t_stop} s is before the start time {t} s"
        )));
    }
    Ok(())
}

/// The error of [`Stepper::step`] called at the stop time.
pub(crate) fn at_stop_time(t: f64) -> SimError {
    SimError::Other(format!("the solver is at its stop time t = {t} s"))
}

#[cfg(test)]
mod finite_tests {
    use super::{all_finite, check_finite};

    #[test]
    fn all_finite_finds_every_non_finite_value_at_every_position() {
        for len in 0..20 {
            let finite: Vec<f64> = (0..len)
                .map(|k| [f64::MAX, -f64::MAX, 0.0, -0.0, 1e-310, -3.5][k % 6])
                .collect();
            assert!(all_finite(&finite), "{finite:?}");
            for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
                for k in 0..len {
                    let mut data = finite.clone();
                    data[k] = bad;
                    assert!(!all_finite(&data), "{data:?}");
                    let e = check_finite(0.0, "x", &data).unwrap_err().to_string();
                    assert!(e.contains(&format!("x[{k}]")), "{e}");
                }
            }
        }
    }
}
