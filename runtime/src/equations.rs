//! The `Equations` interface: what an engine (numeric-iterative or a compiled
//! symbolic plugin) computes for given (t, q, q̇, parameters).
//!
//! ```text
//!     M(q) q̈ + k(q, q̇, t) = Q_g(q, t) + Σ_j Γ_jᵀ F_j + Gᵀ λ,     g(q, t) = 0
//! ```
//!
//! - `M` the mass matrix (n×n), `k` the inertia/velocity (bias) terms: the
//!   generalized inertia forces at q̈ = 0, including Coriolis, centripetal,
//!   gyroscopic and rheonomic terms;
//! - `Q_g` the generalized gravity forces;
//! - `Γ_j` (6×n) the Jacobian of body j: rows 0–2 the velocity of its centre of
//!   mass, rows 3–5 its angular velocity, both in the inertial frame SC0, so that
//!   `(v_j, ω_j) = Γ_j q̇ + (rheonomic part)`. Force elements give wrenches
//!   `F_j = (force, moment about the centre of mass)` in SC0, projected by `Γ_jᵀ`;
//! - `g` the constraint equations of cut joints and `G = ∂g/∂q`.

use crate::system::SimError;
use nalgebra::{DMatrix, DVector, Matrix3, Vector3};

/// Position, orientation and velocities of one body's frame (its centre of
/// mass), all in SC0.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BodyKinematics {
    /// Position of the centre of mass, m.
    pub position: Vector3<f64>,
    /// Direction cosine matrix: columns are the body axes in SC0
    /// (a vector in body coordinates `x_b` is `rotation * x_b` in SC0).
    pub rotation: Matrix3<f64>,
    /// Velocity of the centre of mass, m/s.
    pub velocity: Vector3<f64>,
    /// Angular velocity, rad/s.
    pub angular_velocity: Vector3<f64>,
}

impl Default for BodyKinematics {
    fn default() -> Self {
        Self {
            position: Vector3::zeros(),
            rotation: Matrix3::identity(),
            velocity: Vector3::zeros(),
            angular_velocity: Vector3::zeros(),
        }
    }
}

impl BodyKinematics {
    /// Position in SC0 of a point given in body coordinates, m.
    pub fn point_position(&self, local: &Vector3<f64>) -> Vector3<f64> {
        self.position + self.rotation * local
    }

    /// Velocity in SC0 of a point given in body coordinates, m/s.
    pub fn point_velocity(&self, local: &Vector3<f64>) -> Vector3<f64> {
        self.velocity + self.angular_velocity.cross(&(self.rotation * local))
    }
}

/// Which parts of an [`Evaluation`] to compute (others are left untouched).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Parts {
    /// The mass matrix M ([`Evaluation::mass`]).
    pub mass: bool,
    /// The bias terms k ([`Evaluation::bias`]): generalized inertia forces
    /// at q̈ = 0 (see the module docs).
    pub bias: bool,
    /// The generalized gravity forces Q_g ([`Evaluation::gravity`]).
    pub gravity: bool,
    /// Body kinematics (always cheap; computed whenever anything else is).
    pub kinematics: bool,
    /// The stacked body Jacobians Γ_j ([`Evaluation::jacobians`]).
    pub jacobians: bool,
    /// The cut-joint constraints g and G = ∂g/∂q
    /// ([`Evaluation::constraints`], [`Evaluation::constraint_jacobian`]).
    pub constraints: bool,
}

impl Parts {
    /// Everything.
    pub const ALL: Parts = Parts {
        mass: true,
        bias: true,
        gravity: true,
        kinematics: true,
        jacobians: true,
        constraints: true,
    };
    /// M and k only (the benchmark quantity).
    pub const MASS_AND_BIAS: Parts = Parts {
        mass: true,
        bias: true,
        gravity: false,
        kinematics: false,
        jacobians: false,
        constraints: false,
    };
    /// Body kinematics only (outputs).
    pub const KINEMATICS: Parts = Parts {
        mass: false,
        bias: false,
        gravity: false,
        kinematics: true,
        jacobians: false,
        constraints: false,
    };
}

/// Host-owned buffers an engine writes into.
#[derive(Debug, Clone)]
pub struct Evaluation {
    /// M, n×n, symmetric (both triangles filled).
    pub mass: DMatrix<f64>,
    /// k, n.
    pub bias: DVector<f64>,
    /// Q_g, n.
    pub gravity: DVector<f64>,
    /// One per body, in model order.
    pub bodies: Vec<BodyKinematics>,
    /// Stacked Γ_j: rows 6j..6j+6 belong to body j (6·nb × n).
    pub jacobians: DMatrix<f64>,
    /// g, nc.
    pub constraints: DVector<f64>,
    /// G = ∂g/∂q, nc×n.
    pub constraint_jacobian: DMatrix<f64>,
}

impl Evaluation {
    /// Zeroed buffers for an engine with the given sizes.
    pub fn new(dof: usize, bodies: usize, constraints: usize) -> Self {
        Self {
            mass: DMatrix::zeros(dof, dof),
            bias: DVector::zeros(dof),
            gravity: DVector::zeros(dof),
            bodies: vec![BodyKinematics::default(); bodies],
            jacobians: DMatrix::zeros(6 * bodies, dof),
            constraints: DVector::zeros(constraints),
            constraint_jacobian: DMatrix::zeros(constraints, dof),
        }
    }

    /// Buffers sized for `equations`.
    pub fn for_equations(equations: &dyn Equations) -> Self {
        Self::new(
            equations.dof(),
            equations.body_count(),
            equations.constraint_count(),
        )
    }
}

/// An engine computing the equations of motion of one model.
pub trait Equations: Send {
    /// Short name for messages and benchmark tables ("numeric", "symbolic").
    fn engine_name(&self) -> &str;
    /// Number of generalized coordinates n.
    fn dof(&self) -> usize;
    /// Number of bodies (ground excluded).
    fn body_count(&self) -> usize;
    /// Number of scalar constraint equations.
    fn constraint_count(&self) -> usize;
    /// Number of parameters (identifiers) the engine takes.
    fn parameter_count(&self) -> usize;
    /// Sets the parameter values (in `Model::parameters` order). Must be called
    /// before the first evaluation; engines precompute what depends on them only.
    fn set_parameters(&mut self, params: &[f64]) -> Result<(), SimError>;
    /// Number of runtime inputs (the six pose components of each
    /// track-following frame, `Model::track_frames`).
    fn input_count(&self) -> usize {
        0
    }
    /// Sets the runtime inputs for the next evaluations: for input k,
    /// `u[3k]` its value, `u[3k + 1]` its rate, `u[3k + 2]` its acceleration
    /// (m, m/s, m/s² or rad, rad/s, rad/s²).
    fn set_inputs(&mut self, u: &[f64]) -> Result<(), SimError> {
        if u.is_empty() {
            Ok(())
        } else {
            Err(SimError::Other(format!(
                "the {} engine takes no runtime inputs, got {}",
                self.engine_name(),
                u.len()
            )))
        }
    }
    /// Whether [`Equations::solve_mass`] solves (an O(n) method without M,
    /// the articulated-body formalism of the numeric engine). `false` by
    /// default: callers factor M themselves.
    fn solves_mass(&self) -> bool {
        false
    }
    /// Solves M x = b in place (b generalized forces in, x accelerations
    /// out) at the state of the last [`Equations::evaluate`] that computed
    /// the bias terms or M, without forming M. `Ok(false)` with `b`
    /// untouched when the engine has no such method
    /// ([`Equations::solves_mass`]).
    fn solve_mass(&mut self, _b: &mut [f64]) -> Result<bool, SimError> {
        Ok(false)
    }
    /// Evaluates the requested parts at (t, q, q̇) into `out`.
    fn evaluate(
        &mut self,
        t: f64,
        q: &[f64],
        v: &[f64],
        parts: Parts,
        out: &mut Evaluation,
    ) -> Result<(), SimError>;
}
