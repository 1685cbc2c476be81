//! Wheelset variants: massless elastic rails (seed paper Sect. 4.2) and
//! independently rotating wheels, against physics.

mod common;

use common::*;
use railmbs_models::{IntegratorSpec, Scenario};
use railmbs_runtime::NumericEquations;

/// Loads a bundled scenario, applies `edit`, runs it with the numeric engine.
fn run_edited(path: &str, edit: impl FnOnce(&mut Scenario)) -> Table {
    let mut scenario = railmbs_models::load_scenario(&model_path(path)).unwrap();
    edit(&mut scenario);
    let model = railmbs_models::load_model(&scenario.model).unwrap();
    run_to_table(&scenario, &model, Box::new(NumericEquations::new(&model)))
}

/// Value of column `name` in the last row.
fn last(t: &Table, name: &str) -> f64 {
    *t.col(name).last().unwrap()
}

fn set_parameters(s: &mut Scenario, values: &[(&str, &str)]) {
    s.parameters = values
        .iter()
        .map(|(k, v)| (k.to_string(), v.to_string()))
        .collect();
}

/// The wheelset on springs standing (no running speed) on perfect straight
/// track, centred, with the vertical primary stiffness off so that each wheel
/// carries exactly its axlebox preload plus half the wheelset's weight:
/// Q = 45 650 + 1813·9.81/2 N. `extra` adds parameter overrides.
fn standing(path: &str, extra: &[(&str, &str)], end_time: f64) -> Table {
    run_edited(path, |s| {
        s.track.as_mut().unwrap().speed = 0.0;
        let mut p = vec![("v0", "0"), ("y0", "0"), ("kz", "0")];
        p.extend_from_slice(extra);
        set_parameters(s, &p);
        s.end_time = end_time;
        s.output.interval = 0.01;
        // Tight enough that the integration's error (a wobble of the vertical
        // mode at the size of atol times the 1e8 N/m support, ±10 N at the
        // scenario's atol = 1e-7 m) stays below 1e-6 of the wheel load.
        s.integrator = IntegratorSpec::Park {
            rtol: 1e-7,
            atol: 1e-10,
            max_step: 0.005,
            initial_step: None,
            jacobian: Default::default(),
        };
    })
}

/// Static wheel load of [`standing`], N.
const STANDING_Q: f64 = 45650.0 + 1813.0 * 9.81 / 2.0;
/// Rail support of `wheelset_on_springs_elastic_rail.ron`, N/m.
const KZ_RAIL: f64 = 100e6;
const KY_RAIL: f64 = 65e6;

/// A wheelset standing on elastic rails (released 0.24 mm above its
/// equilibrium) settles with each rail deflected downwards by Q/k_z, Q the
/// static wheel load. Tolerance 1e-6 relative: the static equilibrium is a
/// fixed point of the integration (no truncation error remains once the
/// vertical mode, 53 Hz with about a third of critical damping from the rail
/// dampers, has died out after 1 s), and the rail's force balance is solved
/// to 1 mN against 54.5 kN (2e-8).
#[test]
fn elastic_rails_settle_to_the_wheel_load_over_their_vertical_stiffness() {
    let t = standing(
        "scenarios/wheelset_elastic_rail_30.ron",
        &[("penetration", "0")],
        1.0,
    );
    let expected = -STANDING_Q / KZ_RAIL;
    for side in ["L", "R"] {
        let q = last(&t, &format!("contact.{side}.Q [N]"));
        let dz = last(&t, &format!("contact.{side}.rail_dz [m]"));
        println!(
            "{side}: Q {q:.3} N (expected {STANDING_Q:.3}), rail dz {:.6} mm (expected {:.6})",
            dz * 1e3,
            expected * 1e3
        );
        assert!(
            (q - STANDING_Q).abs() < 1e-6 * STANDING_Q,
            "{side}: Q {q} N"
        );
        assert!(
            (dz - expected).abs() < 1e-6 * expected.abs(),
            "{side}: rail deflection {dz} m, expected {expected} m"
        );
    }
}

/// The rail support in series with the Hertz contact: the wheelset on
/// elastic rails sits lower than on rigid rails by the rails' deflection
/// Q/k_z (the Hertz approach under the same load is the same), plus what the
/// rails' lateral spread d_y (a few µm: the 1:40 rails lean outwards under
/// load) does to the rolling contact: the wheel's contact moves by d_y across
/// the coned tread, lowering the axle by tan δ·d_y (δ the contact angle),
/// about 7e-4 of Q/k_z here. Tolerance 1e-4 of Q/k_z for what remains
/// (second order in d_y, the profiles' curvature); the static states
/// themselves are exact to the integration tolerance.
#[test]
fn elastic_rails_lower_the_wheelset_by_the_rail_deflection() {
    let rigid = standing("scenarios/wheelset_on_springs_30.ron", &[], 1.0);
    let elastic = standing(
        "scenarios/wheelset_elastic_rail_30.ron",
        &[("penetration", "0")],
        1.0,
    );
    let (z_rigid, z_elastic) = (last(&rigid, "ws.z"), last(&elastic, "ws.z"));
    let q_rigid = last(&rigid, "contact.L.Q [N]");
    let drop = z_rigid - z_elastic;
    let spread = last(&elastic, "contact.L.rail_dy [m]");
    let angle = last(&elastic, "contact.L.contact_angle [rad]");
    let series = STANDING_Q / KZ_RAIL;
    let expected = series + angle.tan() * spread;
    println!(
        "rigid: z {z_rigid:.9} m (Q {q_rigid:.2} N); elastic: z {z_elastic:.9} m; drop {:.6} mm; \
         Q/kz {:.6} mm, + tan δ·d_y ({:.4} rad, {:.2} µm) = {:.6} mm",
        drop * 1e3,
        series * 1e3,
        angle,
        spread * 1e6,
        expected * 1e3
    );
    assert!((q_rigid - STANDING_Q).abs() < 1e-6 * STANDING_Q);
    assert!(
        (drop - expected).abs() < 1e-4 * series,
        "drop {drop} m, expected {expected} m"
    );
}

/// A lateral force F on the axle of a standing wheelset (lateral primary
/// stiffness off, so that only the rails hold it) is balanced by the rails'
/// lateral supports: per rail k_y d_y equals the lateral force of the wheel on
/// the rail (the rails' dampers carry ≤ c_y ḋ_y, bounded from the output),
/// and in sum k_y (d_y,L + d_y,R) = F. Tolerance: 1 % of F covers the
/// dampers' share and the wheelset's lateral inertia while its contacts
/// creep sideways under the load (at standstill the creep forces are a
/// viscous regularisation, so the wheelset drifts slowly rather than
/// sticking); the measured residual is printed.
#[test]
fn elastic_rails_balance_a_lateral_axle_force() {
    let force = 20e3;
    let t = standing(
        "scenarios/wheelset_elastic_rail_30.ron",
        &[("ky", "0"), ("Fy", "20e3")],
        0.5,
    );
    let (dl, dr) = (
        last(&t, "contact.L.rail_dy [m]"),
        last(&t, "contact.R.rail_dy [m]"),
    );
    let (yl, yr) = (last(&t, "contact.L.Y [N]"), last(&t, "contact.R.Y [N]"));
    let total = KY_RAIL * (dl + dr);
    println!(
        "rail dy L {:.4} mm, R {:.4} mm: k_y Σd_y {total:.1} N against F {force} N; \
         Y L {yl:.1} N, R {yr:.1} N; k_y d_y L {:.1} N, R {:.1} N",
        dl * 1e3,
        dr * 1e3,
        KY_RAIL * dl,
        KY_RAIL * dr
    );
    assert!(
        (total - force).abs() < 0.01 * force,
        "k_y Σd_y {total} N, F {force} N"
    );
    // Per rail: the support force equals the wheel's lateral force on it
    // (Y is positive towards the field side: +y on the left, −y on the right).
    assert!((KY_RAIL * dl - yl).abs() < 0.01 * force, "left");
    assert!((KY_RAIL * dr + yr).abs() < 0.01 * force, "right");
}
