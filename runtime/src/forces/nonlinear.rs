//! Nonlinear bipolar elements (Pogorelov 2005, Sect. 3.1): Coulomb friction with
//! sticking and sliding, load-dependent friction (Fig. 3) and tabulated
//! force–deflection characteristics (bump stops).
//!
//! # State and mode switches
//!
//! The friction elements keep a state (mode, stored f0/x0, the deformation of
//! the inner spring) that changes only in [`ForceElement::accept_step`], never
//! during Newton iterations or in rejected steps. Within a step the force is a
//! continuous function of (q, q̇) given that state:
//!
//! * sticking: the elastic law; when its force would exceed the static limit
//!   it is held at the limit (saturated) for the rest of the step, and the
//!   element slides from the next step on;
//! * sliding: the sliding force against the relative velocity, with the sign
//!   function regularized below [`V_REG`]; when the velocity has reversed or
//!   dropped below [`V_STICK`] at the end of an accepted step, the element
//!   sticks again with f0 and x0 stored so that the force is continuous.
//!
//! A mode switch is therefore delayed by at most one step and never smeared
//! over several: the step-size control sees the kink of the saturated law
//! and shortens the steps around it.

use super::bipolar::TwoPoint;
use super::{ForceContext, ForceElement, ForceJacobian, Wrench, eval_scalar};
use crate::system::SimError;

use railmbs_models::{Expr, Interpolation};

/// Velocity below which the sign of the sliding velocity is regularized
/// linearly, m/s.
pub const V_REG: f64 = 1e-5;
/// Sliding speed below which an element sticks again at the end of a step, m/s.
pub const V_STICK: f64 = 1e-4;

/// Regularized sign: v/|v| for |v| ≥ V_REG, v/V_REG below; and its derivative.
pub(crate) fn reg_sign(v: f64) -> (f64, f64) {
    if v.abs() >= V_REG {
        (v.signum(), 0.0)
    } else {
        (v / V_REG, 1.0 / V_REG)
    }
}

// ---------------------------------------------------------------------------
// Coulomb friction
// ---------------------------------------------------------------------------

/// Mode of a friction element (changes only in `accept_step`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum FrictionMode {
    /// No state yet (before the first accepted step): behaves as sliding.
    Initial,
    /// Sticking with the stored force f0 (N) at the stored length x0 (m).
    Stick {
        /// Force when sticking began, N.
        f0: f64,
        /// Length when sticking began, m.
        x0: f64,
    },
    /// Sliding; `dir` is the sign of ẋ when the mode was entered or last
    /// confirmed; `established` once the sliding speed has reached
    /// [`V_STICK`].
    Slide {
        /// Sign of ẋ (±1) when the mode was entered or last confirmed.
        dir: f64,
        /// Whether the sliding speed has reached [`V_STICK`].
        established: bool,
    },
}

/// Bipolar Coulomb friction: sticking F = f0 + c (x − x0) + d ẋ (f0, x0
/// stored when sticking begins) while |F| ≤ F0 (the static limit); sliding
/// F = F_s sign(ẋ) (F_s ≤ F0). Positive F pulls the points together (it
/// resists extension). See the module docs for the mode switches.
#[derive(Debug, Clone)]
pub struct CoulombFriction {
    name: String,
    pair: TwoPoint,
    exprs: [Expr; 4],
    /// N/m.
    pub stiffness: f64,
    /// N s/m.
    pub damping: f64,
    /// Static limit F0, N.
    pub static_limit: f64,
    /// Sliding force F_s, N.
    pub sliding_force: f64,
    /// Current mode.
    pub mode: FrictionMode,
}

/// How a friction force was obtained (for the Jacobian and the next mode).
#[derive(Debug, Clone, Copy, PartialEq)]
enum Branch {
    Stick,
    /// Stick law beyond the limit, held at the limit (sign of the trial force).
    Saturated(f64),
    Slide,
}

impl CoulombFriction {
    /// From the model's `Coulomb` spec (`railmbs_models::forces::Coulomb`).
    pub fn new(name: String, spec: &railmbs_models::forces::Coulomb) -> Self {
        let railmbs_models::forces::Coulomb {
            ends,
            stiffness,
            damping,
            static_limit,
            sliding_force,
        } = spec;
        Self {
            name,
            pair: TwoPoint::new(ends),
            exprs: [
                stiffness.clone(),
                damping.clone(),
                static_limit.clone(),
                sliding_force.clone(),
            ],
            stiffness: 0.0,
            damping: 0.0,
            static_limit: 0.0,
            sliding_force: 0.0,
            mode: FrictionMode::Initial,
        }
    }

    /// Tension (N), ∂F/∂x, ∂F/∂ẋ and the branch at length x, rate v.
    fn law(&self, x: f64, v: f64) -> (f64, f64, f64, Branch) {
        match self.mode {
            FrictionMode::Stick { f0, x0 } => {
                let f = f0 + self.stiffness * (x - x0) + self.damping * v;
                if f.abs() <= self.static_limit {
                    (f, self.stiffness, self.damping, Branch::Stick)
                } else {
                    let s = f.signum();
                    (s * self.static_limit, 0.0, 0.0, Branch::Saturated(s))
                }
            }
            FrictionMode::Slide { .. } | FrictionMode::Initial => {
                let (s, ds) = reg_sign(v);
                (
                    self.sliding_force * s,
                    0.0,
                    self.sliding_force * ds,
                    Branch::Slide,
                )
            }
        }
    }
}

impl ForceElement for CoulombFriction {
    fn name(&self) -> &str {
        &self.name
    }

    fn set_parameters(&mut self, params: &[f64]) -> Result<(), SimError> {
        self.pair.set_parameters(params, &self.name)?;
        let [c, d, f0, fs] = &self.exprs;
        self.stiffness = eval_scalar(c, params, &self.name, "stiffness c")?;
        self.damping = eval_scalar(d, params, &self.name, "damping d")?;
        self.static_limit = eval_scalar(f0, params, &self.name, "static limit")?;
        self.sliding_force = eval_scalar(fs, params, &self.name, "sliding force")?;
        if self.stiffness <= 0.0 || self.damping < 0.0 {
            return Err(SimError::Other(format!(
                "force element \"{}\": needs c > 0 and d ≥ 0, got c = {}, d = {}",
                self.name, self.stiffness, self.damping
            )));
        }
        if !(0.0 <= self.sliding_force && self.sliding_force <= self.static_limit) {
            return Err(SimError::Other(format!(
                "force element \"{}\": needs 0 ≤ sliding force ≤ static limit, got {} and {}",
                self.name, self.sliding_force, self.static_limit
            )));
        }
        Ok(())
    }

    fn apply(&self, ctx: &ForceContext, wrenches: &mut [Wrench]) -> Result<(), SimError> {
        let s = self.pair.state(ctx);
        let (f, ..) = self.law(s.length, s.rate);
        self.pair.apply(ctx, &s, f, wrenches);
        Ok(())
    }

    fn output_names(&self) -> Vec<String> {
        ["F[N]", "x[m]", "v[m/s]", "sliding[-]", "E[J]", "P[W]"]
            .iter()
            .map(|s| s.to_string())
            .collect()
    }

    /// Force, length, rate, mode (1 sliding); the elastic energy f_e²/(2c)
    /// of the sticking spring, f_e = f0 + c (x − x0) (J; also beyond the
    /// limit until the breakaway is accepted, 0 sliding), and the dissipated
    /// power F ẋ − f_e ẋ (W): d ẋ² sticking, F_s |ẋ| sliding (F resists
    /// extension, so its power on the bodies is −F ẋ, and d/dt f_e²/(2c) =
    /// f_e ẋ). Held at the static limit within a step, P = (F − f_e) ẋ may be
    /// negative until the breakaway. At a mode change (an accepted step) the
    /// spring's energy is released (breakaway, about F0²/(2c)) or stored (a
    /// new stick carrying the sliding force, F_s²/(2c)); P does not hold
    /// these jumps.
    fn outputs(&self, ctx: &ForceContext, out: &mut Vec<f64>) {
        let s = self.pair.state(ctx);
        let (f, ..) = self.law(s.length, s.rate);
        let f = if s.direction.is_some() { f } else { 0.0 };
        let sliding = matches!(self.mode, FrictionMode::Slide { .. }) as u8 as f64;
        let spring = match self.mode {
            FrictionMode::Stick { f0, x0 } => f0 + self.stiffness * (s.length - x0),
            FrictionMode::Slide { .. } | FrictionMode::Initial => 0.0,
        };
        out.extend([
            f,
            s.length,
            s.rate,
            sliding,
            0.5 * spring * spring / self.stiffness,
            (f - spring) * s.rate,
        ]);
    }

    fn remembers_accepted_steps(&self) -> bool {
        true
    }

    fn accept_step(&mut self, ctx: &ForceContext) -> Result<(), SimError> {
        let s = self.pair.state(ctx);
        let (f, _, _, branch) = self.law(s.length, s.rate);
        self.mode = match (self.mode, branch) {
            (FrictionMode::Stick { .. }, Branch::Saturated(sign)) => FrictionMode::Slide {
                dir: sign,
                established: s.rate.abs() >= V_STICK,
            },
            (FrictionMode::Stick { .. }, _) => self.mode,
            (FrictionMode::Slide { dir, established }, _) => {
                // As for the contacts: after a breakaway only a clear
                // reversal stops the slip until it has reached V_STICK.
                let est = established || s.rate.abs() >= V_STICK;
                let stop = if est {
                    s.rate * dir <= 0.0 || s.rate.abs() < V_STICK
                } else {
                    s.rate * dir < -V_STICK
                };
                if stop {
                    FrictionMode::Stick {
                        f0: f,
                        x0: s.length,
                    }
                } else {
                    FrictionMode::Slide {
                        dir,
                        established: est,
                    }
                }
            }
            (FrictionMode::Initial, _) => {
                if s.rate.abs() < V_STICK {
                    FrictionMode::Stick {
                        f0: f,
                        x0: s.length,
                    }
                } else {
                    FrictionMode::Slide {
                        dir: s.rate.signum(),
                        established: true,
                    }
                }
            }
        };
        Ok(())
    }

    fn add_jacobian(&self, ctx: &ForceContext, jac: &mut ForceJacobian) -> Result<(), SimError> {
        let s = self.pair.state(ctx);
        let (f, fx, fv, _) = self.law(s.length, s.rate);
        self.pair.add_jacobian(&s, f, fx, fv, jac);
        Ok(())
    }
}

// ---------------------------------------------------------------------------
// Load-dependent friction
// ---------------------------------------------------------------------------

/// Load-dependent friction (Pogorelov 2005, Sect. 3.1, Fig. 3): spring c1 in series
/// with a block of spring c2 in parallel with friction μ·|c2·x2| (x2 the
/// block's deformation). With x = distance − x0 and the force
/// F = c1 (x − x2):
///
/// * sticking (x2 stored): F = c1 (x − x2) while |F − c2 x2| ≤ μ0 c2 |x2|;
/// * sliding in direction s (sign of ẋ2): F = c2 x2 (1 + s μ sign x2), so
///   x2 = c1 x / (c1 + a) and F = c1 a x / (c1 + a) with a = c2 (1 + s μ sign x),
///   stiffer when loading than when unloading: a hysteresis loop whose area
///   does not depend on the rate.
///
/// Beyond the static limit within a step the law follows the sliding branch
/// with μ0 (continuous with the sticking line); see the module docs.
#[derive(Debug, Clone)]
pub struct LoadFriction {
    name: String,
    pair: TwoPoint,
    exprs: [Expr; 5],
    /// N/m.
    pub c1: f64,
    /// N/m.
    pub c2: f64,
    /// Static friction coefficient μ0 of the block (dimensionless): the
    /// sticking limit is μ0 c2 |x2|.
    pub mu_static: f64,
    /// Sliding friction coefficient μ of the block (dimensionless).
    pub mu: f64,
    /// m.
    pub free_length: f64,
    /// Stored deformation of the c2 block, m.
    pub x2: f64,
    /// Current mode (`Stick` uses only the mode, not its f0/x0).
    pub mode: FrictionMode,
}

impl LoadFriction {
    /// From the model's `LoadFriction` spec (`railmbs_models::forces::LoadFriction`).
    pub fn new(name: String, spec: &railmbs_models::forces::LoadFriction) -> Self {
        let railmbs_models::forces::LoadFriction {
            ends,
            c1,
            c2,
            mu_static,
            mu,
            free_length,
        } = spec;
        Self {
            name,
            pair: TwoPoint::new(ends),
            exprs: [
                c1.clone(),
                c2.clone(),
                mu_static.clone(),
                mu.clone(),
                free_length.clone(),
            ],
            c1: 0.0,
            c2: 0.0,
            mu_static: 0.0,
            mu: 0.0,
            free_length: 0.0,
            x2: 0.0,
            // Unloaded block: no friction capacity, so the first motion
            // slides (see `law` and `accept_step`).
            mode: FrictionMode::Initial,
        }
    }

    /// x2/x = c1/(c1 + a), a = c2 (1 + s μ sign x), on the sliding branch in
    /// direction `s` with coefficient `mu` (`sx` the sign of x).
    fn branch_ratio(&self, sx: f64, s: f64, mu: f64) -> f64 {
        let a = self.c2 * (1.0 + s * sx * mu);
        self.c1 / (self.c1 + a)
    }

    /// Sliding branch in direction `s` with coefficient `mu`: (F, ∂F/∂x, x2).
    fn sliding(&self, x: f64, s: f64, mu: f64) -> (f64, f64, f64) {
        let sx = if x >= 0.0 { 1.0 } else { -1.0 };
        let a = self.c2 * (1.0 + s * sx * mu);
        let k = self.c1 * a / (self.c1 + a);
        (k * x, k, self.c1 * x / (self.c1 + a))
    }

    /// (F, ∂F/∂x, x2, branch) at deflection x (m) and rate v.
    fn law(&self, x: f64, v: f64) -> (f64, f64, f64, Branch) {
        match self.mode {
            FrictionMode::Slide { dir, .. } => {
                let (f, k, x2) = self.sliding(x, dir, self.mu);
                (f, k, x2, Branch::Slide)
            }
            FrictionMode::Initial => {
                // Never accepted (a static equilibrium): the virgin loading
                // branch, as the first accepted step makes it (unloaded, the
                // block has no friction capacity and slides away from x = 0).
                let sx = if x >= 0.0 { 1.0 } else { -1.0 };
                let (f, k, x2) = self.sliding(x, sx, self.mu);
                (f, k, x2, Branch::Slide)
            }
            FrictionMode::Stick { .. } => {
                let f = self.c1 * (x - self.x2);
                let excess = f - self.c2 * self.x2;
                if excess.abs() <= self.mu_static * self.c2 * self.x2.abs() {
                    (f, self.c1, self.x2, Branch::Stick)
                } else {
                    let s = if excess != 0.0 {
                        excess.signum()
                    } else {
                        v.signum()
                    };
                    let (f, k, x2) = self.sliding(x, s, self.mu_static);
                    (f, k, x2, Branch::Saturated(s))
                }
            }
        }
    }
}

impl ForceElement for LoadFriction {
    fn name(&self) -> &str {
        &self.name
    }

    fn set_parameters(&mut self, params: &[f64]) -> Result<(), SimError> {
        self.pair.set_parameters(params, &self.name)?;
        let [c1, c2, m0, m, x0] = &self.exprs;
        self.c1 = eval_scalar(c1, params, &self.name, "c1")?;
        self.c2 = eval_scalar(c2, params, &self.name, "c2")?;
        self.mu_static = eval_scalar(m0, params, &self.name, "mu0")?;
        self.mu = eval_scalar(m, params, &self.name, "mu")?;
        self.free_length = eval_scalar(x0, params, &self.name, "x0")?;
        if self.c1 <= 0.0 || self.c2 <= 0.0 {
            return Err(SimError::Other(format!(
                "force element \"{}\": needs c1 > 0 and c2 > 0, got {} and {}",
                self.name, self.c1, self.c2
            )));
        }
        if !(0.0 <= self.mu && self.mu <= self.mu_static && self.mu_static < 1.0) {
            return Err(SimError::Other(format!(
                "force element \"{}\": needs 0 ≤ mu ≤ mu0 < 1, got mu = {}, mu0 = {}",
                self.name, self.mu, self.mu_static
            )));
        }
        Ok(())
    }

    fn apply(&self, ctx: &ForceContext, wrenches: &mut [Wrench]) -> Result<(), SimError> {
        let s = self.pair.state(ctx);
        let (f, ..) = self.law(s.length - self.free_length, s.rate);
        self.pair.apply(ctx, &s, f, wrenches);
        Ok(())
    }

    fn output_names(&self) -> Vec<String> {
        ["F[N]", "x[m]", "x2[m]", "sliding[-]", "E[J]", "P[W]"]
            .iter()
            .map(|s| s.to_string())
            .collect()
    }

    /// Force, deflection, the block's deformation x2, mode (1 sliding); the
    /// elastic energy ½ c1 (x − x2)² + ½ c2 x2² of the two springs (J) and
    /// the dissipated power F ẋ − dE/dt (W; F resists extension, so its power
    /// on the bodies is −F ẋ): 0 sticking (x2 held), and on a sliding branch
    /// (x2 = r x, r = c1/(c1 + a)) r ẋ (F − c2 x2) = r μ c2 |x2| |ẋ| while
    /// the block slides the way ẋ goes.
    fn outputs(&self, ctx: &ForceContext, out: &mut Vec<f64>) {
        let s = self.pair.state(ctx);
        let x = s.length - self.free_length;
        let (f, _, x2, branch) = self.law(x, s.rate);
        let f = if s.direction.is_some() { f } else { 0.0 };
        let sliding = matches!(self.mode, FrictionMode::Slide { .. }) as u8 as f64;
        let energy = 0.5 * self.c1 * (x - x2).powi(2) + 0.5 * self.c2 * x2 * x2;
        // ẋ2 on the branch the law took (its direction s and coefficient).
        let sx = if x >= 0.0 { 1.0 } else { -1.0 };
        let x2_rate = match (branch, self.mode) {
            (Branch::Stick, _) => 0.0,
            (Branch::Saturated(sign), _) => self.branch_ratio(sx, sign, self.mu_static) * s.rate,
            (Branch::Slide, FrictionMode::Slide { dir, .. }) => {
                self.branch_ratio(sx, dir, self.mu) * s.rate
            }
            (Branch::Slide, _) => self.branch_ratio(sx, sx, self.mu) * s.rate,
        };
        let power = f * s.rate - self.c1 * (x - x2) * (s.rate - x2_rate) - self.c2 * x2 * x2_rate;
        out.extend([f, x, x2, sliding, energy, power]);
    }

    fn remembers_accepted_steps(&self) -> bool {
        true
    }

    fn accept_step(&mut self, ctx: &ForceContext) -> Result<(), SimError> {
        if self.mode == FrictionMode::Initial {
            // The unloaded block (x2 = 0), sticking with no capacity.
            self.mode = FrictionMode::Stick { f0: 0.0, x0: 0.0 };
        }
        let s = self.pair.state(ctx);
        let (_, _, x2, branch) = self.law(s.length - self.free_length, s.rate);
        self.mode = match (self.mode, branch) {
            (_, Branch::Saturated(sign)) => FrictionMode::Slide {
                dir: sign,
                established: true,
            },
            (FrictionMode::Slide { dir, .. }, _) if s.rate * dir > 0.0 => FrictionMode::Slide {
                dir,
                established: true,
            },
            _ => FrictionMode::Stick { f0: 0.0, x0: 0.0 },
        };
        self.x2 = x2;
        Ok(())
    }

    fn add_jacobian(&self, ctx: &ForceContext, jac: &mut ForceJacobian) -> Result<(), SimError> {
        let s = self.pair.state(ctx);
        let (f, k, ..) = self.law(s.length - self.free_length, s.rate);
        self.pair.add_jacobian(&s, f, k, 0.0, jac);
        Ok(())
    }
}

// ---------------------------------------------------------------------------
// Tabulated characteristic
// ---------------------------------------------------------------------------

/// A force–deflection characteristic f(u) through table rows (deflections
/// increasing), interpolated straight or by a monotone cubic, and extended
/// beyond the end rows with the end slope (a bump stop keeps its end
/// stiffness). Shared by [`Tabulated`] and the nonlinear longitudinal
/// characteristic of couplers.
#[derive(Debug, Clone, Default)]
pub struct Characteristic {
    interpolation: Interpolation,
    /// Deflections, m (increasing).
    deflections: Vec<f64>,
    /// Forces, N.
    forces: Vec<f64>,
    /// Slopes at the rows (N/m) of the cubic interpolation.
    slopes: Vec<f64>,
}

impl Characteristic {
    /// Through the rows `(deflection m, force N)`; at least two rows with
    /// increasing, finite deflections and finite forces, or an error saying
    /// what is wrong.
    pub fn new(rows: &[(f64, f64)], interpolation: Interpolation) -> Result<Self, String> {
        if rows.len() < 2
            || rows.windows(2).any(|w| w[1].0 <= w[0].0)
            || rows.iter().any(|(x, f)| !(x.is_finite() && f.is_finite()))
        {
            return Err(format!(
                "the table needs at least 2 finite rows with increasing deflections, got {rows:?}"
            ));
        }
        let mut c = Self {
            interpolation,
            deflections: rows.iter().map(|r| r.0).collect(),
            forces: rows.iter().map(|r| r.1).collect(),
            slopes: Vec::new(),
        };
        if interpolation == Interpolation::Spline {
            c.monotone_slopes();
        }
        Ok(c)
    }

    /// The rows' deflections (m) and forces (N).
    pub fn rows(&self) -> (&[f64], &[f64]) {
        (&self.deflections, &self.forces)
    }

    /// Value f(u) (N) and slope (N/m) at deflection u (m); zero for an
    /// empty characteristic (`Default`, before any rows are set).
    pub fn eval(&self, u: f64) -> (f64, f64) {
        let xs = &self.deflections;
        let fs = &self.forces;
        if xs.len() < 2 {
            return (0.0, 0.0);
        }
        // Segment k spans xs[k]..xs[k+1]; the end segments extend outwards.
        let k = match xs.partition_point(|&x| x <= u) {
            0 => 0,
            i => (i - 1).min(xs.len() - 2),
        };
        let dx = xs[k + 1] - xs[k];
        let secant = (fs[k + 1] - fs[k]) / dx;
        if self.interpolation == Interpolation::Linear {
            return (fs[k] + secant * (u - xs[k]), secant);
        }
        let n = xs.len();
        // Beyond the end rows: straight on with the end slope.
        if u < xs[0] {
            return (fs[0] + self.slopes[0] * (u - xs[0]), self.slopes[0]);
        }
        if u > xs[n - 1] {
            return (
                fs[n - 1] + self.slopes[n - 1] * (u - xs[n - 1]),
                self.slopes[n - 1],
            );
        }
        // Cubic Hermite on the segment in s = (u − x_k)/Δx.
        let s = (u - xs[k]) / dx;
        let (m0, m1) = (self.slopes[k] * dx, self.slopes[k + 1] * dx);
        let (s2, s3) = (s * s, s * s * s);
        let f = (2.0 * s3 - 3.0 * s2 + 1.0) * fs[k]
            + (s3 - 2.0 * s2 + s) * m0
            + (-2.0 * s3 + 3.0 * s2) * fs[k + 1]
            + (s3 - s2) * m1;
        let df = ((6.0 * s2 - 6.0 * s) * fs[k]
            + (3.0 * s2 - 4.0 * s + 1.0) * m0
            + (-6.0 * s2 + 6.0 * s) * fs[k + 1]
            + (3.0 * s2 - 2.0 * s) * m1)
            / dx;
        (f, df)
    }

    /// The work ∫₀ᵘ f(s) ds (J for N and m): the elastic energy of the
    /// characteristic at deflection u, exact for the straight or cubic pieces
    /// and the linear extensions.
    pub fn energy(&self, u: f64) -> f64 {
        self.integral_to(u) - self.integral_to(0.0)
    }

    /// ∫ f from the first row to u (negative below it).
    fn integral_to(&self, u: f64) -> f64 {
        let (xs, fs) = (&self.deflections, &self.forces);
        let n = xs.len();
        if n < 2 {
            return 0.0;
        }
        let f_at = |x: f64| self.eval(x).0;
        if u <= xs[0] {
            // Linear extension below the first row: trapezoid from u to x₀.
            return -0.5 * (f_at(u) + fs[0]) * (xs[0] - u);
        }
        let mut total = 0.0;
        for k in 0..n - 1 {
            let (x0, x1) = (xs[k], xs[k + 1]);
            if u <= x0 {
                break;
            }
            let dx = x1 - x0;
            let end = u.min(x1);
            let s = (end - x0) / dx;
            total += match self.interpolation {
                Interpolation::Linear => 0.5 * (fs[k] + f_at(end)) * (end - x0),
                Interpolation::Spline => {
                    // ∫₀ˢ of the Hermite basis times Δx.
                    let (m0, m1) = (self.slopes[k] * dx, self.slopes[k + 1] * dx);
                    let (s2, s3, s4) = (s * s, s * s * s, s * s * s * s);
                    dx * ((0.5 * s4 - s3 + s) * fs[k]
                        + (0.25 * s4 - 2.0 / 3.0 * s3 + 0.5 * s2) * m0
                        + (-0.5 * s4 + s3) * fs[k + 1]
                        + (0.25 * s4 - s3 / 3.0) * m1)
                }
            };
        }
        if u > xs[n - 1] {
            // Linear extension above the last row.
            total += 0.5 * (fs[n - 1] + f_at(u)) * (u - xs[n - 1]);
        }
        total
    }

    /// Fritsch–Carlson slopes: the three-point average inside (zero where the
    /// secants change sign or one vanishes), one-sided at the ends, then
    /// limited so that α² + β² ≤ 9 on every segment (α, β the end slopes over
    /// the secant), which keeps each segment monotone.
    fn monotone_slopes(&mut self) {
        let (xs, fs) = (&self.deflections, &self.forces);
        let n = xs.len();
        let secants: Vec<f64> = (0..n - 1)
            .map(|k| (fs[k + 1] - fs[k]) / (xs[k + 1] - xs[k]))
            .collect();
        let mut m = vec![0.0; n];
        m[0] = secants[0];
        m[n - 1] = secants[n - 2];
        for k in 1..n - 1 {
            let (a, b) = (secants[k - 1], secants[k]);
            m[k] = if a * b <= 0.0 { 0.0 } else { 0.5 * (a + b) };
        }
        for k in 0..n - 1 {
            let d = secants[k];
            if d == 0.0 {
                m[k] = 0.0;
                m[k + 1] = 0.0;
                continue;
            }
            let (a, b) = (m[k] / d, m[k + 1] / d);
            let r = a * a + b * b;
            if r > 9.0 {
                let t = 3.0 / r.sqrt();
                m[k] = t * a * d;
                m[k + 1] = t * b * d;
            }
        }
        self.slopes = m;
    }
}

/// Tabulated force–deflection characteristic: F = f(x − x0) + d ẋ with f
/// through the table rows ([`Characteristic`]: straight lines or a monotone
/// cubic between them, extended linearly beyond the first and last rows).
/// Positive F pulls the points together.
#[derive(Debug, Clone)]
pub struct Tabulated {
    name: String,
    pair: TwoPoint,
    table_expr: Vec<(Expr, Expr)>,
    damping_expr: Expr,
    x0_expr: Expr,
    interpolation: Interpolation,
    /// The characteristic f with the current parameters.
    curve: Characteristic,
    /// N s/m.
    pub damping: f64,
    /// m.
    pub free_length: f64,
}

impl Tabulated {
    /// From the model's `Tabulated` spec (`railmbs_models::forces::Tabulated`).
    pub fn new(name: String, spec: &railmbs_models::forces::Tabulated) -> Self {
        let railmbs_models::forces::Tabulated {
            ends,
            table,
            interpolation,
            damping,
            free_length,
        } = spec;
        Self {
            name,
            pair: TwoPoint::new(ends),
            table_expr: table.clone(),
            damping_expr: damping.clone(),
            x0_expr: free_length.clone(),
            interpolation: *interpolation,
            curve: Characteristic::default(),
            damping: 0.0,
            free_length: 0.0,
        }
    }

    /// Table value f(u) (N) and slope (N/m) at deflection u (m).
    pub fn characteristic(&self, u: f64) -> (f64, f64) {
        self.curve.eval(u)
    }
}

impl ForceElement for Tabulated {
    fn name(&self) -> &str {
        &self.name
    }

    fn set_parameters(&mut self, params: &[f64]) -> Result<(), SimError> {
        self.pair.set_parameters(params, &self.name)?;
        let mut rows = Vec::with_capacity(self.table_expr.len());
        for (k, (x, f)) in self.table_expr.iter().enumerate() {
            rows.push((
                eval_scalar(x, params, &self.name, &format!("table[{k}].deflection"))?,
                eval_scalar(f, params, &self.name, &format!("table[{k}].force"))?,
            ));
        }
        self.curve = Characteristic::new(&rows, self.interpolation)
            .map_err(|e| SimError::Other(format!("force element \"{}\": {e}", self.name)))?;
        self.damping = eval_scalar(&self.damping_expr, params, &self.name, "damping d")?;
        self.free_length = eval_scalar(&self.x0_expr, params, &self.name, "free length x0")?;
        Ok(())
    }

    fn apply(&self, ctx: &ForceContext, wrenches: &mut [Wrench]) -> Result<(), SimError> {
        let s = self.pair.state(ctx);
        let (f, _) = self.characteristic(s.length - self.free_length);
        self.pair
            .apply(ctx, &s, f + self.damping * s.rate, wrenches);
        Ok(())
    }

    fn output_names(&self) -> Vec<String> {
        ["F[N]", "x[m]", "v[m/s]", "E[J]", "P[W]"]
            .iter()
            .map(|s| s.to_string())
            .collect()
    }

    /// Force, length, rate; the elastic energy ∫ f (J) and the damper's
    /// dissipated power d ẋ² (W).
    fn outputs(&self, ctx: &ForceContext, out: &mut Vec<f64>) {
        let s = self.pair.state(ctx);
        let u = s.length - self.free_length;
        let (f, _) = self.characteristic(u);
        let f = if s.direction.is_some() {
            f + self.damping * s.rate
        } else {
            0.0
        };
        out.extend([
            f,
            s.length,
            s.rate,
            self.curve.energy(u),
            self.damping * s.rate * s.rate,
        ]);
    }

    fn add_jacobian(&self, ctx: &ForceContext, jac: &mut ForceJacobian) -> Result<(), SimError> {
        let s = self.pair.state(ctx);
        let (f, k) = self.characteristic(s.length - self.free_length);
        self.pair
            .add_jacobian(&s, f + self.damping * s.rate, k, self.damping, jac);
        Ok(())
    }
}
