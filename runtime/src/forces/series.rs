//! Stiffness and damping in series (Pogorelov 2005, Sect. 3.1): a spring c and a
//! damper d connected end to end between two points, with a preload f0 in
//! parallel. The massless node between them gives the element a first-order
//! state, the spring's extension s (m):
//!
//! ```text
//!     F = c s + f0                 (tension, N; positive pulls the points together)
//!     d (ẋ − ṡ) = c s              (the damper carries the spring's force)
//! ```
//!
//! x being the distance of the points. The state equation is written as the
//! residual r = d (ẋ − ṡ) − c s (N) and solved with the equations of motion by
//! the implicit integrator (see [`super::ForceElement::state_count`]). Its
//! time constant is τ = d/c: slow motion (ω τ ≪ 1) sees a damper d, fast
//! motion (ω τ ≫ 1) a spring c. In static equilibrium the damper has relaxed
//! the spring, so the element starts with s = 0 and ṡ = ẋ.

use super::bipolar::{PairState, TwoPoint};
use super::{ForceContext, ForceElement, ForceJacobian, Wrench, eval_scalar};
use crate::system::SimError;
use railmbs_models::Expr;

/// A spring in series with a damper (Maxwell element) plus a parallel preload.
#[derive(Debug, Clone)]
pub struct SeriesSpringDamper {
    name: String,
    pair: TwoPoint,
    exprs: [Expr; 3],
    /// Index of the spring extension s in the system's state vector.
    offset: usize,
    /// N/m.
    pub stiffness: f64,
    /// N s/m.
    pub damping: f64,
    /// N.
    pub preload: f64,
}

impl SeriesSpringDamper {
    /// From the model's `SeriesSpringDamper` spec (`railmbs_models::forces::SeriesSpringDamper`).
    pub fn new(name: String, spec: &railmbs_models::forces::SeriesSpringDamper) -> Self {
        let railmbs_models::forces::SeriesSpringDamper {
            ends,
            stiffness,
            damping,
            preload,
        } = spec;
        Self {
            name,
            pair: TwoPoint::new(ends),
            exprs: [stiffness.clone(), damping.clone(), preload.clone()],
            offset: 0,
            stiffness: 0.0,
            damping: 0.0,
            preload: 0.0,
        }
    }

    /// Spring extension s (m) and its rate (m/s).
    fn spring(&self, ctx: &ForceContext) -> (f64, f64) {
        (ctx.states[self.offset], ctx.state_rates[self.offset])
    }

    /// Tension F (N); zero at zero length (no direction to act along).
    fn force(&self, s: &PairState, extension: f64) -> f64 {
        if s.direction.is_none() {
            return 0.0;
        }
        self.stiffness * extension + self.preload
    }
}

impl ForceElement for SeriesSpringDamper {
    fn name(&self) -> &str {
        &self.name
    }

    fn set_parameters(&mut self, params: &[f64]) -> Result<(), SimError> {
        self.pair.set_parameters(params, &self.name)?;
        let [c, d, f0] = &self.exprs;
        self.stiffness = eval_scalar(c, params, &self.name, "stiffness c")?;
        self.damping = eval_scalar(d, params, &self.name, "damping d")?;
        self.preload = eval_scalar(f0, params, &self.name, "preload f0")?;
        if self.stiffness <= 0.0 || self.damping <= 0.0 {
            return Err(SimError::Other(format!(
                "force element \"{}\": a spring in series with a damper needs c > 0 and d > 0, \
                 got c = {} N/m, d = {} N s/m",
                self.name, self.stiffness, self.damping
            )));
        }
        Ok(())
    }

    fn apply(&self, ctx: &ForceContext, wrenches: &mut [Wrench]) -> Result<(), SimError> {
        let s = self.pair.state(ctx);
        let (extension, _) = self.spring(ctx);
        self.pair
            .apply(ctx, &s, self.force(&s, extension), wrenches);
        Ok(())
    }

    fn output_names(&self) -> Vec<String> {
        ["F[N]", "x[m]", "v[m/s]", "s[m]", "E[J]", "P[W]"]
            .iter()
            .map(|s| s.to_string())
            .collect()
    }

    /// Force, length, rate, spring extension; the elastic energy ½ c s² + f0 x
    /// (J, the preload's potential up to a constant) and the damper's
    /// dissipated power (c s)²/d (W, the damper carries the spring's force).
    fn outputs(&self, ctx: &ForceContext, out: &mut Vec<f64>) {
        let s = self.pair.state(ctx);
        let (extension, _) = self.spring(ctx);
        let spring = self.stiffness * extension;
        out.extend([
            self.force(&s, extension),
            s.length,
            s.rate,
            extension,
            0.5 * spring * extension + self.preload * s.length,
            spring * spring / self.damping,
        ]);
    }

    fn state_count(&self) -> usize {
        1
    }

    fn state_names(&self) -> Vec<String> {
        vec!["s".into()]
    }

    fn set_state_offset(&mut self, offset: usize) {
        self.offset = offset;
    }

    fn initial_states(&self, ctx: &ForceContext, z: &mut [f64], zdot: &mut [f64]) {
        // Relaxed spring; then ṡ = ẋ − (c/d)·0 from the state equation.
        z[0] = 0.0;
        zdot[0] = self.pair.state(ctx).rate;
    }

    fn state_residuals(&self, ctx: &ForceContext, out: &mut [f64]) {
        let s = self.pair.state(ctx);
        let (extension, rate) = self.spring(ctx);
        out[0] = self.damping * (s.rate - rate) - self.stiffness * extension;
    }

    /// Body block: only the turning of the line of action (F/x transverse
    /// term); the force on P₂, −F e, depends on the state: ∂f₂/∂s = −c e.
    /// State row: with ẋ = eᵀḋ, ∂r/∂ḋ = d e and ∂r/∂d = d (E − e eᵀ) ḋ / x;
    /// ∂r/∂s = −c, ∂r/∂ṡ = −d.
    fn add_jacobian(&self, ctx: &ForceContext, jac: &mut ForceJacobian) -> Result<(), SimError> {
        let s = self.pair.state(ctx);
        let (extension, _) = self.spring(ctx);
        let k = jac.dq.ncols() - ctx.states.len() + self.offset;
        jac.dq[(k, k)] -= self.stiffness;
        jac.dv[(k, k)] -= self.damping;
        let Some(e) = s.direction else {
            return Ok(());
        };
        self.pair
            .add_jacobian(&s, self.force(&s, extension), 0.0, 0.0, jac);
        let transverse = s.relative_velocity - e * s.rate;
        let [a, b] = self.pair.ends();
        jac.add_pair_state(
            a.body,
            &s.p1,
            b.body,
            &s.p2,
            k,
            &(-self.stiffness * e),
            &(self.damping / s.length * transverse),
            &(self.damping * e),
        );
        Ok(())
    }
}
