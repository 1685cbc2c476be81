//! Runtime inputs: the pose of track-following frames (and anything else a
//! model drives from outside the equations), supplied at every evaluation.
//!
//! An engine built from a model with track frames has `input_count() > 0` and
//! must not be evaluated before its inputs are set. [`DrivenEquations`] wraps
//! such an engine with an [`InputProvider`] that computes the inputs at the
//! evaluation's time, so the integrators and force elements see an ordinary
//! `Equations` engine.

use crate::equations::{Equations, Evaluation, Parts};
use crate::system::SimError;

/// Computes the runtime inputs at time t.
pub trait InputProvider: Send {
    /// Number of inputs provided (6 per track-following frame).
    fn input_count(&self) -> usize;
    /// Writes value, rate and acceleration of every input (3 numbers per
    /// input, in the model's input order: for each track frame x, y, z in m,
    /// yaw, pitch, roll in rad; then per s and per s²) at time `t` (s).
    fn inputs(&mut self, t: f64, out: &mut [f64]) -> Result<(), SimError>;
    /// Times in (t0, t1) at which an input's rate may jump (a kink in the
    /// track: the ends of linear cant ramps, section joints), in increasing
    /// order. A run stops there and restarts with velocities that keep every
    /// body's absolute velocity continuous (`run::run_scenario`).
    fn breakpoints(&self, _t0: f64, _t1: f64) -> Vec<f64> {
        Vec::new()
    }
}

/// An engine whose inputs come from a provider.
pub struct DrivenEquations {
    inner: Box<dyn Equations>,
    provider: Box<dyn InputProvider>,
    values: Vec<f64>,
}

impl std::fmt::Debug for DrivenEquations {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("DrivenEquations")
            .field("engine", &self.inner.engine_name())
            .field("inputs", &self.provider.input_count())
            .finish()
    }
}

impl DrivenEquations {
    /// Wraps `inner`; the provider must supply exactly the inputs it takes.
    pub fn new(
        inner: Box<dyn Equations>,
        provider: Box<dyn InputProvider>,
    ) -> Result<Self, SimError> {
        if provider.input_count() != inner.input_count() {
            return Err(SimError::Other(format!(
                "the {} engine takes {} runtime inputs (6 per track-following frame), the provider gives {}",
                inner.engine_name(),
                inner.input_count(),
                provider.input_count()
            )));
        }
        let values = vec![0.0; 3 * inner.input_count()];
        Ok(Self {
            inner,
            provider,
            values,
        })
    }
}

impl Equations for DrivenEquations {
    fn engine_name(&self) -> &str {
        self.inner.engine_name()
    }
    fn dof(&self) -> usize {
        self.inner.dof()
    }
    fn body_count(&self) -> usize {
        self.inner.body_count()
    }
    fn constraint_count(&self) -> usize {
        self.inner.constraint_count()
    }
    fn parameter_count(&self) -> usize {
        self.inner.parameter_count()
    }
    /// The inputs are driven here: none are left for the caller.
    fn input_count(&self) -> usize {
        0
    }
    fn set_parameters(&mut self, params: &[f64]) -> Result<(), SimError> {
        self.inner.set_parameters(params)
    }
    fn solves_mass(&self) -> bool {
        self.inner.solves_mass()
    }
    fn solve_mass(&mut self, b: &mut [f64]) -> Result<bool, SimError> {
        self.inner.solve_mass(b)
    }
    fn evaluate(
        &mut self,
        t: f64,
        q: &[f64],
        v: &[f64],
        parts: Parts,
        out: &mut Evaluation,
    ) -> Result<(), SimError> {
        self.provider.inputs(t, &mut self.values)?;
        if let Some(i) = self.values.iter().position(|x| !x.is_finite()) {
            return Err(SimError::NonFinite {
                t,
                what: format!("runtime input value {i} = {}", self.values[i]),
            });
        }
        self.inner.set_inputs(&self.values)?;
        self.inner.evaluate(t, q, v, parts, out)
    }
}
