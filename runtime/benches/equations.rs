//! Speed of the numeric-iterative engine on the planar chains of issue 2
//! (`models/mechanisms/chain{3,10,30}.ron`):
//!
//! - `mass_and_bias/N`: one evaluation of M and k (`Parts::MASS_AND_BIAS`);
//! - `dynamics/N`: one `ModelSystem::dynamics` call (M, k, gravity, force
//!   projection), the quantity an integrator stage needs;
//! - `forward_dynamics/N`: `dynamics` plus the Cholesky solve M q̈ = f, to
//!   compare with forward-dynamics timings of other codes;
//! - `rk4_run/N`: the whole 10 s RK4 run of `models/scenarios/chainN_rk4.ron`
//!   (1 ms step, no CSV output).
//!
//! The states are pseudo-random (fixed seed) in q ∈ [−1.5, 1.5) rad and
//! q̇ ∈ [−2, 2) rad/s, cycled through so branch prediction cannot learn one
//! state.
//!
//! Run: `cargo bench -p railmbs-runtime --bench equations`.

use std::hint::black_box;
use std::path::PathBuf;
use std::time::Duration;

use criterion::{BenchmarkId, Criterion, criterion_group, criterion_main};
use nalgebra::{DMatrix, DVector};
use railmbs_models::Model;
use railmbs_runtime::run::run_scenario;
use railmbs_runtime::{
    Equations, Evaluation, MechanicalSystem, ModelSystem, NumericEquations, Parts,
};

const CHAINS: [usize; 3] = [3, 10, 30];
const STATES: usize = 64;

fn models_dir() -> PathBuf {
    PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../models"))
}

fn chain(n: usize) -> Model {
    let path = models_dir().join(format!("mechanisms/chain{n}.ron"));
    railmbs_models::load_model(&path).unwrap_or_else(|e| panic!("{e}"))
}

/// Deterministic states (xorshift64*): STATES pairs (q, q̇).
fn states(n: usize) -> Vec<(Vec<f64>, Vec<f64>)> {
    let mut x: u64 = 0x9E37_79B9_7F4A_7C15;
    let mut uniform = |lo: f64, hi: f64| {
        x ^= x >> 12;
        x ^= x << 25;
        x ^= x >> 27;
        let u = (x.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 / (1u64 << 53) as f64;
        lo + (hi - lo) * u
    };
    (0..STATES)
        .map(|_| {
            let q = (0..n).map(|_| uniform(-1.5, 1.5)).collect();
            let v = (0..n).map(|_| uniform(-2.0, 2.0)).collect();
            (q, v)
        })
        .collect()
}

fn numeric(model: &Model) -> NumericEquations {
    let mut eng = NumericEquations::new(model);
    eng.set_parameters(&model.default_parameter_values())
        .unwrap_or_else(|e| panic!("{e}"));
    eng
}

fn system(model: &Model) -> ModelSystem {
    let params = model.default_parameter_values();
    ModelSystem::new(model, Box::new(NumericEquations::new(model)), params)
        .unwrap_or_else(|e| panic!("{e}"))
}

fn mass_and_bias(c: &mut Criterion) {
    let mut group = c.benchmark_group("mass_and_bias");
    for n in CHAINS {
        let model = chain(n);
        let mut eng = numeric(&model);
        let mut out = Evaluation::for_equations(&eng);
        let xs = states(n);
        let mut k = 0;
        group.bench_function(BenchmarkId::from_parameter(n), |b| {
            b.iter(|| {
                let (q, v) = &xs[k % STATES];
                k += 1;
                eng.evaluate(
                    0.0,
                    black_box(q),
                    black_box(v),
                    Parts::MASS_AND_BIAS,
                    &mut out,
                )
                .unwrap();
                black_box(&out.mass);
            })
        });
    }
    group.finish();
}

fn dynamics(c: &mut Criterion) {
    let mut group = c.benchmark_group("dynamics");
    for n in CHAINS {
        let model = chain(n);
        let mut sys = system(&model);
        let mut mass = DMatrix::zeros(n, n);
        let mut force = DVector::zeros(n);
        let xs = states(n);
        let mut k = 0;
        group.bench_function(BenchmarkId::from_parameter(n), |b| {
            b.iter(|| {
                let (q, v) = &xs[k % STATES];
                k += 1;
                sys.dynamics(0.0, black_box(q), black_box(v), &mut mass, &mut force)
                    .unwrap();
                black_box(&force);
            })
        });
    }
    group.finish();
}

fn forward_dynamics(c: &mut Criterion) {
    let mut group = c.benchmark_group("forward_dynamics");
    for n in CHAINS {
        let model = chain(n);
        let mut sys = system(&model);
        let mut mass = DMatrix::zeros(n, n);
        let mut force = DVector::zeros(n);
        let xs = states(n);
        let mut k = 0;
        group.bench_function(BenchmarkId::from_parameter(n), |b| {
            b.iter(|| {
                let (q, v) = &xs[k % STATES];
                k += 1;
                sys.dynamics(0.0, black_box(q), black_box(v), &mut mass, &mut force)
                    .unwrap();
                let m = std::mem::replace(&mut mass, DMatrix::zeros(0, 0));
                let chol = m.cholesky().expect("M is positive definite");
                chol.solve_mut(&mut force);
                mass = chol.unpack_dirty();
                black_box(&force);
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
                let summary = run_scenario(
                    &scenario,
                    &model,
                    Box::new(NumericEquations::new(&model)),
                    None,
                    |_| {},
                )
                .unwrap();
                assert!(summary.error.is_none(), "{:?}", summary.error);
                black_box(summary.steps)
            })
        });
    }
    group.finish();
}

criterion_group!(benches, mass_and_bias, dynamics, forward_dynamics, rk4_run);
criterion_main!(benches);
