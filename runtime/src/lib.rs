//! # railmbs-runtime
//!
//! The simulator's library: numeric-iterative equations of motion
//! ([`numeric`]), force elements ([`forces`]), the glue that makes a model
//! with parameters an integrable system ([`model_system`], trains in
//! [`train`]), and the runner that owns a run's time loop and writes its
//! output columns to a sink ([`run`]). The integrators (Park's implicit
//! method, RK4) are the crate `railmbs-integrate`, re-exported as
//! [`integrate`].
//!
//! # How the types stack
//!
//! | type | implements | what it is |
//! |---|---|---|
//! | [`NumericEquations`], [`PluginEquations`] | [`Equations`] | an engine: M, k, Q_g, body kinematics and Jacobians at (t, q, q̇) for given parameters (numeric-iterative, or a compiled symbolic plugin) |
//! | [`DrivenEquations`] | [`Equations`] | an engine whose runtime inputs (track-following frames) come from an [`InputProvider`] such as [`TrackInputs`] |
//! | [`ModelSystem`] | [`MechanicalSystem`] | one model: an engine plus its force elements and parameters, M q̈ = Q_g − k + Σ Γᵀ F |
//! | [`train::TrainSystem`] | [`MechanicalSystem`] | several `ModelSystem`s (the vehicles) and the couplers between them |
//! | [`integrate::Park`], [`integrate::Rk4`] | [`Stepper`] | a solver stepping a `MechanicalSystem` |
//! | [`run`] | | the runner: steps a solver, writes rows to an [`run::OutputSink`] |

pub mod analysis;
pub mod equations;
pub mod forces;
pub mod inputs;
pub mod model_system;
pub mod numeric;
pub mod plugin;
pub mod run;
pub mod track_inputs;
pub mod train;

pub use equations::{BodyKinematics, Equations, Evaluation, Parts};
pub use inputs::{DrivenEquations, InputProvider};
pub use model_system::ModelSystem;
pub use numeric::{Formalism, NumericEquations};
pub use plugin::{Plugin, PluginEquations, PluginError};
pub use railmbs_integrate as integrate;
pub use railmbs_integrate::system;
pub use railmbs_integrate::{MechanicalSystem, SimError, Stepper};
pub use track_inputs::TrackInputs;
