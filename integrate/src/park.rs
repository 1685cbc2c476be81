//! Park's stiffly stable implicit method for `M(q,t) q̈ = f(t,q,q̇) + Gᵀλ`,
//! `g(q,t) = 0` (index-3 form: positions satisfy the constraints exactly at
//! every step).
//!
//! # Method
//!
//! K. C. Park (1975), "An improved stiffly stable method for direct
//! integration of nonlinear structural dynamic equations", J. Appl. Mech. 42;
//! used in Universal Mechanism (D. Yu. Pogorelov 2005, Sect. 6). The derivative
//! at the new time is the half-sum of the BDF2 and BDF3 formulas; at constant
//! step h
//!
//! ```text
//!     v₊ = (10 q₊ − 15 q + 6 q₋ − q₋₋) / (6h),   a₊ = (10 v₊ − 15 v + 6 v₋ − v₋₋) / (6h).
//! ```
//!
//! With variable steps both BDF formulas are the derivative at t₊ of the
//! polynomial interpolating the last 3 (BDF2) resp. 4 (BDF3) points, which
//! reduces to the formula above at constant step. Writing the formula as
//! `v₊ = (q₊ − q̂)/β`, `a₊ = (v₊ − v̂)/β` (β = 0.6h at constant step, q̂ and v̂
//! collect the history terms), the only unknowns are q₊ and λ. Newton
//! iterations solve
//!
//! ```text
//!     R = M a₊ − f(t₊, q₊, v₊) − Gᵀλ = 0,    g(q₊, t₊) = 0
//! ```
//!
//! with the iteration matrix (rows multiplied by β², unknowns (Δq, β²Δλ) so all
//! blocks are O(1))
//!
//! ```text
//!     [ M − β ∂f/∂q̇ − β² ∂f/∂q   −Gᵀ ] [ Δq    ]   [ −β² R ]
//!     [ G                         0  ] [ β²Δλ  ] = [ −g    ]
//! ```
//!
//! factorized by LU and reused across iterations and steps (modified Newton);
//! it is refactorized when β changes by more than 20 %, and the Jacobians
//! ∂f/∂q, ∂f/∂q̇ (analytic from
//! [`MechanicalSystem::force_jacobian`]
//! or finite differences of `dynamics`) are re-evaluated when the iterations
//! converge slowly or fail. The Newton stopping test is Hairer & Wanner's
//! (Solving ODEs II, Sect. IV.8): with the contraction rate θ and
//! η = θ/(1 − θ), stop when η‖Δ‖ ≤ κ in the error-weighted norm; the
//! multipliers take part through the displacement their change causes,
//! (GᵀΔμ)ᵢ/Mᵢᵢ.
//!
//! Start-up: one BDF1 (implicit Euler) step, one BDF2 step, then Park.
//!
//! # Error control
//!
//! The predictor is the polynomial of degree p (the order of the corrector:
//! 1 for BDF1, 2 for BDF2 and Park) through the history (with the derivative at
//! the initial point while the history is short). Its error is
//! `y − yᴾ = Y·P` with `Y = y⁽ᵖ⁺¹⁾/(p+1)!` and P the product of the distances
//! from t₊ to its nodes. The corrector's truncation error is
//! `y_c − y = β·C·Y` with `C = Π sⱼ` for BDFk (sⱼ = t₊ − tⱼ) and half of the
//! BDF2 value for Park (its BDF3 half is one order higher). Hence the
//! Milne-type estimate of the local error
//!
//! ```text
//!     LTE = βC / (βC + P) · (y_c − yᴾ)      (= (y_c − yᴾ)/11 for Park at constant step)
//! ```
//!
//! for q and v, measured in the weighted RMS norm with weights
//! `atol + rtol·max(|y|, |y₊|)` over all 2n components. Steps with norm > 1 are
//! rejected; the step size follows `h·0.9·err^(−1/(p+1))`, limited to
//! [0.2, 1.6]·h, kept unchanged when the factor lies in [1, 1.2] (to reuse the
//! factorization), capped by `max_step`, and the last steps are adjusted to
//! end exactly at the stop time ([`Stepper::set_stop_time`]).
//!
//! Velocities of coordinates that appear in the constraints are index-2
//! variables of the index-3 system: their error enters the norm multiplied by
//! min(h, 1) (Hairer & Wanner's RADAU5 scaling), otherwise the Newton error
//! δq/β in v would drive the step size down without end. The last steps
//! approach the stop time in at most five equal steps.
//!
//! # Accuracy of accelerations and multipliers (constrained systems)
//!
//! Positions satisfy g = 0 to Newton accuracy at every step, and q, v converge
//! with order 2. Accelerations a = D(D q) and the multipliers λ that balance
//! them converge with order 2 at constant step, but each step-size change
//! leaves an error ~h·|q'''|·|Δh/h| in them (the truncation error of v depends
//! on the step and D divides its change by h), a known property of BDF-type
//! methods on index-3 systems (Brenan, Campbell & Petzold 1996, Sect. 3.2).
//! For accurate constraint forces set
//! [`ParkSettings::consistent_multipliers`]: the reported a and λ are then
//! recomputed from the acceleration-level equations at each accepted state.
//!
//! # Consistent initial conditions (constrained systems)
//!
//! Before the first step q0 is projected onto g(q, t0) = 0 by Gauss–Newton
//! iterations with the minimum-norm correction `Δq = −Gᵀ(GGᵀ)⁻¹g`, and v0 onto
//! `G v + ∂g/∂t = 0` by the least-squares (minimum Euclidean norm) correction.
//! The initial accelerations and multipliers solve the acceleration-level
//! system `M a − Gᵀλ = f`, `G a = −γ`, where γ = d²g/dt² at fixed a is taken by a
//! central second difference of g along (q + s v, t + s).

use std::ops::ControlFlow;

use std::sync::Arc;

use nalgebra::{Cholesky, DMatrix, DVector};

use super::block::{BlockMatrix, BlockPattern, BorderedLu};
use super::linalg::DenseLu;
use super::{
    BeforeAccept, IntegrationStats, StepView, Stepper, at_stop_time, check_end_time, check_finite,
    check_initial_state, check_stop_time,
};
use crate::system::{MechanicalSystem, SimError};

/// How the Jacobians ∂f/∂q and ∂f/∂q̇ of the iteration matrix are obtained.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum JacobianKind {
    /// Forward differences of `dynamics` (n + n extra evaluations), increment
    /// √ε·max(|x|, 1). The default.
    #[default]
    ForwardDifference,
    /// Central differences of `dynamics` (2n + 2n extra evaluations),
    /// increment ε^(1/3)·max(|x|, 1).
    CentralDifference,
    /// [`MechanicalSystem::force_jacobian`];
    /// falls back to forward differences when the system returns `false`.
    Analytic,
}

/// How Park's method solves its linear systems: the Newton iteration
/// matrix `M − β ∂f/∂q̇ − β² ∂f/∂q` and, without constraints, the q̈ solve
/// `M q̈ = f` of the initial state.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum LinearSolver {
    /// Dense LU with partial pivoting of the whole matrix.
    Dense,
    /// The bordered block-diagonal LU of [`crate::block`] with M and the
    /// Jacobians assembled blockwise, when the system has a block pattern
    /// ([`MechanicalSystem::block_pattern`]: a train's vehicles coupled
    /// through their couplers' bodies, a vehicle's bogies through the car
    /// body) and no constraints; the dense LU
    /// otherwise. Same solutions to rounding (the summation order differs).
    /// The default: systems without a pattern solve exactly as with
    /// [`LinearSolver::Dense`].
    #[default]
    Block,
}

/// Settings of Park's method.
#[derive(Debug, Clone, PartialEq)]
pub struct ParkSettings {
    /// Relative tolerance (≥ 0) of the local error in q and v.
    pub rtol: f64,
    /// Absolute tolerance (> 0) of the local error, in the units of each
    /// coordinate (m or rad) and velocity (m/s or rad/s).
    pub atol: f64,
    /// Largest step, s (> 0, may be infinite).
    pub max_step: f64,
    /// First step, s; `None` chooses it from the initial derivatives
    /// (Hairer–Nørsett–Wanner's starting-step heuristic for order 1).
    pub initial_step: Option<f64>,
    /// Smallest step, s: a run that would need a smaller step fails with
    /// [`SimError::Diverged`].
    pub min_step: f64,
    /// Source of ∂f/∂q and ∂f/∂q̇.
    pub jacobian: JacobianKind,
    /// Constant step `initial_step` without error control (the last step is
    /// shortened to hit the stop time); rtol/atol then only set the Newton accuracy.
    /// Meant for convergence studies.
    pub fixed_step: bool,
    /// Newton iterations per step attempt before the attempt fails (≥ 1).
    pub max_newton_iterations: usize,
    /// Newton stopping tolerance κ in the weighted norm (units of the error
    /// tolerance); `None` uses max(10ε/rtol, min(0.03, √rtol)).
    pub newton_tol: Option<f64>,
    /// Constrained systems: report accelerations and multipliers recomputed
    /// after every accepted step from the acceleration-level equations
    /// `M a − Gᵀλ = f`, `G a = −γ` at the accepted (t, q, v), instead of
    /// Park's a = D(D q) and its λ, which carry O(h·Δh/h) errors after
    /// step-size changes (module docs). Costs one `dynamics` evaluation, three
    /// constraint evaluations and one LU factorization of size n + nc per
    /// step. The integration itself is unchanged.
    pub consistent_multipliers: bool,
    /// How the linear systems are solved.
    pub solver: LinearSolver,
}

impl Default for ParkSettings {
    fn default() -> Self {
        Self {
            rtol: 1e-6,
            atol: 1e-6,
            max_step: f64::INFINITY,
            initial_step: None,
            min_step: 1e-12,
            jacobian: JacobianKind::default(),
            fixed_step: false,
            max_newton_iterations: 8,
            newton_tol: None,
            consistent_multipliers: false,
            solver: LinearSolver::default(),
        }
    }
}

impl ParkSettings {
    /// Adaptive settings with the given tolerances, other fields default.
    pub fn with_tolerances(rtol: f64, atol: f64) -> Self {
        Self {
            rtol,
            atol,
            ..Self::default()
        }
    }

    /// Fixed step `h` (s) without error control; Newton iterations converge
    /// to rtol = atol = 1e-10.
    pub fn fixed(h: f64) -> Self {
        Self {
            rtol: 1e-10,
            atol: 1e-10,
            max_step: h,
            initial_step: Some(h),
            fixed_step: true,
            ..Self::default()
        }
    }

    fn validate(&self) -> Result<(), SimError> {
        let bad = |what: String| Err(SimError::Other(format!("Park settings: {what}")));
        if !(self.rtol >= 0.0 && self.rtol.is_finite()) {
            return bad(format!("rtol must be finite and ≥ 0, got {}", self.rtol));
        }
        if !(self.atol > 0.0 && self.atol.is_finite()) {
            return bad(format!("atol must be finite and > 0, got {}", self.atol));
        }
        if self.max_step.is_nan() || self.max_step <= 0.0 {
            return bad(format!("max_step must be > 0, got {}", self.max_step));
        }
        if !(self.min_step >= 0.0 && self.min_step < self.max_step) {
            return bad(format!(
                "min_step must be ≥ 0 and below max_step = {}, got {}",
                self.max_step, self.min_step
            ));
        }
        if let Some(h) = self.initial_step
            && !(h > 0.0 && h.is_finite())
        {
            return bad(format!("initial_step must be finite and > 0, got {h}"));
        }
        if self.fixed_step && self.initial_step.is_none() {
            return bad("fixed_step needs initial_step (the step size)".into());
        }
        if self.max_newton_iterations == 0 {
            return bad("max_newton_iterations must be ≥ 1".into());
        }
        if let Some(k) = self.newton_tol
            && !(k > 0.0 && k.is_finite())
        {
            return bad(format!("newton_tol must be finite and > 0, got {k}"));
        }
        Ok(())
    }

    fn newton_kappa(&self) -> f64 {
        self.newton_tol.unwrap_or_else(|| {
            let rtol = self.rtol.max(f64::EPSILON);
            (10.0 * f64::EPSILON / rtol).max(0.03_f64.min(rtol.sqrt()))
        })
    }
}

/// Step-size controller constants.
/// Consecutive rejected attempts of one step after which the history is
/// dropped and the integration restarts with BDF1 from the current point.
const RESTART_AFTER_REJECTIONS: usize = 3;
const SAFETY: f64 = 0.9;
const FAC_MIN: f64 = 0.2;
/// Largest growth per step. Variable-step BDF formulas stay zero-stable for
/// moderate step ratios; 1.6 keeps well inside that.
const FAC_MAX: f64 = 1.6;
/// Step factors in [1, HOLD_MAX] keep the step (and the factorization).
const HOLD_MAX: f64 = 1.2;
/// Refactorize when β differs from the factorized one by more than this.
const REFACTOR_RATIO: f64 = 0.2;
/// Step reduction after a Newton failure with a fresh Jacobian.
const NEWTON_FAIL_FACTOR: f64 = 0.25;

/// Result of one Newton solve.
enum Newton {
    Converged { iterations: usize, theta_max: f64 },
    Failed(String),
}

/// Coefficients of one step attempt.
struct StepCoefficients {
    /// 1/(leading coefficient of the derivative formula), s.
    beta: f64,
    /// Order of the corrector.
    order: usize,
    /// LTE = ratio·(corrector − predictor).
    lte_ratio: f64,
}

/// The matrices of a system with a block pattern ([`LinearSolver::Block`]),
/// in place of the dense ones of [`Work`].
#[derive(Debug)]
struct BlockWork {
    /// M of the current evaluation.
    mass: BlockMatrix,
    /// M, ∂f/∂q, ∂f/∂q̇ of the Jacobian snapshot.
    mass_j: BlockMatrix,
    dfdq: BlockMatrix,
    dfdv: BlockMatrix,
    /// M of the finite-difference evaluations (unused).
    mass_pert: BlockMatrix,
    /// The matrix being factorized.
    scratch: BlockMatrix,
    /// Factorization of the iteration matrix.
    lu: BorderedLu,
    /// Factorization of M (the q̈ solve).
    lu_mass: BorderedLu,
    /// The pattern and its finite-difference column groups.
    pattern: Arc<BlockPattern>,
    groups: Vec<Vec<usize>>,
}

impl BlockWork {
    fn new(pattern: &Arc<BlockPattern>) -> Self {
        let z = || BlockMatrix::zeros(pattern);
        Self {
            mass: z(),
            mass_j: z(),
            dfdq: z(),
            dfdv: z(),
            mass_pert: z(),
            scratch: z(),
            lu: BorderedLu::new(pattern),
            lu_mass: BorderedLu::new(pattern),
            groups: pattern.difference_groups(),
            pattern: pattern.clone(),
        }
    }
}

/// Fails with [`SimError::NonFinite`] naming the time, the quantity and the
/// first offending entry (i, j) when `m` holds a NaN or an infinity.
fn check_finite_blocks(t: f64, what: &str, m: &BlockMatrix) -> Result<(), SimError> {
    if m.slices().all(crate::all_finite) {
        return Ok(());
    }
    let n = m.pattern().dim();
    for j in 0..n {
        for i in 0..n {
            let x = m.get(i, j);
            if !x.is_finite() {
                return Err(SimError::NonFinite {
                    t,
                    what: format!("{what}[({i}, {j})] = {x}"),
                });
            }
        }
    }
    Ok(())
}

/// The state and buffers of a finite-difference Jacobian at (t, q, v):
/// f0 = f(t, q, v) evaluated, `x_pert`, `f_pert`, `f_pert2` scratch.
struct Differences<'a> {
    /// Central differences (steps ε^{1/3}) or forward ones (ε^{1/2}).
    central: bool,
    t: f64,
    q: &'a DVector<f64>,
    v: &'a DVector<f64>,
    f0: &'a DVector<f64>,
    x_pert: &'a mut DVector<f64>,
    f_pert: &'a mut DVector<f64>,
    f_pert2: &'a mut DVector<f64>,
    /// The steps of a group's columns up and down (reused storage).
    steps: &'a mut (Vec<f64>, Vec<f64>),
}

/// `eval(q, q̇, f)` of [`difference_columns`]: f at a perturbed state.
type EvaluateForce<'a> = dyn FnMut(&[f64], &[f64], &mut DVector<f64>) -> Result<(), SimError> + 'a;

/// `store(wrt_v, j, step, f_high, f_low)` of [`difference_columns`].
type StoreColumn<'a> = dyn FnMut(bool, usize, f64, &DVector<f64>, &DVector<f64>) + 'a;

/// The finite-difference columns of ∂f/∂q, then ∂f/∂q̇: the coordinates
/// of each group of `groups` (columns that touch disjoint rows) perturbed
/// together by rel·max(|x|, 1), f evaluated by `eval(q, q̇, f)`; for each
/// column j `store(wrt_v, j, step, f_high, f_low)` with the exactly
/// representable step (the sum of both for central differences), the one
/// difference loop of the dense and the block paths.
fn difference_columns(
    d: Differences<'_>,
    groups: &[Vec<usize>],
    st: &mut IntegrationStats,
    eval: &mut EvaluateForce<'_>,
    store: &mut StoreColumn<'_>,
) -> Result<(), SimError> {
    let Differences {
        central,
        t,
        q,
        v,
        f0,
        x_pert,
        f_pert,
        f_pert2,
        steps,
    } = d;
    let rel = if central {
        f64::EPSILON.cbrt()
    } else {
        f64::EPSILON.sqrt()
    };
    let (steps_p, steps_m) = (&mut steps.0, &mut steps.1);
    // Columns with respect to q (wrt_v = false) and q̇ (wrt_v = true).
    for wrt_v in [false, true] {
        let base = if wrt_v { v } else { q };
        x_pert.copy_from(base);
        for group in groups {
            steps_p.clear();
            for &j in group {
                let xj = x_pert[j];
                x_pert[j] = xj + rel * xj.abs().max(1.0);
                steps_p.push(x_pert[j] - xj); // exactly representable increment
            }
            st.dynamics_evaluations += 1;
            if wrt_v {
                eval(q.as_slice(), x_pert.as_slice(), f_pert)?;
            } else {
                eval(x_pert.as_slice(), v.as_slice(), f_pert)?;
            }
            check_finite(t, "force f (Jacobian difference)", f_pert.as_slice())?;
            if central {
                steps_m.clear();
                for &j in group {
                    let xj = base[j];
                    x_pert[j] = xj - rel * xj.abs().max(1.0);
                    steps_m.push(xj - x_pert[j]);
                }
                st.dynamics_evaluations += 1;
                if wrt_v {
                    eval(q.as_slice(), x_pert.as_slice(), f_pert2)?;
                } else {
                    eval(x_pert.as_slice(), v.as_slice(), f_pert2)?;
                }
                check_finite(t, "force f (Jacobian difference)", f_pert2.as_slice())?;
                for ((&j, dp), dm) in group.iter().zip(steps_p.iter()).zip(steps_m.iter()) {
                    store(wrt_v, j, dp + dm, f_pert, f_pert2);
                }
            } else {
                for (&j, dp) in group.iter().zip(steps_p.iter()) {
                    store(wrt_v, j, *dp, f_pert, f0);
                }
            }
            for &j in group {
                x_pert[j] = base[j];
            }
        }
    }
    Ok(())
}

/// Workspaces sized for one system (n coordinates, nc constraints).
#[derive(Debug)]
struct Work {
    n: usize,
    nc: usize,
    // Current evaluation.
    mass: DMatrix<f64>,
    force: DVector<f64>,
    gval: DVector<f64>,
    gjac: DMatrix<f64>,
    // Jacobian snapshot for the iteration matrix.
    mass_j: DMatrix<f64>,
    dfdq: DMatrix<f64>,
    dfdv: DMatrix<f64>,
    gjac_j: DMatrix<f64>,
    f0: DVector<f64>,
    f_pert: DVector<f64>,
    f_pert2: DVector<f64>,
    mass_pert: DMatrix<f64>,
    x_pert: DVector<f64>,
    /// The finite-difference column groups of the dense path: every
    /// coordinate alone (the block path's are [`BlockWork::groups`]).
    dense_groups: Vec<Vec<usize>>,
    /// The steps of a group's columns in [`difference_columns`].
    difference_steps: (Vec<f64>, Vec<f64>),
    analytic_ok: bool,
    /// Coordinates that appear in the constraints (a nonzero column of G at
    /// any Jacobian evaluation so far): their velocities are index-2
    /// variables of the index-3 system.
    constrained: Vec<bool>,
    // Linear algebra.
    lu: DenseLu,
    /// LU workspace of the acceleration-level (KKT) system.
    lu_kkt: DenseLu,
    /// Rows of M that are entirely zero (first-order states).
    massless: Vec<usize>,
    /// Per coordinate: a first-order state (zero row of M). Its "velocity" is
    /// the derivative the formula computes, not a state of its own, and stays
    /// out of the error test: the Newton error δz would show in it as δz/β.
    first_order: Vec<bool>,
    gamma: DVector<f64>,
    gp: DVector<f64>,
    rhs: DVector<f64>,
    gtl: DVector<f64>,
    // History, index 0 = most recent accepted point.
    ht: [f64; 4],
    hq: [DVector<f64>; 4],
    hv: [DVector<f64>; 4],
    ha: [DVector<f64>; 4],
    hlen: usize,
    /// Accepted multipliers.
    lambda: DVector<f64>,
    /// Iterates / new point.
    lam: DVector<f64>,
    q: DVector<f64>,
    v: DVector<f64>,
    a: DVector<f64>,
    qhat: DVector<f64>,
    vhat: DVector<f64>,
    qp: DVector<f64>,
    vp: DVector<f64>,
    wq: DVector<f64>,
    /// Derivative-formula weights c₀..c₃ and predictor weights.
    c: [f64; 4],
    /// The block matrices and factorizations ([`LinearSolver::Block`]); the
    /// dense matrices `mass` … `mass_pert`, `lu`, `lu_kkt` are then empty.
    block: Option<BlockWork>,
}

impl Work {
    fn new(n: usize, nc: usize, pattern: Option<&Arc<BlockPattern>>) -> Self {
        let v = || DVector::zeros(n);
        // Dense matrices only without a block pattern.
        let nd = if pattern.is_some() { 0 } else { n };
        let sq = || DMatrix::zeros(nd, nd);
        Self {
            block: pattern.map(BlockWork::new),
            n,
            nc,
            mass: sq(),
            force: v(),
            gval: DVector::zeros(nc),
            gjac: DMatrix::zeros(nc, n),
            mass_j: sq(),
            dfdq: sq(),
            dfdv: sq(),
            gjac_j: DMatrix::zeros(nc, n),
            f0: v(),
            f_pert: v(),
            f_pert2: v(),
            mass_pert: sq(),
            x_pert: v(),
            dense_groups: (0..nd).map(|j| vec![j]).collect(),
            difference_steps: (Vec::with_capacity(n), Vec::with_capacity(n)),
            analytic_ok: true,
            constrained: vec![false; n],
            lu: DenseLu::new(nd + nc),
            lu_kkt: DenseLu::new(nd + nc),
            massless: Vec::new(),
            first_order: vec![false; n],
            gamma: DVector::zeros(nc),
            gp: DVector::zeros(nc),
            rhs: DVector::zeros(n + nc),
            gtl: v(),
            ht: [0.0; 4],
            hq: [v(), v(), v(), v()],
            hv: [v(), v(), v(), v()],
            ha: [v(), v(), v(), v()],
            hlen: 0,
            lambda: DVector::zeros(nc),
            lam: DVector::zeros(nc),
            q: v(),
            v: v(),
            a: v(),
            qhat: v(),
            vhat: v(),
            qp: v(),
            vp: v(),
            wq: v(),
            c: [0.0; 4],
        }
    }

    /// Evaluates M and f at (t, q, v) into `mass`, `force`, checking both.
    fn eval_dynamics<S: MechanicalSystem + ?Sized>(
        &mut self,
        system: &mut S,
        t: f64,
        st: &mut IntegrationStats,
    ) -> Result<(), SimError> {
        st.dynamics_evaluations += 1;
        if let Some(b) = &mut self.block {
            system.dynamics_blocks(
                t,
                self.q.as_slice(),
                self.v.as_slice(),
                &mut b.mass,
                &mut self.force,
            )?;
            check_finite_blocks(t, "mass matrix M", &b.mass)?;
            return check_finite(t, "force f", self.force.as_slice());
        }
        system.dynamics(
            t,
            self.q.as_slice(),
            self.v.as_slice(),
            &mut self.mass,
            &mut self.force,
        )?;
        check_finite(t, "mass matrix M", self.mass.as_slice())?;
        check_finite(t, "force f", self.force.as_slice())
    }

    /// Evaluates g and G at (t, q) into `gval`, `gjac`, checking both.
    fn eval_constraints<S: MechanicalSystem + ?Sized>(
        &mut self,
        system: &mut S,
        t: f64,
        q: &DVector<f64>,
    ) -> Result<(), SimError> {
        system.constraints(t, q.as_slice(), &mut self.gval, &mut self.gjac)?;
        check_finite(t, "constraint residual g", self.gval.as_slice())?;
        check_finite(t, "constraint Jacobian G", self.gjac.as_slice())
    }

    /// Accelerations and multipliers consistent with the constraints at
    /// (t, q, v): solves `M a − Gᵀλ = f`, `G a = −γ` (γ by a central second
    /// difference of g along the motion). Result in `a` and `lam`.
    fn consistent_acceleration<S: MechanicalSystem + ?Sized>(
        &mut self,
        system: &mut S,
        t: f64,
        st: &mut IntegrationStats,
    ) -> Result<(), SimError> {
        let (n, nc) = (self.n, self.nc);
        self.eval_dynamics(system, t, st)?;
        if nc > 0 {
            // φ(s) = g(q + s v, t + s); φ''(0) = γ. Step in time units chosen
            // so that s·|v| stays ~1e-4 of the coordinate scale; the central
            // difference is then accurate to O(s²) with rounding O(ε/s²)·|g|.
            let qn = self.q.amax().max(1.0);
            let vn = self.v.amax().max(1e-12);
            let s = (1e-4 * qn / vn).min(1e-3);
            for (sign, out) in [(1.0, &mut self.gp), (-1.0, &mut self.gamma)] {
                self.x_pert.copy_from(&self.q);
                self.x_pert.axpy(sign * s, &self.v, 1.0);
                system.constraints(
                    t + sign * s,
                    self.x_pert.as_slice(),
                    &mut self.gval,
                    &mut self.gjac,
                )?;
                check_finite(t, "constraint residual g", self.gval.as_slice())?;
                out.copy_from(&self.gval);
            }
            system.constraints(t, self.q.as_slice(), &mut self.gval, &mut self.gjac)?;
            check_finite(t, "constraint residual g", self.gval.as_slice())?;
            check_finite(t, "constraint Jacobian G", self.gjac.as_slice())?;
            for k in 0..nc {
                self.gamma[k] = (self.gp[k] - 2.0 * self.gval[k] + self.gamma[k]) / (s * s);
            }
        }
        if let Some(b) = &mut self.block {
            // No constraints (a block pattern is used only without): M a = f
            // by the bordered LU of M, its own workspace.
            b.scratch.copy_from(&b.mass);
            self.massless.clear();
            for i in 0..n {
                let first_order = system.is_first_order(i);
                self.first_order[i] = first_order;
                if first_order {
                    self.massless.push(i);
                    b.scratch.add(i, i, 1.0);
                }
            }
            if b.lu_mass.factorize(&b.scratch).is_err() {
                return Err(SimError::Diverged {
                    t,
                    reason: "cannot solve for the accelerations: mass matrix singular".into(),
                });
            }
            self.a.copy_from(&self.force);
            for &i in &self.massless {
                self.a[i] = 0.0;
            }
            b.lu_mass.solve_vector(&mut self.a);
            return check_finite(t, "acceleration q̈", self.a.as_slice());
        }
        // KKT system [[M, −Gᵀ], [G, 0]] (a, λ) = (f, −γ), in its own LU
        // workspace so the iteration matrix survives.
        let m = self.lu_kkt.matrix_mut();
        for j in 0..n {
            for i in 0..n {
                m[(i, j)] = self.mass[(i, j)];
            }
        }
        // Rows of first-order states (`MechanicalSystem::is_first_order`):
        // no inertia, their second derivative does not enter the equations;
        // take it as zero. Any other zero row stays singular (and is refused).
        self.massless.clear();
        for i in 0..n {
            let first_order = system.is_first_order(i);
            self.first_order[i] = first_order;
            if first_order {
                self.massless.push(i);
                m[(i, i)] = 1.0;
            }
        }
        for k in 0..nc {
            for j in 0..n {
                let gkj = self.gjac[(k, j)];
                m[(n + k, j)] = gkj;
                m[(j, n + k)] = -gkj;
            }
            for l in 0..nc {
                m[(n + k, n + l)] = 0.0;
            }
        }
        if self.lu_kkt.factorize().is_err() {
            return Err(SimError::Diverged {
                t,
                reason: "cannot solve for the accelerations: mass matrix singular or constraint \
                         Jacobian G rank-deficient"
                    .into(),
            });
        }
        self.rhs.rows_mut(0, n).copy_from(&self.force);
        for &i in &self.massless {
            self.rhs[i] = 0.0;
        }
        for k in 0..nc {
            self.rhs[n + k] = -self.gamma[k];
        }
        self.lu_kkt.solve_in_place(&mut self.rhs);
        self.a.copy_from(&self.rhs.rows(0, n));
        self.lam.copy_from(&self.rhs.rows(n, nc));
        check_finite(t, "acceleration q̈", self.a.as_slice())?;
        check_finite(t, "multiplier λ", self.lam.as_slice())
    }

    /// Projects q onto g(q, t) = 0 and v onto G v + ∂g/∂t = 0 (minimum-norm
    /// corrections).
    fn project_initial<S: MechanicalSystem + ?Sized>(
        &mut self,
        system: &mut S,
        t: f64,
    ) -> Result<(), SimError> {
        let nc = self.nc;
        let solve_ggt =
            |gjac: &DMatrix<f64>, rhs: &DVector<f64>| -> Result<DVector<f64>, SimError> {
                let ggt = gjac * gjac.transpose();
                match Cholesky::new(ggt) {
                    Some(ch) => Ok(ch.solve(rhs)),
                    None => Err(SimError::Other(format!(
                        "constraint Jacobian G has linearly dependent rows at t = {t} s \
                     (redundant constraints): cannot make the initial state consistent"
                    ))),
                }
            };
        let mut converged = false;
        for _ in 0..50 {
            let q = self.q.clone();
            self.eval_constraints(system, t, &q)?;
            let y = solve_ggt(&self.gjac, &self.gval)?;
            let dq = self.gjac.transpose() * y;
            self.q -= &dq;
            check_finite(t, "projected initial coordinate q0", self.q.as_slice())?;
            if dq.amax() <= 1e-13 * self.q.amax().max(1.0) {
                converged = true;
                break;
            }
        }
        let q = self.q.clone();
        self.eval_constraints(system, t, &q)?;
        if !converged {
            return Err(SimError::Other(format!(
                "initial coordinates could not be projected onto the constraints g(q, t0) = 0 \
                 (|g| = {:e} after 50 Newton iterations)",
                self.gval.amax()
            )));
        }
        // ∂g/∂t by central differences (zero for scleronomic constraints).
        let dt = f64::EPSILON.cbrt() * t.abs().max(1.0);
        let gjac = self.gjac.clone();
        self.eval_constraints(system, t + dt, &q)?;
        let mut gt = self.gval.clone();
        self.eval_constraints(system, t - dt, &q)?;
        for k in 0..nc {
            gt[k] = (gt[k] - self.gval[k]) / (2.0 * dt);
        }
        let resid = &gjac * &self.v + gt;
        let y = solve_ggt(&gjac, &resid)?;
        self.v -= gjac.transpose() * y;
        check_finite(t, "projected initial velocity v0", self.v.as_slice())?;
        // Leave g, G of the final q in the workspace.
        self.eval_constraints(system, t, &q)?;
        mark_constrained(&self.gjac, &mut self.constrained);
        Ok(())
    }

    /// Evaluates M, ∂f/∂q, ∂f/∂q̇ and G at (t, q, v) into the snapshot.
    fn evaluate_jacobian<S: MechanicalSystem + ?Sized>(
        &mut self,
        system: &mut S,
        kind: JacobianKind,
        t: f64,
        st: &mut IntegrationStats,
    ) -> Result<(), SimError> {
        let n = self.n;
        st.jacobian_evaluations += 1;
        st.dynamics_evaluations += 1;
        if self.block.is_some() {
            return self.evaluate_jacobian_blocks(system, kind, t, st);
        }
        system.dynamics(
            t,
            self.q.as_slice(),
            self.v.as_slice(),
            &mut self.mass_j,
            &mut self.f0,
        )?;
        check_finite(t, "mass matrix M", self.mass_j.as_slice())?;
        check_finite(t, "force f", self.f0.as_slice())?;
        if self.nc > 0 {
            system.constraints(t, self.q.as_slice(), &mut self.gval, &mut self.gjac_j)?;
            check_finite(t, "constraint Jacobian G", self.gjac_j.as_slice())?;
            mark_constrained(&self.gjac_j, &mut self.constrained);
        }
        if kind == JacobianKind::Analytic && self.analytic_ok {
            if system.force_jacobian(
                t,
                self.q.as_slice(),
                self.v.as_slice(),
                &mut self.dfdq,
                &mut self.dfdv,
            )? {
                check_finite(t, "Jacobian ∂f/∂q", self.dfdq.as_slice())?;
                return check_finite(t, "Jacobian ∂f/∂q̇", self.dfdv.as_slice());
            }
            self.analytic_ok = false;
        }
        let (dfdq, dfdv, mass_pert) = (&mut self.dfdq, &mut self.dfdv, &mut self.mass_pert);
        difference_columns(
            Differences {
                central: kind == JacobianKind::CentralDifference,
                t,
                q: &self.q,
                v: &self.v,
                f0: &self.f0,
                x_pert: &mut self.x_pert,
                f_pert: &mut self.f_pert,
                f_pert2: &mut self.f_pert2,
                steps: &mut self.difference_steps,
            },
            &self.dense_groups,
            st,
            &mut |q, v, f| system.dynamics(t, q, v, mass_pert, f),
            &mut |wrt_v, j, step, high, low| {
                let out = if wrt_v { &mut *dfdv } else { &mut *dfdq };
                for i in 0..n {
                    out[(i, j)] = (high[i] - low[i]) / step;
                }
            },
        )
    }

    /// [`Work::evaluate_jacobian`] into the block matrices: the same
    /// differences, with the columns of coordinates that touch disjoint rows
    /// ([`BlockPattern::difference_groups`]) from one evaluation, and only
    /// the entries the pattern holds (the others are zero by the structure).
    fn evaluate_jacobian_blocks<S: MechanicalSystem + ?Sized>(
        &mut self,
        system: &mut S,
        kind: JacobianKind,
        t: f64,
        st: &mut IntegrationStats,
    ) -> Result<(), SimError> {
        let Some(b) = self.block.as_mut() else {
            return Ok(());
        };
        system.dynamics_blocks(
            t,
            self.q.as_slice(),
            self.v.as_slice(),
            &mut b.mass_j,
            &mut self.f0,
        )?;
        check_finite_blocks(t, "mass matrix M", &b.mass_j)?;
        check_finite(t, "force f", self.f0.as_slice())?;
        if kind == JacobianKind::Analytic && self.analytic_ok {
            if system.force_jacobian_blocks(
                t,
                self.q.as_slice(),
                self.v.as_slice(),
                &mut b.dfdq,
                &mut b.dfdv,
            )? {
                check_finite_blocks(t, "Jacobian ∂f/∂q", &b.dfdq)?;
                return check_finite_blocks(t, "Jacobian ∂f/∂q̇", &b.dfdv);
            }
            self.analytic_ok = false;
        }
        b.dfdq.fill_zero();
        b.dfdv.fill_zero();
        // Columns by groups of the pattern (coordinates whose columns touch
        // disjoint rows, perturbed together): a train's vehicles are
        // differentiated at once, the border coordinates one by one; only
        // the entries the pattern holds are stored.
        let (dfdq, dfdv, mass_pert, pattern) =
            (&mut b.dfdq, &mut b.dfdv, &mut b.mass_pert, &b.pattern);
        difference_columns(
            Differences {
                central: kind == JacobianKind::CentralDifference,
                t,
                q: &self.q,
                v: &self.v,
                f0: &self.f0,
                x_pert: &mut self.x_pert,
                f_pert: &mut self.f_pert,
                f_pert2: &mut self.f_pert2,
                steps: &mut self.difference_steps,
            },
            &b.groups,
            st,
            &mut |q, v, f| system.dynamics_blocks(t, q, v, mass_pert, f),
            &mut |wrt_v, j, step, high, low| {
                let out = if wrt_v { &mut *dfdv } else { &mut *dfdq };
                for i in pattern.column_rows(j) {
                    out.add(i, j, (high[i] - low[i]) / step);
                }
            },
        )
    }

    /// Forms and factorizes the iteration matrix for `beta`. Returns `false`
    /// when it is singular.
    fn factor_iteration_matrix(&mut self, beta: f64, st: &mut IntegrationStats) -> bool {
        if let Some(b) = &mut self.block {
            b.scratch
                .set_iteration_matrix(&b.mass_j, &b.dfdv, &b.dfdq, beta);
            st.lu_factorizations += 1;
            return b.lu.factorize(&b.scratch).is_ok();
        }
        let (n, nc) = (self.n, self.nc);
        let b2 = beta * beta;
        let m = self.lu.matrix_mut();
        // Column by column on slices (no index checks): m = M − β D − β² C.
        let mass = self.mass_j.as_slice().chunks_exact(n.max(1));
        let dv = self.dfdv.as_slice().chunks_exact(n.max(1));
        let dq = self.dfdq.as_slice().chunks_exact(n.max(1));
        let cols = m.as_mut_slice().chunks_exact_mut(n + nc);
        for (((col, mj), dvj), dqj) in cols.zip(mass).zip(dv).zip(dq) {
            for (((x, &a), &d), &c) in col[..n].iter_mut().zip(mj).zip(dvj).zip(dqj) {
                *x = a - beta * d - b2 * c;
            }
        }
        for k in 0..nc {
            for j in 0..n {
                let gkj = self.gjac_j[(k, j)];
                m[(n + k, j)] = gkj;
                m[(j, n + k)] = -gkj;
            }
            for l in 0..nc {
                m[(n + k, n + l)] = 0.0;
            }
        }
        st.lu_factorizations += 1;
        self.lu.factorize().is_ok()
    }

    /// Derivative weights of the step to `t_new` (into `c`), β, order and the
    /// error-estimate ratio; also the predictor (into `qp`, `vp`) and the
    /// history terms q̂, v̂.
    fn prepare_step(&mut self, t_new: f64) -> StepCoefficients {
        let k = self.hlen.min(3);
        let s1 = t_new - self.ht[0];
        let mut c = [0.0; 4];
        let (order, cm) = match k {
            1 => {
                bdf_weights(&[s1], &mut c[..2]);
                (1, s1)
            }
            2 => {
                let s2 = t_new - self.ht[1];
                bdf_weights(&[s1, s2], &mut c[..3]);
                (2, s1 * s2)
            }
            _ => {
                let s2 = t_new - self.ht[1];
                let s3 = t_new - self.ht[2];
                let mut c2 = [0.0; 3];
                bdf_weights(&[s1, s2], &mut c2);
                bdf_weights(&[s1, s2, s3], &mut c);
                for i in 0..3 {
                    c[i] = 0.5 * (c[i] + c2[i]);
                }
                c[3] *= 0.5;
                // Park's truncation error is half of BDF2's.
                (2, 0.5 * s1 * s2)
            }
        };
        self.c = c;
        let beta = 1.0 / c[0];
        // History terms: v₊ = c₀q₊ + Σ cᵢ qᵢ₋₁ = (q₊ − q̂)/β.
        self.qhat.fill(0.0);
        self.vhat.fill(0.0);
        for (i, ci) in c.iter().enumerate().take(k + 1).skip(1) {
            self.qhat.axpy(-beta * ci, &self.hq[i - 1], 1.0);
            self.vhat.axpy(-beta * ci, &self.hv[i - 1], 1.0);
        }
        // Predictor of degree `order` and its error factor P.
        let p = match k {
            1 => {
                // Taylor (Hermite at the initial point): y₀ + s y₀'.
                self.qp.copy_from(&self.hq[0]);
                self.qp.axpy(s1, &self.hv[0], 1.0);
                self.vp.copy_from(&self.hv[0]);
                self.vp.axpy(s1, &self.ha[0], 1.0);
                s1 * s1
            }
            2 => {
                // Quadratic through y_old, y_rec with derivative at the old
                // (initial) point: p = y_old + y'_old x + (y[old,rec] − y'_old) x²/Δ.
                let d = self.ht[0] - self.ht[1];
                let x = t_new - self.ht[1];
                let w_old = 1.0 - x * x / (d * d);
                let w_rec = x * x / (d * d);
                let w_der = x - x * x / d;
                self.qp.copy_from(&self.hq[1]);
                self.qp.scale_mut(w_old);
                self.qp.axpy(w_rec, &self.hq[0], 1.0);
                self.qp.axpy(w_der, &self.hv[1], 1.0);
                self.vp.copy_from(&self.hv[1]);
                self.vp.scale_mut(w_old);
                self.vp.axpy(w_rec, &self.hv[0], 1.0);
                self.vp.axpy(w_der, &self.ha[1], 1.0);
                x * x * s1
            }
            _ => {
                // Lagrange extrapolation through the last three points.
                let tt = [self.ht[0], self.ht[1], self.ht[2]];
                let mut e = [0.0; 3];
                for j in 0..3 {
                    let mut w = 1.0;
                    for m in 0..3 {
                        if m != j {
                            w *= (t_new - tt[m]) / (tt[j] - tt[m]);
                        }
                    }
                    e[j] = w;
                }
                self.qp.fill(0.0);
                self.vp.fill(0.0);
                for (j, ej) in e.iter().enumerate() {
                    self.qp.axpy(*ej, &self.hq[j], 1.0);
                    self.vp.axpy(*ej, &self.hv[j], 1.0);
                }
                (t_new - tt[0]) * (t_new - tt[1]) * (t_new - tt[2])
            }
        };
        let bc = beta * cm;
        StepCoefficients {
            beta,
            order,
            lte_ratio: bc / (bc + p),
        }
    }

    /// Sets v = (q − q̂)/β and a = (v − v̂)/β from the current q.
    fn derivatives_from_q(&mut self, beta: f64) {
        let inv = 1.0 / beta;
        for i in 0..self.n {
            self.v[i] = (self.q[i] - self.qhat[i]) * inv;
            self.a[i] = (self.v[i] - self.vhat[i]) * inv;
        }
    }

    /// Modified Newton iterations for q₊ and λ starting from `q`, `lam`.
    #[allow(clippy::too_many_arguments)]
    fn newton<S: MechanicalSystem + ?Sized>(
        &mut self,
        system: &mut S,
        t: f64,
        beta: f64,
        kappa: f64,
        max_iter: usize,
        eta: &mut f64,
        st: &mut IntegrationStats,
    ) -> Result<Newton, SimError> {
        let (n, nc) = (self.n, self.nc);
        let b2 = beta * beta;
        let mut norm_prev = 0.0;
        let mut theta_max: f64 = 0.0;
        for it in 0..max_iter {
            self.derivatives_from_q(beta);
            st.newton_iterations += 1;
            self.eval_dynamics(system, t, st)?;
            if nc > 0 {
                system.constraints(t, self.q.as_slice(), &mut self.gval, &mut self.gjac)?;
                check_finite(t, "constraint residual g", self.gval.as_slice())?;
                check_finite(t, "constraint Jacobian G", self.gjac.as_slice())?;
            }
            // rhs = [−β² (M a − f − Gᵀλ); −g]
            if let Some(b) = &mut self.block {
                // No constraints with a block pattern.
                let top = &mut self.rhs.as_mut_slice()[..n];
                b.mass.mul_to(self.a.as_slice(), top);
                for (r, f) in top.iter_mut().zip(self.force.iter()) {
                    *r = -b2 * (*r - f);
                }
                b.lu.solve_in_place(top);
            } else {
                let mut top = self.rhs.rows_mut(0, n);
                top.gemv(1.0, &self.mass, &self.a, 0.0);
                top -= &self.force;
                if nc > 0 {
                    top.gemv_tr(-1.0, &self.gjac, &self.lam, 1.0);
                }
                top *= -b2;
                for k in 0..nc {
                    self.rhs[n + k] = -self.gval[k];
                }
                self.lu.solve_in_place(&mut self.rhs);
            }
            // Update and measure the correction.
            let mut sum = 0.0;
            let mut at_noise = true;
            for i in 0..n {
                let dq = self.rhs[i];
                self.q[i] += dq;
                let r = dq / self.wq[i];
                sum += r * r;
                if dq.abs() > 1e3 * f64::EPSILON * (self.q[i].abs() + self.wq[i]) {
                    at_noise = false;
                }
            }
            let mut norm = (sum / n as f64).sqrt();
            if nc > 0 {
                for k in 0..nc {
                    self.lam[k] += self.rhs[n + k] / b2;
                }
                // Displacement caused by the multiplier change: (Gᵀ Δμ)ᵢ / Mᵢᵢ.
                self.gtl
                    .gemv_tr(1.0, &self.gjac, &self.rhs.rows(n, nc), 0.0);
                let mut sum_l = 0.0;
                for i in 0..n {
                    let d = self.gtl[i] / self.mass[(i, i)].abs().max(f64::MIN_POSITIVE);
                    let r = d / self.wq[i];
                    sum_l += r * r;
                    if d.abs() > 1e3 * f64::EPSILON * (self.q[i].abs() + self.wq[i]) {
                        at_noise = false;
                    }
                }
                norm = norm.max((sum_l / n as f64).sqrt());
            }
            if !norm.is_finite() {
                return Ok(Newton::Failed("non-finite Newton correction".into()));
            }
            if at_noise {
                self.derivatives_from_q(beta);
                return Ok(Newton::Converged {
                    iterations: it + 1,
                    theta_max,
                });
            }
            if it == 0 {
                if *eta * norm <= kappa {
                    self.derivatives_from_q(beta);
                    return Ok(Newton::Converged {
                        iterations: 1,
                        theta_max,
                    });
                }
            } else {
                let theta = norm / norm_prev;
                theta_max = theta_max.max(theta);
                if theta >= 0.99 {
                    return Ok(Newton::Failed(format!(
                        "Newton iterations diverge (contraction rate {theta:.3})"
                    )));
                }
                *eta = theta / (1.0 - theta);
                if *eta * norm <= kappa {
                    self.derivatives_from_q(beta);
                    return Ok(Newton::Converged {
                        iterations: it + 1,
                        theta_max,
                    });
                }
                let left = (max_iter - 1 - it) as i32;
                if theta.powi(left) / (1.0 - theta) * norm > kappa {
                    return Ok(Newton::Failed(format!(
                        "Newton iterations converge too slowly (contraction rate {theta:.3})"
                    )));
                }
            }
            norm_prev = norm;
        }
        Ok(Newton::Failed(format!(
            "Newton iterations did not converge in {max_iter} iterations"
        )))
    }

    /// Weighted RMS norm of the local error estimate over q and v. Velocities
    /// of constrained coordinates (index-2 variables) enter multiplied by
    /// min(h, 1) as in Hairer & Wanner's RADAU5 (Solving ODEs II, Sect. VII.8):
    /// in an index-3 system the Newton residual error δq shows up in v as δq/β,
    /// and an unscaled test would chase it with ever smaller steps.
    fn error_norm(&self, ratio: f64, rtol: f64, atol: f64, h: f64) -> f64 {
        let mut sum = 0.0;
        let mut terms = 0usize;
        let hs = h.min(1.0);
        for i in 0..self.n {
            let wq = atol + rtol * self.hq[0][i].abs().max(self.q[i].abs());
            let eq = ratio * (self.q[i] - self.qp[i]) / wq;
            if self.first_order[i] {
                sum += eq * eq;
                terms += 1;
                continue;
            }
            terms += 2;
            let mut wv = atol + rtol * self.hv[0][i].abs().max(self.v[i].abs());
            if self.constrained[i] {
                wv /= hs;
            }
            let ev = ratio * (self.v[i] - self.vp[i]) / wv;
            sum += eq * eq + ev * ev;
        }
        (sum / terms.max(1) as f64).sqrt()
    }

    /// Makes the new point (t, q, v, a, λ) the most recent history entry.
    fn push_history(&mut self, t: f64) {
        self.ht.rotate_right(1);
        self.hq.rotate_right(1);
        self.hv.rotate_right(1);
        self.ha.rotate_right(1);
        self.ht[0] = t;
        self.hq[0].copy_from(&self.q);
        self.hv[0].copy_from(&self.v);
        self.ha[0].copy_from(&self.a);
        self.hlen = (self.hlen + 1).min(4);
        self.lambda.copy_from(&self.lam);
    }

    /// Starting step for the BDF1 start (order 1), after Hairer, Nørsett &
    /// Wanner, Solving ODEs I, Sect. II.4 ("starting step size").
    fn initial_step<S: MechanicalSystem + ?Sized>(
        &mut self,
        system: &mut S,
        t0: f64,
        span: f64,
        s: &ParkSettings,
        st: &mut IntegrationStats,
    ) -> Result<f64, SimError> {
        let n = self.n;
        let w = |x: f64| s.atol + s.rtol * x.abs();
        let (mut d0, mut d1) = (0.0, 0.0);
        for i in 0..n {
            let (wq, wv) = (w(self.hq[0][i]), w(self.hv[0][i]));
            d0 += (self.hq[0][i] / wq).powi(2) + (self.hv[0][i] / wv).powi(2);
            d1 += (self.hv[0][i] / wq).powi(2) + (self.ha[0][i] / wv).powi(2);
        }
        let m = (2 * n).max(1) as f64;
        let (d0, d1) = ((d0 / m).sqrt(), (d1 / m).sqrt());
        let mut h0 = if d0 < 1e-5 || d1 < 1e-5 {
            1e-6
        } else {
            0.01 * d0 / d1
        };
        h0 = h0.min(s.max_step).min(span);
        // Explicit Euler trial step and the derivative change over it.
        self.q.copy_from(&self.hq[0]);
        self.q.axpy(h0, &self.hv[0], 1.0);
        self.v.copy_from(&self.hv[0]);
        self.v.axpy(h0, &self.ha[0], 1.0);
        self.consistent_acceleration(system, t0 + h0, st)?;
        let mut d2 = 0.0;
        for i in 0..n {
            let (wq, wv) = (w(self.hq[0][i]), w(self.hv[0][i]));
            d2 += ((self.v[i] - self.hv[0][i]) / wq).powi(2)
                + ((self.a[i] - self.ha[0][i]) / wv).powi(2);
        }
        let d2 = (d2 / m).sqrt() / h0;
        let dm = d1.max(d2);
        let h1 = if dm <= 1e-15 {
            (h0 * 1e-3).max(1e-6)
        } else {
            (0.01 / dm).sqrt()
        };
        self.lam.copy_from(&self.lambda);
        Ok((100.0 * h0).min(h1).min(s.max_step).max(s.min_step))
    }
}

/// Marks the coordinates with a nonzero column in the constraint Jacobian.
fn mark_constrained(gjac: &DMatrix<f64>, constrained: &mut [bool]) {
    for (j, c) in constrained.iter_mut().enumerate() {
        if gjac.column(j).iter().any(|&x| x != 0.0) {
            *c = true;
        }
    }
}

/// Weights cᵢ of the derivative at τ₀ of the polynomial interpolating
/// τ₀ … τ_k, given sⱼ = τ₀ − τⱼ (j = 1..k): `y'(τ₀) ≈ Σ cᵢ y(τᵢ)`.
/// Lagrange basis derivative at the node τ₀:
/// c₀ = Σ 1/sⱼ, cᵢ = Π_{j≠i} sⱼ / Π_{j≠i} (τᵢ − τⱼ) with τᵢ − τ₀ = −sᵢ and
/// τᵢ − τⱼ = sⱼ − sᵢ.
fn bdf_weights(s: &[f64], c: &mut [f64]) {
    let k = s.len();
    c[0] = s.iter().map(|x| 1.0 / x).sum();
    for i in 1..=k {
        let mut num = 1.0;
        let mut den = -s[i - 1];
        for j in 1..=k {
            if j != i {
                num *= s[j - 1];
                den *= s[j - 1] - s[i - 1];
            }
        }
        c[i] = num / den;
    }
}

/// Park's implicit method stepping one system ([`Stepper`]): the system,
/// the settings, the workspaces and the step-size controller's state.
#[derive(Debug)]
pub struct Park<S> {
    system: S,
    settings: ParkSettings,
    work: Work,
    stats: IntegrationStats,
    /// Start time (fixed steps end at t0 + k·h), s.
    t0: f64,
    /// Current time, s.
    t: f64,
    /// Stop time, s.
    t_stop: f64,
    /// Length of the last accepted step, s (0 before the first).
    h_last: f64,
    /// Proposed next step, s; `None` until the first step chooses it.
    h: Option<f64>,
    kappa: f64,
    eta: f64,
    need_jacobian: bool,
    jacobian_fresh: bool,
    /// β of the current factorization (NaN: none usable).
    beta_lu: f64,
    rejected_last: bool,
    /// Consecutive rejections of the current step. After a discontinuity in
    /// the forcing (a kink in the track's curvature, a friction mode
    /// change) the history polynomial spans the jump and its error estimate
    /// no longer falls with the step: restart from the current point with
    /// the one-step BDF1 (the start-up sequence builds the history again).
    consecutive_rejections: usize,
}

impl<S: MechanicalSystem> Park<S> {
    /// A solver for `system` at `(t0, q0, v0)` (s, and the coordinates'
    /// units) with `settings`.
    ///
    /// For constrained systems q0 and v0 are first made consistent (see the
    /// module documentation); the initial accelerations and multipliers are
    /// computed here ([`Stepper::state`] shows them).
    ///
    /// # Errors
    /// [`SimError::Other`] for bad settings or state sizes, or constraints
    /// that cannot be satisfied initially; [`SimError::NonFinite`] with the
    /// time when a NaN or infinity appears in M, f, g, G or the state; and any
    /// error of the system itself. [`Stepper::step`] fails the same way, and
    /// with [`SimError::Diverged`] (time and reason) when the step would fall
    /// below `min_step` (or Newton fails at a fixed step).
    pub fn new(
        mut system: S,
        settings: ParkSettings,
        t0: f64,
        q0: &[f64],
        v0: &[f64],
    ) -> Result<Self, SimError> {
        settings.validate()?;
        let n = system.dof();
        let nc = system.n_constraints();
        check_initial_state(n, t0, q0, v0)?;
        // The block pattern, if asked for and usable (no constraints).
        let pattern = match settings.solver {
            LinearSolver::Block if nc == 0 => system
                .block_pattern()
                .filter(|p| p.dim() == n && !p.blocks().is_empty()),
            _ => None,
        };
        let mut w = Work::new(n, nc, pattern.as_ref());
        let mut st = IntegrationStats::new(t0, n, nc);
        // Consistent initial state, accelerations and multipliers.
        w.q.copy_from_slice(q0);
        w.v.copy_from_slice(v0);
        if nc > 0 {
            w.project_initial(&mut system, t0)?;
        }
        w.consistent_acceleration(&mut system, t0, &mut st)?;
        w.hlen = 0;
        w.push_history(t0);
        let h = settings.initial_step.map(|h| h.min(settings.max_step));
        let mut solver = Self {
            system,
            kappa: settings.newton_kappa(),
            settings,
            work: w,
            stats: st,
            t0,
            t: t0,
            t_stop: f64::INFINITY,
            h_last: 0.0,
            h,
            eta: 1.0,
            need_jacobian: true,
            jacobian_fresh: false,
            beta_lu: f64::NAN,
            rejected_last: false,
            consecutive_rejections: 0,
        };
        solver.record_state();
        Ok(solver)
    }

    /// Whether the linear systems are solved by the bordered block-diagonal
    /// LU of the system's block pattern ([`LinearSolver::Block`] and a
    /// pattern offered), else by the dense LU.
    pub fn uses_block_solver(&self) -> bool {
        self.work.block.is_some()
    }

    /// The settings.
    pub fn settings(&self) -> &ParkSettings {
        &self.settings
    }

    /// Copies the current state into the statistics.
    fn record_state(&mut self) {
        let (w, st) = (&self.work, &mut self.stats);
        st.t = self.t;
        st.q.copy_from(&w.hq[0]);
        st.v.copy_from(&w.hv[0]);
        st.accel.copy_from(&w.ha[0]);
        st.lambda.copy_from(&w.lambda);
    }
}

impl<S: MechanicalSystem> Stepper for Park<S> {
    type System = S;

    fn t(&self) -> f64 {
        self.t
    }

    fn state(&self) -> StepView<'_> {
        let w = &self.work;
        StepView {
            t: self.t,
            h: self.h_last,
            q: w.hq[0].as_slice(),
            v: w.hv[0].as_slice(),
            accel: w.ha[0].as_slice(),
            lambda: w.lambda.as_slice(),
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

    /// One accepted step of Park's method: Newton iterations on the
    /// corrector, the local error test, rejected attempts retried with a
    /// smaller step (or a fresh Jacobian) until one is accepted.
    /// [`MechanicalSystem::accept_step`] is called once with its state.
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

impl<S: MechanicalSystem> Park<S> {
    /// One accepted step, calling `before_accept` with its end state
    /// before [`MechanicalSystem::accept_step`] (see [`Stepper::step_observed`]).
    fn advance(&mut self, before_accept: BeforeAccept<'_, S>) -> Result<StepView<'_>, SimError> {
        let s = &self.settings;
        let (t, t_end, t0) = (self.t, self.t_stop, self.t0);
        if t >= t_end {
            return Err(at_stop_time(t));
        }
        let n = self.work.n;
        let nc = self.work.nc;
        let w = &mut self.work;
        let st = &mut self.stats;
        let system = &mut self.system;
        let mut h = match self.h {
            Some(h) => h,
            None => w.initial_step(system, t0, t_end - t0, s, st)?,
        };
        loop {
            if self.consecutive_rejections >= RESTART_AFTER_REJECTIONS && w.hlen > 1 {
                w.hlen = 1;
                self.consecutive_rejections = 0;
                self.need_jacobian = true;
                self.beta_lu = f64::NAN;
            }
            // Step length, ending exactly at t_end and avoiding a sliver.
            let remaining = t_end - t;
            let (hs, t_new) = if s.fixed_step {
                // Times t0 + k h without accumulated rounding; a last step
                // within 1e-6 h of t_end is merged (no sliver steps: in an
                // index-3 system λ would carry the Newton error divided by h²).
                let tk = t0 + (st.steps + 1) as f64 * h;
                if tk >= t_end - 1e-6 * h {
                    (remaining, t_end)
                } else {
                    (tk - t, tk)
                }
            } else if h * 1.05 >= remaining {
                (remaining, t_end)
            } else if 5.0 * h >= remaining {
                // Approach t_end in n ≤ 5 equal steps: the step shrinks by a
                // factor ≥ 0.8 once, instead of a sudden sliver or halving
                // (in an index-3 system λ reacts to step ratios with O(h)
                // errors).
                let hn = remaining / (remaining / h).ceil();
                (hn, t + hn)
            } else {
                (h, t + h)
            };
            if t_new <= t {
                return Err(SimError::Diverged {
                    t,
                    reason: format!("step size {hs:e} s underflows the time resolution"),
                });
            }

            let coef = w.prepare_step(t_new);
            let beta = coef.beta;
            // Newton start: the predictor; weights from the current point.
            w.q.copy_from(&w.qp);
            w.lam.copy_from(&w.lambda);
            for i in 0..n {
                w.wq[i] = s.atol + s.rtol * w.hq[0][i].abs();
            }
            if self.need_jacobian {
                w.derivatives_from_q(beta);
                w.evaluate_jacobian(system, s.jacobian, t_new, st)?;
                self.need_jacobian = false;
                self.jacobian_fresh = true;
                self.beta_lu = f64::NAN;
            }
            let mut singular = false;
            // (A NaN beta_lu, no usable factorization, also refactorizes.)
            let stale = ((beta / self.beta_lu) - 1.0).abs();
            if stale.is_nan() || stale > REFACTOR_RATIO {
                if w.factor_iteration_matrix(beta, st) {
                    self.beta_lu = beta;
                } else {
                    self.beta_lu = f64::NAN;
                    singular = true;
                }
            }
            self.eta = self.eta.max(f64::EPSILON).powf(0.8);
            let outcome = if singular {
                Newton::Failed("iteration matrix is singular".into())
            } else {
                w.newton(
                    system,
                    t_new,
                    beta,
                    self.kappa,
                    s.max_newton_iterations,
                    &mut self.eta,
                    st,
                )?
            };
            let (iterations, theta_max) = match outcome {
                Newton::Converged {
                    iterations,
                    theta_max,
                } => (iterations, theta_max),
                Newton::Failed(reason) => {
                    st.rejected_steps += 1;
                    st.newton_failures += 1;
                    self.consecutive_rejections += 1;
                    self.eta = 1.0;
                    if !singular && self.beta_lu != beta {
                        // First retry: factorize for the exact β (cheap).
                        self.beta_lu = f64::NAN;
                        continue;
                    }
                    if !self.jacobian_fresh {
                        // Retry the same step with a new Jacobian.
                        self.need_jacobian = true;
                        continue;
                    }
                    if s.fixed_step {
                        return Err(SimError::Diverged {
                            t: t_new,
                            reason: format!("at the fixed step h = {hs:e} s: {reason}"),
                        });
                    }
                    h = hs * NEWTON_FAIL_FACTOR;
                    if h < s.min_step {
                        return Err(SimError::Diverged {
                            t,
                            reason: format!(
                                "step size {h:e} s fell below min_step = {:e} s: {reason}",
                                s.min_step
                            ),
                        });
                    }
                    self.rejected_last = true;
                    continue;
                }
            };
            check_finite(t_new, "coordinate q", w.q.as_slice())?;
            check_finite(t_new, "velocity v", w.v.as_slice())?;
            check_finite(t_new, "acceleration q̈", w.a.as_slice())?;
            check_finite(t_new, "multiplier λ", w.lam.as_slice())?;

            // Local error test.
            let exponent = -1.0 / (coef.order as f64 + 1.0);
            let mut fac = FAC_MAX;
            if !s.fixed_step {
                let err = w.error_norm(coef.lte_ratio, s.rtol, s.atol, hs);
                if !err.is_finite() {
                    return Err(SimError::NonFinite {
                        t: t_new,
                        what: "local error estimate".into(),
                    });
                }
                if err > 1.0 {
                    st.rejected_steps += 1;
                    self.consecutive_rejections += 1;
                    h = hs * (SAFETY * err.powf(exponent)).clamp(FAC_MIN, 1.0);
                    self.rejected_last = true;
                    if h < s.min_step {
                        return Err(SimError::Diverged {
                            t,
                            reason: format!(
                                "step size {h:e} s needed by the local error test \
                                 (error {err:.3e} of tolerance) is below min_step = {:e} s; \
                                 either the solution is singular here, or rtol = {:e} / \
                                 atol = {:e} ask for more than double precision allows \
                                 (velocities follow from position differences over the step, \
                                 so their rounding grows like 1e-16·|q|/h): loosen the \
                                 tolerances (atol ≥ 1e-9 is a safe floor)",
                                s.min_step, s.rtol, s.atol
                            ),
                        });
                    }
                    continue;
                }
                if err > 0.0 {
                    fac = (SAFETY * err.powf(exponent)).clamp(FAC_MIN, FAC_MAX);
                }
            }

            // Accept.
            self.consecutive_rejections = 0;
            w.push_history(t_new);
            if s.consistent_multipliers && nc > 0 {
                // w.q, w.v hold the accepted state; replace the reported
                // (and only reported: ha is used by the start-up predictor
                // alone) accelerations and multipliers.
                w.consistent_acceleration(system, t_new, st)?;
                w.ha[0].copy_from(&w.a);
                w.lambda.copy_from(&w.lam);
            }
            before_accept(
                system,
                StepView {
                    t: t_new,
                    h: hs,
                    q: w.hq[0].as_slice(),
                    v: w.hv[0].as_slice(),
                    accel: w.ha[0].as_slice(),
                    lambda: w.lambda.as_slice(),
                },
            )?;
            st.steps += 1;
            system.accept_step(t_new, w.hq[0].as_slice(), w.hv[0].as_slice())?;
            if iterations >= 6 || theta_max > 0.2 {
                self.need_jacobian = true; // slow convergence: refresh for the next step
            }
            self.jacobian_fresh = false;
            if !s.fixed_step {
                if self.rejected_last {
                    fac = fac.min(1.0);
                }
                self.rejected_last = false;
                h = if (1.0..=HOLD_MAX).contains(&fac) {
                    hs
                } else {
                    hs * fac
                };
                h = h.min(s.max_step).max(s.min_step);
            }
            self.h = Some(h);
            self.t = t_new;
            self.h_last = hs;
            self.record_state();
            return Ok(self.state());
        }
    }
}

/// Integrates with Park's method from `(t0, q0, v0)` to `t_end` (reached
/// exactly), calling `observer` with a [`StepView`] of the initial state and
/// of the end of every accepted step: a loop over [`Park`]'s
/// [`Stepper::step`] (see there and [`Park::new`] for the errors and the
/// constraint handling). `observer` may stop the run with
/// `ControlFlow::Break`; [`MechanicalSystem::accept_step`] is called once per
/// accepted step, before the observer.
pub fn integrate_park_steps<S, F>(
    system: &mut S,
    settings: &ParkSettings,
    t0: f64,
    q0: &[f64],
    v0: &[f64],
    t_end: f64,
    mut observer: F,
) -> Result<IntegrationStats, SimError>
where
    S: MechanicalSystem + ?Sized,
    F: FnMut(&StepView<'_>) -> ControlFlow<()>,
{
    check_end_time(t0, t_end)?;
    let mut solver = Park::new(system, settings.clone(), t0, q0, v0)?;
    solver.set_stop_time(t_end)?;
    loop {
        if observer(&solver.state()).is_break() {
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

/// [`integrate_park_steps`] with an observer of `(t, q, v, q̈)`.
pub fn integrate_park<S, F>(
    system: &mut S,
    settings: &ParkSettings,
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
    integrate_park_steps(system, settings, t0, q0, v0, t_end, |s| {
        observer(s.t, s.q, s.v, s.accel)
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn constant_step_weights_are_parks_formula() {
        // Half-sum of BDF2 and BDF3 at constant h = 0.1: (10, −15, 6, −1)/(6h).
        let h = 0.1;
        let mut c2 = [0.0; 3];
        let mut c3 = [0.0; 4];
        bdf_weights(&[h, 2.0 * h], &mut c2);
        bdf_weights(&[h, 2.0 * h, 3.0 * h], &mut c3);
        let expect = [10.0, -15.0, 6.0, -1.0];
        for i in 0..4 {
            let c = 0.5 * (c3[i] + if i < 3 { c2[i] } else { 0.0 });
            assert!((c * 6.0 * h - expect[i]).abs() < 1e-12, "c{i} = {c}");
        }
        // BDF2: (3, −4, 1)/(2h); BDF1: (1, −1)/h.
        assert!((c2[0] * 2.0 * h - 3.0).abs() < 1e-12);
        assert!((c2[1] * 2.0 * h + 4.0).abs() < 1e-12);
        assert!((c2[2] * 2.0 * h - 1.0).abs() < 1e-12);
    }

    #[test]
    fn variable_weights_differentiate_cubics_exactly() {
        // BDF3 weights on uneven nodes differentiate any cubic exactly at τ₀.
        let t0 = 1.3;
        let nodes = [t0, t0 - 0.07, t0 - 0.2, t0 - 0.26];
        let s = [
            nodes[0] - nodes[1],
            nodes[0] - nodes[2],
            nodes[0] - nodes[3],
        ];
        let mut c = [0.0; 4];
        bdf_weights(&s, &mut c);
        let y = |t: f64| 2.0 - t + 0.5 * t * t - 0.3 * t * t * t;
        let dy = -1.0 + t0 - 0.9 * t0 * t0;
        let approx: f64 = (0..4).map(|i| c[i] * y(nodes[i])).sum();
        assert!((approx - dy).abs() < 1e-10, "{approx} vs {dy}");
    }
}
