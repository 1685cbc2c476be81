//! # railmbs-runtime
//!
//! The simulator's library: numeric-iterative equations of motion
//! ([`numeric`]), force elements ([`forces`]), integrators ([`integrate`]:
//! Park's implicit method, RK4), and the glue that makes a model with
//! parameters an integrable system ([`model_system`]).

pub mod equations;
pub mod forces;
pub mod inputs;
pub mod integrate;
pub mod model_system;
pub mod numeric;
pub mod plugin;
pub mod simulate;
pub mod system;
pub mod track_inputs;
pub mod train;

pub use equations::{BodyKinematics, Equations, Evaluation, Parts};
pub use inputs::{DrivenEquations, InputProvider};
pub use model_system::ModelSystem;
pub use numeric::NumericEquations;
pub use plugin::{Plugin, PluginEquations, PluginError};
pub use system::{MechanicalSystem, SimError};
pub use track_inputs::TrackInputs;
