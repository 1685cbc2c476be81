//! Park's method on a stiff model with many frictional contacts, with the
//! analytic approximate Jacobian (Pogorelov 2005, Sect. 6: local Jacobians of the
//! force elements mapped by the point Jacobians) against the finite-difference
//! Jacobian (2n extra `dynamics` calls per Jacobian), same tolerances.
//!
//! Models: `models/mechanisms/boxes_on_plane.ron`, five free boxes (n = 30)
//! on 200 point–plane contacts (40 each), and `boxes20_on_plane.ron`, twenty
//! boxes (n = 120) on 200 contacts (10 each), with Coulomb friction; they
//! land, slide and stick within the 1 s run. A finite-difference Jacobian
//! costs 2n `dynamics` calls, the analytic one a pass over the contacts, so
//! the advantage grows with the number of coordinates.
//!
//! Before timing, one run of each prints steps, rejected steps, Newton
//! iterations, Jacobian and `dynamics` evaluations, and the largest
//! difference of the final coordinates between the two runs.
//!
//! `jacobian/*` times one Jacobian evaluation at the final (resting, all
//! contacts sticking) state: `MechanicalSystem::force_jacobian` against the
//! 1 + 2n `dynamics` calls of forward differences (what Park spends per
//! Jacobian with `JacobianKind::ForwardDifference`). How many Jacobians a run
//! needs is Park's business (it reuses them while Newton converges fast).
//!
//! `jacobian_freight/*`: the same for one Jacobian of the freight car
//! (issue 16's "analytic Jacobian ≥ 5× faster than finite differences on
//! this car").
//!
//! Run: `cargo bench -p railmbs-runtime --bench contacts`.

use std::hint::black_box;
use std::ops::ControlFlow;
use std::path::PathBuf;
use std::time::{Duration, Instant};

use criterion::{Criterion, criterion_group, criterion_main};
use nalgebra::{DMatrix, DVector};
use railmbs_models::Model;
use railmbs_runtime::integrate::{IntegrationStats, JacobianKind, ParkSettings, integrate_park};
use railmbs_runtime::{MechanicalSystem, ModelSystem, NumericEquations};

const T_END: f64 = 1.0;

const MODELS: [&str; 2] = ["boxes_on_plane", "boxes20_on_plane"];

fn model(name: &str) -> Model {
    let path = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../models/mechanisms"))
        .join(format!("{name}.ron"));
    railmbs_models::load_model(&path).unwrap_or_else(|e| panic!("{e}"))
}

fn run(model: &Model, kind: JacobianKind) -> IntegrationStats {
    run_system(model, kind, 1e-6).0
}

fn run_system(model: &Model, kind: JacobianKind, tol: f64) -> (IntegrationStats, ModelSystem) {
    let params = model.parameter_values(&[], &[]).unwrap();
    let (q0, v0) = model.initial_state(&params);
    let mut sys = ModelSystem::new(model, Box::new(NumericEquations::new(model)), params).unwrap();
    let settings = ParkSettings {
        jacobian: kind,
        max_step: 0.01,
        ..ParkSettings::with_tolerances(tol, tol)
    };
    let st = integrate_park(&mut sys, &settings, 0.0, &q0, &v0, T_END, |_, _, _, _| {
        ControlFlow::Continue(())
    })
    .unwrap_or_else(|e| panic!("{e}"));
    (st, sys)
}

fn contacts(c: &mut Criterion) {
    for name in MODELS {
        contacts_of(c, name);
    }
}

fn contacts_of(c: &mut Criterion, model_name: &str) {
    let model = model(model_name);
    eprintln!("{model_name}:");
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
    // Both against a run at 100× tighter tolerance: the Jacobian only steers
    // Newton's iterations, so both should be as close to it as the
    // tolerance and the step-end timing of the stick/slip switches allow.
    let reference = run_system(&model, JacobianKind::Analytic, 1e-8).0.q;
    eprintln!(
        "largest difference of the final coordinates: {diff:.3e} between the two, \
         {:.3e} (analytic) and {:.3e} (finite-difference) from the 1e-8 run (m or rad)",
        (&finals[0] - &reference).amax(),
        (&finals[1] - &reference).amax()
    );

    let mut group = c.benchmark_group(format!("{model_name}_1s"));
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

fn jacobian(c: &mut Criterion) {
    let model = model(MODELS[0]);
    let (st, mut sys) = run_system(&model, JacobianKind::Analytic, 1e-6);
    let (q, v) = (st.q.as_slice().to_vec(), st.v.as_slice().to_vec());
    let n = q.len();
    let (mut dq, mut dv) = (DMatrix::zeros(n, n), DMatrix::zeros(n, n));
    let mut mass = DMatrix::zeros(n, n);
    let (mut f0, mut f) = (DVector::zeros(n), DVector::zeros(n));
    let mut group = c.benchmark_group("jacobian");
    group.bench_function("analytic", |b| {
        b.iter(|| {
            sys.dynamics(0.0, &q, &v, &mut mass, &mut f0).unwrap();
            sys.force_jacobian(0.0, &q, &v, &mut dq, &mut dv).unwrap();
            black_box(&dq);
        })
    });
    group.bench_function("forward_difference", |b| {
        b.iter(|| {
            sys.dynamics(0.0, &q, &v, &mut mass, &mut f0).unwrap();
            let (mut qp, mut vp) = (q.clone(), v.clone());
            for j in 0..n {
                let h = f64::EPSILON.sqrt() * q[j].abs().max(1.0);
                qp[j] += h;
                sys.dynamics(0.0, &qp, &v, &mut mass, &mut f).unwrap();
                dq.set_column(j, &((&f - &f0) / h));
                qp[j] = q[j];
                vp[j] += h;
                sys.dynamics(0.0, &q, &vp, &mut mass, &mut f).unwrap();
                dv.set_column(j, &((&f - &f0) / h));
                vp[j] = v[j];
            }
            black_box(&dq);
        })
    });
    group.finish();
}

/// One Jacobian of the freight car (Pogorelov 2005, Sect. 7.2: 114
/// coordinates, 264 point–plane contacts and 8 wheel–rail contacts) at the
/// start of `freight_straight_loaded.ron` (its static equilibrium):
/// the analytic approximate Jacobian (one evaluation with the body
/// Jacobians, then the elements' local Jacobians, Eq. 31) against forward
/// differences as Park's method takes them, 1 + 2 g `dynamics` calls for
/// the g column groups of the model's block pattern (Curtis–Powell–Reid:
/// one interior coordinate of each bogie per call, the border one by one;
/// 1 + 2n without a pattern). The columns are formed whole here; Park forms
/// only their pattern's rows, a small part of a call's cost.
fn freight_jacobian(c: &mut Criterion) {
    let dir = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../models/scenarios"));
    let scenario = railmbs_models::load_scenario(&dir.join("freight_straight_loaded.ron"))
        .unwrap_or_else(|e| panic!("{e}"));
    let model = railmbs_models::load_model(&scenario.model).unwrap_or_else(|e| panic!("{e}"));
    let setup = railmbs_runtime::run::scenario::scenario_system(
        &scenario,
        &model,
        Box::new(NumericEquations::new(&model)),
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let mut sys = setup.system;
    let (q, v) = (setup.q0, setup.v0);
    let n = q.len();
    let groups: Vec<Vec<usize>> = match sys.block_pattern() {
        Some(p) => p.difference_groups(),
        None => (0..n).map(|j| vec![j]).collect(),
    };
    eprintln!(
        "freight car: n = {n}, {} difference groups, {} dynamics calls per FD Jacobian",
        groups.len(),
        1 + 2 * groups.len()
    );
    let (mut dq, mut dv) = (DMatrix::zeros(n, n), DMatrix::zeros(n, n));
    let mut mass = DMatrix::zeros(n, n);
    let (mut f0, mut f) = (DVector::zeros(n), DVector::zeros(n));
    let t = 0.0;
    let mut group = c.benchmark_group("jacobian_freight");
    group.sample_size(20);
    group.bench_function("analytic", |b| {
        b.iter(|| {
            sys.dynamics(t, &q, &v, &mut mass, &mut f0).unwrap();
            sys.force_jacobian(t, &q, &v, &mut dq, &mut dv).unwrap();
            black_box(&dq);
        })
    });
    group.bench_function("forward_difference", |b| {
        b.iter(|| {
            sys.dynamics(t, &q, &v, &mut mass, &mut f0).unwrap();
            let (mut qp, mut vp) = (q.clone(), v.clone());
            for g in &groups {
                for &j in g {
                    qp[j] += f64::EPSILON.sqrt() * q[j].abs().max(1.0);
                }
                sys.dynamics(t, &qp, &v, &mut mass, &mut f).unwrap();
                for &j in g {
                    let h = qp[j] - q[j];
                    dq.set_column(j, &((&f - &f0) / h));
                    qp[j] = q[j];
                }
                for &j in g {
                    vp[j] += f64::EPSILON.sqrt() * v[j].abs().max(1.0);
                }
                sys.dynamics(t, &q, &vp, &mut mass, &mut f).unwrap();
                for &j in g {
                    let h = vp[j] - v[j];
                    dv.set_column(j, &((&f - &f0) / h));
                    vp[j] = v[j];
                }
            }
            black_box(&dq);
        })
    });
    group.finish();
}

criterion_group!(benches, jacobian, freight_jacobian, contacts);
criterion_main!(benches);
