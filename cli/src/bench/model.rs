//! `umsim bench` on a model file: its evaluations on random states with
//! each engine, and its scenario (`--scenario`, or the default one found
//! beside the model) run with each engine.

use super::process::whole_process;
use super::report::{BenchReport, EngineTimes};
use super::timing::median_run;
use super::workload::{MakeEngine, random_states, run_scenario_once, time_engine};
use super::{Args, BenchEngine, parse_creep};
use crate::engine::{Engine, build_engine, build_engine_with};
use railmbs_models::{Model, Scenario};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Median time of `run_scenario` (no CSV output) with engines from `make`, s,
/// and the number of steps of a run.
fn time_run(scenario: &Scenario, model: &Model, make: &MakeEngine) -> Result<(f64, usize), String> {
    median_run(|| run_scenario_once(scenario, model, make()?))
}

fn same_file(a: &Path, b: &Path) -> bool {
    match (a.canonicalize(), b.canonicalize()) {
        (Ok(a), Ok(b)) => a == b,
        _ => a == b,
    }
}

/// The default scenario of the model file `model_file`: a file
/// `<stem>*.ron` in `<model dir>/../scenarios` (then `<model dir>/scenarios`,
/// then the model's own folder) whose `model` is this model file; `<stem>.ron`
/// first, then in name order. `Err` says where it looked.
pub fn default_scenario(model_file: &Path) -> Result<Scenario, String> {
    let stem = model_file
        .file_stem()
        .and_then(|s| s.to_str())
        .ok_or_else(|| format!("{}: not a file name", model_file.display()))?;
    let dir = model_file
        .parent()
        .filter(|d| !d.as_os_str().is_empty())
        .unwrap_or(Path::new("."));
    let folders = [
        dir.join("../scenarios"),
        dir.join("scenarios"),
        dir.to_path_buf(),
    ];
    for folder in &folders {
        let Ok(entries) = std::fs::read_dir(folder) else {
            continue;
        };
        let mut candidates: Vec<PathBuf> = entries
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| {
                p.extension().is_some_and(|x| x == "ron")
                    && p.file_name()
                        .and_then(|n| n.to_str())
                        .is_some_and(|n| n.starts_with(stem))
                    && !same_file(p, model_file)
            })
            .collect();
        candidates.sort_by_key(|p| (p.file_stem().is_none_or(|s| s != stem), p.clone()));
        for p in candidates {
            if let Ok(s) = railmbs_models::load_scenario(&p)
                && same_file(&s.model, model_file)
            {
                return Ok(s);
            }
        }
    }
    Err(format!(
        "no scenario file {stem}*.ron for this model in {}",
        folders
            .iter()
            .map(|f| f.display().to_string())
            .collect::<Vec<_>>()
            .join(", ")
    ))
}

/// All measurements of a model file (`args.model` is not a train).
pub(super) fn measure_model(args: &Args) -> Result<BenchReport, Box<dyn std::error::Error>> {
    let mut model = railmbs_models::load_model(&args.model)?;
    if let Some(text) = &args.creep {
        let law = parse_creep(text)?;
        if model.set_creep_law(&law) == 0 {
            return Err(format!(
                "--creep: model {} has no wheel–rail element",
                args.model.display()
            )
            .into());
        }
    }
    let (scenario, scenario_note) = match &args.scenario {
        Some(p) => {
            let s = railmbs_models::load_scenario(p)?;
            if !same_file(&s.model, &args.model) {
                return Err(format!(
                    "{}: the scenario runs the model {}, not {}",
                    p.display(),
                    s.model.display(),
                    args.model.display()
                )
                .into());
            }
            (Some(s), None)
        }
        None => match default_scenario(&args.model) {
            Ok(s) => (Some(s), None),
            Err(e) => (None, Some(e)),
        },
    };
    let params = model.default_parameter_values();
    if let Some(i) = params.iter().position(|p| !p.is_finite()) {
        return Err(format!(
            "{}: the default value of parameter \"{}\" is not finite",
            args.model.display(),
            model.parameters[i].name
        )
        .into());
    }
    let states = random_states(&model, &params, args.states);

    let numeric_make = || build_engine(&model, Engine::Numeric, None).map_err(|e| e.to_string());
    let linear_ns = numeric_make()
        .and_then(|e| super::workload::time_linear_solves(e, &params, &states))
        .ok();
    let mut numeric = EngineTimes::default();
    match time_engine(&model, &params, &states, &numeric_make) {
        Ok((e, d)) => {
            numeric.eval_ns = Some(e);
            numeric.dynamics_ns = d;
        }
        Err(e) => numeric.note = Some(e),
    }
    if let Some(s) = &scenario {
        match time_run(s, &model, &numeric_make) {
            Ok((t, n)) => {
                numeric.run_s = Some(t);
                numeric.run_steps = Some(n);
            }
            Err(e) => numeric.note = Some(e),
        }
        whole_process(&s.source, Engine::Numeric, args, &mut numeric);
    }

    let mut symbolic = EngineTimes::default();
    let (mut derive_s, mut compile_s) = (None, None);
    if args.engine == BenchEngine::Numeric {
        symbolic.note = Some("not requested (--engine numeric)".into());
    } else {
        let start = Instant::now();
        let first = build_engine_with(&model, Engine::Symbolic, None, args.portable);
        let build_s = start.elapsed().as_secs_f64();
        match first {
            Err(e) => symbolic.note = Some(format!("unavailable: {e}")),
            Ok(first) => {
                drop(first);
                let generated =
                    railmbs_codegen::generate(&model, &railmbs_codegen::GenerateOptions::new())?;
                let d = generated.derive_time.as_secs_f64();
                let emit = generated.emit_time.as_secs_f64();
                derive_s = Some(d);
                compile_s = Some((build_s - d - emit).max(0.0));
                // Later engines come from the plugin cache.
                let make = || {
                    build_engine_with(&model, Engine::Symbolic, None, args.portable)
                        .map_err(|e| e.to_string())
                };
                match time_engine(&model, &params, &states, &make) {
                    Ok((e, dy)) => {
                        symbolic.eval_ns = Some(e);
                        symbolic.dynamics_ns = dy;
                    }
                    Err(e) => symbolic.note = Some(e),
                }
                if let Some(s) = &scenario {
                    match time_run(s, &model, &make) {
                        Ok((t, n)) => {
                            symbolic.run_s = Some(t);
                            symbolic.run_steps = Some(n);
                        }
                        Err(e) => symbolic.note = Some(e),
                    }
                    whole_process(&s.source, Engine::Symbolic, args, &mut symbolic);
                }
            }
        }
    }

    Ok(BenchReport {
        model: model.name.clone(),
        model_file: args.model.clone(),
        dof: model.coordinates.len(),
        bodies: model.bodies.len(),
        states: args.states,
        scenario: scenario.map(|s| s.source),
        scenario_note,
        numeric,
        symbolic,
        derive_s,
        compile_s,
        creep: args.creep.clone(),
        linear_ns,
        train_linear: None,
    })
}
