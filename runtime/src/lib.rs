//! # railmbs-runtime
//!
//! The simulator's library: numeric-iterative equations of motion, force
//! elements, integrators (Park's implicit method, RK4), plugin loading, outputs.

pub mod integrate;
pub mod system;

pub use system::{MechanicalSystem, SimError};
