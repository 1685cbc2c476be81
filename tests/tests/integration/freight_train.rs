//! The three-car freight train `models/scenarios/freight3_curve.ron`
//! (Pogorelov 2005, Sect. 5 and Fig. 31): loaded, empty and loaded
//! instances of the one freight-car model joined by two SA-3 automatic
//! couplings with their own bodies; its statics from the train's
//! equilibrium, Newton's third law across its couplers during a run, the
//! parallel run against the sequential one and the two engines' equations.

use super::train_couplers::{bundled_text, train_at};
use nalgebra::{DMatrix, DVector};
use railmbs_models::{Model, TrainScenario, load_model};
use railmbs_runtime::integrate::{JacobianKind, Park, ParkSettings, Stepper};
use railmbs_runtime::train::{build_train, run_train};
use railmbs_runtime::{Equations, MechanicalSystem, NumericEquations};
use railmbs_testkit::*;
use std::path::Path;

const FILE: &str = "freight3_curve.ron";

fn numeric(model: &Model) -> Box<dyn Equations> {
    Box::new(NumericEquations::new(model))
}

/// The bundled train (read from a temporary copy with absolute paths) and
/// its vehicles' models.
fn freight_train(dir: &Path) -> (TrainScenario, Vec<Model>) {
    let train = train_at(dir, FILE, &bundled_text(FILE));
    let models = train
        .vehicles
        .iter()
        .map(|v| load_model(&v.model).unwrap())
        .collect();
    (train, models)
}

/// Parameter `name` of vehicle `k` with the vehicle's macros and overrides.
fn value(train: &TrainScenario, models: &[Model], k: usize, name: &str) -> f64 {
    let scenario = train.vehicle_scenario(k, &models[k]);
    let values = scenario.parameter_values(&models[k]).unwrap();
    values[models[k].parameter_index(name).unwrap()]
}

/// Statics at the train's equilibrium (straight, level lead-in of the track,
/// 20 m/s, the last car braked by F₀ = 20 kN at t = 0):
///
/// - the wheel loads of each car sum to its own weight, car body, two
///   bolsters, four side frames, eight wedges and four wheelsets, plus the
///   weight of the coupler bodies hanging on its pins (one on each end car,
///   two on the middle car; the contour contacts between the heads are
///   normal to the track, so they carry nothing vertically): empty and loaded
///   cars differ by the 69.5 t payload;
/// - every draft gear carries the braking force F₀ (the longitudinal balance
///   of the last car and of the last two cars), up to the cars' rolling
///   resistance on straight track (spin creep of centred wheelsets, a few
///   newtons: 1e-3 F₀).
///
/// At zero draft force the couplings' contour slack (10 mm with no force)
/// leaves the unbraked cars' positions indeterminate; the bundled scenario
/// therefore brakes from t = 0 and starts with the contours closed in draft.
#[test]
fn freight_train_statics_carry_each_cars_weight_and_the_braking_force() {
    let dir = tempfile::tempdir().unwrap();
    let (train, models) = freight_train(dir.path());
    let refs: Vec<&Model> = models.iter().collect();
    let engines = models.iter().map(numeric).collect();
    let mut setup = build_train(&train, &refs, engines).unwrap();
    let eq = setup
        .equilibrium
        .clone()
        .expect("initial_state: Equilibrium");
    let loads = setup.system.wheel_loads(eq.t, &eq.q, &eq.v).unwrap();
    let mk = value(&train, &models, 1, "mk");
    let mut sums = Vec::new();
    for (k, heads) in [(0, 1.0), (2, 2.0), (4, 1.0)] {
        let car = &train.vehicles[k].name;
        let v = |n: &str| value(&train, &models, k, n);
        let g = v("g");
        let mass = v("mc")
            + 2.0
                * (v("Bogie1.mb")
                    + 2.0 * v("Bogie1.msf")
                    + 4.0 * v("Bogie1.mw")
                    + 2.0 * v("Bogie1.mws"));
        let weight = (mass + heads * mk) * g;
        let mine: Vec<_> = loads
            .iter()
            .filter(|(n, _)| n.starts_with(&format!("{car}.")))
            .collect();
        assert_eq!(mine.len(), 4, "{car}: {} wheelsets", mine.len());
        let sum: f64 = mine.iter().map(|(_, l)| l.loads[0].0 + l.loads[1].0).sum();
        eprintln!("{car}: sum of Q {sum} N, weight {weight} N");
        // 1e-4: the draft gear lines tilt by the cars' different static
        // deflections (about 0.1 mm over 0.5 m): a few newtons.
        assert!(
            (sum - weight).abs() < 1e-4 * weight,
            "{car}: sum of wheel loads {sum} N, weight {weight} N"
        );
        sums.push(sum);
    }
    // Loaded, empty, loaded.
    assert!(sums[1] < 0.4 * sums[0] && (sums[0] - sums[2]).abs() < 1e-4 * sums[0]);
    let couplers = setup
        .system
        .named_coupler_outputs(eq.t, &eq.q, &eq.v)
        .unwrap();
    let f0 = 2e4;
    let mut gears = 0;
    for (name, f) in &couplers {
        if name.contains("DraftGear") && name.ends_with(".F[N]") {
            gears += 1;
            assert!(
                (f - f0).abs() < 1e-3 * f0,
                "{name} = {f} N, braking force {f0} N"
            );
        }
    }
    assert_eq!(gears, 4);
}

/// Newton's third law across every coupler element of the train (draft
/// gears and pins between a car body and a coupler body) along a 0.1 s run
/// from the equilibrium: the forces on the two bodies are equal and
/// opposite and their moments about one point cancel, to rounding of the
/// forces (1e-9 of the largest force).
#[test]
fn freight_train_coupler_forces_are_equal_and_opposite() {
    let dir = tempfile::tempdir().unwrap();
    let (train, models) = freight_train(dir.path());
    let refs: Vec<&Model> = models.iter().collect();
    let engines = models.iter().map(numeric).collect();
    let setup = build_train(&train, &refs, engines).unwrap();
    let settings = ParkSettings {
        max_step: 0.005,
        jacobian: JacobianKind::Analytic,
        ..ParkSettings::with_tolerances(1e-4, 1e-6)
    };
    let mut park = Park::new(setup.system, settings, 0.0, &setup.q0, &setup.v0).unwrap();
    park.set_stop_time(0.1).unwrap();
    let (mut checked, mut largest) = (0, 0.0_f64);
    while park.t() < 0.1 {
        park.step_observed(&mut |system, s| {
            for (c, pair) in system.coupler_wrenches(s.t, s.q, s.v)?.iter().enumerate() {
                // The brake (an applied force on one body) has no partner.
                let [(b1, w1), (b2, w2)] = pair.as_slice() else {
                    continue;
                };
                let scale = w1.force.norm().max(1.0);
                largest = largest.max(w1.force.norm());
                let sum = w1.force + w2.force;
                // Moments about the first body's centre of mass.
                let moment = w1.moment + w2.moment + (b2.position - b1.position).cross(&w2.force);
                assert!(
                    sum.norm() < 1e-9 * scale && moment.norm() < 1e-9 * scale,
                    "t = {}: coupler {c}: force sum {sum:?}, moment sum {moment:?} (forces {:?}, {:?})",
                    s.t,
                    w1.force,
                    w2.force
                );
                checked += 1;
            }
            Ok(())
        })
        .unwrap();
    }
    assert!(checked > 8 * 20, "{checked} checks");
    // The draft gears carry the braking force (more than 20 kN).
    assert!(largest > 2e4, "largest coupler force {largest} N");
}

/// The five vehicles (three freight cars, two couplings) evaluated in two
/// threads give the CSV bytes of the sequential run (0.1 s).
#[test]
fn freight_train_parallel_run_gives_the_bytes_of_the_sequential_run() {
    let dir = tempfile::tempdir().unwrap();
    let (mut train, models) = freight_train(dir.path());
    train.end_time = 0.1;
    let refs: Vec<&Model> = models.iter().collect();
    let mut csv = Vec::new();
    for threads in [1, 2] {
        train.threads = threads;
        let out = dir.path().join(format!("{threads}.csv"));
        let engines = models.iter().map(numeric).collect();
        let summary = run_train(&train, &refs, engines, Some(&out), |_| {}).unwrap();
        assert!(summary.error.is_none(), "{:?}", summary.error);
        csv.push(std::fs::read(&out).unwrap());
    }
    assert!(csv[0] == csv[1], "the CSVs of 1 and 2 threads differ");
}

/// The symbolic plugins (one per model file, shared by the cars and by the
/// couplings) and the numeric engine give the same train equations: mass
/// matrix and generalized forces (vehicles and couplers) of the whole
/// 358-DOF train at its start and at a state moved from it, to 1e-12
/// relative (the project's standard for the two engines).
#[test]
fn freight_train_engines_give_the_same_equations() {
    let dir = tempfile::tempdir().unwrap();
    let (mut train, models) = freight_train(dir.path());
    // The initial state as given (no equilibrium solve, which each engine
    // would do to its own rounding): both systems' element states (stick
    // anchors) are built at the same state.
    train.initial_kind = railmbs_models::InitialStateKind::Given;
    let refs: Vec<&Model> = models.iter().collect();
    let engines = models.iter().map(numeric).collect();
    let mut a = build_train(&train, &refs, engines).unwrap();
    let engines: Vec<Box<dyn Equations>> = models
        .iter()
        .map(|m| Box::new(symbolic_engine(m)) as Box<dyn Equations>)
        .collect();
    let mut b = build_train(&train, &refs, engines).unwrap();
    assert_eq!(a.q0, b.q0);
    let n = a.system.dof();
    assert_eq!(n, 3 * 114 + 2 * 8);
    let mut rng = seeded_rng(16);
    let moved: Vec<f64> = uniform_vec(&mut rng, n, -1e-4, 1e-4);
    for (label, dq) in [("start", vec![0.0; n]), ("moved", moved)] {
        let q: Vec<f64> = a.q0.iter().zip(&dq).map(|(x, d)| x + d).collect();
        let v: Vec<f64> = a.v0.iter().zip(&dq).map(|(x, d)| x + 10.0 * d).collect();
        let (mut ma, mut fa) = (DMatrix::zeros(n, n), DVector::zeros(n));
        let (mut mb, mut fb) = (DMatrix::zeros(n, n), DVector::zeros(n));
        a.system.dynamics(0.0, &q, &v, &mut ma, &mut fa).unwrap();
        b.system.dynamics(0.0, &q, &v, &mut mb, &mut fb).unwrap();
        let dm = (&ma - &mb).amax() / ma.amax();
        let df = (&fa - &fb).amax() / fa.amax();
        eprintln!("{label}: mass matrix {dm:e}, forces {df:e}");
        assert!(
            dm < 1e-12 && df < 1e-12,
            "{label}: M differs by {dm:e}, f by {df:e}"
        );
    }
}
