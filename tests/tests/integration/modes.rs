//! Linearization and modes (`umsim modes`) against analytic eigenvalues:
//! a damped mass on a spring, a double pendulum's small oscillations, and
//! the car body of Manchester Vehicle 1 bouncing and pitching on its
//! secondary suspension in series with the primary; both engines alike.

use railmbs_models::{InitialStateKind, Model, Scenario, load_model, load_scenario};
use railmbs_runtime::analysis::modes::Modes;
use railmbs_runtime::analysis::speed::{SpeedModes, scenario_modes};
use railmbs_runtime::forces::ContactTableCache;
use railmbs_runtime::{Equations, NumericEquations};
use railmbs_testkit::*;

fn scenario(file: &str, set: &[(&str, &str)]) -> (Scenario, Model) {
    let mut s = load_scenario(&model_path(&format!("scenarios/{file}"))).unwrap();
    s.initial_kind = InitialStateKind::Equilibrium;
    for (n, v) in set {
        s.set_parameter(n, v);
    }
    let model = load_model(&s.model).unwrap();
    (s, model)
}

fn modes_of(s: &Scenario, model: &Model, engine: Box<dyn Equations>) -> SpeedModes {
    scenario_modes(s, model, engine, &ContactTableCache::new()).unwrap_or_else(|e| panic!("{e}"))
}

fn param(model: &Model, s: &Scenario, name: &str) -> f64 {
    s.parameter_values(model).unwrap()[model.parameter_index(name).unwrap()]
}

/// The lower and upper ω² (1/s²) of two masses in a chain, M1 on k1 on M2
/// on k2 on the ground: M1 M2 ω⁴ − (M1 (k1 + k2) + M2 k1) ω² + k1 k2 = 0.
fn two_mass_chain(m1: f64, k1: f64, m2: f64, k2: f64) -> (f64, f64) {
    let (a, b, c) = (m1 * m2, -(m1 * (k1 + k2) + m2 * k1), k1 * k2);
    let d = (b * b - 4.0 * a * c).sqrt();
    ((-b - d) / (2.0 * a), (-b + d) / (2.0 * a))
}

#[test]
fn a_damped_mass_on_a_spring_has_its_analytic_eigenvalue() {
    // spring_mass.ron: m = 1 kg, k = 100 N/m, ζ = 0.1: λ = −ζω ± iω√(1−ζ²),
    // ω = √(k/m) = 10 rad/s. The spring is linear, so the central
    // difference is exact up to rounding (ε |f| / h ≈ 2e-8 of k): 1e-8.
    let (s, model) = scenario("spring_mass.ron", &[]);
    for engine in [
        Box::new(NumericEquations::new(&model)) as Box<dyn Equations>,
        Box::new(symbolic_engine(&model)),
    ] {
        let one = modes_of(&s, &model, engine);
        let Modes { modes, zero_modes } = &one.modes;
        assert!(zero_modes.is_empty());
        assert_eq!(modes.len(), 1);
        let (omega, zeta) = (10.0, 0.1);
        let m = &modes[0];
        assert!((m.re + zeta * omega).abs() < 1e-8 * omega, "{m:?}");
        assert!(
            (m.im - omega * (1.0 - zeta * zeta).sqrt()).abs() < 1e-8 * omega,
            "{m:?}"
        );
        assert!((m.damping_ratio - zeta).abs() < 1e-8, "{m:?}");
        assert!((m.natural_frequency - omega / (2.0 * std::f64::consts::PI)).abs() < 1e-8);
        assert_eq!(m.name, "mass vertical");
        assert_eq!(m.shape, vec![(1.0, 0.0)]);
    }
}

#[test]
fn a_double_pendulum_hangs_and_swings_at_its_two_analytic_frequencies() {
    // double_pendulum.ron: uniform rods l1 = 1 m, m1 = 1 kg and l2 = 0.7 m,
    // m2 = 0.5 kg, started at 1.2 and −0.8 rad. It settles hanging, and in
    // absolute angles (θ1, θ2) the small oscillations have
    //   M = [[m1 l1²/3 + m2 l1², m2 l1 l2/2], [m2 l1 l2/2, m2 l2²/3]],
    //   K = diag((m1/2 + m2) g l1, m2 g l2/2),
    // ω² the roots of det(K − ω² M) = 0 (the model's relative angle
    // q2 = θ2 − θ1 is a change of coordinates, same eigenvalues). The
    // rods' tiny inertia about their own axis (iyy) plays no part in the
    // plane. Gravity's stiffness is sin θ ≈ θ: the central difference with
    // h = 1e-7 rad errs by h²/6 ≈ 2e-15; 1e-9 relative is rounding.
    let (s, model) = scenario("double_pendulum.ron", &[]);
    let one = modes_of(&s, &model, Box::new(NumericEquations::new(&model)));
    for (i, q) in one.equilibrium.q.iter().enumerate() {
        let wrapped = (q + std::f64::consts::PI).rem_euclid(2.0 * std::f64::consts::PI)
            - std::f64::consts::PI;
        assert!(wrapped.abs() < 1e-9, "q{} = {q} rad: not hanging", i + 1);
    }
    let (l1, m1, l2, m2, g): (f64, f64, f64, f64, f64) = (1.0, 1.0, 0.7, 0.5, 9.81);
    let (a11, a12, a22) = (
        m1 * l1 * l1 / 3.0 + m2 * l1 * l1,
        m2 * l1 * l2 / 2.0,
        m2 * l2 * l2 / 3.0,
    );
    let (k1, k2) = ((m1 / 2.0 + m2) * g * l1, m2 * g * l2 / 2.0);
    // det([[k1 − w a11, −w a12], [−w a12, k2 − w a22]]) = 0 in w = ω².
    let (a, b, c) = (a11 * a22 - a12 * a12, -(k1 * a22 + k2 * a11), k1 * k2);
    let d = (b * b - 4.0 * a * c).sqrt();
    let expected = [((-b - d) / (2.0 * a)).sqrt(), ((-b + d) / (2.0 * a)).sqrt()];
    let modes = &one.modes.modes;
    assert_eq!(modes.len(), 2, "{modes:?}");
    for (m, w) in modes.iter().zip(expected) {
        assert!(m.re.abs() < 1e-9 * w, "undamped: {m:?}");
        assert!(
            (m.im - w).abs() < 1e-9 * w,
            "ω = {} rad/s, expected {w}",
            m.im
        );
    }
}

/// Vehicle 1 at 30 m/s on straight track with every vertical damper (and
/// the contact's normal damping) set to zero, so that the vertical modes
/// are undamped and their |λ| is the undamped ω of the hand formulas.
fn vehicle1_undamped_vertical() -> (Scenario, Model) {
    scenario(
        "vehicle1_equilibrium_straight.ron",
        &[
            ("cz2", "0"),
            ("Bogie1.cz", "0"),
            ("Bogie2.cz", "0"),
            ("Bogie1.WS1.cn", "0"),
            ("Bogie1.WS2.cn", "0"),
            ("Bogie2.WS1.cn", "0"),
            ("Bogie2.WS2.cn", "0"),
        ],
    )
}

#[test]
fn vehicle1_car_body_bounces_and_pitches_at_the_hand_frequencies_of_its_suspension() {
    let (s, model) = vehicle1_undamped_vertical();
    let one = modes_of(&s, &model, Box::new(NumericEquations::new(&model)));
    let p = |n: &str| param(&model, &s, n);
    let (mc, icy, lb) = (p("mc"), p("Icy"), p("lb"));
    let (kz2, kx2, h2, hc) = (p("kz2"), p("kx2"), p("h2"), p("hc"));
    let (mf, kz) = (p("Bogie1.mf"), p("Bogie1.kz"));
    // Bounce: the car body (mc) on its four secondary springs (4 kz2) on
    // both bogie frames moving together (2 mf) on their eight primary
    // springs (8 kz); the wheelsets sit on the rails (contact stiffness
    // ~4e8 N/m per wheel against 1.2e6 N/m of primary: 0.3 % softer primary,
    // under 0.1 % on the car body's frequency).
    let (bounce, _) = two_mass_chain(mc, 4.0 * kz2, 2.0 * mf, 8.0 * kz);
    // Pitch: the car body's pitch θ moves the secondary springs at ±lb by
    // ±lb θ (u = lb θ: mass Icy/lb²), the bogie frames move oppositely
    // (2 mf on 8 kz); the longitudinal secondary springs at h2 − hc below
    // the centre of gravity add 4 kx2 (h2 − hc)² to the pitch stiffness
    // (0.3 %; the car body's longitudinal motion that it couples to is
    // held by the traction spring: a further 0.2 % at most).
    let (pitch, _) = two_mass_chain(
        icy / (lb * lb),
        4.0 * kz2 + 4.0 * kx2 * (h2 - hc).powi(2) / (lb * lb),
        2.0 * mf,
        8.0 * kz,
    );
    for (motion, w2) in [("body vertical", bounce), ("body pitch", pitch)] {
        let f_hand = w2.sqrt() / (2.0 * std::f64::consts::PI);
        let m = one
            .modes
            .modes
            .iter()
            .find(|m| m.name.starts_with(motion))
            .unwrap_or_else(|| panic!("no mode named {motion}: {:#?}", one.modes.modes));
        // 0.5 %: the contact's and the longitudinal coupling's effects
        // above, with margin.
        assert!(
            (m.natural_frequency - f_hand).abs() < 5e-3 * f_hand,
            "{motion}: {} Hz, by hand {f_hand} Hz",
            m.natural_frequency
        );
        // Undamped but for what the longitudinal dampers (traction hold,
        // primary cx) take through the pitch's longitudinal coupling.
        assert!(m.damping_ratio.abs() < 1e-2, "{motion} undamped: {m:?}");
    }
}

#[test]
fn vehicle1_linearizes_alike_with_both_engines() {
    // The same model through two engines: their A matrices agree to the
    // difference noise (ε |f| / h ≈ 2e-4 N/m against stiffnesses of 1e6 to
    // 1e9 N/m, divided by masses): 1e-6 of the largest entry.
    let (s, model) = scenario("vehicle1_equilibrium_straight.ron", &[]);
    let a = modes_of(&s, &model, Box::new(NumericEquations::new(&model)));
    let b = modes_of(&s, &model, Box::new(symbolic_engine(&model)));
    let (a, b) = (&a.linearization.a, &b.linearization.a);
    let scale = a.amax();
    assert!(
        (a - b).amax() < 1e-6 * scale,
        "{} of {scale}",
        (a - b).amax()
    );
}

#[test]
fn a_parallelogram_four_bar_closed_by_a_cut_joint_swings_as_a_compound_pendulum() {
    // fourbar.ron: crank and rocker of length a = 0.5 m (m1 = m3 = 1 kg),
    // coupler m2 = 2 kg translating without rotation: one degree of freedom,
    // a compound pendulum of inertia J = (m1 + m3) a²/3 + m2 a² about the
    // pivots under the gravity stiffness k = g a (m1/2 + m3/2 + m2), so
    // ω = √(k/J). The tree has three angles and the cut joint two
    // constraints: the linearization works on the constraint's tangent
    // space (one position, one rate) with the constraint forces' geometric
    // stiffness. Central differences of sin/cos terms with h = 1e-7 rad:
    // 1e-8 relative is rounding with margin.
    let (s, model) = scenario("fourbar.ron", &[]);
    let one = modes_of(&s, &model, Box::new(NumericEquations::new(&model)));
    assert_eq!(one.linearization.a.nrows(), 2);
    let (a, m1, m2, m3, g): (f64, f64, f64, f64, f64) = (0.5, 1.0, 2.0, 1.0, 9.81);
    let j = (m1 + m3) * a * a / 3.0 + m2 * a * a;
    let k = g * a * (m1 / 2.0 + m3 / 2.0 + m2);
    let omega = (k / j).sqrt();
    let modes = &one.modes.modes;
    assert_eq!(modes.len(), 1, "{modes:?}");
    assert!(modes[0].re.abs() < 1e-8 * omega, "{:?}", modes[0]);
    assert!(
        (modes[0].im - omega).abs() < 1e-8 * omega,
        "ω = {} rad/s, expected {omega}",
        modes[0].im
    );
}

/// `umsim modes --sweep k=…`'s locus over a parameter: the mass on a
/// spring at k = 100, 400, 900 N/m has ω = √(k/m) = 10, 20, 30 rad/s and
/// keeps ζ = 0.1 (its damper is 2 ζ √(k m)), to 1e-8 as above.
#[test]
fn a_sweep_over_a_parameter_follows_the_analytic_frequency() {
    use railmbs_runtime::analysis::speed::parameter_locus;
    let (s, model) = scenario("spring_mass.ron", &[]);
    let values = [100.0, 400.0, 900.0];
    let mut engine = || -> Result<Box<dyn Equations>, railmbs_runtime::run::RunError> {
        Ok(Box::new(NumericEquations::new(&model)))
    };
    let locus = parameter_locus(&s, &model, "k", &values, &mut engine).unwrap();
    for (one, k) in locus.iter().zip(values) {
        let m = &one.modes.modes[0];
        let omega = k.sqrt();
        assert!(
            (m.natural_frequency - omega / (2.0 * std::f64::consts::PI)).abs() < 1e-8 * omega,
            "k = {k}: {m:?}"
        );
        assert!((m.damping_ratio - 0.1).abs() < 1e-8, "k = {k}: {m:?}");
    }
    let mut engine = || -> Result<Box<dyn Equations>, railmbs_runtime::run::RunError> {
        Ok(Box::new(NumericEquations::new(&model)))
    };
    let err = parameter_locus(&s, &model, "stiffness", &values, &mut engine).unwrap_err();
    assert!(
        err.to_string().contains("no parameter \"stiffness\""),
        "{err}"
    );
}
