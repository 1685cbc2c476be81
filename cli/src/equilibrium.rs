//! `umsim equilibrium SCENARIO [--engine numeric|symbolic] [--plugin FILE]
//! [--set NAME=VALUE]…`: the static (steady) equilibrium at the scenario's
//! start (the state `initial_state: Equilibrium` starts a run from): a table
//! of the coordinates (long names, units, what the solve did with each) and,
//! for vehicles, the wheel loads Q and lateral forces Y of every wheel. A
//! train file is solved as one system (all vehicles and couplers), its
//! coupler forces listed too.

use crate::engine::EngineOptions;
use railmbs_models::InitialStateKind;
use railmbs_runtime::analysis::equilibrium::{Equilibrium, Role};
use railmbs_runtime::analysis::{self, CoordinateInfo};
use railmbs_runtime::forces::WheelLoads;
use railmbs_runtime::run::scenario::{ScenarioSystem, scenario_system};
use std::fmt::Write as _;
use std::path::PathBuf;

/// Arguments of `umsim equilibrium`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Scenario file (RON); its model's `init`/`vel` and the scenario's
    /// `initial` overrides are the starting guess.
    pub scenario: PathBuf,
    /// Engine and parameters.
    #[command(flatten)]
    pub engine: EngineOptions,
}

/// Runs `umsim equilibrium` (of one vehicle or of a train).
pub fn run(args: &Args) -> Result<(), Box<dyn std::error::Error>> {
    if let railmbs_models::AnyScenario::Train(mut train) =
        railmbs_models::load_any_scenario(&args.scenario)?
    {
        return run_train(args, &mut train);
    }
    let (mut scenario, model) = args.engine.load(&args.scenario)?;
    scenario.initial_kind = InitialStateKind::Equilibrium;
    let equations = args.engine.build(&model)?;
    let start = std::time::Instant::now();
    let mut solved = scenario_system(&scenario, &model, equations)?;
    let elapsed = start.elapsed().as_secs_f64();
    print!("{}", report(&mut solved, elapsed)?);
    Ok(())
}

/// `umsim equilibrium` of a train file: all vehicles and couplers solved
/// together; the tables of [`report`] with the vehicles' names as prefixes,
/// then the couplers' forces.
fn run_train(
    args: &Args,
    train: &mut railmbs_models::TrainScenario,
) -> Result<(), Box<dyn std::error::Error>> {
    for (name, value) in &args.engine.set {
        train.set_parameter(name, value);
    }
    train.initial_kind = InitialStateKind::Equilibrium;
    let engine = if args.engine.plugin.is_some() {
        crate::engine::Engine::Symbolic
    } else {
        args.engine.engine
    };
    let start = std::time::Instant::now();
    let crate::run::TrainEngines {
        models,
        vehicle_models,
        engines,
    } = crate::run::TrainEngines::build(train, engine, args.engine.plugin.as_deref(), None)?;
    let models: Vec<&railmbs_models::Model> = vehicle_models.iter().map(|&k| &models[k]).collect();
    let mut setup = railmbs_runtime::train::build_train(train, &models, engines)?;
    let elapsed = start.elapsed().as_secs_f64();
    let eq = setup
        .equilibrium
        .clone()
        .ok_or("the train was built without an equilibrium")?;
    let loads = setup.system.wheel_loads(eq.t, &eq.q, &eq.v)?;
    let couplers = setup.system.named_coupler_outputs(eq.t, &eq.q, &eq.v)?;
    print!(
        "{}",
        tables(&setup.coordinates, &eq, &loads, &couplers, elapsed)?
    );
    Ok(())
}

/// The tables `umsim equilibrium` prints: coordinates, then wheel loads.
/// `seconds` is the time the set-up and solve took.
pub fn report(
    solved: &mut ScenarioSystem,
    seconds: f64,
) -> Result<String, Box<dyn std::error::Error>> {
    let eq = solved
        .equilibrium
        .clone()
        .ok_or("the scenario system was built without an equilibrium")?;
    let loads = analysis::wheel_loads(&mut solved.system, eq.t, &eq.q, &eq.v)?;
    Ok(tables(&solved.coordinates, &eq, &loads, &[], seconds)?)
}

/// The tables of an equilibrium: its coordinates (`coordinates`, system
/// order), the wheel loads `loads` (N) and the couplers' outputs
/// `couplers` (named, in their units), if any.
fn tables(
    coordinates: &[CoordinateInfo],
    eq: &Equilibrium,
    loads: &[(String, WheelLoads)],
    couplers: &[(String, f64)],
    seconds: f64,
) -> Result<String, std::fmt::Error> {
    let mut s = String::new();
    writeln!(
        s,
        "equilibrium at t = {} s: {} Newton iterations, largest residual force {:.2e} \
         (tolerance {:.1e}); solve {:.1} ms (with the set-up of the model, track and contact \
         tables {:.1} ms)",
        eq.t,
        eq.iterations,
        eq.residual,
        eq.tolerance,
        1e3 * eq.seconds,
        1e3 * seconds
    )?;
    let width = coordinates
        .iter()
        .map(|c| c.name.len())
        .max()
        .unwrap_or(10)
        .max(10);
    writeln!(
        s,
        "\n{:<width$}  {:<11}  {:>14}  {:>14}  unit",
        "coordinate", "solve", "value", "change"
    )?;
    for (i, c) in coordinates.iter().enumerate() {
        let (value, change, unit) = match eq.roles[i] {
            Role::Rate => (eq.v[i], eq.v[i] - eq.v_start[i], c.kind.rate_unit()),
            _ => (eq.q[i], eq.q[i] - eq.q_start[i], c.kind.unit()),
        };
        writeln!(
            s,
            "{:<width$}  {:<11}  {value:>14.6e}  {change:>14.3e}  {unit}",
            c.name,
            eq.roles[i].describe()
        )?;
    }
    let held: Vec<&str> = coordinates
        .iter()
        .zip(&eq.roles)
        .filter(|(_, r)| **r == Role::Held)
        .map(|(c, _)| c.name.as_str())
        .collect();
    if !held.is_empty() {
        writeln!(
            s,
            "held as given (no force depends on them): {}",
            held.join(", ")
        )?;
    }
    if !loads.is_empty() {
        let width = loads.iter().map(|(n, _)| n.len()).max().unwrap_or(7).max(7);
        writeln!(
            s,
            "\n{:<width$}  {:>12}  {:>12}  {:>12}  {:>12}",
            "wheel–rail", "Q left [kN]", "Y left [kN]", "Q right [kN]", "Y right [kN]"
        )?;
        let mut total = 0.0;
        for (name, w) in loads {
            let [(ql, yl), (qr, yr)] = w.loads;
            total += ql + qr;
            writeln!(
                s,
                "{name:<width$}  {:>12.4}  {:>12.4}  {:>12.4}  {:>12.4}",
                ql / 1e3,
                yl / 1e3,
                qr / 1e3,
                yr / 1e3
            )?;
        }
        writeln!(s, "sum of wheel loads: {:.4} kN", total / 1e3)?;
    }
    if !couplers.is_empty() {
        let width = couplers
            .iter()
            .map(|(n, _)| n.len())
            .max()
            .unwrap_or(0)
            .max(14);
        writeln!(s, "\n{:<width$}  {:>14}", "coupler output", "value")?;
        for (name, value) in couplers {
            writeln!(s, "{name:<width$}  {value:>14.6e}")?;
        }
    }
    Ok(s)
}
