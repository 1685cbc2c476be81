//! The analyses besides time simulation on Manchester Vehicle 1
//! (`models/vehicles/vehicle1.ron`, 42 coordinates), against the goals of
//! issue 15: static equilibrium < 50 ms, linearization plus all eigenvalues
//! and eigenvectors < 50 ms, a 60-speed root locus < 2 s, quasi-static
//! curving < 20 ms per curve.
//!
//! - `equilibrium/solve`: the equilibrium on straight track at 30 m/s
//!   (`vehicle1_equilibrium_straight.ron`) from the model's initial state,
//!   the system built once (model, track, contact tables outside the
//!   timing); `equilibrium/with_setup` includes building the system
//!   (the contact tables shared, as a sweep does);
//! - `modes/linearize_eig`: the linearization at that equilibrium and the
//!   eigendecomposition with all eigenvectors, named modes;
//! - `root_locus/60_speeds`: equilibrium, linearization and modes at 60
//!   speeds from 10 to 69 m/s (`umsim modes --speed 10:69:1`), each from
//!   its own steady state, contact tables built once;
//! - `curving/cold`: the 150 m curve with 100 mm cant of track case 1 at
//!   4.4 m/s (`vehicle1_tc1.ron`) without a guess (the direct solve from
//!   `first_guess`, the rigid vehicle in the curve), everything but the
//!   contact tables included;
//!   `curving/warm`: the same curve at 4.4 m/s from the solution at
//!   4.0 m/s (a speed sweep's next point); `curving/wide`: a 3000 m curve
//!   without cant at 30 m/s without a guess.
//!
//! Before timing, one solve of each prints its own figures (Newton
//! iterations, seconds). Run: `cargo bench -p railmbs-runtime --bench
//! analyses`. On a loaded machine the absolute times are upper bounds; the
//! ratios between them hold.

use std::hint::black_box;
use std::path::PathBuf;
use std::time::Duration;

use criterion::{Criterion, criterion_group, criterion_main};
use railmbs_models::{InitialStateKind, Model, Scenario};
use railmbs_runtime::analysis::curving::{Curve, curving, curving_from};
use railmbs_runtime::analysis::equilibrium::{EquilibriumSettings, Role, solve};
use railmbs_runtime::analysis::linear::linearize;
use railmbs_runtime::analysis::modes::modes;
use railmbs_runtime::analysis::speed::root_locus;
use railmbs_runtime::forces::ContactTableCache;
use railmbs_runtime::run::RunError;
use railmbs_runtime::run::scenario::scenario_system_sharing;
use railmbs_runtime::{Equations, NumericEquations};

fn scenario(name: &str) -> (Scenario, Model) {
    let path =
        PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../models/scenarios")).join(name);
    let s = railmbs_models::load_scenario(&path).unwrap_or_else(|e| panic!("{e}"));
    let model = railmbs_models::load_model(&s.model).unwrap_or_else(|e| panic!("{e}"));
    (s, model)
}

fn numeric(model: &Model) -> impl FnMut() -> Result<Box<dyn Equations>, RunError> + '_ {
    || Ok(Box::new(NumericEquations::new(model)))
}

fn settings<'a>(
    c: &'a mut Criterion,
    name: &str,
) -> criterion::BenchmarkGroup<'a, criterion::measurement::WallTime> {
    let mut g = c.benchmark_group(name);
    g.sample_size(10)
        .warm_up_time(Duration::from_millis(200))
        .measurement_time(Duration::from_secs(2));
    g
}

fn bench_equilibrium_and_modes(c: &mut Criterion) {
    let (s, model) = scenario("vehicle1_equilibrium_straight.ron");
    let tables = ContactTableCache::new();
    let mut given = s.clone();
    given.initial_kind = InitialStateKind::Given;
    let mut built = scenario_system_sharing(
        &given,
        &model,
        Box::new(NumericEquations::new(&model)),
        &tables,
    )
    .unwrap_or_else(|e| panic!("{e}"));
    let (q0, v0) = (built.q0.clone(), built.v0.clone());
    let coordinates = built.coordinates.clone();
    let defaults = EquilibriumSettings::default();
    let eq = solve(&mut built.system, &coordinates, 0.0, &q0, &v0, &defaults)
        .unwrap_or_else(|e| panic!("{e}"));
    println!(
        "equilibrium: {} Newton iterations, residual {:.2e} N, {:.1} ms",
        eq.iterations,
        eq.residual,
        1e3 * eq.seconds
    );
    let left_out: Vec<usize> = (0..eq.roles.len())
        .filter(|&i| eq.roles[i] != Role::Position)
        .collect();
    let mut g = settings(c, "equilibrium");
    g.bench_function("solve", |b| {
        b.iter(|| {
            black_box(
                solve(&mut built.system, &coordinates, 0.0, &q0, &v0, &defaults)
                    .unwrap_or_else(|e| panic!("{e}")),
            )
        })
    });
    g.bench_function("with_setup", |b| {
        b.iter(|| {
            black_box(
                scenario_system_sharing(
                    &s,
                    &model,
                    Box::new(NumericEquations::new(&model)),
                    &tables,
                )
                .unwrap_or_else(|e| panic!("{e}")),
            )
        })
    });
    g.finish();
    let mut g = settings(c, "modes");
    g.bench_function("linearize_eig", |b| {
        b.iter(|| {
            let lin = linearize(
                &mut built.system,
                &coordinates,
                (eq.t, &eq.q, &eq.v),
                &eq.lambda,
                &left_out,
            )
            .unwrap_or_else(|e| panic!("{e}"));
            black_box(modes(&lin, &coordinates).unwrap_or_else(|e| panic!("{e}")))
        })
    });
    g.finish();
}

fn bench_root_locus(c: &mut Criterion) {
    let (s, model) = scenario("vehicle1_equilibrium_straight.ron");
    let speeds: Vec<f64> = (10..70).map(f64::from).collect();
    let mut g = settings(c, "root_locus");
    g.measurement_time(Duration::from_secs(20));
    g.bench_function("60_speeds", |b| {
        b.iter(|| {
            black_box(
                root_locus(&s, &model, &speeds, &mut numeric(&model))
                    .unwrap_or_else(|e| panic!("{e}")),
            )
        })
    });
    g.finish();
}

fn bench_curving(c: &mut Criterion) {
    let (s, model) = scenario("vehicle1_tc1.ron");
    let tables = ContactTableCache::new();
    let tight = Curve {
        radius: -150.0,
        cant: 0.1,
        speed: 4.4,
    };
    let wide = Curve {
        radius: 3000.0,
        cant: 0.0,
        speed: 30.0,
    };
    let before = curving(
        &s,
        &model,
        &mut numeric(&model),
        &tables,
        &Curve {
            speed: 4.0,
            ..tight
        },
    )
    .unwrap_or_else(|e| panic!("{e}"));
    for (name, guess, curve) in [
        ("cold", None, tight),
        ("warm", Some(&before), tight),
        ("wide", None, wide),
    ] {
        let one = curving_from(&s, &model, &mut numeric(&model), &tables, &curve, guess)
            .unwrap_or_else(|e| panic!("{e}"));
        println!(
            "curving/{name}: final solve {} Newton iterations, {:.1} ms; before it {:.1} ms",
            one.equilibrium.iterations,
            1e3 * one.seconds[1],
            1e3 * one.seconds[0]
        );
    }
    let mut g = settings(c, "curving");
    for (name, guess, curve) in [
        ("cold", None, tight),
        ("warm", Some(&before), tight),
        ("wide", None, wide),
    ] {
        g.bench_function(name, |b| {
            b.iter(|| {
                black_box(
                    curving_from(&s, &model, &mut numeric(&model), &tables, &curve, guess)
                        .unwrap_or_else(|e| panic!("{e}")),
                )
            })
        });
    }
    g.finish();
}

criterion_group!(
    benches,
    bench_equilibrium_and_modes,
    bench_curving,
    bench_root_locus
);
criterion_main!(benches);
