//! The interface between the equations of motion and the integrators.
//!
//! A mechanical system with n generalized coordinates q and nc constraints:
//!
//! ```text
//!     M(q, t) q̈ = f(t, q, q̇) + Gᵀ λ,      g(q, t) = 0,   G = ∂g/∂q
//! ```
//!
//! with f = Q − k (applied generalized forces minus inertia/velocity terms).
//! The integrators ([`crate::park`], [`crate::rk4`]) know nothing else about
//! the model.

use std::sync::Arc;

use nalgebra::{DMatrix, DVector};

use crate::block::{BlockMatrix, BlockPattern};

/// Why an evaluation or a simulation failed. Always says where (time) and why.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SimError {
    /// A non-finite number appeared in the equations.
    #[error("non-finite value at t = {t} s: {what}")]
    NonFinite {
        /// Time, s.
        t: f64,
        /// The quantity and the offending entry.
        what: String,
    },
    /// The integrator could not continue (Newton failure at the minimum step,
    /// step size underflow, singular iteration matrix...).
    #[error("simulation diverged at t = {t} s: {reason}")]
    Diverged {
        /// Time, s.
        t: f64,
        /// Why.
        reason: String,
    },
    /// Anything else with a message (bad settings, a force element's complaint).
    #[error("{0}")]
    Other(String),
}

/// A system of second-order ODEs or index-3 DAEs, as the integrators see it.
pub trait MechanicalSystem {
    /// Number of generalized coordinates n.
    fn dof(&self) -> usize;

    /// Whether coordinate `i` is a first-order state variable (a zero row and
    /// column of M, its equation in row i of f). Any other zero row of M is
    /// an error (a body without mass).
    fn is_first_order(&self, _i: usize) -> bool {
        false
    }

    /// Number of scalar constraint equations nc (0 without closed loops).
    fn n_constraints(&self) -> usize {
        0
    }

    /// Mass matrix M (n×n, symmetric) and f = Q − k (n). `mass` and `force`
    /// come sized; implementations overwrite them.
    ///
    /// M is positive definite except for the rows of first-order state
    /// variables z ([`MechanicalSystem::is_first_order`]; a spring in series
    /// with a damper), which are entirely zero: their equations
    /// r(q, q̇, z, ż) = 0 are the corresponding rows of f. Park's method
    /// solves them with the equations of motion; explicit integrators refuse
    /// such systems.
    fn dynamics(
        &mut self,
        t: f64,
        q: &[f64],
        v: &[f64],
        mass: &mut DMatrix<f64>,
        force: &mut DVector<f64>,
    ) -> Result<(), SimError>;

    /// q̈ = M⁻¹ f into `accel` (n) without forming and factoring M, for
    /// systems whose equations have such a solve (the articulated-body
    /// method, O(n)). Returns `Ok(false)`, `accel` unspecified, when the
    /// system has none: explicit integrators then call
    /// [`MechanicalSystem::dynamics`] and factor M. Implicit methods (Park's)
    /// need M and its Jacobians and never call this.
    fn accelerations(
        &mut self,
        _t: f64,
        _q: &[f64],
        _v: &[f64],
        _accel: &mut DVector<f64>,
    ) -> Result<bool, SimError> {
        Ok(false)
    }
    /// Constraint residual g (nc) and its Jacobian G = ∂g/∂q (nc×n). Called only
    /// when `n_constraints() > 0`.
    fn constraints(
        &mut self,
        _t: f64,
        _q: &[f64],
        _g: &mut DVector<f64>,
        _jacobian: &mut DMatrix<f64>,
    ) -> Result<(), SimError> {
        Ok(())
    }

    /// Approximate analytic Jacobians of f: `dfdq` ≈ ∂f/∂q (≈ −C) and `dfdv` ≈
    /// ∂f/∂q̇ (≈ −D), assembled from the force elements' local Jacobians (Pogorelov 2005,
    /// Sect. 6). Returns `Ok(false)` when the system has none, and the integrator
    /// then uses finite differences of [`MechanicalSystem::dynamics`].
    fn force_jacobian(
        &mut self,
        _t: f64,
        _q: &[f64],
        _v: &[f64],
        _dfdq: &mut DMatrix<f64>,
        _dfdv: &mut DMatrix<f64>,
    ) -> Result<bool, SimError> {
        Ok(false)
    }

    /// Called once for every accepted step with its final state. Force elements
    /// with state (stick anchors, friction modes) update here and only here.
    /// An error ends the integration (the solver's `step` returns it).
    fn accept_step(&mut self, _t: f64, _q: &[f64], _v: &[f64]) -> Result<(), SimError> {
        Ok(())
    }

    /// Whether [`MechanicalSystem::accept_step`] can change what
    /// [`MechanicalSystem::dynamics`] returns for the same (t, q, q̇) (force
    /// elements with state). `true` unless the system knows better; a solver
    /// that evaluates the state at the end of a step both before and after
    /// accepting it skips the second evaluation when `false`.
    fn remembers_accepted_steps(&self) -> bool {
        true
    }

    /// The block structure of M, ∂f/∂q and ∂f/∂q̇, if the system has one
    /// that pays ([`BlockPattern::pays`]): diagonal blocks coupled only
    /// through border coordinates, as the system's elements couple them.
    /// Park's method then assembles and factorizes its matrices blockwise
    /// ([`crate::block`], [`crate::LinearSolver::Block`]) through
    /// [`MechanicalSystem::dynamics_blocks`] and
    /// [`MechanicalSystem::force_jacobian_blocks`]. `None` (the default):
    /// dense matrices only.
    fn block_pattern(&self) -> Option<Arc<BlockPattern>> {
        None
    }

    /// [`MechanicalSystem::dynamics`] with M in the block form of
    /// [`MechanicalSystem::block_pattern`] (`mass` comes with that pattern;
    /// implementations overwrite every entry the pattern holds). The default
    /// evaluates the dense M and copies its entries into the blocks.
    fn dynamics_blocks(
        &mut self,
        t: f64,
        q: &[f64],
        v: &[f64],
        mass: &mut BlockMatrix,
        force: &mut DVector<f64>,
    ) -> Result<(), SimError> {
        let n = self.dof();
        let mut dense = DMatrix::zeros(n, n);
        self.dynamics(t, q, v, &mut dense, force)?;
        mass.copy_from_dense(&dense);
        Ok(())
    }

    /// [`MechanicalSystem::force_jacobian`] into the block form of
    /// [`MechanicalSystem::block_pattern`] (overwriting every entry). The
    /// default evaluates the dense Jacobians and copies their entries into
    /// the blocks.
    fn force_jacobian_blocks(
        &mut self,
        t: f64,
        q: &[f64],
        v: &[f64],
        dfdq: &mut BlockMatrix,
        dfdv: &mut BlockMatrix,
    ) -> Result<bool, SimError> {
        let n = self.dof();
        let (mut dq, mut dv) = (DMatrix::zeros(n, n), DMatrix::zeros(n, n));
        if !self.force_jacobian(t, q, v, &mut dq, &mut dv)? {
            return Ok(false);
        }
        dfdq.copy_from_dense(&dq);
        dfdv.copy_from_dense(&dv);
        Ok(true)
    }
}

/// A mutable reference integrates as the system itself (a solver can then
/// borrow the system instead of owning it).
impl<S: MechanicalSystem + ?Sized> MechanicalSystem for &mut S {
    fn dof(&self) -> usize {
        (**self).dof()
    }

    fn is_first_order(&self, i: usize) -> bool {
        (**self).is_first_order(i)
    }

    fn n_constraints(&self) -> usize {
        (**self).n_constraints()
    }

    fn dynamics(
        &mut self,
        t: f64,
        q: &[f64],
        v: &[f64],
        mass: &mut DMatrix<f64>,
        force: &mut DVector<f64>,
    ) -> Result<(), SimError> {
        (**self).dynamics(t, q, v, mass, force)
    }
    fn accelerations(
        &mut self,
        t: f64,
        q: &[f64],
        v: &[f64],
        accel: &mut DVector<f64>,
    ) -> Result<bool, SimError> {
        (**self).accelerations(t, q, v, accel)
    }

    fn constraints(
        &mut self,
        t: f64,
        q: &[f64],
        g: &mut DVector<f64>,
        jacobian: &mut DMatrix<f64>,
    ) -> Result<(), SimError> {
        (**self).constraints(t, q, g, jacobian)
    }

    fn force_jacobian(
        &mut self,
        t: f64,
        q: &[f64],
        v: &[f64],
        dfdq: &mut DMatrix<f64>,
        dfdv: &mut DMatrix<f64>,
    ) -> Result<bool, SimError> {
        (**self).force_jacobian(t, q, v, dfdq, dfdv)
    }

    fn accept_step(&mut self, t: f64, q: &[f64], v: &[f64]) -> Result<(), SimError> {
        (**self).accept_step(t, q, v)
    }

    fn remembers_accepted_steps(&self) -> bool {
        (**self).remembers_accepted_steps()
    }

    fn block_pattern(&self) -> Option<Arc<BlockPattern>> {
        (**self).block_pattern()
    }

    fn dynamics_blocks(
        &mut self,
        t: f64,
        q: &[f64],
        v: &[f64],
        mass: &mut BlockMatrix,
        force: &mut DVector<f64>,
    ) -> Result<(), SimError> {
        (**self).dynamics_blocks(t, q, v, mass, force)
    }

    fn force_jacobian_blocks(
        &mut self,
        t: f64,
        q: &[f64],
        v: &[f64],
        dfdq: &mut BlockMatrix,
        dfdv: &mut BlockMatrix,
    ) -> Result<bool, SimError> {
        (**self).force_jacobian_blocks(t, q, v, dfdq, dfdv)
    }
}
