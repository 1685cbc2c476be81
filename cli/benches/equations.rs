//! Speed of the numeric-iterative engine on the planar chains of issue 2
//! (`models/mechanisms/chain{3,10,30}.ron`), with criterion's statistics, on
//! the calls `umsim bench` times (`railmbs_cli::bench::workload`):
//!
//! - `mass_and_bias/N`: one evaluation of M and k (`Parts::MASS_AND_BIAS`,
//!   [`MassAndBias`]);
//! - `dynamics/N`: one `ModelSystem::dynamics` call (M, k, gravity, force
//!   projection; [`Dynamics`]), the quantity an integrator stage needs;
//! - `forward_dynamics/N`: `dynamics` plus the Cholesky solve M q̈ = f, to
//!   compare with forward-dynamics timings of other codes;
//! - `rk4_run/N`: the whole 10 s RK4 run of `models/scenarios/chainN_rk4.ron`
//!   (1 ms step, no CSV output; [`run_scenario_once`]).
//!
//! The states are those of `umsim bench` ([`random_states`]: near the
//! initial state, fixed seed), cycled through so branch prediction cannot
//! learn one state.
//!
//! Run: `cargo bench -p railmbs-cli --bench equations`.

use std::hint::black_box;
use std::path::PathBuf;
use std::time::Duration;

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use nalgebra::DMatrix;
use railmbs_cli::bench::{Dynamics, MassAndBias, State, random_states, run_scenario_once};
use railmbs_models::Model;
use railmbs_runtime::NumericEquations;

const CHAINS: [usize; 3] = [3, 10, 30];
const STATES: usize = 64;

fn models_dir() -> PathBuf {
    PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../models"))
}

/// The chain of `n` links, its default parameters and its states.
fn chain(n: usize) -> (Model, Vec<f64>, Vec<State>) {
    let path = models_dir().join(format!("mechanisms/chain{n}.ron"));
    let model = railmbs_models::load_model(&path).unwrap_or_else(|e| panic!("{e}"));
    let params = model.default_parameter_values();
    let states = random_states(&model, &params, STATES);
    (model, params, states)
}

fn mass_and_bias(c: &mut Criterion) {
    let mut group = c.benchmark_group("mass_and_bias");
    for n in CHAINS {
        let (model, params, states) = chain(n);
        let engine = Box::new(NumericEquations::new(&model));
        let mut w = MassAndBias::new(engine, &params, &states).unwrap_or_else(|e| panic!("{e}"));
        group.bench_function(BenchmarkId::from_parameter(n), |b| {
            b.iter(|| w.call().unwrap())
        });
    }
    group.finish();
}

fn dynamics(c: &mut Criterion) {
    let mut group = c.benchmark_group("dynamics");
    for n in CHAINS {
        let (model, params, states) = chain(n);
        let engine = Box::new(NumericEquations::new(&model));
        let mut w =
            Dynamics::new(&model, engine, &params, &states).unwrap_or_else(|e| panic!("{e}"));
        group.bench_function(BenchmarkId::from_parameter(n), |b| {
            b.iter(|| w.call().unwrap())
        });
    }
    group.finish();
}

fn forward_dynamics(c: &mut Criterion) {
    let mut group = c.benchmark_group("forward_dynamics");
    for n in CHAINS {
        let (model, params, states) = chain(n);
        let engine = Box::new(NumericEquations::new(&model));
        let mut w =
            Dynamics::new(&model, engine, &params, &states).unwrap_or_else(|e| panic!("{e}"));
        group.bench_function(BenchmarkId::from_parameter(n), |b| {
            b.iter(|| {
                w.call().unwrap();
                let m = std::mem::replace(&mut w.mass, DMatrix::zeros(0, 0));
                let chol = m.cholesky().expect("M is positive definite");
                chol.solve_mut(&mut w.force);
                w.mass = chol.unpack_dirty();
                black_box(&w.force);
            })
        });
    }
    group.finish();
}

fn rk4_run(c: &mut Criterion) {
    let mut group = c.benchmark_group("rk4_run");
    group.sample_size(10);
    group.measurement_time(Duration::from_secs(5));
    for n in CHAINS {
        let path = models_dir().join(format!("scenarios/chain{n}_rk4.ron"));
        let scenario = railmbs_models::load_scenario(&path).unwrap_or_else(|e| panic!("{e}"));
        let model = railmbs_models::load_model(&scenario.model).unwrap_or_else(|e| panic!("{e}"));
        group.bench_function(BenchmarkId::from_parameter(n), |b| {
            b.iter(|| {
                let engine = Box::new(NumericEquations::new(&model));
                let (_, steps) =
                    run_scenario_once(&scenario, &model, engine).unwrap_or_else(|e| panic!("{e}"));
                black_box(steps)
            })
        });
    }
    group.finish();
}

criterion_group!(benches, mass_and_bias, dynamics, forward_dynamics, rk4_run);
criterion_main!(benches);
