//! `umsim bench` on a train file (`Train(...)`): the evaluation times summed
//! over its vehicles (the train's M and k are block-diagonal in the
//! vehicles), and the whole train scenario run by `run_train` with every
//! vehicle on the same engine.

use super::process::whole_process;
use super::report::{BenchReport, EngineTimes, TrainLinear};
use super::timing::{Stopwatch, median_run, time_per_call};
use super::workload::{random_states, time_engine};
use super::{Args, BenchEngine, parse_creep};
use crate::engine::{Engine, build_engine, build_engine_with};
use railmbs_models::Model;
use railmbs_runtime::Equations;
use railmbs_runtime::train::{build_train, run_train};
use std::path::Path;
use std::time::Instant;

/// True if the file is a train (`Train(...)`, read as a scenario of either
/// kind).
pub(super) fn is_train_file(path: &Path) -> bool {
    matches!(
        railmbs_models::load_any_scenario(path),
        Ok(railmbs_models::AnyScenario::Train(_))
    )
}

/// Builds the engine of one vehicle's model.
type VehicleEngines = dyn Fn(&Model) -> Result<Box<dyn Equations>, String>;

/// Median CPU time of `run_train` (no CSV) with every vehicle's engine from
/// `make`, s, and the steps of a run, recorded in `times`. A train with
/// `threads` > 1 steps its vehicles on worker threads, so its CPU time is
/// the process's (all threads), and its median wall time is recorded too:
/// what the threads save.
fn time_train_run(
    train: &railmbs_models::TrainScenario,
    models: &[Model],
    make: &VehicleEngines,
    times: &mut EngineTimes,
) -> Result<(), String> {
    let refs: Vec<&Model> = models.iter().collect();
    let threaded = train.threads > 1;
    let mut walls = Vec::new();
    let (t, n) = median_run(|| {
        let engines = models.iter().map(make).collect::<Result<Vec<_>, _>>()?;
        let watch = if threaded {
            Stopwatch::start_process()
        } else {
            Stopwatch::start()
        };
        let summary = run_train(train, &refs, engines, None, |_| {}).map_err(|e| e.to_string())?;
        let seconds = watch.seconds();
        walls.push(watch.wall_seconds());
        match summary.error {
            Some(e) => Err(format!("the train run failed: {e}")),
            None => Ok((seconds, summary.steps)),
        }
    })?;
    times.run_s = Some(t);
    times.run_steps = Some(n);
    if threaded {
        walls.sort_by(f64::total_cmp);
        times.run_wall_s = Some(walls[walls.len() / 2]);
    }
    Ok(())
}

/// `measure` for a train file: evaluations summed over the vehicles, the
/// train run with each engine.
pub(super) fn measure_train(args: &Args) -> Result<BenchReport, Box<dyn std::error::Error>> {
    let train = railmbs_models::load_train(&args.model)?;
    let law = args.creep.as_deref().map(parse_creep).transpose()?;
    let mut models = Vec::new();
    for v in &train.vehicles {
        let mut m = railmbs_models::load_model(&v.model)?;
        if let Some(law) = &law {
            m.set_creep_law(law);
        }
        models.push(m);
    }
    if law.is_some()
        && !models.iter().any(|m| {
            m.forces
                .iter()
                .any(|f| matches!(f.kind, railmbs_models::ForceKind::WheelRail(_)))
        })
    {
        return Err(format!(
            "--creep: no vehicle of the train {} has a wheel–rail element",
            args.model.display()
        )
        .into());
    }
    let mut numeric = EngineTimes::default();
    let mut symbolic = EngineTimes::default();
    let (mut derive_s, mut compile_s) = (Some(0.0), Some(0.0));
    let add = |acc: &mut Option<f64>, x: Option<f64>| {
        *acc = match (*acc, x) {
            (Some(a), Some(b)) => Some(a + b),
            _ => None,
        }
    };
    let (mut numeric_sum, mut symbolic_sum) = (Some(0.0), Some(0.0));
    for model in &models {
        let params = model.default_parameter_values();
        let states = random_states(model, &params, args.states);
        let numeric_make = || build_engine(model, Engine::Numeric, None).map_err(|e| e.to_string());
        let e = time_engine(model, &params, &states, &numeric_make)?.0;
        add(&mut numeric_sum, Some(e));
        if args.engine != BenchEngine::Numeric {
            let start = Instant::now();
            match build_engine_with(model, Engine::Symbolic, None, args.portable) {
                Err(e) => {
                    symbolic.note = Some(format!("unavailable: {e}"));
                    symbolic_sum = None;
                }
                Ok(_) => {
                    let build_s = start.elapsed().as_secs_f64();
                    let g =
                        railmbs_codegen::generate(model, &railmbs_codegen::GenerateOptions::new())?;
                    let d = g.derive_time.as_secs_f64();
                    add(&mut derive_s, Some(d));
                    add(
                        &mut compile_s,
                        Some((build_s - d - g.emit_time.as_secs_f64()).max(0.0)),
                    );
                    let make = || {
                        build_engine_with(model, Engine::Symbolic, None, args.portable)
                            .map_err(|e| e.to_string())
                    };
                    add(
                        &mut symbolic_sum,
                        Some(time_engine(model, &params, &states, &make)?.0),
                    );
                }
            }
        }
    }
    numeric.eval_ns = numeric_sum;
    time_train_run(
        &train,
        &models,
        &|m| build_engine(m, Engine::Numeric, None).map_err(|e| e.to_string()),
        &mut numeric,
    )?;
    whole_process(&train.source, Engine::Numeric, args, &mut numeric);
    if args.engine == BenchEngine::Numeric {
        symbolic.note = Some("not requested (--engine numeric)".into());
        (derive_s, compile_s) = (None, None);
    } else if symbolic.note.is_none() {
        symbolic.eval_ns = symbolic_sum;
        let portable = args.portable;
        time_train_run(
            &train,
            &models,
            &move |m| {
                build_engine_with(m, Engine::Symbolic, None, portable).map_err(|e| e.to_string())
            },
            &mut symbolic,
        )?;
        whole_process(&train.source, Engine::Symbolic, args, &mut symbolic);
    } else {
        (derive_s, compile_s) = (None, None);
    }
    let train_linear = time_train_linear_solves(&train, &models).ok();
    let name = args
        .model
        .file_stem()
        .map_or("train".into(), |s| s.to_string_lossy().into_owned());
    Ok(BenchReport {
        model: format!("{name} (train of {})", train.vehicles.len()),
        model_file: args.model.clone(),
        dof: models.iter().map(|m| m.coordinates.len()).sum(),
        bodies: models.iter().map(|m| m.bodies.len()).sum(),
        states: args.states,
        scenario: Some(train.source.clone()),
        scenario_note: None,
        numeric,
        symbolic,
        derive_s,
        compile_s,
        creep: args.creep.clone(),
        linear_ns: None,
        train_linear,
    })
}

/// Park's linear solves of the train at its initial state (numeric
/// engines): the q̈ solve with M, the factorization of the iteration matrix
/// `M − β ∂f/∂q̇ − β² ∂f/∂q` (β = 0.6 ms, Park's β at a 1 ms step) and one
/// Newton solve, dense and with the bordered block-diagonal LU, ns per call.
/// Without an analytic Jacobian the iteration matrix is M alone.
pub(super) fn time_train_linear_solves(
    train: &railmbs_models::TrainScenario,
    models: &[Model],
) -> Result<TrainLinear, String> {
    use nalgebra::{DMatrix, DVector};
    use railmbs_runtime::MechanicalSystem;
    use railmbs_runtime::integrate::linalg::{DenseLu, cholesky_in_place, cholesky_solve};
    use railmbs_runtime::integrate::{BlockMatrix, BorderedLu};
    let refs: Vec<&Model> = models.iter().collect();
    let engines = models
        .iter()
        .map(|m| build_engine(m, Engine::Numeric, None).map_err(|e| e.to_string()))
        .collect::<Result<Vec<_>, _>>()?;
    let mut setup = build_train(train, &refs, engines).map_err(|e| e.to_string())?;
    let sys = &mut setup.system;
    let (q, v) = (&setup.q0, &setup.v0);
    let n = sys.dof();
    let err = |e: railmbs_runtime::SimError| e.to_string();
    let mut mass = DMatrix::zeros(n, n);
    let mut f = DVector::zeros(n);
    sys.dynamics(0.0, q, v, &mut mass, &mut f).map_err(err)?;
    let (mut dq, mut dv) = (DMatrix::zeros(n, n), DMatrix::zeros(n, n));
    if !sys
        .force_jacobian(0.0, q, v, &mut dq, &mut dv)
        .map_err(err)?
    {
        dq.fill(0.0);
        dv.fill(0.0);
    }
    let beta = 6e-4;
    let a = &mass - &dv * beta - &dq * (beta * beta);
    let rhs = DVector::from_element(n, 1.0);
    let mut work = mass.clone();
    let mut x = rhs.clone();
    let singular = |what: &str| format!("the train's {what} is singular");
    let chol = time_per_call(|_| {
        work.copy_from(&mass);
        x.copy_from(&rhs);
        if !cholesky_in_place(&mut work) {
            return Err(singular("mass matrix"));
        }
        cholesky_solve(&work, x.as_mut_slice());
        std::hint::black_box(&x);
        Ok(())
    })?;
    let mut lu = DenseLu::new(n);
    let factor = time_per_call(|_| {
        lu.matrix_mut().copy_from(&a);
        lu.factorize().map_err(|_| singular("iteration matrix"))?;
        std::hint::black_box(&lu);
        Ok::<(), String>(())
    })?;
    let solve = time_per_call(|_| {
        x.copy_from(&rhs);
        lu.solve_in_place(&mut x);
        std::hint::black_box(&x);
        Ok::<(), String>(())
    })?;
    let Some(pattern) = sys.block_pattern() else {
        return Ok(TrainLinear {
            border: 0,
            dense_ns: [chol, factor, solve],
            block_ns: None,
        });
    };
    let z = || BlockMatrix::zeros(&pattern);
    let (mut mb, mut dqb, mut dvb, mut ab) = (z(), z(), z(), z());
    sys.dynamics_blocks(0.0, q, v, &mut mb, &mut f)
        .map_err(err)?;
    if !sys
        .force_jacobian_blocks(0.0, q, v, &mut dqb, &mut dvb)
        .map_err(err)?
    {
        dqb.fill_zero();
        dvb.fill_zero();
    }
    ab.set_iteration_matrix(&mb, &dvb, &dqb, beta);
    let mut blu = BorderedLu::new(&pattern);
    let block_qdd = time_per_call(|_| {
        blu.factorize(&mb).map_err(|_| singular("mass matrix"))?;
        x.copy_from(&rhs);
        blu.solve_vector(&mut x);
        std::hint::black_box(&x);
        Ok::<(), String>(())
    })?;
    let block_factor = time_per_call(|_| {
        blu.factorize(&ab)
            .map_err(|_| singular("iteration matrix"))?;
        std::hint::black_box(&blu);
        Ok::<(), String>(())
    })?;
    let block_solve = time_per_call(|_| {
        x.copy_from(&rhs);
        blu.solve_vector(&mut x);
        std::hint::black_box(&x);
        Ok::<(), String>(())
    })?;
    Ok(TrainLinear {
        border: pattern.border().len(),
        dense_ns: [chol, factor, solve],
        block_ns: Some([block_qdd, block_factor, block_solve]),
    })
}
