//! Wheelset variants: massless elastic rails (Pogorelov 2005, Sect. 4.2) and
//! independently rotating wheels, against physics.

use railmbs_models::{IntegratorSpec, Scenario};
use railmbs_runtime::NumericEquations;
use railmbs_testkit::*;

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
        s.integrator = tight_park();
    })
}

/// Park's method tight enough that the integration's error (a wobble of the
/// vertical mode at the size of atol times the 1e8 N/m support, ±10 N at the
/// scenarios' atol = 1e-7 m) stays below 1e-6 of the wheel load.
fn tight_park() -> IntegratorSpec {
    IntegratorSpec::Park {
        rtol: 1e-7,
        atol: 1e-10,
        max_step: 0.005,
        initial_step: None,
        jacobian: Default::default(),
        solver: Default::default(),
    }
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
/// about 7e-4 of Q/k_z here. That small correction takes d_y and δ from the
/// run's own outputs (the rails' balance of d_y is tested on its own below);
/// the main term Q/k_z is independent of the code. Tolerance 1e-4 of Q/k_z
/// for what remains (second order in d_y, the profiles' curvature); the
/// static states themselves are exact to the integration tolerance.
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

/// Primary suspension of the IRW comparison: yaw held by soft longitudinal
/// springs and dampers (0.5 MN/m and 15 kN s/m per axlebox, 1 m either side),
/// no lateral spring: only the wheel–rail forces centre the wheelset.
const YAW_SPRINGS: [(&str, &str); 4] = [("kx", "0.5e6"), ("cx", "15e3"), ("ky", "0"), ("cy", "0")];

/// The wheelset with independently rotating wheels on [`YAW_SPRINGS`],
/// released 2 mm off centre at 10 m/s on straight track, 6 s (60 m).
fn irw_released_off_centre() -> Table {
    run_edited("scenarios/wheelset_irw_off_centre.ron", |s| {
        let mut p = vec![("v0", "10.0"), ("y0", "0.002")];
        p.extend_from_slice(&YAW_SPRINGS);
        set_parameters(s, &p);
    })
}

/// Independently rotating wheels lose the kinematic oscillation: a solid
/// wheelset steers back to the centre through the longitudinal creep forces
/// of its rolling-radius difference, overshoots and runs Klingel's sinuous
/// motion; with each wheel free to spin there is no longitudinal creep force
/// (ξ = 0) and no steering moment, so the wheelset released 2 mm off centre
/// only drifts back on the gravitational stiffness of the profiles against
/// the lateral creep damping: no oscillation at all. Over 60 m (seven of
/// Klingel's wavelengths, 8 m at this amplitude: tests/wheelsets.rs) the IRW
/// wheelset's lateral displacement never crosses zero and decreases
/// monotonically after the release transient (0.3 s), while the solid
/// wheelset in the same suspension oscillates (five or more cycles).
#[test]
fn independently_rotating_wheels_do_not_run_the_kinematic_oscillation() {
    let irw = irw_released_off_centre();
    let (t, y) = (irw.col("time"), irw.col("WS.ws.y[m]"));
    let solid = run_edited("scenarios/wheelset_on_springs_30.ron", |s| {
        s.track.as_mut().unwrap().speed = 10.0;
        let mut p = vec![("v0", "10.0"), ("y0", "0.002")];
        p.extend_from_slice(&YAW_SPRINGS);
        set_parameters(s, &p);
        s.end_time = 6.0;
        s.output.interval = 0.005;
    });
    let solid_ups = up_crossings(&solid.col("time"), &solid.col("ws.y[m]"));
    let y_min = y.iter().cloned().fold(f64::INFINITY, f64::min);
    println!(
        "IRW: y from {:.3} mm to {:.3} mm, smallest {:.3} mm; solid: {} up-crossings at {:?} s",
        y[0] * 1e3,
        y.last().unwrap() * 1e3,
        y_min * 1e3,
        solid_ups.len(),
        solid_ups
    );
    assert!(solid_ups.len() >= 5, "the solid wheelset should oscillate");
    assert!(y_min > 0.0, "the IRW wheelset crossed the centre line");
    // Monotonic decrease after the release transient (1 nm for rounding).
    for i in 1..t.len() {
        if t[i - 1] >= 0.3 {
            assert!(y[i] <= y[i - 1] + 1e-9, "y rises at t = {} s", t[i]);
        }
    }
    assert!(
        *y.last().unwrap() < 0.5 * y[0],
        "no drift back to the centre"
    );
}

/// Each independently rotating wheel rolls at its own speed: in steady
/// running its longitudinal creepage vanishes and ω r equals the running
/// speed for its own rolling radius, so ω_L r_L = ω_R r_R although the
/// wheelset runs off centre with r_L ≠ r_R (a solid wheelset's common ω
/// would need ξ = ±(r_L − r_R)/(r_L + r_R), 7e-4 here). Tolerances over the
/// last 3 s: |ξ| < 1e-6 (the creep force left to turn the free wheels is
/// nil); ω_L r_L/(ω_R r_R) − 1 below 1e-4, a tenth of the solid wheelset's
/// 1.3e-3: the table's rolling radius is that of the undeformed contact,
/// while the wheels roll on radii shortened by their Hertz approaches (about
/// 0.1 mm each, 2e-4 of r, equal to within some percent between the wheels).
#[test]
fn independently_rotating_wheels_each_roll_at_their_own_speed() {
    let irw = irw_released_off_centre();
    let t = irw.col("time");
    let c = |name: &str| irw.col(&format!("WS.contact.{name}"));
    let (xi_l, xi_r) = (c("L.xi [-]"), c("R.xi [-]"));
    let (r_l, r_r) = (c("L.rolling_radius [m]"), c("R.rolling_radius [m]"));
    let (w_l, w_r) = (
        irw.col("WS.WheelL.wy[rad/s]"),
        irw.col("WS.WheelR.wy[rad/s]"),
    );
    let (mut xi_max, mut ratio_err, mut radius_diff) = (0.0_f64, 0.0_f64, f64::INFINITY);
    for i in (0..t.len()).filter(|&i| t[i] >= 3.0) {
        xi_max = xi_max.max(xi_l[i].abs()).max(xi_r[i].abs());
        ratio_err = ratio_err.max((w_l[i] * r_l[i] / (w_r[i] * r_r[i]) - 1.0).abs());
        radius_diff = radius_diff.min((r_l[i] / r_r[i] - 1.0).abs());
    }
    println!(
        "last 3 s: max |ξ| {xi_max:.2e}, max |ω_L r_L/(ω_R r_R) − 1| {ratio_err:.2e}, \
         smallest |r_L/r_R − 1| {radius_diff:.2e}"
    );
    assert!(xi_max < 1e-6, "ξ {xi_max}");
    assert!(radius_diff > 1e-3, "the wheelset should run off centre");
    assert!(ratio_err < 1e-4, "ω r ratio off by {ratio_err}");
}

/// In a curve each independently rotating wheel rolls at the speed of its
/// own path: in steady curving the wheelset turns about the curve's centre
/// at V/R, so a wheel whose contact lies y_c to the left of the track centre
/// line runs at V (R − y_c)/R (left curve), and with ξ = 0 its spin is that
/// over its rolling radius: ω_L r_L/(ω_R r_R) = (R − y_L)/(R − y_R), 0.5 %
/// below 1 in a left curve of R = 300 m, where a solid wheelset would have to
/// shift outwards for the rolling-radius difference to make it. Wheelset
/// guided by Manchester Vehicle 1's primary suspension to a frame that
/// follows the track; 10 m/s with the balancing cant (50 mm); means over
/// the last 4 s of 10 s in the circular curve. Tolerance 1e-4 (as on
/// straight track: the wheels roll on radii shortened by their Hertz
/// approaches) against the 5e-3 being measured.
#[test]
fn independently_rotating_wheels_roll_at_the_speed_of_their_own_path_in_a_curve() {
    let radius = 300.0;
    let dir = tempfile::tempdir().unwrap();
    let track = dir.path().join("curve_300.ron");
    std::fs::write(
        &track,
        "Custom((sections: [
            Straight(length: 60.0),
            Transition(length: 40.0, direction: Left, radius_end: Some(300.0), cant_end: 0.05),
            Curve(length: 300.0, radius: 300.0, direction: Left, cant: 0.05),
        ]))",
    )
    .unwrap();
    let t = run_edited("scenarios/wheelset_irw_off_centre.ron", |s| {
        let tr = s.track.as_mut().unwrap();
        tr.load_file(&track).unwrap();
        tr.start = 0.0;
        tr.speed = 10.0;
        // Manchester Vehicle 1's primary suspension (wheelset_on_springs.ron).
        set_parameters(
            s,
            &[
                ("v0", "10.0"),
                ("y0", "0"),
                ("kx", "31391e3"),
                ("ky", "3884e3"),
                ("cx", "15e3"),
                ("cy", "2e3"),
            ],
        );
        s.end_time = 20.0;
        s.output.interval = 0.01;
    });
    let time = t.col("time");
    let c = |name: &str| t.col(&format!("WS.contact.{name}"));
    let (y_l, y_r) = (c("L.contact_y [m]"), c("R.contact_y [m]"));
    let (r_l, r_r) = (c("L.rolling_radius [m]"), c("R.rolling_radius [m]"));
    let (xi_l, xi_r) = (c("L.xi [-]"), c("R.xi [-]"));
    let (w_l, w_r) = (t.col("WS.WheelL.wy[rad/s]"), t.col("WS.WheelR.wy[rad/s]"));
    let window: Vec<usize> = (0..time.len()).filter(|&i| time[i] >= 16.0).collect();
    let mean =
        |f: &dyn Fn(usize) -> f64| window.iter().map(|&i| f(i)).sum::<f64>() / window.len() as f64;
    let measured = mean(&|i| w_l[i] * r_l[i] / (w_r[i] * r_r[i]));
    let expected = mean(&|i| (radius - y_l[i]) / (radius - y_r[i]));
    let xi_max = window
        .iter()
        .fold(0.0_f64, |m, &i| m.max(xi_l[i].abs()).max(xi_r[i].abs()));
    println!(
        "ω_L r_L/(ω_R r_R) = {measured:.6}, (R − y_L)/(R − y_R) = {expected:.6}, max |ξ| {xi_max:.2e}"
    );
    assert!(1.0 - expected > 4e-3, "the paths should differ by 0.5 %");
    assert!(xi_max < 1e-6, "ξ {xi_max}");
    assert!(
        (measured - expected).abs() < 1e-4,
        "ω r ratio {measured}, path ratio {expected}"
    );
}

/// `wheels` naming the axle itself (a solid wheelset written as IRW) is
/// refused at loading, naming the field and the bodies.
#[test]
fn a_wheel_that_is_the_wheelset_is_refused() {
    let path = model_path("vehicles/components/wheelset_s1002_irw.ron");
    let text = std::fs::read_to_string(&path).unwrap().replace(
        "wheels: Some((\"WheelL\", \"WheelR\"))",
        "wheels: Some((\"ws\", \"WheelR\"))",
    );
    let err = railmbs_models::parse_model(&text, &path)
        .unwrap_err()
        .to_string();
    println!("{err}");
    assert!(
        err.contains("wheels") && err.contains("two different bodies") && err.contains("\"ws\""),
        "{err}"
    );
}

/// A contact damper along the normal together with elastic rails (whose
/// dampers already act in series with the Hertz spring) is refused with an
/// error naming the element and the field.
#[test]
fn normal_damping_with_elastic_rails_is_refused() {
    let path = model_path("vehicles/components/wheelset_on_springs_elastic_rail.ron");
    let text = std::fs::read_to_string(&path)
        .unwrap()
        .replace("normal_damping: 0,", "normal_damping: 2e5,");
    let model = railmbs_models::parse_model(&text, &path).unwrap();
    let scenario =
        railmbs_models::load_scenario(&model_path("scenarios/wheelset_elastic_rail_30.ron"))
            .unwrap();
    let engine = Box::new(NumericEquations::new(&model));
    let err = match railmbs_runtime::run::run_scenario(&scenario, &model, engine, None, |_| {}) {
        Err(e) => e.to_string(),
        Ok(summary) => format!("{:?}", summary.error),
    };
    println!("{err}");
    assert!(
        err.contains("\"contact\"") && err.contains("normal_damping must be 0"),
        "{err}"
    );
}

/// Newton's iterations converge on the analytic Jacobian with elastic rails:
/// the contact's normal stiffness there is the Hertz spring in series with
/// the rail support (K + C/h along the normal), not the much stiffer Hertz
/// spring alone, which overestimates the wheelset's vertical stiffness
/// several times, so that the iterations keep failing and the Jacobian is
/// rebuilt again and again. The wheelset on springs on elastic rails, 3 s at
/// 30 m/s from 3 mm off centre, with the analytic Jacobian: under 1.5 Newton
/// iterations per step and a handful of Jacobian evaluations (measured: 1148
/// steps, 90 rejected, 1.30 iterations per step, 3 Jacobians; with the Hertz
/// stiffness alone 2249 steps, 392 rejected, 41 Jacobians).
#[test]
fn newton_converges_on_the_analytic_jacobian_with_elastic_rails() {
    let s = run_with_jacobian(
        "scenarios/wheelset_elastic_rail_30.ron",
        railmbs_models::JacobianKind::Analytic,
    );
    let per_step = s.newton_iterations as f64 / (s.steps + s.rejected_steps) as f64;
    println!(
        "{} steps ({} rejected), {per_step:.2} Newton iterations per step, {} Jacobians",
        s.steps, s.rejected_steps, s.jacobian_evaluations
    );
    assert!(per_step < 1.5, "{per_step} Newton iterations per step");
    assert!(
        s.jacobian_evaluations <= 5,
        "{} Jacobians",
        s.jacobian_evaluations
    );
}

/// The creep forces of an independently rotating wheel follow its own spin:
/// the finite-difference Jacobian (which perturbs one wheel's spin rate
/// alone) sees the wheel's longitudinal creep damping, so Newton's
/// iterations converge and the Jacobian is seldom rebuilt. (When the
/// element reused its contact solution for unchanged axle kinematics, the
/// spin columns came out zero: 6779 steps, 2956 rejected, 1588 Jacobians.)
/// Measured: 2318 steps, 59 rejected, 3 Jacobians.
#[test]
fn the_finite_difference_jacobian_sees_each_wheels_spin() {
    let s = run_with_jacobian(
        "scenarios/wheelset_irw_off_centre.ron",
        railmbs_models::JacobianKind::FiniteDifference,
    );
    println!(
        "{} steps ({} rejected), {} Jacobians",
        s.steps, s.rejected_steps, s.jacobian_evaluations
    );
    assert!(
        s.jacobian_evaluations <= 10,
        "{} Jacobians",
        s.jacobian_evaluations
    );
    assert!(
        s.rejected_steps * 10 < s.steps,
        "{} rejected",
        s.rejected_steps
    );
}

/// Angular frequency (rad/s) of the oscillation of column `name` about the
/// middle of its range, from its up-crossings.
fn angular_frequency(t: &Table, name: &str) -> f64 {
    let (time, x) = (t.col("time"), t.col(name));
    let lo = x.iter().cloned().fold(f64::INFINITY, f64::min);
    let hi = x.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
    let mid = 0.5 * (lo + hi);
    let shifted: Vec<f64> = x.iter().map(|v| v - mid).collect();
    let ups = up_crossings(&time, &shifted);
    assert!(ups.len() >= 10, "too few cycles of {name}: {}", ups.len());
    let period = (ups[ups.len() - 1] - ups[0]) / (ups.len() - 1) as f64;
    2.0 * std::f64::consts::PI / period
}

/// The wheelset on springs at 30 m/s on straight track, centred, with no
/// vertical primary spring or damper, `extra` overrides, the vertical
/// coordinate started at `z0` if given; 0.3 s with steps of at most
/// `max_step` (s).
fn bounce(path: &str, extra: &[(&str, &str)], z0: Option<f64>, max_step: f64) -> Table {
    run_edited(path, |s| {
        let mut p = vec![("v0", "30.0"), ("y0", "0"), ("kz", "0"), ("cz", "0")];
        p.extend_from_slice(extra);
        set_parameters(s, &p);
        if let Some(z) = z0 {
            s.initial = vec![railmbs_models::InitialOverride {
                coordinate: "ws.z".into(),
                value: Some(z),
                velocity: None,
            }];
        }
        s.end_time = 0.3;
        s.output.interval = max_step.min(2e-4);
        s.integrator = IntegratorSpec::Park {
            rtol: 1e-6,
            atol: 1e-9,
            max_step,
            initial_step: None,
            jacobian: Default::default(),
            solver: Default::default(),
        };
    })
}

/// [`bounce`] on rigid rails without contact damping, released about 3 µm
/// above the equilibrium at z ≈ 0.459742 m (r0 less 0.258 mm).
fn rigid_bounce() -> Table {
    bounce(
        "scenarios/wheelset_on_springs_30.ron",
        &[("cn", "0")],
        Some(0.459745),
        2e-4,
    )
}

/// [`bounce`] on elastic rails with vertical rail damping `czr` (N s/m) and
/// no lateral one, started at r0 − 0.255 mm − Q/k_z (about 3 µm above the
/// equilibrium).
fn elastic_bounce(czr: &str, max_step: f64) -> Table {
    bounce(
        "scenarios/wheelset_elastic_rail_30.ron",
        &[("cyr", "0"), ("czr", czr), ("penetration", "2.55e-4")],
        None,
        max_step,
    )
}

/// Dynamics on elastic rails: the wheelset's vertical bounce on its two
/// contacts is a mass on springs in series, the Hertz contact (k_H, per
/// wheel) and the rail support (k_z), so its frequency on elastic rails ω_e
/// and on rigid rails ω_r satisfy 1/ω_e² − 1/ω_r² = m/(2 k_z), whatever
/// k_H. The wheelset on springs at 30 m/s on straight track, centred, with
/// no vertical primary spring or damper and no contact or rail dampers,
/// released about 3 µm above its equilibrium (1 % of the Hertz approach:
/// linear). Tolerance 0.5 %: Park's method at ω h ≤ 0.22 (steps ≤ 0.2 ms)
/// shifts the periods by less than 0.1 %; measured 0.07 %.
#[test]
fn elastic_rails_soften_the_vertical_bounce_as_springs_in_series() {
    // Rigid rails: equilibrium at z ≈ 0.459742 m (r0 less 0.258 mm).
    let rigid = rigid_bounce();
    let elastic = elastic_bounce("0", 2e-4);
    let (w_r, w_e) = (
        angular_frequency(&rigid, "ws.z[m]"),
        angular_frequency(&elastic, "ws.z[m]"),
    );
    let measured = 1.0 / (w_e * w_e) - 1.0 / (w_r * w_r);
    let expected = 1813.0 / (2.0 * KZ_RAIL);
    println!(
        "ω rigid {w_r:.2} rad/s, elastic {w_e:.2} rad/s: 1/ω_e² − 1/ω_r² = {measured:.5e} s², \
         m/(2 k_z) = {expected:.5e} s² ({:+.3} %)",
        100.0 * (measured / expected - 1.0)
    );
    assert!(
        (measured / expected - 1.0).abs() < 5e-3,
        "{measured} vs {expected}"
    );
}

/// Decay rate σ (1/s) and damped angular frequency ω_d (rad/s) of the
/// oscillation of column `name` about its final value: σ from the first and
/// fourth peak, ω_d from the up-crossings between them.
fn decay_and_frequency(t: &Table, name: &str) -> (f64, f64) {
    let (time, x) = (t.col("time"), t.col(name));
    let end = *x.last().unwrap();
    let d: Vec<f64> = x.iter().map(|v| v - end).collect();
    let peaks: Vec<usize> = (1..d.len() - 1)
        .filter(|&i| d[i] > 0.0 && d[i] > d[i - 1] && d[i] >= d[i + 1])
        .collect();
    let ups = up_crossings(&time, &d);
    assert!(peaks.len() >= 4 && ups.len() >= 4, "too few cycles");
    let (i0, i3) = (peaks[0], peaks[3]);
    let sigma = (d[i0] / d[i3]).ln() / (time[i3] - time[i0]);
    let omega = 3.0 * 2.0 * std::f64::consts::PI / (ups[3] - ups[0]);
    (sigma, omega)
}

/// The complex root (σ, ω) with s = −σ + iω of the cubic
/// s³ + a s² + b s + c = 0 with one real root (found by Newton's method from
/// s = −a, then deflated).
fn complex_root_of_cubic(a: f64, b: f64, c: f64) -> (f64, f64) {
    let mut s = -a;
    for _ in 0..200 {
        let f = ((s + a) * s + b) * s + c;
        let df = (3.0 * s + 2.0 * a) * s + b;
        s -= f / df;
    }
    // s² + p s + q = cubic / (s − real root).
    let p = a + s;
    let q = b + p * s;
    (0.5 * p, (q - 0.25 * p * p).sqrt())
}

/// The rail damper acts through the Hertz spring: on elastic rails with
/// vertical damping c_z the wheelset's bounce (mass m on two contacts, each
/// the Hertz spring k_H in series with k_z ∥ c_z on a massless rail) decays
/// as the complex root of m s² + 2 k_H (k_z + c_z s)/(k_H + k_z + c_z s) = 0,
/// i.e. m c_z s³ + m (k_H + k_z) s² + 2 k_H c_z s + 2 k_H k_z = 0, with k_H
/// = m ω_r²/2 from the bounce on rigid rails. The damper's rate is backward
/// Euler from the rail displacement of the last accepted step, first-order
/// accurate: the errors in σ and ω_d halve with the step (measured 0.75 %
/// and 0.48 % at 0.1 ms, 0.39 % and 0.24 % at 0.05 ms). Tolerances: 1 % at
/// 0.05 ms, and an error ratio between the two steps of 1.6 to 2.6.
#[test]
fn the_rail_damper_decays_the_bounce_as_springs_and_damper_in_series() {
    let m = 1813.0;
    let cz = 2e5;
    let w_r = angular_frequency(&rigid_bounce(), "ws.z[m]");
    let k_h = m * w_r * w_r / 2.0;
    let (sigma, omega) = complex_root_of_cubic(
        (k_h + KZ_RAIL) / cz,
        2.0 * k_h / m,
        2.0 * k_h * KZ_RAIL / (m * cz),
    );
    let mut errors = Vec::new();
    for max_step in [1e-4, 5e-5] {
        let (s, w) = decay_and_frequency(&elastic_bounce("2e5", max_step), "ws.z[m]");
        let (es, ew) = (s / sigma - 1.0, w / omega - 1.0);
        println!(
            "max step {max_step:e} s: σ {s:.3} 1/s ({:+.2} %), ω_d {w:.3} rad/s ({:+.2} %); \
             expected σ {sigma:.3}, ω_d {omega:.3}",
            100.0 * es,
            100.0 * ew
        );
        errors.push((es, ew));
    }
    let (coarse, fine) = (errors[0], errors[1]);
    assert!(fine.0.abs() < 0.01 && fine.1.abs() < 0.01, "{fine:?}");
    for (c, f) in [(coarse.0, fine.0), (coarse.1, fine.1)] {
        let ratio = c / f;
        assert!(
            (1.6..2.6).contains(&ratio),
            "error ratio {ratio} (first order: 2)"
        );
    }
}

/// As [`elastic_rails_balance_a_lateral_axle_force`], with the wheelset
/// pushed by 40 kN from 6.5 mm off centre onto its left flange root (contact
/// angle about 20° against the tread's 1.4°, the left wheel carrying 78 kN
/// along its normal): the rails' lateral supports still carry F,
/// k_y (d_y,L + d_y,R) = F within 1 % (same reasons as there). On this
/// steep part of the profile the rail's Newton iterations need the
/// finite-difference fallback of `elastic_rail::solve`.
#[test]
fn elastic_rails_balance_a_lateral_axle_force_on_the_flange_root() {
    let force = 40e3;
    let t = run_edited("scenarios/wheelset_elastic_rail_30.ron", |s| {
        s.track.as_mut().unwrap().speed = 0.0;
        set_parameters(
            s,
            &[
                ("v0", "0"),
                ("y0", "0.0065"),
                ("kz", "0"),
                ("ky", "0"),
                ("Fy", "40e3"),
            ],
        );
        s.end_time = 0.5;
        s.output.interval = 0.01;
        s.integrator = tight_park();
    });
    let (dl, dr) = (
        last(&t, "contact.L.rail_dy [m]"),
        last(&t, "contact.R.rail_dy [m]"),
    );
    let angle = last(&t, "contact.L.contact_angle [rad]");
    let total = KY_RAIL * (dl + dr);
    println!(
        "left contact angle {angle:.3} rad; rail dy L {:.4} mm, R {:.4} mm: k_y Σd_y {total:.1} N \
         against F {force} N",
        dl * 1e3,
        dr * 1e3
    );
    assert!(angle > 0.3, "not on the flange root: {angle} rad");
    assert!(
        (total - force).abs() < 0.01 * force,
        "k_y Σd_y {total} N, F {force} N"
    );
}

/// Runs a bundled scenario (no output file) with Park's Jacobian of `kind`;
/// returns the run's summary.
fn run_with_jacobian(
    scenario: &str,
    kind: railmbs_models::JacobianKind,
) -> railmbs_runtime::run::RunSummary {
    let mut scenario = railmbs_models::load_scenario(&model_path(scenario)).unwrap();
    if let IntegratorSpec::Park { jacobian, .. } = &mut scenario.integrator {
        *jacobian = kind;
    }
    let model = railmbs_models::load_model(&scenario.model).unwrap();
    let engine = Box::new(NumericEquations::new(&model));
    let s = railmbs_runtime::run::run_scenario(&scenario, &model, engine, None, |_| {}).unwrap();
    assert!(s.error.is_none(), "{:?}", s.error);
    s
}
