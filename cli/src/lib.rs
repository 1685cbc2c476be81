//! # railmbs-cli
//!
//! The command-line tools: `umsim` (run, study, bench, conicity, creep, info, plot, equilibrium, modes, curving, critical-speed) and `umgen`.
//! Each subcommand lives in its own module with its clap arguments and a `run`
//! function; the binaries only dispatch.

pub mod bench;
pub mod conicity;
pub mod creep;
pub mod critical;
pub mod curving;
pub mod engine;
pub mod equilibrium;
pub mod info;
pub mod modes;
pub mod plot;
pub mod run;
pub mod study;
pub mod umgen;
