//! Integrators against analytic solutions: harmonic oscillators, a stiff
//! overdamped oscillator, a Cartesian pendulum (index-3 DAE), blow-ups.
//!
//! Every expected value below comes from a closed-form solution or a
//! conservation law, never from a run of the integrators themselves.

use std::f64::consts::PI;
use std::ops::ControlFlow;

use nalgebra::{DMatrix, DVector};
use railmbs_integrate::{
    JacobianKind, Park, ParkSettings, Rk4, Rk4Settings, Stepper, integrate_park,
    integrate_park_steps, integrate_rk4,
};
use railmbs_integrate::{MechanicalSystem, SimError};

// ---------------------------------------------------------------------------
// Allocation counting (per thread, so parallel tests do not interfere)
// ---------------------------------------------------------------------------

struct CountingAllocator;

thread_local! {
    static ALLOCATIONS: std::cell::Cell<usize> = const { std::cell::Cell::new(0) };
}

// SAFETY: forwards every call unchanged to the system allocator; the
// thread-local counter is const-initialized and has no destructor, so it
// never allocates itself.
unsafe impl std::alloc::GlobalAlloc for CountingAllocator {
    unsafe fn alloc(&self, layout: std::alloc::Layout) -> *mut u8 {
        let _ = ALLOCATIONS.try_with(|c| c.set(c.get() + 1));
        unsafe { std::alloc::System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: std::alloc::Layout) {
        unsafe { std::alloc::System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: std::alloc::Layout, new_size: usize) -> *mut u8 {
        let _ = ALLOCATIONS.try_with(|c| c.set(c.get() + 1));
        unsafe { std::alloc::System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static GLOBAL: CountingAllocator = CountingAllocator;

fn allocations() -> usize {
    ALLOCATIONS.with(|c| c.get())
}

// ---------------------------------------------------------------------------
// Test systems
// ---------------------------------------------------------------------------

/// m q̈ = −c q̇ − k q (+ k·cos t when `forced`).
struct Oscillator {
    m: f64,
    c: f64,
    k: f64,
    forced: bool,
    analytic_jacobian: bool,
    accepted: usize,
}

impl Oscillator {
    fn new(m: f64, c: f64, k: f64) -> Self {
        Self {
            m,
            c,
            k,
            forced: false,
            analytic_jacobian: false,
            accepted: 0,
        }
    }
}

impl MechanicalSystem for Oscillator {
    fn dof(&self) -> usize {
        1
    }
    fn dynamics(
        &mut self,
        t: f64,
        q: &[f64],
        v: &[f64],
        mass: &mut DMatrix<f64>,
        force: &mut DVector<f64>,
    ) -> Result<(), SimError> {
        mass[(0, 0)] = self.m;
        force[0] = -self.c * v[0] - self.k * q[0];
        if self.forced {
            force[0] += self.k * t.cos();
        }
        Ok(())
    }
    fn force_jacobian(
        &mut self,
        _t: f64,
        _q: &[f64],
        _v: &[f64],
        dfdq: &mut DMatrix<f64>,
        dfdv: &mut DMatrix<f64>,
    ) -> Result<bool, SimError> {
        if !self.analytic_jacobian {
            return Ok(false);
        }
        dfdq[(0, 0)] = -self.k;
        dfdv[(0, 0)] = -self.c;
        Ok(true)
    }
    fn accept_step(&mut self, _t: f64, _q: &[f64], _v: &[f64]) -> Result<(), SimError> {
        self.accepted += 1;
        Ok(())
    }
}

/// Exact (q, q̇) of the free underdamped oscillator m q̈ + c q̇ + k q = 0.
fn oscillator_exact(m: f64, c: f64, k: f64, q0: f64, v0: f64, t: f64) -> (f64, f64) {
    let w = (k / m).sqrt();
    let zeta = c / (2.0 * (k * m).sqrt());
    assert!(zeta < 1.0);
    let wd = w * (1.0 - zeta * zeta).sqrt();
    let s = zeta * w;
    let a = q0;
    let b = (v0 + s * q0) / wd;
    let e = (-s * t).exp();
    let (sn, cs) = (wd * t).sin_cos();
    let q = e * (a * cs + b * sn);
    let v = e * (-s * (a * cs + b * sn) + wd * (-a * sn + b * cs));
    (q, v)
}

/// Point mass on a massless rod of length l in Cartesian coordinates (x, y),
/// x horizontal, y up, pivot at the origin: m ẍ = 2xλ, m ÿ = −m g + 2yλ,
/// g(q) = x² + y² − l² = 0.
struct Pendulum {
    m: f64,
    l: f64,
    g: f64,
}

impl MechanicalSystem for Pendulum {
    fn dof(&self) -> usize {
        2
    }
    fn n_constraints(&self) -> usize {
        1
    }
    fn dynamics(
        &mut self,
        _t: f64,
        _q: &[f64],
        _v: &[f64],
        mass: &mut DMatrix<f64>,
        force: &mut DVector<f64>,
    ) -> Result<(), SimError> {
        mass.fill(0.0);
        mass[(0, 0)] = self.m;
        mass[(1, 1)] = self.m;
        force[0] = 0.0;
        force[1] = -self.m * self.g;
        Ok(())
    }
    fn constraints(
        &mut self,
        _t: f64,
        q: &[f64],
        g: &mut DVector<f64>,
        jacobian: &mut DMatrix<f64>,
    ) -> Result<(), SimError> {
        g[0] = q[0] * q[0] + q[1] * q[1] - self.l * self.l;
        jacobian[(0, 0)] = 2.0 * q[0];
        jacobian[(0, 1)] = 2.0 * q[1];
        Ok(())
    }
}

/// Two free masses on a line; the first is driven along x₁ = A sin ωt by a
/// rheonomic constraint g(q, t) = x₁ − A sin ωt = 0, the second moves freely.
/// The multiplier is the driving force: λ = m ẍ₁ = −m A ω² sin ωt.
struct Driven {
    m: f64,
    amp: f64,
    omega: f64,
}

impl MechanicalSystem for Driven {
    fn dof(&self) -> usize {
        2
    }
    fn n_constraints(&self) -> usize {
        1
    }
    fn dynamics(
        &mut self,
        _t: f64,
        _q: &[f64],
        _v: &[f64],
        mass: &mut DMatrix<f64>,
        force: &mut DVector<f64>,
    ) -> Result<(), SimError> {
        mass.fill(0.0);
        mass[(0, 0)] = self.m;
        mass[(1, 1)] = self.m;
        force.fill(0.0);
        Ok(())
    }
    fn constraints(
        &mut self,
        t: f64,
        q: &[f64],
        g: &mut DVector<f64>,
        jacobian: &mut DMatrix<f64>,
    ) -> Result<(), SimError> {
        g[0] = q[0] - self.amp * (self.omega * t).sin();
        jacobian[(0, 0)] = 1.0;
        jacobian[(0, 1)] = 0.0;
        Ok(())
    }
}

/// q̈ = q³: from q0 = 1, q̇0 = 1/√2 (zero energy ½q̇² − ¼q⁴) the solution is
/// q = 1/(1 − t/√2), which blows up at t* = √2.
struct BlowUp;

impl MechanicalSystem for BlowUp {
    fn dof(&self) -> usize {
        1
    }
    fn dynamics(
        &mut self,
        _t: f64,
        q: &[f64],
        _v: &[f64],
        mass: &mut DMatrix<f64>,
        force: &mut DVector<f64>,
    ) -> Result<(), SimError> {
        mass[(0, 0)] = 1.0;
        force[0] = q[0].powi(3);
        Ok(())
    }
}

/// A force that becomes NaN after t = 1 s: f = −q + √(1 − t).
struct NanAfterOne;

impl MechanicalSystem for NanAfterOne {
    fn dof(&self) -> usize {
        1
    }
    fn dynamics(
        &mut self,
        t: f64,
        q: &[f64],
        _v: &[f64],
        mass: &mut DMatrix<f64>,
        force: &mut DVector<f64>,
    ) -> Result<(), SimError> {
        mass[(0, 0)] = 1.0;
        force[0] = -q[0] + (1.0 - t).sqrt();
        Ok(())
    }
}

/// A recorded accepted state.
#[derive(Clone, Copy, Debug)]
struct Sample {
    t: f64,
    q: [f64; 2],
    v: [f64; 2],
    lambda: f64,
}

/// Cubic Hermite interpolation of component i between two samples.
fn hermite(a: &Sample, b: &Sample, i: usize, t: f64) -> f64 {
    let h = b.t - a.t;
    let s = (t - a.t) / h;
    let h00 = 2.0 * s * s * s - 3.0 * s * s + 1.0;
    let h10 = s * s * s - 2.0 * s * s + s;
    let h01 = -2.0 * s * s * s + 3.0 * s * s;
    let h11 = s * s * s - s * s;
    h00 * a.q[i] + h10 * h * a.v[i] + h01 * b.q[i] + h11 * h * b.v[i]
}

/// Times where q[i] crosses zero from above, by bisection on the Hermite
/// interpolant of each step.
fn downward_crossings(samples: &[Sample], i: usize) -> Vec<f64> {
    let mut out = Vec::new();
    for w in samples.windows(2) {
        let (a, b) = (&w[0], &w[1]);
        if a.q[i] > 0.0 && b.q[i] <= 0.0 {
            let (mut lo, mut hi) = (a.t, b.t);
            for _ in 0..80 {
                let mid = 0.5 * (lo + hi);
                if hermite(a, b, i, mid) > 0.0 {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            out.push(0.5 * (lo + hi));
        }
    }
    out
}

/// Complete elliptic integral of the first kind K(k) by the arithmetic–
/// geometric mean, K = π / (2 AGM(1, √(1 − k²))) (Abramowitz & Stegun 17.6).
fn elliptic_k(k: f64) -> f64 {
    let (mut a, mut b) = (1.0_f64, (1.0 - k * k).sqrt());
    for _ in 0..40 {
        let an = 0.5 * (a + b);
        b = (a * b).sqrt();
        a = an;
    }
    PI / (2.0 * a)
}

// ---------------------------------------------------------------------------
// Harmonic oscillators
// ---------------------------------------------------------------------------

/// Max error in q and in v along the run (at every accepted step).
fn park_oscillator_error(
    sys: &mut Oscillator,
    settings: &ParkSettings,
    t_end: f64,
) -> (f64, f64, usize) {
    let (m, c, k) = (sys.m, sys.c, sys.k);
    let (mut eq, mut ev) = (0.0_f64, 0.0_f64);
    let stats = integrate_park(sys, settings, 0.0, &[1.0], &[0.0], t_end, |t, q, v, _a| {
        let (qe, ve) = oscillator_exact(m, c, k, 1.0, 0.0, t);
        eq = eq.max((q[0] - qe).abs());
        ev = ev.max((v[0] - ve).abs());
        ControlFlow::Continue(())
    })
    .unwrap();
    assert_eq!(stats.t, t_end, "must end exactly at t_end");
    (eq, ev, stats.steps)
}

#[test]
fn park_undamped_oscillator_matches_cosine_and_error_falls_with_tolerance() {
    // q̈ = −(2π)² q, q(0) = 1: q = cos 2πt, over 5 periods.
    let k = 4.0 * PI * PI;
    let mut errors = Vec::new();
    for tol in [1e-4, 1e-6, 1e-8] {
        let mut sys = Oscillator::new(1.0, 0.0, k);
        let s = ParkSettings::with_tolerances(tol, tol);
        let (eq, ev, steps) = park_oscillator_error(&mut sys, &s, 5.0);
        assert_eq!(sys.accepted, steps, "accept_step once per accepted step");
        errors.push((tol, eq, ev, steps));
    }
    println!("{errors:?}");
    for w in errors.windows(2) {
        // Local error ∝ h³ and global error ∝ h² give global ∝ tol^(2/3):
        // two decades of tolerance buy ~21× accuracy; demand at least 10×.
        assert!(w[1].1 < 0.1 * w[0].1, "q error did not fall: {errors:?}");
        assert!(w[1].2 < 0.1 * w[0].2, "v error did not fall: {errors:?}");
        assert!(w[1].3 > w[0].3);
    }
    for (tol, eq, ev, steps) in &errors {
        assert!(*eq < accumulated_bound(*steps, *tol, 1.0), "{errors:?}");
        assert!(
            *ev < accumulated_bound(*steps, *tol, 2.0 * PI),
            "{errors:?}"
        );
    }
}

/// Bound on the global error of a run with local error control: each
/// accepted step commits a local error of at most ~√2·tol·(1 + |y|) per
/// component (weighted RMS over q and v ≤ 1), and in these stable linear
/// systems the global error stays below the sum of the local ones; factor 3
/// for the error estimate being an estimate.
fn accumulated_bound(steps: usize, tol: f64, amplitude: f64) -> f64 {
    3.0 * steps as f64 * tol * (1.0 + amplitude)
}

#[test]
fn park_damped_oscillator_matches_exact_solution() {
    // m = 2 kg, k = 800 N/m (ω = 20 rad/s), ζ = 0.05.
    let (m, k): (f64, f64) = (2.0, 800.0);
    let c = 2.0 * 0.05 * (k * m).sqrt();
    let mut errors = Vec::new();
    for tol in [1e-5, 1e-7, 1e-9] {
        let mut sys = Oscillator::new(m, c, k);
        let (eq, ev, steps) =
            park_oscillator_error(&mut sys, &ParkSettings::with_tolerances(tol, tol), 2.0);
        errors.push((tol, eq, ev, steps));
    }
    println!("{errors:?}");
    for w in errors.windows(2) {
        assert!(w[1].1 < 0.1 * w[0].1 && w[1].2 < 0.1 * w[0].2, "{errors:?}");
    }
    for (tol, eq, ev, steps) in &errors {
        // Velocity amplitude is ω = 20 times the displacement amplitude.
        assert!(*eq < accumulated_bound(*steps, *tol, 1.0), "{errors:?}");
        assert!(*ev < accumulated_bound(*steps, *tol, 20.0), "{errors:?}");
    }
}

#[test]
fn jacobian_kinds_agree_and_analytic_saves_evaluations() {
    let (m, k): (f64, f64) = (2.0, 800.0);
    let c = 2.0 * 0.05 * (k * m).sqrt();
    let mut results = Vec::new();
    for kind in [
        JacobianKind::ForwardDifference,
        JacobianKind::CentralDifference,
        JacobianKind::Analytic,
    ] {
        let mut sys = Oscillator::new(m, c, k);
        sys.analytic_jacobian = true;
        let settings = ParkSettings {
            jacobian: kind,
            ..ParkSettings::with_tolerances(1e-7, 1e-7)
        };
        let mut err = 0.0_f64;
        let stats = integrate_park(
            &mut sys,
            &settings,
            0.0,
            &[1.0],
            &[0.0],
            1.0,
            |t, q, _, _| {
                err = err.max((q[0] - oscillator_exact(m, c, k, 1.0, 0.0, t).0).abs());
                ControlFlow::Continue(())
            },
        )
        .unwrap();
        assert!(stats.jacobian_evaluations >= 1);
        results.push((kind, err, stats));
    }
    for (kind, err, st) in &results {
        assert!(
            *err < accumulated_bound(st.steps, 1e-7, 1.0),
            "{kind:?}: error {err}"
        );
    }
    // The three Jacobians agree to ~1e-7 relative, so the runs must agree far
    // better than they agree with the exact solution.
    for r in &results[1..] {
        let d = (r.2.q[0] - results[0].2.q[0]).abs();
        assert!(d < 0.1 * results[0].1.max(1e-9), "{:?} differs by {d}", r.0);
    }
    // Per Jacobian: forward differences cost 1 + 2n dynamics evaluations,
    // central 1 + 4n, analytic 1 (n = 1 here).
    let per_jac = |r: &(JacobianKind, f64, railmbs_integrate::IntegrationStats)| {
        r.2.dynamics_evaluations - r.2.newton_iterations - 2 // start: a0 and the initial-step probe
    };
    assert_eq!(per_jac(&results[0]), 3 * results[0].2.jacobian_evaluations);
    assert_eq!(per_jac(&results[1]), 5 * results[1].2.jacobian_evaluations);
    assert_eq!(per_jac(&results[2]), results[2].2.jacobian_evaluations);

    // A system without analytic Jacobians falls back to forward differences.
    let mut sys = Oscillator::new(m, c, k);
    let settings = ParkSettings {
        jacobian: JacobianKind::Analytic,
        ..ParkSettings::with_tolerances(1e-7, 1e-7)
    };
    let st = integrate_park(
        &mut sys,
        &settings,
        0.0,
        &[1.0],
        &[0.0],
        1.0,
        |_, _, _, _| ControlFlow::Continue(()),
    )
    .unwrap();
    assert_eq!(st.q, results[0].2.q);
    assert_eq!(
        st.dynamics_evaluations - st.newton_iterations - 2,
        3 * st.jacobian_evaluations
    );
}

// ---------------------------------------------------------------------------
// Convergence order
// ---------------------------------------------------------------------------

/// Error at t_end of the damped oscillator for the fixed steps given.
fn final_errors(hs: &[f64], run: impl Fn(f64, &mut Oscillator) -> (f64, f64)) -> Vec<f64> {
    let (m, c, k, t_end) = (1.0, 0.4, 25.0, 2.0);
    let (qe, ve) = oscillator_exact(m, c, k, 1.0, 0.0, t_end);
    hs.iter()
        .map(|&h| {
            let mut sys = Oscillator::new(m, c, k);
            let (q, v) = run(h, &mut sys);
            (q - qe).abs().max((v - ve).abs())
        })
        .collect()
}

fn slope(hs: &[f64], errs: &[f64]) -> f64 {
    // Least-squares slope of log e against log h.
    let n = hs.len() as f64;
    let xs: Vec<f64> = hs.iter().map(|h| h.ln()).collect();
    let ys: Vec<f64> = errs.iter().map(|e| e.ln()).collect();
    let (mx, my) = (xs.iter().sum::<f64>() / n, ys.iter().sum::<f64>() / n);
    let sxy: f64 = xs.iter().zip(&ys).map(|(x, y)| (x - mx) * (y - my)).sum();
    let sxx: f64 = xs.iter().map(|x| (x - mx) * (x - mx)).sum();
    sxy / sxx
}

#[test]
fn park_fixed_step_converges_with_order_two() {
    let hs = [0.02, 0.01, 0.005];
    let errs = final_errors(&hs, |h, sys| {
        let st = integrate_park(
            sys,
            &ParkSettings::fixed(h),
            0.0,
            &[1.0],
            &[0.0],
            2.0,
            |_, _, _, _| ControlFlow::Continue(()),
        )
        .unwrap();
        assert_eq!(st.steps, (2.0 / h).round() as usize);
        assert_eq!(st.rejected_steps, 0);
        (st.q[0], st.v[0])
    });
    let p = slope(&hs, &errs);
    println!("Park errors {errs:?}, order {p}");
    assert!((1.8..=2.3).contains(&p), "Park order {p}, errors {errs:?}");
}

#[test]
fn rk4_converges_with_order_four() {
    let hs = [0.04, 0.02, 0.01];
    let errs = final_errors(&hs, |h, sys| {
        let st = integrate_rk4(
            sys,
            &Rk4Settings::new(h),
            0.0,
            &[1.0],
            &[0.0],
            2.0,
            |_, _, _, _| ControlFlow::Continue(()),
        )
        .unwrap();
        assert_eq!(st.steps, (2.0 / h).round() as usize);
        assert_eq!(sys.accepted, st.steps);
        (st.q[0], st.v[0])
    });
    let p = slope(&hs, &errs);
    println!("RK4 errors {errs:?}, order {p}");
    assert!((3.7..=4.3).contains(&p), "RK4 order {p}, errors {errs:?}");
}

#[test]
fn rk4_shortens_the_last_step_to_hit_t_end() {
    let mut sys = Oscillator::new(1.0, 0.0, 1.0);
    let mut times = Vec::new();
    let st = integrate_rk4(
        &mut sys,
        &Rk4Settings::new(0.3),
        0.0,
        &[1.0],
        &[0.0],
        1.0,
        |t, _, _, _| {
            times.push(t);
            ControlFlow::Continue(())
        },
    )
    .unwrap();
    assert_eq!(st.steps, 4);
    assert_eq!(*times.last().unwrap(), 1.0);
    assert!((times[3] - 0.9).abs() < 1e-15);
    // q = cos t; RK4 local error ~ h⁵/120 per step.
    assert!((st.q[0] - 1f64.cos()).abs() < 1e-4);
}

// ---------------------------------------------------------------------------
// Stiffness
// ---------------------------------------------------------------------------

/// q̈ + (1 + 10⁶) q̇ + 10⁶ q = 10⁶ cos t: eigenvalues −1 and −10⁶.
fn stiff_system() -> Oscillator {
    let mut s = Oscillator::new(1.0, 1e6 + 1.0, 1e6);
    s.forced = true;
    s
}

/// Exact solution with q(0) = q̇(0) = 0.
fn stiff_exact(t: f64) -> (f64, f64) {
    let (c, k) = (1e6 + 1.0, 1e6);
    // Particular solution A cos t + B sin t.
    let a = k * (k - 1.0) / ((k - 1.0) * (k - 1.0) + c * c);
    let b = c * a / (k - 1.0);
    // Homogeneous C1 e^{−t} + C2 e^{−10⁶ t}: q(0) = 0, q̇(0) = 0.
    // A + C1 + C2 = 0, B − C1 − 10⁶ C2 = 0.
    let c2 = (b + a) / (1.0 - 1e6);
    let c1 = -a - c2;
    let q = a * t.cos() + b * t.sin() + c1 * (-t).exp() + c2 * (-1e6 * t).exp();
    let v = -a * t.sin() + b * t.cos() - c1 * (-t).exp() - 1e6 * c2 * (-1e6 * t).exp();
    (q, v)
}

#[test]
fn park_is_stable_and_accurate_on_a_stiff_system_at_large_fixed_step() {
    // h = 1e-3 is 1000 times the fast time constant: explicit methods blow up
    // (see below), Park damps the fast mode and follows the slow one.
    let mut sys = stiff_system();
    let mut max_err = 0.0_f64;
    let st = integrate_park(
        &mut sys,
        &ParkSettings::fixed(1e-3),
        0.0,
        &[0.0],
        &[0.0],
        3.0,
        |t, q, v, _| {
            if t >= 0.01 {
                let (qe, ve) = stiff_exact(t);
                max_err = max_err.max((q[0] - qe).abs()).max((v[0] - ve).abs());
            }
            ControlFlow::Continue(())
        },
    )
    .unwrap();
    println!("stiff: max error {max_err:e}, stats {st:?}");
    // Slow mode: second-order global error ~ h²·|q'''| ~ 1e-6 (amplitudes ~1).
    assert!(max_err < 1e-5, "stiff error {max_err}");
    // A linear problem with a good Jacobian: few Jacobians, ~1 Newton iteration per step.
    assert!(st.jacobian_evaluations <= 3, "{st:?}");
    assert!(st.newton_iterations <= 2 * st.steps + 10, "{st:?}");
}

#[test]
fn park_adaptive_handles_the_stiff_system_with_large_steps() {
    let mut sys = stiff_system();
    let settings = ParkSettings::with_tolerances(1e-6, 1e-6);
    let mut max_err = 0.0_f64;
    let st = integrate_park(
        &mut sys,
        &settings,
        0.0,
        &[0.0],
        &[0.0],
        3.0,
        |t, q, _, _| {
            max_err = max_err.max((q[0] - stiff_exact(t).0).abs());
            ControlFlow::Continue(())
        },
    )
    .unwrap();
    println!("stiff adaptive: max error {max_err:e}, stats {st:?}");
    assert!(max_err < 1e-4, "stiff adaptive error {max_err}");
    // An explicit method would need > 3e6·2.8/… steps; the stiff solver far fewer.
    assert!(st.steps < 5000, "{st:?}");
}

/// Two uncoupled unit masses: a slow spring (ω = 1 rad/s) and a stiff one
/// (ω = 10⁴ rad/s, eigenvalues ±10⁴ i), like a wheel–rail contact spring
/// beside the car body modes.
struct SlowAndStiff;

impl MechanicalSystem for SlowAndStiff {
    fn dof(&self) -> usize {
        2
    }
    fn dynamics(
        &mut self,
        _t: f64,
        q: &[f64],
        _v: &[f64],
        mass: &mut DMatrix<f64>,
        force: &mut DVector<f64>,
    ) -> Result<(), SimError> {
        mass.fill(0.0);
        mass[(0, 0)] = 1.0;
        mass[(1, 1)] = 1.0;
        force[0] = -q[0];
        force[1] = -1e8 * q[1];
        Ok(())
    }
}

#[test]
fn park_damps_unresolved_stiff_oscillations_and_keeps_the_slow_mode() {
    // At h = 1e-3 the stiff mode has ωh = 10 (unresolved). Park's method is
    // stiffly stable: for y' = μy its amplification factor
    // (15 − 6ρ⁻¹ + ρ⁻²)/(10 − 6hμ) → 0 as |hμ| → ∞, so the unresolved mode
    // must decay instead of growing (the exact one keeps its amplitude), while
    // the resolved slow mode stays second-order accurate: q₁ = cos t.
    let mut max_stiff_late = 0.0_f64;
    let mut max_stiff = 0.0_f64;
    let mut slow_err = 0.0_f64;
    integrate_park(
        &mut SlowAndStiff,
        &ParkSettings::fixed(1e-3),
        0.0,
        &[1.0, 1e-3],
        &[0.0, 0.0],
        2.0,
        |t, q, _, _| {
            max_stiff = max_stiff.max(q[1].abs());
            if t >= 1.0 {
                max_stiff_late = max_stiff_late.max(q[1].abs());
            }
            slow_err = slow_err.max((q[0] - t.cos()).abs());
            ControlFlow::Continue(())
        },
    )
    .unwrap();
    println!("stiff mode max {max_stiff:e}, after 1 s {max_stiff_late:e}; slow error {slow_err:e}");
    assert!(
        max_stiff <= 1e-3 * (1.0 + 1e-12),
        "stiff mode grew to {max_stiff}"
    );
    assert!(
        max_stiff_late < 1e-12,
        "stiff mode not damped: {max_stiff_late}"
    );
    // Global error of the resolved mode ~ h²·t (phase error), 2e-6 at 2 s.
    assert!(slow_err < 1e-5, "slow mode error {slow_err}");
}

#[test]
fn rk4_blows_up_on_the_stiff_system_and_names_the_time() {
    let mut sys = stiff_system();
    let mut last_t = 0.0;
    let err = integrate_rk4(
        &mut sys,
        &Rk4Settings::new(1e-3),
        0.0,
        &[0.0],
        &[0.0],
        3.0,
        |t, _, _, _| {
            last_t = t;
            ControlFlow::Continue(())
        },
    )
    .unwrap_err();
    match &err {
        SimError::NonFinite { t, .. } => assert!(*t > last_t && *t <= last_t + 1e-3 + 1e-12),
        other => panic!("expected NonFinite, got {other:?}"),
    }
    assert!(err.to_string().contains("t = "), "{err}");
}

// ---------------------------------------------------------------------------
// Pendulum: index-3 DAE with a Lagrange multiplier
// ---------------------------------------------------------------------------

fn run_pendulum(
    theta0: f64,
    tol: f64,
    t_end: f64,
) -> (Pendulum, Vec<Sample>, railmbs_integrate::IntegrationStats) {
    let mut p = Pendulum {
        m: 3.0,
        l: 1.2,
        g: 9.81,
    };
    let q0 = [p.l * theta0.sin(), -p.l * theta0.cos()];
    let mut samples = Vec::new();
    let settings = ParkSettings::with_tolerances(tol, tol);
    let st = integrate_park_steps(&mut p, &settings, 0.0, &q0, &[0.0, 0.0], t_end, |s| {
        samples.push(Sample {
            t: s.t,
            q: [s.q[0], s.q[1]],
            v: [s.v[0], s.v[1]],
            lambda: s.lambda[0],
        });
        ControlFlow::Continue(())
    })
    .unwrap();
    (p, samples, st)
}

#[test]
fn pendulum_small_amplitude_period_is_two_pi_sqrt_l_over_g() {
    let theta0 = 0.02;
    // Tolerance relative to the 24 mm amplitude.
    let (p, samples, _) = run_pendulum(theta0, 1e-10, 7.0);
    let cross = downward_crossings(&samples, 0);
    assert!(cross.len() >= 3, "{cross:?}");
    let period = (cross[cross.len() - 1] - cross[0]) / (cross.len() - 1) as f64;
    let t0 = 2.0 * PI * (p.l / p.g).sqrt();
    // Finite amplitude lengthens the period by θ0²/16 = 2.5e-5 (relative);
    // allow that plus 1e-5 for the integration (phase error ∝ tol^(2/3)).
    assert!(
        ((period - t0) / t0).abs() < theta0 * theta0 / 16.0 + 1e-5,
        "period {period} vs {t0}"
    );
}

#[test]
fn pendulum_large_amplitude_period_constraint_and_tension() {
    // θ0 = 60°: exact period 4√(l/g) K(sin(θ0/2)).
    let theta0 = PI / 3.0;
    let tol = 1e-9;
    let (p, samples, st) = run_pendulum(theta0, tol, 6.0);
    println!("pendulum stats {st:?}");
    let exact = 4.0 * (p.l / p.g).sqrt() * elliptic_k((theta0 / 2.0).sin());
    let cross = downward_crossings(&samples, 0);
    assert!(cross.len() >= 2, "{cross:?}");
    let period = (cross[cross.len() - 1] - cross[0]) / (cross.len() - 1) as f64;
    assert!(
        ((period - exact) / exact).abs() < 1e-5,
        "period {period} vs exact {exact}"
    );

    let e0 = -p.m * p.g * p.l * theta0.cos();
    let mut worst_g = 0.0_f64;
    let mut worst_tension = 0.0_f64;
    let mut worst_energy = 0.0_f64;
    for s in &samples {
        let [x, y] = s.q;
        let [vx, vy] = s.v;
        // Constraint residual as a length: |x² + y² − l²| / (2l).
        worst_g = worst_g.max((x * x + y * y - p.l * p.l).abs() / (2.0 * p.l));
        // Rod tension T = m (g cos θ + l θ̇²), cos θ = −y/l, l θ̇² = |v|²/l; the
        // multiplier of g = x² + y² − l² is λ = −T / (2l).
        let tension = p.m * (p.g * (-y / p.l) + (vx * vx + vy * vy) / p.l);
        worst_tension = worst_tension.max((-2.0 * p.l * s.lambda - tension).abs());
        let energy = 0.5 * p.m * (vx * vx + vy * vy) + p.m * p.g * y;
        worst_energy = worst_energy.max((energy - e0).abs());
    }
    println!("constraint {worst_g:e} m, tension {worst_tension:e} N, energy {worst_energy:e} J");
    // Positions satisfy g = 0 to the Newton accuracy, far below the tolerance.
    assert!(worst_g < tol * p.l, "constraint residual {worst_g}");
    // Tension scale m g = 29 N. In the index-3 formulation λ is fixed by the
    // accelerations a₊ = D(D q), twice-differentiated positions: at constant
    // step it converges with O(h²) (next test), but every step-size change
    // leaves an O(h) error in it (Brenan, Campbell & Petzold, Numerical
    // Solution of IVPs in DAEs, 1996, Sect. 3.2: BDF on index-3 Hessenberg
    // systems with variable steps). With h ≈ 1e-3 s here, 1e-3 relative.
    assert!(
        worst_tension < 1e-3 * p.m * p.g,
        "tension error {worst_tension}"
    );
    // Energy m g l ≈ 35 J, conserved to the accumulated tolerance.
    assert!(
        worst_energy < 1e-4 * p.m * p.g * p.l,
        "energy drift {worst_energy}"
    );
}

#[test]
fn consistent_multipliers_equal_the_rod_tension_of_the_state() {
    // With `consistent_multipliers` λ comes from the acceleration-level
    // equations at each accepted state, so it must equal the tension
    // m (g cos θ + |v|²/l) of that state up to the central-difference γ
    // (~1e-7 relative) and the O(tol) velocity-constraint residual G v.
    let theta0 = PI / 3.0;
    let mut p = Pendulum {
        m: 3.0,
        l: 1.2,
        g: 9.81,
    };
    let (m, l, g) = (p.m, p.l, p.g);
    let q0 = [l * theta0.sin(), -l * theta0.cos()];
    let settings = ParkSettings {
        consistent_multipliers: true,
        ..ParkSettings::with_tolerances(1e-8, 1e-8)
    };
    let mut worst = 0.0_f64;
    let mut worst_accel = 0.0_f64;
    let st = integrate_park_steps(&mut p, &settings, 0.0, &q0, &[0.0, 0.0], 3.0, |s| {
        let (x, y, vx, vy) = (s.q[0], s.q[1], s.v[0], s.v[1]);
        let tension = m * (g * (-y / l) + (vx * vx + vy * vy) / l);
        worst = worst.max((-2.0 * l * s.lambda[0] - tension).abs());
        // Newton's law for the mass: m a = (0, −m g) − T (x, y)/l.
        let ax = -tension * x / (l * m);
        let ay = -g - tension * y / (l * m);
        worst_accel = worst_accel
            .max((s.accel[0] - ax).abs())
            .max((s.accel[1] - ay).abs());
        ControlFlow::Continue(())
    })
    .unwrap();
    println!("consistent multipliers: tension {worst:e} N, accel {worst_accel:e}, {st:?}");
    assert!(worst < 1e-6 * m * g, "tension error {worst}");
    assert!(worst_accel < 1e-6 * g, "acceleration error {worst_accel}");
}

#[test]
fn pendulum_multiplier_converges_with_order_two_at_fixed_step() {
    let theta0 = PI / 3.0;
    let worst = |h: f64| {
        let mut p = Pendulum {
            m: 3.0,
            l: 1.2,
            g: 9.81,
        };
        let q0 = [p.l * theta0.sin(), -p.l * theta0.cos()];
        let (m, l, g) = (p.m, p.l, p.g);
        let mut worst = 0.0_f64;
        integrate_park_steps(
            &mut p,
            &ParkSettings::fixed(h),
            0.0,
            &q0,
            &[0.0, 0.0],
            2.5,
            |s| {
                let (y, vx, vy) = (s.q[1], s.v[0], s.v[1]);
                let tension = m * (g * (-y / l) + (vx * vx + vy * vy) / l);
                worst = worst.max((-2.0 * l * s.lambda[0] - tension).abs());
                ControlFlow::Continue(())
            },
        )
        .unwrap();
        worst
    };
    let (e1, e2) = (worst(2e-3), worst(1e-3));
    let order = (e1 / e2).log2();
    println!("tension errors {e1:e} {e2:e}, order {order}");
    assert!((1.8..=2.3).contains(&order), "multiplier order {order}");
    assert!(e2 < 1e-4 * 3.0 * 9.81, "tension error {e2} at h = 1e-3");
}

#[test]
fn inconsistent_pendulum_start_is_projected_onto_the_constraints() {
    let mut p = Pendulum {
        m: 1.0,
        l: 1.0,
        g: 9.81,
    };
    // Start 10 % too long and with a velocity component along the rod.
    let mut first = None;
    let st = integrate_park_steps(
        &mut p,
        &ParkSettings::default(),
        0.0,
        &[0.6, -0.9],
        &[0.3, 0.5],
        0.1,
        |s| {
            if first.is_none() {
                first = Some((s.q.to_vec(), s.v.to_vec(), s.lambda[0]));
            }
            ControlFlow::Continue(())
        },
    )
    .unwrap();
    let (q, v, lambda) = first.unwrap();
    assert!((q[0].hypot(q[1]) - 1.0).abs() < 1e-12, "{q:?}");
    // Minimum-norm projection moves q along the rod direction: same angle.
    assert!((q[0].atan2(q[1]) - 0.6_f64.atan2(-0.9)).abs() < 1e-12);
    // Radial velocity removed, tangential kept (least-squares projection).
    assert!((q[0] * v[0] + q[1] * v[1]).abs() < 1e-12);
    let tangential = (0.3 * q[1] - 0.5 * q[0]).abs();
    assert!(((v[0] * q[1] - v[1] * q[0]).abs() - tangential).abs() < 1e-12);
    // Initial multiplier from the acceleration-level equations, λ = −T/(2l).
    let tension = p.g * (-q[1]) + v[0] * v[0] + v[1] * v[1];
    assert!(
        (-2.0 * lambda - tension).abs() < 1e-6,
        "{lambda} vs {tension}"
    );
    assert_eq!(st.t, 0.1);
}

#[test]
fn rheonomic_constraint_drives_the_motion_and_lambda_is_the_driving_force() {
    let mut sys = Driven {
        m: 2.0,
        amp: 0.1,
        omega: 5.0,
    };
    let (m, amp, w) = (sys.m, sys.amp, sys.omega);
    let tol = 1e-8;
    let (mut worst_x, mut worst_v, mut worst_force, mut worst_free) =
        (0.0_f64, 0.0_f64, 0.0_f64, 0.0_f64);
    let mut h_max = 0.0_f64;
    // Both masses start at rest: v0 is projected onto G v + ∂g/∂t = 0, which
    // gives the driven mass its velocity A ω and leaves the free one alone.
    let st = integrate_park_steps(
        &mut sys,
        &ParkSettings::with_tolerances(tol, tol),
        0.0,
        &[0.0, 0.3],
        &[0.0, 0.0],
        2.0,
        |s| {
            let t = s.t;
            h_max = h_max.max(s.h);
            worst_x = worst_x.max((s.q[0] - amp * (w * t).sin()).abs());
            worst_v = worst_v.max((s.v[0] - amp * w * (w * t).cos()).abs());
            worst_force = worst_force.max((s.lambda[0] + m * amp * w * w * (w * t).sin()).abs());
            worst_free = worst_free.max((s.q[1] - 0.3).abs()).max(s.v[1].abs());
            ControlFlow::Continue(())
        },
    )
    .unwrap();
    println!(
        "driven: x {worst_x:e}, v {worst_v:e}, force {worst_force:e}, free {worst_free:e}, {st:?}"
    );
    // The constraint is imposed exactly on positions at every step.
    assert!(worst_x < 1e-12, "{worst_x}");
    // With exact positions v = D q carries only Park's truncation error
    // |q'''|·h₀(h₀ + h₁)/12 ≤ A ω³ h²/6 (module docs); 1.5× for step variation.
    let v_bound = 1.5 * amp * w.powi(3) * h_max * h_max / 6.0;
    assert!(worst_v < v_bound, "{worst_v} vs {v_bound}");
    // Driving force amplitude m A ω² = 5 N. a = D(D q) reacts to each step
    // size change by ~h·|q'''|·|Δh/h| (the truncation error of v changes with
    // the step, and D divides that change by h): with h ≈ 2.5e-3 s and
    // changes up to 20 %, ~1e-2 N at most; allow 2.5e-3 relative.
    assert!(worst_force < 2.5e-3 * m * amp * w * w, "{worst_force}");
    // The free mass is not coupled at all.
    assert!(worst_free < 1e-12, "{worst_free}");
}

#[test]
fn too_large_initial_step_is_recovered_by_newton_failure_or_error_test() {
    // A 0.5 s first step on the pendulum (a quarter period) must be refused by
    // Newton or by the error test and reduced; the run then stays accurate.
    let mut p = Pendulum {
        m: 1.0,
        l: 1.0,
        g: 9.81,
    };
    let theta0 = 1.0_f64;
    let settings = ParkSettings {
        initial_step: Some(0.5),
        ..ParkSettings::with_tolerances(1e-7, 1e-7)
    };
    let e0 = -p.g * theta0.cos();
    let mut worst_energy = 0.0_f64;
    let st = integrate_park_steps(
        &mut p,
        &settings,
        0.0,
        &[theta0.sin(), -theta0.cos()],
        &[0.0, 0.0],
        3.0,
        |s| {
            let energy = 0.5 * (s.v[0] * s.v[0] + s.v[1] * s.v[1]) + 9.81 * s.q[1];
            worst_energy = worst_energy.max((energy - e0).abs());
            ControlFlow::Continue(())
        },
    )
    .unwrap();
    println!("large first step: energy {worst_energy:e}, {st:?}");
    assert!(st.rejected_steps >= 1, "{st:?}");
    // Energy g l (1 − cos θ0) ≈ 4.5 J per kg conserved to 1e-4 relative.
    assert!(worst_energy < 1e-4 * p.g, "{worst_energy}");
}

#[test]
fn step_loops_do_not_allocate() {
    // Allocations of a whole run must not depend on the number of steps: runs
    // to 1 s and to 4 s (4× the steps) allocate the same amount (workspaces
    // at the start, the returned statistics).
    let count = |t_end: f64, which: u8| {
        let before = allocations();
        match which {
            0 => {
                let mut sys = Oscillator::new(1.0, 0.1, 100.0);
                let s = ParkSettings::with_tolerances(1e-7, 1e-7);
                let st = integrate_park(&mut sys, &s, 0.0, &[1.0], &[0.0], t_end, |_, _, _, _| {
                    ControlFlow::Continue(())
                })
                .unwrap();
                assert_eq!(st.newton_failures, 0);
            }
            1 => {
                let mut p = Pendulum {
                    m: 1.0,
                    l: 1.0,
                    g: 9.81,
                };
                let settings = ParkSettings {
                    consistent_multipliers: true,
                    ..ParkSettings::fixed(1e-3)
                };
                integrate_park_steps(
                    &mut p,
                    &settings,
                    0.0,
                    &[0.6, -0.8],
                    &[0.0, 0.0],
                    t_end,
                    |_| ControlFlow::Continue(()),
                )
                .unwrap();
            }
            _ => {
                let mut sys = Oscillator::new(1.0, 0.1, 100.0);
                integrate_rk4(
                    &mut sys,
                    &Rk4Settings::new(1e-3),
                    0.0,
                    &[1.0],
                    &[0.0],
                    t_end,
                    |_, _, _, _| ControlFlow::Continue(()),
                )
                .unwrap();
            }
        }
        allocations() - before
    };
    for which in 0..3 {
        let (a1, a4) = (count(1.0, which), count(4.0, which));
        assert_eq!(
            a1, a4,
            "integrator {which}: {a1} allocations to 1 s, {a4} to 4 s"
        );
    }
}

// ---------------------------------------------------------------------------
// Failures
// ---------------------------------------------------------------------------

#[test]
fn blow_up_is_reported_with_the_time() {
    let settings = ParkSettings {
        min_step: 1e-10,
        ..ParkSettings::with_tolerances(1e-6, 1e-6)
    };
    let mut last_t = 0.0;
    let err = integrate_park(
        &mut BlowUp,
        &settings,
        0.0,
        &[1.0],
        &[1.0 / 2f64.sqrt()],
        3.0,
        |t, _, _, _| {
            last_t = t;
            ControlFlow::Continue(())
        },
    )
    .unwrap_err();
    let t_star = 2f64.sqrt();
    let t = match &err {
        SimError::Diverged { t, .. } | SimError::NonFinite { t, .. } => *t,
        other => panic!("unexpected error {other:?}"),
    };
    println!("{err}");
    // The run gets close to the singularity and stops there, not elsewhere.
    assert!(
        (t - t_star).abs() < 1e-2,
        "stopped at {t}, singularity at {t_star}"
    );
    assert!(last_t <= t_star);
    assert!(err.to_string().contains("t = "));
}

#[test]
fn nan_force_stops_with_non_finite_error_at_that_time() {
    let settings = ParkSettings {
        max_step: 0.01,
        ..ParkSettings::default()
    };
    let err = integrate_park(
        &mut NanAfterOne,
        &settings,
        0.0,
        &[0.0],
        &[0.0],
        2.0,
        |_, _, _, _| ControlFlow::Continue(()),
    )
    .unwrap_err();
    match &err {
        SimError::NonFinite { t, what } => {
            assert!(*t > 1.0 && *t <= 1.01 + 1e-12, "t = {t}");
            assert!(what.contains("force"), "{what}");
        }
        other => panic!("expected NonFinite, got {other:?}"),
    }
}

#[test]
fn rk4_refuses_constrained_systems() {
    let mut p = Pendulum {
        m: 1.0,
        l: 1.0,
        g: 9.81,
    };
    let err = integrate_rk4(
        &mut p,
        &Rk4Settings::new(0.01),
        0.0,
        &[0.0, -1.0],
        &[0.0, 0.0],
        1.0,
        |_, _, _, _| ControlFlow::Continue(()),
    )
    .unwrap_err();
    assert!(matches!(err, SimError::Other(_)));
    assert!(err.to_string().contains("constrained"), "{err}");
}

#[test]
fn bad_settings_and_states_are_refused() {
    let mut sys = Oscillator::new(1.0, 0.0, 1.0);
    let run = |sys: &mut Oscillator, s: &ParkSettings, q0: &[f64], t_end: f64| {
        integrate_park(sys, s, 0.0, q0, &[0.0], t_end, |_, _, _, _| {
            ControlFlow::Continue(())
        })
    };
    let bad_atol = ParkSettings::with_tolerances(1e-6, 0.0);
    assert!(
        run(&mut sys, &bad_atol, &[1.0], 1.0)
            .unwrap_err()
            .to_string()
            .contains("atol")
    );
    assert!(run(&mut sys, &ParkSettings::default(), &[f64::NAN], 1.0).is_err());
    assert!(run(&mut sys, &ParkSettings::default(), &[1.0, 2.0], 1.0).is_err());
    assert!(run(&mut sys, &ParkSettings::default(), &[1.0], -1.0).is_err());
    let e = integrate_rk4(
        &mut sys,
        &Rk4Settings::new(0.0),
        0.0,
        &[1.0],
        &[0.0],
        1.0,
        |_, _, _, _| ControlFlow::Continue(()),
    );
    assert!(e.unwrap_err().to_string().contains("step"));
}

#[test]
fn observer_can_stop_the_run() {
    let mut sys = Oscillator::new(1.0, 0.0, 1.0);
    let mut calls = 0;
    let st = integrate_park(
        &mut sys,
        &ParkSettings::default(),
        0.0,
        &[1.0],
        &[0.0],
        10.0,
        |t, _, _, _| {
            calls += 1;
            if t > 1.0 {
                ControlFlow::Break(())
            } else {
                ControlFlow::Continue(())
            }
        },
    )
    .unwrap();
    assert!(st.stopped_by_observer);
    assert!(st.t > 1.0 && st.t < 10.0);
    assert_eq!(calls, st.steps + 1, "initial state + one call per step");
    assert!((st.q[0] - st.t.cos()).abs() < 1e-3);
}

// ---------------------------------------------------------------------------
// Stepping API
// ---------------------------------------------------------------------------

#[test]
fn stepping_reaches_stop_times_exactly_and_not_beyond() {
    // Undamped oscillator m = k = 1 from q = 1: q = cos t.
    let mut sys = Oscillator::new(1.0, 0.0, 1.0);
    let mut park = Park::new(
        &mut sys,
        ParkSettings::with_tolerances(1e-8, 1e-8),
        0.0,
        &[1.0],
        &[0.0],
    )
    .unwrap();
    assert_eq!(park.state().t, 0.0);
    assert_eq!(park.state().accel, &[-1.0]);
    let at = park.step_until(1.0).unwrap();
    assert_eq!(at.t, 1.0);
    assert!((at.q[0] - 1.0_f64.cos()).abs() < 1e-5, "{}", at.q[0]);
    let steps = park.stats().steps;
    assert!(park.step().is_err(), "no step past the stop time");
    assert_eq!(park.stats().steps, steps);
    // Continue to a second stop time, one step at a time (the caller's loop).
    park.set_stop_time(2.5).unwrap();
    while park.t() < 2.5 {
        let s = park.step().unwrap();
        assert!(s.t <= 2.5 && s.h > 0.0);
    }
    assert_eq!(park.t(), 2.5);
    assert!((park.state().q[0] - 2.5_f64.cos()).abs() < 1e-5);
    assert_eq!(park.stats().t, 2.5);
    assert!(park.set_stop_time(2.0).is_err(), "a stop time in the past");

    let mut rk4 = Rk4::new(&mut sys, &Rk4Settings::new(0.01), 0.0, &[1.0], &[0.0]).unwrap();
    let at = rk4.step_until(0.995).unwrap();
    assert_eq!(at.t, 0.995);
    assert!((at.q[0] - 0.995_f64.cos()).abs() < 1e-8);
    assert!(rk4.step().is_err());
}

#[test]
fn stepping_loop_matches_the_observer_loop() {
    let settings = ParkSettings::with_tolerances(1e-7, 1e-7);
    let mut a = Oscillator::new(1.0, 0.3, 4.0);
    let mut observed = Vec::new();
    let st = integrate_park_steps(&mut a, &settings, 0.0, &[1.0], &[0.0], 3.0, |s| {
        observed.push((s.t, s.h, s.q[0], s.v[0], s.accel[0]));
        ControlFlow::Continue(())
    })
    .unwrap();
    let mut b = Oscillator::new(1.0, 0.3, 4.0);
    let mut park = Park::new(&mut b, settings, 0.0, &[1.0], &[0.0]).unwrap();
    park.set_stop_time(3.0).unwrap();
    let s = park.state();
    let mut stepped = vec![(s.t, s.h, s.q[0], s.v[0], s.accel[0])];
    while park.t() < 3.0 {
        let s = park.step().unwrap();
        stepped.push((s.t, s.h, s.q[0], s.v[0], s.accel[0]));
    }
    assert_eq!(observed, stepped);
    assert_eq!(park.stats(), &st);
}

/// An oscillator whose `accept_step` fails at a given time.
struct FailingAccept {
    inner: Oscillator,
    fail_after: f64,
}

impl MechanicalSystem for FailingAccept {
    fn dof(&self) -> usize {
        1
    }

    fn dynamics(
        &mut self,
        t: f64,
        q: &[f64],
        v: &[f64],
        mass: &mut DMatrix<f64>,
        force: &mut DVector<f64>,
    ) -> Result<(), SimError> {
        self.inner.dynamics(t, q, v, mass, force)
    }

    fn accept_step(&mut self, t: f64, _q: &[f64], _v: &[f64]) -> Result<(), SimError> {
        if t > self.fail_after {
            return Err(SimError::Other(format!("refused the step to t = {t} s")));
        }
        Ok(())
    }
}

#[test]
fn accept_step_errors_end_the_run() {
    let mut sys = FailingAccept {
        inner: Oscillator::new(1.0, 0.0, 1.0),
        fail_after: 0.5,
    };
    let err = integrate_park(
        &mut sys,
        &ParkSettings::default(),
        0.0,
        &[1.0],
        &[0.0],
        2.0,
        |_, _, _, _| ControlFlow::Continue(()),
    )
    .unwrap_err();
    assert!(err.to_string().contains("refused the step"), "{err}");
    let err = integrate_rk4(
        &mut sys,
        &Rk4Settings::new(0.1),
        0.0,
        &[1.0],
        &[0.0],
        2.0,
        |_, _, _, _| ControlFlow::Continue(()),
    )
    .unwrap_err();
    // The first step past 0.5 s ends at t0 + 6 h (with its rounding).
    let t6 = 6.0 * 0.1;
    assert_eq!(
        err,
        SimError::Other(format!("refused the step to t = {t6} s"))
    );
}

/// `step_observed` shows the end of every step before the step is accepted,
/// with the acceleration of the system's equation there (m q̈ = −c q̇ − k q
/// for the oscillator): RK4 evaluates it there (rounding only); Park's
/// method takes q̈ from its last Newton iterate, which stops on the
/// coordinate increment (rtol 1e-8), so q̈ carries that error amplified by
/// the 1/h² of the difference formula: measured 1.8e-6 relative on the tiny
/// first step, tolerance 1e-4.
#[test]
fn step_observed_shows_the_step_before_accepting_it() {
    let (m, c, k) = (2.0, 0.3, 50.0);
    let check = |solver: &mut dyn Stepper<System = Oscillator>, tol: f64| {
        for step in 0..40 {
            let mut seen = false;
            solver
                .step_observed(&mut |sys, s| {
                    assert_eq!(sys.accepted, step, "accepted before observed");
                    let a = (-c * s.v[0] - k * s.q[0]) / m;
                    let err = (s.accel[0] - a).abs() / a.abs().max(1.0);
                    assert!(
                        err <= tol,
                        "step {step}: q̈ {} against {a}: {err:e}",
                        s.accel[0]
                    );
                    assert!(s.h > 0.0);
                    seen = true;
                    Ok(())
                })
                .unwrap();
            assert!(seen);
            assert_eq!(solver.system().accepted, step + 1);
        }
    };
    let settings = ParkSettings::with_tolerances(1e-8, 1e-10);
    let mut park = Park::new(Oscillator::new(m, c, k), settings, 0.0, &[0.1], &[0.0]).unwrap();
    check(&mut park, 1e-4);
    let mut rk4 = Rk4::new(
        Oscillator::new(m, c, k),
        &Rk4Settings::new(1e-3),
        0.0,
        &[0.1],
        &[0.0],
    )
    .unwrap();
    check(&mut rk4, 1e-14);
    // An error of the observer ends the step without accepting it.
    let err = rk4
        .step_observed(&mut |_, _| Err(SimError::Other("stop".into())))
        .unwrap_err();
    assert_eq!(err, SimError::Other("stop".into()));
    assert_eq!(rk4.system().accepted, 40);
}
