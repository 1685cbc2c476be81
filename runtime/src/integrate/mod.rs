//! Integrators: Park's implicit method (variable step, Newton iterations,
//! Lagrange multipliers for cut joints) and the classical fixed-step RK4.
//!
//! Both integrate a [`MechanicalSystem`](crate::MechanicalSystem)
//!
//! ```text
//!     M(q, t) q̈ = f(t, q, q̇) + Gᵀ λ,      g(q, t) = 0
//! ```
//!
//! from `(t0, q0, v0)` to `t_end` (hit exactly) and report every accepted step
//! to an observer. The observer is called first at `t0` with the (consistent)
//! initial state, then after every accepted step with the state at its end:
//! time, positions q, velocities v = q̇ and accelerations q̈. That is what
//! cubic Hermite output interpolation needs (q and v at both ends of a step).
//! Returning [`ControlFlow::Break`](std::ops::ControlFlow::Break) from the
//! observer stops the run early (not an error).
//!
//! * [`park`]: Park's stiffly stable implicit method, the production solver.
//! * [`rk4`]: classical explicit Runge–Kutta of order 4 with fixed step, for
//!   verification and comparison, unconstrained systems only.

use nalgebra::DVector;

use crate::system::SimError;

mod linalg;
pub mod park;
pub mod rk4;

pub use park::{JacobianKind, Park, ParkSettings, integrate_park};
pub use rk4::{Rk4Settings, integrate_rk4};

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

/// What a run did, and where it ended.
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
    /// Calls of [`MechanicalSystem::dynamics`](crate::MechanicalSystem::dynamics),
    /// including those for finite-difference Jacobians.
    pub dynamics_evaluations: usize,
    /// Whether the observer stopped the run before `t_end`.
    pub stopped_by_observer: bool,
    /// Final time, s (`t_end` unless the observer stopped the run).
    pub t: f64,
    /// Final coordinates q.
    pub q: DVector<f64>,
    /// Final velocities q̇.
    pub v: DVector<f64>,
    /// Final accelerations q̈.
    pub accel: DVector<f64>,
    /// Final Lagrange multipliers λ (empty without constraints).
    pub lambda: DVector<f64>,
}

impl IntegrationStats {
    fn new(t: f64, n: usize, nc: usize) -> Self {
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
    match data.iter().position(|x| !x.is_finite()) {
        None => Ok(()),
        Some(i) => Err(SimError::NonFinite {
            t,
            what: format!("{what}[{i}] = {}", data[i]),
        }),
    }
}

/// Checks the common arguments of an integration run.
pub(crate) fn check_run_arguments(
    n: usize,
    t0: f64,
    q0: &[f64],
    v0: &[f64],
    t_end: f64,
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
    if !t0.is_finite() || !t_end.is_finite() {
        return Err(SimError::Other(format!(
            "start time {t0} s and end time {t_end} s must be finite"
        )));
    }
    if t_end < t0 {
        return Err(SimError::Other(format!(
            "end time {t_end} s is before the start time {t0} s"
        )));
    }
    check_finite(t0, "initial coordinate q0", q0)?;
    check_finite(t0, "initial velocity v0", v0)?;
    Ok(())
}
