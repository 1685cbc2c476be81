//! The integration tests of `cli`, one module per topic, linked into one
//! test binary.

mod bench_cli;
mod common;
mod conicity_cli;
mod creep_cli;
mod critical_cli;
mod info_cli;
mod plot_cli;
mod run_cli;
mod study_cli;
mod table_cache_cli;
