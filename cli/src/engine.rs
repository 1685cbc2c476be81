//! Choosing the equations-of-motion engine for a model.

use railmbs_models::Model;
use railmbs_runtime::{Equations, NumericEquations};
use std::path::Path;

/// Which engine computes the equations of motion.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Engine {
    /// Recursive numeric-iterative evaluation, no code generation.
    Numeric,
    /// A compiled symbolic plugin (built through the cache when none is given).
    Symbolic,
}

/// Builds the engine for `model`.
pub fn build_engine(
    model: &Model,
    engine: Engine,
    plugin: Option<&Path>,
) -> Result<Box<dyn Equations>, Box<dyn std::error::Error>> {
    match engine {
        Engine::Numeric => Ok(Box::new(NumericEquations::new(model))),
        Engine::Symbolic => {
            let _ = plugin;
            Err("the symbolic engine (compiled plugins, `umgen`) is not part of this build yet: \
                 it is being built under the symbolic-equations issue; use --engine numeric"
                .into())
        }
    }
}
