//! `umsim`: the railmbs simulator.

use clap::{Parser, Subcommand};
use railmbs_cli::{
    bench, conicity, creep, critical, curving, equilibrium, info, modes, plot, run, study,
};

#[derive(Parser)]
#[command(
    name = "umsim",
    version,
    about = "railmbs simulator: run scenarios, benchmark engines, wheel-rail tools"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Simulate a scenario and write its outputs as CSV.
    Run(run::Args),
    /// Run a parameter study (cases on a local pool, resumable result table).
    Study(study::Args),
    /// Speed of the numeric and symbolic engines on a model.
    Bench(bench::Args),
    /// Equivalent conicity of a wheelset on a track by EN 15302 (Annex B).
    Conicity(conicity::Args),
    /// Creep forces for a table of contact cases.
    Creep(creep::Args),
    /// Plot output columns against time or distance (SVG or PNG).
    Plot(plot::Args),
    /// A model's parameters, macros, coordinates, bodies, force elements and outputs.
    Info(info::Args),
    /// The static (steady) equilibrium at a scenario's start: coordinates and wheel loads.
    Equilibrium(equilibrium::Args),
    /// Linear modes at a scenario's steady state, a root locus over speed, the linear critical speed.
    Modes(modes::Args),
    /// Quasi-static curving: the steady state of the vehicle in a constant curve at constant speed.
    Curving(curving::Args),
    /// Nonlinear critical speed: a decelerating run's limit-cycle collapse, or a bifurcation diagram.
    CriticalSpeed(critical::Args),
}

fn main() {
    let cli = Cli::parse();
    let result = match &cli.command {
        Command::Run(a) => run::run(a),
        Command::Study(a) => study::run(a),
        Command::Bench(a) => bench::run(a),
        Command::Conicity(a) => conicity::run(a),
        Command::Creep(a) => creep::run(a),
        Command::Plot(a) => plot::run(a),
        Command::Info(a) => info::run(a),
        Command::Equilibrium(a) => equilibrium::run(a),
        Command::Modes(a) => modes::run(a),
        Command::Curving(a) => curving::run(a),
        Command::CriticalSpeed(a) => critical::run(a),
    };
    if let Err(e) = result {
        eprintln!("umsim: error: {e}");
        std::process::exit(1);
    }
}
