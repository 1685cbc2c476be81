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

use super::{
    BeforeAccept, IntegrationStats, StepView, Stepper, at_stop_time, check_finite,
    check_initial_state, check_stop_time,
};
use crate::system::{MechanicalSystem, SimError};

/// Settings of the fixed-step RK4 integrator.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Rk4Settings {
    /// Step size h, s (> 0). The last step is shortened to end exactly at
    /// the stop time.
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
    // A system with an O(n) solve (the articulated-body method) gives q̈
    // directly; M is then neither formed nor factored.
    if system.accelerations(t, q.as_slice(), v.as_slice(), accel)? {
        return check_finite(t, "acceleration q̈", accel.as_slice());
    }
    system.dynamics(t, q.as_slice(), v.as_slice(), mass, accel)?;
    // The factorization fails on a NaN, and a NaN in f reaches q̈: M and f are
    // searched for the culprit only then, so the common path pays nothing.
    if cholesky_in_place(mass) {
        cholesky_solve(mass, accel.as_mut_slice());
        if crate::all_finite(accel.as_slice()) {
            return Ok(());
        }
    }
    check_finite(t, "force f", accel.as_slice())?;
    check_finite(t, "mass matrix M", mass.as_slice())?;
    if crate::all_finite(accel.as_slice()) {
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

/// Classical RK4 with a fixed step, stepped by the caller ([`Stepper`]).
///
/// Steps end at t0 + k·h without accumulated rounding; the step that would
/// pass the stop time is shortened to end on it, and a last step within
/// 1e-6·h of it is merged instead of leaving a sliver. Four `dynamics`
/// evaluations per step (the acceleration at the end of a step is the first
/// stage of the next one), plus one at the start.
#[derive(Debug)]
pub struct Rk4<S> {
    system: S,
    h: f64,
    t0: f64,
    t: f64,
    t_stop: f64,
    h_last: f64,
    stats: IntegrationStats,
    mass: DMatrix<f64>,
    q: DVector<f64>,
    v: DVector<f64>,
    /// q̈ at the current state (the first stage of the next step).
    a1: DVector<f64>,
    a2: DVector<f64>,
    a3: DVector<f64>,
    a4: DVector<f64>,
    qs: DVector<f64>,
    v2: DVector<f64>,
    v3: DVector<f64>,
    v4: DVector<f64>,
}

impl<S: MechanicalSystem> Rk4<S> {
    /// A solver for the unconstrained `system` at `(t0, q0, v0)` (s, and the
    /// coordinates' units); evaluates the initial accelerations.
    ///
    /// # Errors
    /// [`SimError::Other`] for bad settings, wrong state sizes or a constrained
    /// system (`n_constraints() > 0`, which RK4 cannot handle: use Park's
    /// method); [`SimError::NonFinite`] with the time when a NaN or an
    /// infinity appears in M, f or the state; [`SimError::Diverged`] when M
    /// is not positive definite; and any error of the system itself. Later
    /// steps fail the same way.
    pub fn new(
        mut system: S,
        settings: &Rk4Settings,
        t0: f64,
        q0: &[f64],
        v0: &[f64],
    ) -> Result<Self, SimError> {
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
        check_initial_state(n, t0, q0, v0)?;
        let mut stats = IntegrationStats::new(t0, n, 0);
        let mut mass = DMatrix::zeros(n, n);
        let q = DVector::from_column_slice(q0);
        let v = DVector::from_column_slice(v0);
        let mut a1 = DVector::zeros(n);
        acceleration(&mut system, t0, &q, &v, &mut mass, &mut a1, &mut stats)?;
        stats.q.copy_from(&q);
        stats.v.copy_from(&v);
        stats.accel.copy_from(&a1);
        let z = || DVector::zeros(n);
        Ok(Self {
            system,
            h,
            t0,
            t: t0,
            t_stop: f64::INFINITY,
            h_last: 0.0,
            stats,
            mass,
            q,
            v,
            a1,
            a2: z(),
            a3: z(),
            a4: z(),
            qs: z(),
            v2: z(),
            v3: z(),
            v4: z(),
        })
    }
}

impl<S: MechanicalSystem> Stepper for Rk4<S> {
    type System = S;

    fn t(&self) -> f64 {
        self.t
    }

    fn state(&self) -> StepView<'_> {
        StepView {
            t: self.t,
            h: self.h_last,
            q: self.q.as_slice(),
            v: self.v.as_slice(),
            accel: self.a1.as_slice(),
            lambda: &[],
        }
    }

    fn set_stop_time(&mut self, t_stop: f64) -> Result<(), SimError> {
        check_stop_time(self.t, t_stop)?;
        self.t_stop = t_stop;
        Ok(())
    }

    fn stop_time(&self) -> f64 {
        self.t_stop
    }

    fn step_observed(
        &mut self,
        before_accept: BeforeAccept<'_, S>,
    ) -> Result<StepView<'_>, SimError> {
        self.advance(before_accept)
    }

    fn stats(&self) -> &IntegrationStats {
        &self.stats
    }

    fn system(&self) -> &S {
        &self.system
    }

    fn system_mut(&mut self) -> &mut S {
        &mut self.system
    }
}

impl<S: MechanicalSystem> Rk4<S> {
    /// One step, calling `before_accept` with its end state before
    /// [`MechanicalSystem::accept_step`] (see [`Stepper::step_observed`]).
    fn advance(&mut self, before_accept: BeforeAccept<'_, S>) -> Result<StepView<'_>, SimError> {
        let (t, h, t_end) = (self.t, self.h, self.t_stop);
        if t >= t_end {
            return Err(at_stop_time(t));
        }
        // Times t0 + k h without accumulated rounding; a last step within
        // 1e-6 h of the stop time is merged instead of leaving a sliver.
        let tk = self.t0 + (self.stats.steps + 1) as f64 * h;
        let t_new = if tk >= t_end - 1e-6 * h { t_end } else { tk };
        let hs = t_new - t;
        let half = 0.5 * hs;
        let (q, v, st) = (self.q.as_slice(), self.v.as_slice(), &mut self.stats);
        let (qs, mass, sys) = (&mut self.qs, &mut self.mass, &mut self.system);
        // One pass per stage state, `y + c·k` without temporaries (the same
        // rounding as `copy` then `axpy`: c·k + y).
        let stage =
            |qs: &mut DVector<f64>, vs: &mut DVector<f64>, c: f64, dq: &[f64], dv: &[f64]| {
                add_scaled(qs.as_mut_slice(), q, c, dq);
                add_scaled(vs.as_mut_slice(), v, c, dv);
            };
        // Stage 2: y + h/2 k1.
        stage(qs, &mut self.v2, half, v, self.a1.as_slice());
        acceleration(sys, t + half, qs, &self.v2, mass, &mut self.a2, st)?;
        // Stage 3: y + h/2 k2.
        stage(
            qs,
            &mut self.v3,
            half,
            self.v2.as_slice(),
            self.a2.as_slice(),
        );
        acceleration(sys, t + half, qs, &self.v3, mass, &mut self.a3, st)?;
        // Stage 4: y + h k3.
        stage(qs, &mut self.v4, hs, self.v3.as_slice(), self.a3.as_slice());
        acceleration(sys, t_new, qs, &self.v4, mass, &mut self.a4, st)?;
        // y₊ = y + h/6 (k1 + 2k2 + 2k3 + k4).
        let w = hs / 6.0;
        let (v2, v3, v4) = (self.v2.as_slice(), self.v3.as_slice(), self.v4.as_slice());
        let (a1, a2, a3, a4) = (
            self.a1.as_slice(),
            self.a2.as_slice(),
            self.a3.as_slice(),
            self.a4.as_slice(),
        );
        rk4_combine(self.q.as_mut_slice(), w, [self.v.as_slice(), v2, v3, v4]);
        rk4_combine(self.v.as_mut_slice(), w, [a1, a2, a3, a4]);
        self.t = t_new;
        self.h_last = hs;
        check_finite(t_new, "coordinate q", self.q.as_slice())?;
        check_finite(t_new, "velocity v", self.v.as_slice())?;
        self.stats.steps += 1;
        // The acceleration at the new state is the next step's first stage.
        // The observer sees it before the step is accepted; it is evaluated
        // again after acceptance only where accepting can change it.
        acceleration(
            &mut self.system,
            t_new,
            &self.q,
            &self.v,
            &mut self.mass,
            &mut self.a1,
            &mut self.stats,
        )?;
        let view = StepView {
            t: t_new,
            h: hs,
            q: self.q.as_slice(),
            v: self.v.as_slice(),
            accel: self.a1.as_slice(),
            lambda: &[],
        };
        before_accept(&mut self.system, view)?;
        self.system
            .accept_step(t_new, self.q.as_slice(), self.v.as_slice())?;
        if self.system.remembers_accepted_steps() {
            acceleration(
                &mut self.system,
                t_new,
                &self.q,
                &self.v,
                &mut self.mass,
                &mut self.a1,
                &mut self.stats,
            )?;
        }
        self.stats.t = t_new;
        self.stats.q.copy_from(&self.q);
        self.stats.v.copy_from(&self.v);
        self.stats.accel.copy_from(&self.a1);
        Ok(self.state())
    }
}

/// `out = y + c·k`, entry by entry. Not inlined: [`Rk4`] is generic and
/// compiled in the crate that names its system, at that crate's
/// optimization level; this loop stays compiled here.
#[inline(never)]
fn add_scaled(out: &mut [f64], y: &[f64], c: f64, k: &[f64]) {
    for ((o, y), k) in out.iter_mut().zip(y).zip(k) {
        *o = y + c * k;
    }
}

/// `y += w (k1 + 2 k2 + 2 k3 + k4)`, entry by entry (the classical RK4
/// update with w = h/6). Not inlined, as [`add_scaled`].
#[inline(never)]
fn rk4_combine(y: &mut [f64], w: f64, [k1, k2, k3, k4]: [&[f64]; 4]) {
    for ((((y, k1), k2), k3), k4) in y.iter_mut().zip(k1).zip(k2).zip(k3).zip(k4) {
        *y += w * (k1 + 2.0 * k2 + 2.0 * k3 + k4);
    }
}

/// Integrates an unconstrained system with classical RK4 from `(t0, q0, v0)`
/// to `t_end` with the fixed step of `settings`: a loop over [`Rk4`]'s
/// [`Stepper::step`] (see there and [`Rk4::new`] for the errors).
///
/// The observer gets `(t, q, v, q̈)` at `t0` and after every step and may stop
/// the run with `ControlFlow::Break`. [`MechanicalSystem::accept_step`] is
/// called once per step, before the observer.
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
    crate::check_end_time(t0, t_end)?;
    let mut solver = Rk4::new(system, settings, t0, q0, v0)?;
    solver.set_stop_time(t_end)?;
    loop {
        let view = solver.state();
        if observer(view.t, view.q, view.v, view.accel).is_break() {
            let mut stats = solver.stats().clone();
            stats.stopped_by_observer = true;
            return Ok(stats);
        }
        if solver.t() >= t_end {
            return Ok(solver.stats().clone());
        }
        solver.step()?;
    }
}
