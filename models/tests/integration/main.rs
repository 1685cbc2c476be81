//! The integration tests of `models`, one module per topic, linked into one
//! test binary.

mod bundled;
mod common;
mod docs;
mod expr;
mod force_validation;
mod load;
mod parameters;
mod scenario;
mod subsystems;
mod torsion_spring;
mod validation;
mod wheel_rail;
