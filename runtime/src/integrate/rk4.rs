//! Classical explicit Runge–Kutta method of order 4 with a fixed step, for
//! unconstrained systems. Used to verify the implicit solver and to compare
//! with other codes; it is not meant for stiff models (wheel–rail contact).
//!
//! The second-order system is integrated as the first-order system
//! y = (q, v), ẏ = (v, M⁻¹f) with the classical tableau (Hairer, Nørsett,
//! Wanner, *Solving ODEs I*, Table II.1.2). Each stage solves M q̈ = f with a
//! Cholesky factorization of the symmetric positive definite mass matrix.

use std::ops::ControlFlow;

use nalgebra::{DMatrix, DVector};

use super::linalg::{cholesky_in_place, cholesky_solve};

use super::{IntegrationStats, check_finite, check_run_arguments};
use crate::system::{MechanicalSystem, SimError};

/// Settings of the fixed-step RK4 integrator.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rk4Settings {
    /// Step size h, s (> 0). The last step is shortened to end exactly at
    /// `t_end`.
    pub step: f64,
}

impl Rk4Settings {
    /// Settings with step `h`, s.
    pub fn new(step: f64) -> Self {
        Self { step }
    }
}

/// Evaluates q̈ = M⁻¹ f at (t, q, v) into `accel`; `mass` is a workspace that
/// holds the Cholesky factor afterwards (no allocation).
fn acceleration<S: MechanicalSystem + ?Sized>(
    system: &mut S,
    t: f64,
    q: &DVector<f64>,
    v: &DVector<f64>,
    mass: &mut DMatrix<f64>,
    accel: &mut DVector<f64>,
    stats: &mut IntegrationStats,
) -> Result<(), SimError> {
    stats.dynamics_evaluations += 1;
    system.dynamics(t, q.as_slice(), v.as_slice(), mass, accel)?;
    // The factorization fails on a NaN, and a NaN in f reaches q̈: M and f are
    // searched for the culprit only then, so the common path pays nothing.
    if cholesky_in_place(mass) {
        cholesky_solve(mass, accel.as_mut_slice());
        if accel.iter().all(|x| x.is_finite()) {
            return Ok(());
        }
    }
    check_finite(t, "force f", accel.as_slice())?;
    check_finite(t, "mass matrix M", mass.as_slice())?;
    if accel.iter().all(|x| x.is_finite()) {
        Err(SimError::Diverged {
            t,
            reason:
                "mass matrix is not symmetric positive definite (Cholesky factorization failed)"
                    .into(),
        })
    } else {
        check_finite(t, "acceleration q̈", accel.as_slice())
    }
}

/// Integrates an unconstrained system with classical RK4 from `(t0, q0, v0)`
/// to `t_end` with the fixed step of `settings` (the last step shortened to
/// end exactly at `t_end`).
///
/// The observer gets `(t, q, v, q̈)` at `t0` and after every step and may stop
/// the run with `ControlFlow::Break`. [`MechanicalSystem::accept_step`] is
/// called once per step. Four `dynamics` evaluations per step (the
/// acceleration at the end of a step is the first stage of the next one),
/// plus one at the start.
///
/// # Errors
/// [`SimError::Other`] for bad settings, wrong state sizes or a constrained
/// system (`n_constraints() > 0`, which RK4 cannot handle: use Park's
/// method); [`SimError::NonFinite`] with the time when a NaN or an infinity
/// appears in M, f or the state; [`SimError::Diverged`] when M is not
/// positive definite; and any error of the system itself.
pub fn integrate_rk4<S, F>(
    system: &mut S,
    settings: &Rk4Settings,
    t0: f64,
    q0: &[f64],
    v0: &[f64],
    t_end: f64,
    mut observer: F,
) -> Result<IntegrationStats, SimError>
where
    S: MechanicalSystem + ?Sized,
    F: FnMut(f64, &[f64], &[f64], &[f64]) -> ControlFlow<()>,
{
    let nc = system.n_constraints();
    if nc > 0 {
        return Err(SimError::Other(format!(
            "RK4 cannot integrate a constrained system (n_constraints = {nc}); use Park's method"
        )));
    }
    let h = settings.step;
    if !(h > 0.0 && h.is_finite()) {
        return Err(SimError::Other(format!(
            "RK4 step must be positive and finite, got {h} s"
        )));
    }
    let n = system.dof();
    check_run_arguments(n, t0, q0, v0, t_end)?;

    let mut stats = IntegrationStats::new(t0, n, 0);
    let mut mass = DMatrix::zeros(n, n);
    let mut q = DVector::from_column_slice(q0);
    let mut v = DVector::from_column_slice(v0);
    let mut a1 = DVector::zeros(n);
    let mut a2 = DVector::zeros(n);
    let mut a3 = DVector::zeros(n);
    let mut a4 = DVector::zeros(n);
    let mut qs = DVector::zeros(n);
    let mut v2 = DVector::zeros(n);
    let mut v3 = DVector::zeros(n);
    let mut v4 = DVector::zeros(n);

    let mut t = t0;
    acceleration(system, t, &q, &v, &mut mass, &mut a1, &mut stats)?;
    let report = |stats: &mut IntegrationStats,
                  observer: &mut F,
                  t: f64,
                  q: &DVector<f64>,
                  v: &DVector<f64>,
                  a: &DVector<f64>|
     -> bool {
        let flow = observer(t, q.as_slice(), v.as_slice(), a.as_slice());
        if flow.is_break() {
            stats.stopped_by_observer = true;
        }
        flow.is_break()
    };
    let mut stop = report(&mut stats, &mut observer, t, &q, &v, &a1);

    while !stop && t < t_end {
        // Times t0 + k h without accumulated rounding; a last step within
        // 1e-6 h of t_end is merged instead of leaving a sliver.
        let tk = t0 + (stats.steps + 1) as f64 * h;
        let t_new = if tk >= t_end - 1e-6 * h { t_end } else { tk };
        let hs = t_new - t;
        let half = 0.5 * hs;
        // Stage 2: y + h/2 k1.
        qs.copy_from(&q);
        qs.axpy(half, &v, 1.0);
        v2.copy_from(&v);
        v2.axpy(half, &a1, 1.0);
        acceleration(system, t + half, &qs, &v2, &mut mass, &mut a2, &mut stats)?;
        // Stage 3: y + h/2 k2.
        qs.copy_from(&q);
        qs.axpy(half, &v2, 1.0);
        v3.copy_from(&v);
        v3.axpy(half, &a2, 1.0);
        acceleration(system, t + half, &qs, &v3, &mut mass, &mut a3, &mut stats)?;
        // Stage 4: y + h k3.
        qs.copy_from(&q);
        qs.axpy(hs, &v3, 1.0);
        v4.copy_from(&v);
        v4.axpy(hs, &a3, 1.0);
        acceleration(system, t_new, &qs, &v4, &mut mass, &mut a4, &mut stats)?;
        // y₊ = y + h/6 (k1 + 2k2 + 2k3 + k4).
        let w = hs / 6.0;
        for i in 0..n {
            q[i] += w * (v[i] + 2.0 * v2[i] + 2.0 * v3[i] + v4[i]);
            v[i] += w * (a1[i] + 2.0 * a2[i] + 2.0 * a3[i] + a4[i]);
        }
        t = t_new;
        check_finite(t, "coordinate q", q.as_slice())?;
        check_finite(t, "velocity v", v.as_slice())?;
        stats.steps += 1;
        system.accept_step(t, q.as_slice(), v.as_slice());
        // The acceleration at the new state is the next step's first stage.
        acceleration(system, t, &q, &v, &mut mass, &mut a1, &mut stats)?;
        stop = report(&mut stats, &mut observer, t, &q, &v, &a1);
    }
    stats.t = t;
    stats.q.copy_from(&q);
    stats.v.copy_from(&v);
    stats.accel.copy_from(&a1);
    Ok(stats)
}
