//! The workspace's shared test kit: the helpers that the integration tests of
//! more than one crate need, in one place. Dev-only (`publish = false`); a
//! crate's `tests/integration/` binary takes it as a dev-dependency and keeps
//! only its own fixtures (model texts, reference-file readers) in a local
//! `common` module.
//!
//! The kit is layered by features so that it never pulls a higher crate into
//! a lower crate's tests (cargo allows the dev-dependency cycle
//! `runtime → testkit → runtime`, and integration tests link the one library
//! build, but a lower crate would otherwise wait for, and build, crates above
//! it):
//!
//! | feature    | adds                                                        | used by |
//! |------------|-------------------------------------------------------------|---------|
//! | (none)     | [`paths`], [`table`], [`random`], [`signal`]                | wheelrail, cli |
//! | `models`   | `model`: models from text and from the bundled library    | models |
//! | `runtime`  | `system`, `run`: numeric systems, Jacobians, integrations, runs to tables | runtime |
//! | `symbolic` | `plugin`: compiled symbolic plugins through the cache     | tests |
//!
//! Expected values never come from here: the kit builds systems and reads
//! outputs, the tests hold the references.

pub mod paths;
pub mod random;
pub mod signal;
pub mod table;

#[cfg(feature = "models")]
pub mod model;
#[cfg(feature = "symbolic")]
pub mod plugin;
#[cfg(feature = "runtime")]
pub mod run;
#[cfg(feature = "runtime")]
pub mod system;

pub use paths::{model_files, model_path, reference_path, repo_path};
pub use random::{Rng, SeedableRng, seeded_rng, uniform_vec};
pub use signal::up_crossings;
pub use table::Table;

#[cfg(feature = "models")]
pub use model::{TEXT_FILE, all_mechanisms, all_vehicles, mechanism, parse, try_parse};
#[cfg(feature = "symbolic")]
pub use plugin::{plugin_cache_dir, symbolic_engine};
#[cfg(feature = "runtime")]
pub use run::{Trajectory, run_park, run_rk4, run_scenario_files, run_to_table};
#[cfg(feature = "runtime")]
pub use system::{
    analytic_jacobians, body_inertia, central_difference, dynamics, mechanical_energy,
    numeric_engine, numeric_system, rel_diff,
};
