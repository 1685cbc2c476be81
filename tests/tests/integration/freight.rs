//! The freight car on two three-piece bogies
//! (models/vehicles/freight/freight_car.ron, Pogorelov 2005, Sect. 7.2):
//! statics from its equilibrium against hand calculations from the masses,
//! spring rates and wedge geometry in its model files.

use railmbs_models::{Model, Scenario, load_model, load_scenario};
use railmbs_runtime::NumericEquations;
use railmbs_testkit::*;

/// The bundled straight-track scenario of the freight car with `macros`
/// (replacing the scenario's), cut to its first output row: the state of
/// the equilibrium solve (frictionless: the contacts start sliding-free),
/// with every force element's outputs.
fn freight_start(macros: &[&str]) -> (Scenario, Model) {
    let mut scenario = load_scenario(&model_path("scenarios/freight_straight_loaded.ron")).unwrap();
    scenario.macros = macros.iter().map(|m| m.to_string()).collect();
    scenario.end_time = 1e-4;
    scenario.output.interval = 1e-4;
    scenario.output.forces = vec!["*".into()];
    // The contacts' start interference `pre` (0.1 mm, for the solve's
    // start) sets each wedge 0.24 mm lower on the bolster than its springs'
    // preload assumes, (1 + cos α)/sin α · pre: 1e-7 m keeps every contact
    // engaged and makes that offset negligible (0.24 µm).
    for b in ["Bogie1", "Bogie2"] {
        scenario.set_parameter(&format!("{b}.pre"), "1e-7");
    }
    scenario.set_parameter("pre", "1e-7");
    let model = load_model(&scenario.model).unwrap();
    (scenario, model)
}

fn value(model: &Model, scenario: &Scenario, name: &str) -> f64 {
    let values = scenario.parameter_values(model).unwrap();
    values[model.parameter_index(name).unwrap()]
}

/// Statics by hand (frictionless, as the equilibrium solve has it):
///
/// - The car is symmetric (body centre of mass midway between the bogies,
///   every part mirrored left–right and front–back), so each of the eight
///   wheels carries an eighth of the weight
///   (m_c + 2 (m_b + 2 m_sf + 4 m_w + 2 m_ws)) g.
/// - Bolster: the centre plate brings L = m_c g / 2; wedges ride with the
///   bolster, so the nest coils (2 n_b sets) and the wedge sets (4, variable
///   damping) are compressed alike by δ, and a wedge passes its spring force
///   less its weight to the bolster: 2 n_b k δ + 4 (k δ − m_w g) = L + m_b g,
///   δ = (L + m_b g + 4 m_w g)/((2 n_b + 4) k).
/// - Wedge (angle α between its vertical face and its inclined face):
///   horizontally the column plate's normal force N₁ balances the incline's
///   normal force N₂ cos α, vertically the spring force P = k δ less the
///   weight balances N₂ sin α, so N₁ = (P − m_w g) cot α.
fn check_statics(macros: &[&str]) {
    let (scenario, model) = freight_start(macros);
    let t = run_to_table(&scenario, &model, Box::new(NumericEquations::new(&model)));
    let v = |n: &str| value(&model, &scenario, n);
    let g = v("g");
    let (mc, mb, msf, mw, mws) = (
        v("mc"),
        v("Bogie1.mb"),
        v("Bogie1.msf"),
        v("Bogie1.mw"),
        v("Bogie1.mws"),
    );
    let weight = (mc + 2.0 * (mb + 2.0 * msf + 4.0 * mw + 2.0 * mws)) * g;
    let first = |col: &str| t.col(col)[0];
    let mut total = 0.0;
    for bogie in ["Bogie1", "Bogie2"] {
        for ws in ["WS1", "WS2"] {
            for side in ["L", "R"] {
                let q = first(&format!("{bogie}.{ws}.contact.{side}.Q [N]"));
                total += q;
                // 1e-4: beyond the statics above, the rolling wheels' creep
                // (spin creepage) and the wedges' small pitch move a few
                // newtons between wheels of 50–115 kN.
                assert!(
                    (q - weight / 8.0).abs() < 1e-4 * weight / 8.0,
                    "{macros:?} {bogie}.{ws} {side}: Q = {q} N, by hand {} N",
                    weight / 8.0
                );
            }
        }
    }
    assert!(
        (total - weight).abs() < 1e-5 * weight,
        "{macros:?}: sum of Q {total} N, weight {weight} N"
    );
    // Spring deflection and wedge spring forces.
    let (nb, ks) = (v("Bogie1.nb"), v("Bogie1.ks"));
    let (kout, kin) = (v("Bogie1.kout"), v("Bogie1.kin"));
    let load = mc * g / 2.0;
    let delta = (load + mb * g + 4.0 * mw * g) / ((2.0 * nb + 4.0) * ks);
    let p = ks * delta;
    for bogie in ["Bogie1", "Bogie2"] {
        for side in ["Left", "Right"] {
            // Fz is the force of the side frame on the bolster (body 2);
            // 1 %: the wedge contacts' own deflections (about 50 µm of the
            // wedge against the bolster, so its spring is compressed that
            // much more than the nest) against the empty car's 10 mm.
            for (coil, k) in [("Outer", kout), ("Inner", kin)] {
                let f = first(&format!("{bogie}.Nest{coil}{side}.Fz[N]"));
                let hand = nb * k * delta;
                assert!(
                    (f - hand).abs() < 1e-2 * hand,
                    "{macros:?} {bogie}.Nest{coil}{side}: {f} N, by hand {hand} N (δ = {delta} m)"
                );
            }
        }
        for w in ["W1", "W2", "W3", "W4"] {
            let f = first(&format!("{bogie}.{w}Spring.Fz[N]"));
            assert!(
                (f - p).abs() < 1e-2 * p,
                "{macros:?} {bogie}.{w}Spring: {f} N, by hand {p} N"
            );
        }
    }
}

#[test]
fn freight_car_loaded_statics_match_the_hand_calculation() {
    check_statics(&["open_wagon", "loaded"]);
}

#[test]
fn freight_car_empty_statics_match_the_hand_calculation() {
    check_statics(&["open_wagon", "empty"]);
}
