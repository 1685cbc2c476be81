//! Park's method on a stiff model with many frictional contacts, with the
//! analytic approximate Jacobian (seed paper Sect. 6: local Jacobians of the
//! force elements mapped by the point Jacobians) against the finite-difference
//! Jacobian (2n extra `dynamics` calls per Jacobian), same tolerances.
//!
//! Model: `models/mechanisms/boxes_on_plane.ron`, five free boxes (n = 30)
//! on 200 point–plane contacts with Coulomb friction; they land, slide and
//! stick within the 1 s run.
//!
//! Before timing, one run of each prints steps, rejected steps, Newton
//! iterations, Jacobian and `dynamics` evaluations, and the largest
//! difference of the final coordinates between the two runs.
//!
//! Run: `cargo bench -p railmbs-runtime --bench contacts`.

use std::hint::black_box;
use std::ops::ControlFlow;
use std::path::PathBuf;
use std::time::{Duration, Instant};

use criterion::{Criterion, criterion_group, criterion_main};
use railmbs_models::Model;
use railmbs_runtime::integrate::{IntegrationStats, JacobianKind, ParkSettings, integrate_park};
use railmbs_runtime::{ModelSystem, NumericEquations};

const T_END: f64 = 1.0;

fn model() -> Model {
    let path = PathBuf::from(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../models/mechanisms/boxes_on_plane.ron"
    ));
    railmbs_models::load_model(&path).unwrap_or_else(|e| panic!("{e}"))
}

fn run(model: &Model, kind: JacobianKind) -> IntegrationStats {
    let params = model.parameter_values(&[], &[]).unwrap();
    let (q0, v0) = model.initial_state(&params);
    let mut sys = ModelSystem::new(model, Box::new(NumericEquations::new(model)), params).unwrap();
    let settings = ParkSettings {
        jacobian: kind,
        max_step: 0.01,
        ..ParkSettings::with_tolerances(1e-6, 1e-6)
    };
    integrate_park(&mut sys, &settings, 0.0, &q0, &v0, T_END, |_, _, _, _| {
        ControlFlow::Continue(())
    })
    .unwrap_or_else(|e| panic!("{e}"))
}

fn contacts(c: &mut Criterion) {
    let model = model();
    let mut finals = Vec::new();
    for (name, kind) in [
        ("analytic", JacobianKind::Analytic),
        ("finite-difference", JacobianKind::ForwardDifference),
    ] {
        let start = Instant::now();
        let st = run(&model, kind);
        eprintln!(
            "{name:>17}: {:.3} s CPU-wall, {} steps, {} rejected, {} Newton iterations, \
             {} Jacobians, {} dynamics calls",
            start.elapsed().as_secs_f64(),
            st.steps,
            st.rejected_steps,
            st.newton_iterations,
            st.jacobian_evaluations,
            st.dynamics_evaluations
        );
        finals.push(st.q);
    }
    let diff = (&finals[0] - &finals[1]).amax();
    eprintln!("largest difference of the final coordinates: {diff:.3e} (m or rad)");

    let mut group = c.benchmark_group("boxes_on_plane_1s");
    group.sample_size(10);
    group.measurement_time(Duration::from_secs(20));
    group.bench_function("park_analytic_jacobian", |b| {
        b.iter(|| black_box(run(&model, JacobianKind::Analytic)))
    });
    group.bench_function("park_finite_difference_jacobian", |b| {
        b.iter(|| black_box(run(&model, JacobianKind::ForwardDifference)))
    });
    group.finish();
}

criterion_group!(benches, contacts);
criterion_main!(benches);
