//! `umsim conicity` (being written).

/// Arguments of `umsim conicity`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Runs `umsim conicity`.
pub fn run(_args: &Args) -> Result<(), Box<dyn std::error::Error>> {
    Err("umsim conicity is not available in this build yet".into())
}
