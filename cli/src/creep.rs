//! `umsim creep` (being written).

/// Arguments of `umsim creep`.
#[derive(Debug, clap::Args)]
pub struct Args {}

/// Runs `umsim creep`.
pub fn run(_args: &Args) -> Result<(), Box<dyn std::error::Error>> {
    Err("umsim creep is not available in this build yet".into())
}
