//! Static equilibrium (`initial_state: Equilibrium`, `umsim equilibrium`)
//! against statics by hand: a mass on a spring (mg/k), the wheel loads of
//! Manchester Vehicle 1 from the masses in its model file, and a run that
//! starts there and does not move.

use railmbs_models::{InitialStateKind, Model, Scenario, load_model, load_scenario};
use railmbs_runtime::analysis::equilibrium::{EquilibriumError, EquilibriumSettings, Role, solve};
use railmbs_runtime::analysis::{self, coordinates};
use railmbs_runtime::run::scenario::{ScenarioSystem, scenario_system};
use railmbs_runtime::{Equations, NumericEquations};
use railmbs_testkit::*;

/// The bundled scenario `file` (under models/scenarios) set to start from
/// its equilibrium, with `set` parameter overrides, and its model.
fn equilibrium_scenario(file: &str, set: &[(&str, &str)]) -> (Scenario, Model) {
    let mut scenario = load_scenario(&model_path(&format!("scenarios/{file}"))).unwrap();
    scenario.initial_kind = InitialStateKind::Equilibrium;
    for (name, value) in set {
        scenario.set_parameter(name, value);
    }
    let model = load_model(&scenario.model).unwrap();
    (scenario, model)
}

fn solved(scenario: &Scenario, model: &Model, engine: Box<dyn Equations>) -> ScenarioSystem {
    scenario_system(scenario, model, engine).unwrap_or_else(|e| panic!("{e}"))
}

fn param(model: &Model, name: &str) -> f64 {
    model.default_parameter_values()[model.parameter_index(name).unwrap()]
}

#[test]
fn a_mass_on_a_spring_settles_m_g_over_k_below_the_free_length() {
    // models/mechanisms/spring_mass.ron: m = 1 kg on k = 100 N/m of free
    // length L0 = 1 m hanging from the origin, so z = −(L0 + m g/k).
    let (scenario, model) = equilibrium_scenario("spring_mass.ron", &[("m", "2.5")]);
    let (m, k, g, l0) = (
        2.5,
        param(&model, "k"),
        param(&model, "g"),
        param(&model, "L0"),
    );
    let expected = -(l0 + m * g / k);
    for engine in [
        Box::new(NumericEquations::new(&model)) as Box<dyn Equations>,
        Box::new(symbolic_engine(&model)),
    ] {
        let s = solved(&scenario, &model, engine);
        let eq = s.equilibrium.unwrap();
        // The residual force is below 1e-9 of max(1, m g) = 2.5e-8 N, i.e.
        // 2.5e-10 m of spring extension at 100 N/m: 1e-9 m is safe and
        // still a millionth of the sag m g/k = 0.245 m.
        assert!(
            (eq.q[0] - expected).abs() < 1e-9,
            "z = {} m, expected {expected} m",
            eq.q[0]
        );
        assert_eq!(eq.roles, vec![Role::Position]);
        assert_eq!(eq.v, vec![0.0]);
    }
}

#[test]
fn a_body_without_support_has_no_equilibrium_and_the_error_names_it() {
    // A body on a vertical slide without any force element: its coordinate
    // is held, and gravity on it is unbalanced.
    let model = parse(
        r#"Model(name: "falling", parameters: {},
            bodies: [Body(name: "mass", mass: 3.0, inertia: (ixx: 1, iyy: 1, izz: 1),
                          joint: Prismatic(parent: "ground", axis: Z, coord: "z"))])"#,
    );
    let (mut system, q0, v0) = numeric_system(&model, &[]);
    let names = coordinates(&model, &system);
    let err = solve(
        &mut system,
        &names,
        0.0,
        &q0,
        &v0,
        &EquilibriumSettings::default(),
    )
    .unwrap_err();
    let EquilibriumError::Unbalanced { carriers } = &err else {
        panic!("expected an unbalanced force, got {err}")
    };
    assert!(
        carriers.len() == 1 && carriers[0].0 == "z" && (carriers[0].1 + 3.0 * 9.81).abs() < 1e-9,
        "{err}"
    );
    assert!(err.to_string().contains("no static equilibrium"), "{err}");
}

/// Statics of Vehicle 1 by hand, from models/vehicles/vehicle1.ron and its
/// components: the car body (mc = 32000 kg) rests on two bogies at ±lb,
/// symmetric, so each bogie carries mc/2; a bogie frame (mf = 2615 kg)
/// rests on two wheelsets at ±a, so each wheelset carries mc/4 + mf/2 and
/// its own mass mw = 1813 kg. On centred, symmetric wheelsets each wheel
/// carries half: Q = (mc/8 + mf/4 + mw/2) g = 5560.25 kg × 9.81 m/s² =
/// 54546.05 N, and the eight wheels the whole weight (mc + 2 mf + 4 mw) g.
fn vehicle1_hand_wheel_load(model: &Model) -> f64 {
    let g = param(model, "g");
    let mc = param(model, "mc");
    let mf = param(model, "Bogie1.mf");
    let mw = param(model, "Bogie1.WS1.m");
    (mc / 8.0 + mf / 4.0 + mw / 2.0) * g
}

fn assert_vehicle1_statics(s: &mut ScenarioSystem, model: &Model) {
    let eq = s.equilibrium.clone().unwrap();
    let loads = analysis::wheel_loads(&mut s.system, eq.t, &eq.q, &eq.v).unwrap();
    assert_eq!(loads.len(), 4);
    let q_hand = vehicle1_hand_wheel_load(model);
    let mut total = 0.0;
    for (name, w) in &loads {
        for (side, (q, _y)) in ["left", "right"].iter().zip(w.loads) {
            total += q;
            // Each wheel within 1e-5 (0.5 N): beyond the statics above,
            // the rolling wheels' creep forces (spin creepage, the traction
            // spring's 0.5 N) pitch the bogies by 3e-8 rad and move about
            // 0.1 N between leading and trailing wheelsets.
            assert!(
                (q - q_hand).abs() < 1e-5 * q_hand,
                "{name} {side}: Q = {q} N, by hand {q_hand} N"
            );
        }
        // Left and right alike on the symmetric vehicle, to rounding.
        assert!(
            (w.loads[0].0 - w.loads[1].0).abs() < 1e-9 * q_hand,
            "{name}: {:?}",
            w.loads
        );
    }
    // The sum is the weight, up to the residual vertical force allowed on
    // the seven vertical coordinates (7 × 0.02 N of 436 kN: 3e-7).
    assert!(
        (total - 8.0 * q_hand).abs() < 1e-6 * 8.0 * q_hand,
        "sum of Q {total} N, weight {} N",
        8.0 * q_hand
    );
    // Rolling: the wheels' spin rates are solved, every other coordinate
    // is at rest in its frame.
    for (i, c) in s.coordinates.iter().enumerate() {
        match eq.roles[i] {
            Role::Rate => {
                assert!(c.name.ends_with("ws.ry"), "{}", c.name);
                assert!(eq.v[i] > 0.0, "{}: {}", c.name, eq.v[i]);
            }
            Role::Position => assert_eq!(eq.v[i], 0.0, "{}", c.name),
            Role::Held => panic!("{} held: everything in Vehicle 1 has stiffness", c.name),
        }
    }
}

#[test]
fn vehicle1_wheel_loads_are_its_weight_distribution_by_hand() {
    let (scenario, model) = equilibrium_scenario("vehicle1_equilibrium_straight.ron", &[]);
    let mut numeric = solved(&scenario, &model, Box::new(NumericEquations::new(&model)));
    assert_vehicle1_statics(&mut numeric, &model);
    let mut symbolic = solved(&scenario, &model, Box::new(symbolic_engine(&model)));
    assert_vehicle1_statics(&mut symbolic, &model);
    // Both engines find the same state: positions within 1e-9 m (the
    // residual 0.02 N over the stiffest coordinate's 1e9 N/m is 2e-11 m).
    let (a, b) = (numeric.equilibrium.unwrap(), symbolic.equilibrium.unwrap());
    for (i, c) in numeric.coordinates.iter().enumerate() {
        if a.roles[i] == Role::Position {
            assert!(
                (a.q[i] - b.q[i]).abs() < 1e-9,
                "{}: {} vs {}",
                c.name,
                a.q[i],
                b.q[i]
            );
        }
    }
}

#[test]
fn vehicle1_wheel_loads_do_not_depend_on_the_primary_preload() {
    // Without the primary springs' preload the frames sink by
    // axlebox_load / kz = 45.65 kN / 1.22 MN/m = 3.7 cm; statics do not
    // care (the solve takes several capped Newton steps to get there).
    let (scenario, model) = equilibrium_scenario(
        "vehicle1_equilibrium_straight.ron",
        &[("Bogie1.axlebox_load", "0"), ("Bogie2.axlebox_load", "0")],
    );
    let mut s = solved(&scenario, &model, Box::new(NumericEquations::new(&model)));
    let eq = s.equilibrium.clone().unwrap();
    let z = s
        .coordinates
        .iter()
        .position(|c| c.name == "Bogie1.frame.z")
        .unwrap();
    let kz = param(&model, "Bogie1.kz");
    let sink = param(&model, "Bogie1.axlebox_load") / kz;
    // The frame sinks by the primary deflection (plus the car body's share
    // of nothing: the secondary keeps its preload), within 1 % (the
    // contact's own settlement, 2e-5 m, is 0.06 % of it).
    assert!(
        ((eq.q_start[z] - eq.q[z]) - sink).abs() < 0.01 * sink,
        "frame sank {} m, expected {sink} m",
        eq.q_start[z] - eq.q[z]
    );
    assert_vehicle1_statics(&mut s, &model);
}

#[test]
fn vehicle1_started_in_equilibrium_on_straight_track_does_not_move() {
    // models/scenarios/vehicle1_equilibrium_straight.ron: 0.1 s at 30 m/s
    // on perfect straight track; every coordinate but the wheels' spin
    // angles (which roll) stays within 1e-6 m (or rad) of its start. A
    // start 2e-5 m off equilibrium, as before, moves the wheelsets by that
    // much within milliseconds.
    let (scenario, model) = equilibrium_scenario("vehicle1_equilibrium_straight.ron", &[]);
    assert_eq!(
        load_scenario(&model_path("scenarios/vehicle1_equilibrium_straight.ron"))
            .unwrap()
            .initial_kind,
        InitialStateKind::Equilibrium
    );
    let t = run_to_table(&scenario, &model, Box::new(NumericEquations::new(&model)));
    let mut moved = 0.0f64;
    for c in &model.coordinates {
        if c.name.ends_with("ws.ry") {
            continue;
        }
        let col = t.col(&c.name);
        for x in &col {
            moved = moved.max((x - col[0]).abs());
        }
    }
    assert!(moved < 1e-6, "a coordinate moved by {moved} m");
    // And the wheel loads stay at their static values (0.01 %).
    let q_hand = vehicle1_hand_wheel_load(&model);
    for q in t.col("Bogie2.WS2.contact.L.Q [N]") {
        assert!((q - q_hand).abs() < 1e-4 * q_hand, "Q = {q} N");
    }
}

#[test]
fn two_bodies_joined_only_to_each_other_are_an_unconstrained_direction() {
    // Two sliders along x joined by a spring and nothing else: any common
    // translation is an equilibrium. Both coordinates have stiffness, the
    // Jacobian [[−k, k], [k, −k]] is singular, and the error names the
    // direction (1, 1).
    let model = parse(
        r#"Model(name: "pair", parameters: {}, gravity: (0, 0, 0),
            bodies: [
                Body(name: "a", mass: 1.0, inertia: (ixx: 1, iyy: 1, izz: 1),
                     joint: Prismatic(parent: "ground", axis: X, coord: "xa")),
                Body(name: "b", mass: 2.0, inertia: (ixx: 1, iyy: 1, izz: 1),
                     joint: Prismatic(parent: "ground", axis: X, coord: "xb", init: 1.5)),
            ],
            forces: [Spring(name: "s", body1: "a", point1: (0, 0, 0), body2: "b", point2: (0, 0, 0),
                            c: 100, d: 0, f0: 0, x0: 1.0)])"#,
    );
    let (mut system, q0, v0) = numeric_system(&model, &[]);
    let names = coordinates(&model, &system);
    let err = solve(
        &mut system,
        &names,
        0.0,
        &q0,
        &v0,
        &EquilibriumSettings::default(),
    )
    .unwrap_err();
    let EquilibriumError::Unconstrained { direction } = &err else {
        panic!("expected an unconstrained direction, got {err}")
    };
    let names: Vec<&str> = direction.iter().map(|(n, _)| n.as_str()).collect();
    assert_eq!(names.len(), 2, "{err}");
    assert!(names.contains(&"xa") && names.contains(&"xb"), "{err}");
    assert!((direction[0].1 - direction[1].1).abs() < 1e-9, "{err}");
    assert!(err.to_string().contains("no force resists"), "{err}");
}

/// Vehicle 1 coasting (its speed hold `k_traction`, `c_traction` set to
/// zero): nothing holds it along the track and the spin creep's rolling
/// resistance pushes it, so there is no steady state; the error says so,
/// naming the longitudinal coordinates, instead of "no equilibrium within
/// N iterations".
#[test]
fn a_coasting_vehicle_is_told_it_has_no_steady_state() {
    let (s, model) = equilibrium_scenario(
        "vehicle1_equilibrium_straight.ron",
        &[("k_traction", "0"), ("c_traction", "0")],
    );
    let err = match scenario_system(&s, &model, Box::new(NumericEquations::new(&model))) {
        Err(e) => e.to_string(),
        Ok(_) => panic!("a coasting vehicle has no steady state"),
    };
    assert!(err.contains("free along the track"), "{err}");
    assert!(
        err.contains("body.x") && err.contains("k_traction"),
        "{err}"
    );
    assert!(!err.contains("iterations"), "{err}");
}

/// Three Vehicle 1 coaches coupled (`train3_straight.ron`: couplers of
/// 2 MN/m longitudinally between the car bodies' ends, each coach with its
/// own speed hold) on level straight track, solved as one system of 126
/// coordinates: every wheel carries the single vehicle's hand statics
/// (`vehicle1_hand_wheel_load`, 54 546 N), as each coach's own equilibrium
/// repeated is a solution at which the couplers are at their free length
/// (the attachment points 13 m ahead and behind coincide for coaches 26 m
/// apart) and the solution is unique. The coupler forces are zero up to
/// what the force tolerance allows: a residual of 0.019 N on a car body's
/// x against its 1 MN/m speed hold moves two bodies apart by at most
/// 4e-8 m, 0.08 N in a 2 MN/m coupler; 0.1 N is asserted.
#[test]
fn a_train_of_three_vehicle1_coaches_settles_to_the_hand_statics_with_free_couplers() {
    let mut train =
        railmbs_models::load_train(&model_path("scenarios/train3_straight.ron")).unwrap();
    train.initial_kind = InitialStateKind::Equilibrium;
    let models: Vec<Model> = train
        .vehicles
        .iter()
        .map(|v| load_model(&v.model).unwrap())
        .collect();
    let refs: Vec<&Model> = models.iter().collect();
    let engines: Vec<Box<dyn Equations>> = models
        .iter()
        .map(|m| Box::new(NumericEquations::new(m)) as Box<dyn Equations>)
        .collect();
    let mut setup = railmbs_runtime::train::build_train(&train, &refs, engines)
        .unwrap_or_else(|e| panic!("{e}"));
    let eq = setup.equilibrium.clone().unwrap();
    assert_eq!(eq.q.len(), 126);
    assert_eq!(setup.coordinates[42].name, "Coach2.body.x");
    for (i, c) in setup.coordinates.iter().enumerate() {
        assert!(eq.roles[i] != Role::Held, "{} held", c.name);
    }
    let q_hand = vehicle1_hand_wheel_load(&models[0]);
    let loads = setup.system.wheel_loads(eq.t, &eq.q, &eq.v).unwrap();
    assert_eq!(loads.len(), 12);
    for (name, w) in &loads {
        for (side, (q, _y)) in ["left", "right"].iter().zip(w.loads) {
            // As for one vehicle (assert_vehicle1_statics): 1e-5.
            assert!(
                (q - q_hand).abs() < 1e-5 * q_hand,
                "{name} {side}: Q = {q} N, by hand {q_hand} N"
            );
        }
    }
    assert!(loads[4].0.starts_with("Coach2."), "{}", loads[4].0);
    let couplers = setup
        .system
        .named_coupler_outputs(eq.t, &eq.q, &eq.v)
        .unwrap();
    let forces: Vec<&(String, f64)> = couplers.iter().filter(|(n, _)| n.contains(".F")).collect();
    assert_eq!(forces.len(), 6, "{couplers:?}");
    for (name, f) in forces {
        assert!(f.abs() < 0.1, "{name} = {f} N");
    }
}
