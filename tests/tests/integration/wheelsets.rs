//! Wheelsets on the track with wheel–rail contact: physics oracles.

use railmbs_runtime::NumericEquations;
use railmbs_testkit::*;
use railmbs_wheelrail::conicity::{RollTreatment, conicity_curve};
use railmbs_wheelrail::geometry::{ContactGeometry, SearchSettings, Track, Wheelset};
use railmbs_wheelrail::profile::{Profile, ProfileKind, ProfileSettings};

/// A free wheelset (S1002 on UIC60 1:40, no suspension) released 2 mm off
/// centre runs Klingel's kinematic oscillation: wavelength
/// λ = 2π √(r0 e0 / tan γe), with tan γe the EN 15302 equivalent conicity at
/// the oscillation's amplitude (profile pair strongly nonlinear: the
/// amplitude is measured over the same cycles as the wavelength). Tolerance
/// 3 % (the issue's): Klingel's formula is the kinematic limit (no creep
/// compliance, no gravitational stiffness), which at 10 m/s and this
/// conicity shifts the wavelength by about 1 %.
#[test]
fn free_wheelset_runs_klingels_kinematic_oscillation() {
    klingel_check(None);
}

/// Klingel's wavelength is the kinematic limit: any creep law with Kalker's
/// linear coefficients at small creepage gives it (within the same 3 %), here
/// Polach's law and FastSim_A with integrated sliding zones chosen in the
/// model language.
#[test]
fn klingel_holds_for_polach_and_integrated_fastsim_a() {
    use railmbs_models::{CreepLawSpec, Expr, SlidingZone};
    klingel_check(Some(CreepLawSpec::Polach {
        ka: Expr::Num(1.0),
        ks: Expr::Num(1.0),
        friction_decrease: None,
    }));
    klingel_check(Some(CreepLawSpec::FastsimA {
        strips: 10,
        sliding: SlidingZone::Integrated { nodes: 8 },
    }));
}

/// Runs the Klingel scenario (with the wheel–rail creep law replaced by
/// `law`) and checks the wavelength.
fn klingel_check(law: Option<railmbs_models::CreepLawSpec<railmbs_models::Expr>>) {
    let speed = 10.0;
    let scenario =
        railmbs_models::load_scenario(&model_path("scenarios/free_wheelset_klingel.ron")).unwrap();
    let mut model = railmbs_models::load_model(&scenario.model).unwrap();
    if let Some(law) = &law {
        for f in &mut model.forces {
            if let railmbs_models::ForceKind::WheelRail(w) = &mut f.kind {
                w.creep = law.clone();
            }
        }
    }
    let out = run_to_table(&scenario, &model, Box::new(NumericEquations::new(&model)));
    let (t, y) = (out.col("time"), out.col("ws.y"));
    let ups = up_crossings(&t, &y);
    assert!(ups.len() >= 5, "too few cycles: {ups:?}");
    // The last three full cycles.
    let (t0, t1) = (ups[ups.len() - 4], ups[ups.len() - 1]);
    let period = (t1 - t0) / 3.0;
    let wavelength = speed * period;
    let amplitude = t
        .iter()
        .zip(&y)
        .filter(|(tt, _)| **tt >= t0 && **tt <= t1)
        .fold(0.0_f64, |m, (_, yy)| m.max(yy.abs()));

    let profiles = model_path("profiles");
    let s = ProfileSettings::default();
    let wheel = Profile::read(
        &profiles.join("MBench_S1002_v3.prw"),
        ProfileKind::Wheel,
        &s,
    )
    .unwrap();
    let rail = Profile::read(&profiles.join("MBench_UIC60_v3.ban"), ProfileKind::Rail, &s).unwrap();
    let geo = ContactGeometry::new(
        &Wheelset::new(wheel.clone(), wheel, 0.46, 1.360),
        &Track::new(rail.clone(), rail, 1.435),
        SearchSettings::default(),
    )
    .unwrap();
    let centre = geo.rigid(0.0).unwrap();
    let e0 = 0.5 * (centre.sides[0].deepest().rail_y - centre.sides[1].deepest().rail_y);
    let conicity = conicity_curve(&geo, &[amplitude], RollTreatment::Neglected).unwrap()[0].1;
    let klingel = 2.0 * std::f64::consts::PI * (0.46 * e0 / conicity).sqrt();
    let err = (wavelength - klingel).abs() / klingel;
    println!(
        "{law:?}: amplitude {:.3} mm, tan γe {conicity:.4}, e0 {e0:.4} m: simulated {wavelength:.3} m, \
         Klingel {klingel:.3} m, error {:.2} %",
        amplitude * 1e3,
        100.0 * err
    );
    assert!(err < 0.03, "wavelength error {:.2} %", 100.0 * err);
}

/// Mass of Manchester Vehicle 1 carried by its wheels (car body, two bogie
/// frames, four wheelsets), kg.
const VEHICLE1_MASS: f64 = 32000.0 + 2.0 * 2615.0 + 4.0 * 1813.0;

/// Runs Vehicle 1 through the 1200 m curve with 150 mm cant at `speed` and
/// returns the means over the car body's arc positions 500–800 m (whole
/// vehicle in the circular curve) of the total track-shifting force ΣY (N,
/// positive to the left) and of the left and right wheel loads (N).
fn vehicle1_in_the_1200_m_curve(speed: f64) -> (f64, f64, f64) {
    let mut scenario =
        railmbs_models::load_scenario(&model_path("scenarios/vehicle1_curve_1200.ron")).unwrap();
    let track = scenario.track.as_mut().unwrap();
    track.speed = speed;
    scenario.parameters = vec![("v0".into(), format!("{speed:?}"))];
    scenario.end_time = (800.0 - track.start) / speed + 0.1;
    scenario.output.interval = 0.05;
    let model = railmbs_models::load_model(&scenario.model).unwrap();
    let t = run_to_table(&scenario, &model, Box::new(NumericEquations::new(&model)));
    let s = t.col("s[m]");
    let sum = |name: &str| -> Vec<f64> {
        let mut acc = vec![0.0; s.len()];
        for b in 1..=2 {
            for w in 1..=2 {
                for (a, v) in acc
                    .iter_mut()
                    .zip(t.col(&format!("Bogie{b}.WS{w}.contact.{name}")))
                {
                    *a += v;
                }
            }
        }
        acc
    };
    let window: Vec<usize> = (0..s.len())
        .filter(|&i| (500.0..=800.0).contains(&s[i]))
        .collect();
    assert!(window.len() > 20);
    let mean = |v: &[f64]| window.iter().map(|&i| v[i]).sum::<f64>() / window.len() as f64;
    (
        mean(&sum("SumY [N]")),
        mean(&sum("L.Q [N]")),
        mean(&sum("R.Q [N]")),
    )
}

/// Steady curving at the balancing speed v = √(g R tan φ) of the 1200 m
/// curve with 150 mm cant: the resultant of gravity and centrifugal force is
/// normal to the track plane, so the vehicle's total lateral force on the
/// track vanishes and the left and right wheel loads are equal. Tolerances:
/// 1 % of the vehicle's weight component m g sin φ for ΣY (the curving
/// wheelsets' creep forces are internal); 5 % for the loads: to steer, the
/// wheelsets run up to 3 mm towards the outer rail, where S1002 on UIC60
/// 1:40 moves the contact points asymmetrically (0.757 m and −0.740 m from
/// the track centre instead of ±0.753 m), so each wheelset's moment balance
/// puts about 3 % more load on the outer wheel; the simulation gives 4.3 %.
#[test]
fn vehicle1_at_the_balancing_speed_loads_both_rails_equally() {
    let (g, radius, cant, e2): (f64, f64, f64, f64) = (9.81, 1200.0, 0.150, 1.5);
    let phi = (cant / e2).asin();
    let speed = (g * radius * phi.tan()).sqrt();
    let (sum_y, ql, qr) = vehicle1_in_the_1200_m_curve(speed);
    let weight_in_plane = VEHICLE1_MASS * g * phi.sin();
    println!("v = {speed:.2} m/s: ΣY {sum_y:.0} N, Q left {ql:.0} N, right {qr:.0} N");
    assert!(sum_y.abs() < 0.01 * weight_in_plane, "ΣY {sum_y} N");
    assert!(
        (ql - qr).abs() < 0.05 * 0.5 * (ql + qr),
        "loads {ql} / {qr} N"
    );
}

/// Steady curving with cant deficiency (45 m/s in the same curve): the total
/// lateral force of the wheels on the track equals the vehicle's mass times
/// the uncompensated acceleration in the track plane,
/// m (v²/R cos φ − g sin φ) (outwards, to the right in this left curve), and
/// the total wheel load m (g cos φ + v²/R sin φ). Tolerance 1 % (suspension
/// and creep forces are internal; what remains is the quasi-static state's
/// residual motion).
#[test]
fn vehicle1_with_cant_deficiency_pushes_the_track_by_m_times_the_uncompensated_acceleration() {
    let (g, radius, cant, e2, speed): (f64, f64, f64, f64, f64) = (9.81, 1200.0, 0.150, 1.5, 45.0);
    let phi = (cant / e2).asin();
    let (sum_y, ql, qr) = vehicle1_in_the_1200_m_curve(speed);
    let centripetal = speed * speed / radius;
    let lateral = -VEHICLE1_MASS * (centripetal * phi.cos() - g * phi.sin());
    let normal = VEHICLE1_MASS * (g * phi.cos() + centripetal * phi.sin());
    println!(
        "ΣY {sum_y:.0} N (expected {lateral:.0}), ΣQ {:.0} N (expected {normal:.0})",
        ql + qr
    );
    assert!(
        (sum_y - lateral).abs() < 0.01 * lateral.abs(),
        "ΣY {sum_y} vs {lateral} N"
    );
    assert!(
        (ql + qr - normal).abs() < 0.01 * normal,
        "ΣQ {} vs {normal} N",
        ql + qr
    );
    assert!(qr > ql, "the outer (right) wheels carry more");
}

/// A symmetric vehicle started centred on perfect straight track stays
/// centred: no lateral motion appears from nothing (left/right symmetry of
/// the model, the contact table and the creep forces).
#[test]
fn vehicle1_on_perfect_straight_track_stays_centred() {
    let mut scenario =
        railmbs_models::load_scenario(&model_path("scenarios/vehicle1_tc1.ron")).unwrap();
    let track = scenario.track.as_mut().unwrap();
    track.load_file(&model_path("tracks/straight.ron")).unwrap();
    track.speed = 30.0;
    scenario.parameters = vec![("v0".into(), "30.0".into())];
    scenario.end_time = 3.0;
    scenario.output.coordinates = true;
    let model = railmbs_models::load_model(&scenario.model).unwrap();
    let t = run_to_table(&scenario, &model, Box::new(NumericEquations::new(&model)));
    let mut worst: f64 = 0.0;
    for c in model
        .coordinates
        .iter()
        .filter(|c| c.name.ends_with(".y") || c.name.ends_with(".rz"))
    {
        worst = t.col(&c.name).iter().fold(worst, |m, v| m.max(v.abs()));
    }
    // Rounding only: lateral displacements and yaw below 1e-9 (m, rad).
    assert!(
        worst < 1e-9,
        "largest lateral displacement or yaw {worst:e}"
    );
}

/// A coasting free wheelset loses energy only through its contacts: after the
/// release transient, the drop of its mechanical energy (translation,
/// rotation, potential energy of its weight and of the constant axle load,
/// elastic energy of the Hertz contacts) equals the integral of the power the wheel–rail element reports as
/// dissipated (creep forces against the creepages, V·(F_x ξ + F_y η + M_z φ),
/// plus the normal damper). The wheelset hunts (Klingel) and slows down by
/// itself: nothing holds its speed.
#[test]
fn coasting_wheelset_loses_energy_only_through_its_contacts() {
    let scenario =
        railmbs_models::load_scenario(&model_path("scenarios/free_wheelset_klingel.ron")).unwrap();
    // From t = 1 s (the vertical release transient has decayed) to the end.
    // What is not exact: each time a wheel's contact point jumps across the
    // S1002 tread (about 10 mm, near the centred position), the table's gap —
    // linear in roll within a 2 mrad cell — and the lever arm of the jumped
    // point disagree, and the balance steps by up to ~0.4 J; the steps
    // alternate in sign. Measured: 3 % net over 5 s, 6 % at worst on the way.
    // (Before the overswing was placed where the wheel's normal is the rail's,
    // the rolling did work against the normal force: 22 % net and growing.)
    assert_balance(
        "free wheelset",
        energy_balance(scenario, 1.0),
        (5.0, 0.05, 0.08),
    );
}

/// The assessment judges Y/Q and ΣY as 2 m sliding means (EN 14363); a run
/// shorter than the window (here 0.05 s at 30 m/s: 1.5 m) has no mean, and
/// then its peaks carry the limits, so no run goes unjudged.
#[test]
fn short_runs_judge_the_peaks() {
    let mut scenario =
        railmbs_models::load_scenario(&model_path("scenarios/wheelset_on_springs_30.ron")).unwrap();
    let model = railmbs_models::load_model(&scenario.model).unwrap();
    let run = |scenario: &railmbs_models::Scenario| {
        let dir = tempfile::tempdir().unwrap();
        let summary = railmbs_runtime::run::run_scenario(
            scenario,
            &model,
            Box::new(NumericEquations::new(&model)),
            Some(&dir.path().join("out.csv")),
            |_| {},
        )
        .unwrap();
        assert!(summary.error.is_none(), "{:?}", summary.error);
        summary.assessment
    };
    let limited = |rows: &[railmbs_runtime::forces::Assessment], q: &str| {
        rows.iter()
            .find(|a| a.quantity == q)
            .unwrap_or_else(|| panic!("no row {q}"))
            .limit
            .is_some()
    };
    let long = run(&scenario);
    assert!(limited(&long, "Y/Q left (2 m)") && !limited(&long, "Y/Q left peak"));
    assert!(limited(&long, "|ΣY| (2 m)") && !limited(&long, "|ΣY| peak"));
    scenario.end_time = 0.05;
    let short = run(&scenario);
    assert!(short.iter().all(|a| !a.quantity.contains("(2 m)")));
    assert!(limited(&short, "Y/Q left peak") && limited(&short, "|ΣY| peak"));
    // The wheel loads' minimum is reported (wheel unloading, 0 at a lift).
    let q_min = short.iter().find(|a| a.quantity == "Q left min").unwrap();
    assert!(q_min.max > 0.0);
}

/// Mechanical energy (kinetic energy of all bodies, potential energy of
/// gravity and of constant applied forces, the elastic energies the force
/// elements report: outputs `E[J]`, `Eel [J]`) and the dissipated power the
/// elements report (`P[W]`, `P [W]`) at every output row of a run of `model`.
pub(crate) fn energy_and_dissipation(
    model: &railmbs_models::Model,
    params: &[f64],
    out: &Table,
) -> (Vec<f64>, Vec<f64>) {
    use nalgebra::{Matrix3, Rotation3, Vector3};
    use railmbs_models::{ForceKind, VectorFrame};
    let c = |n: &str| out.col(n);
    let rows = out.col("time").len();
    let g = Vector3::from_iterator(model.gravity.iter().map(|e| e.eval(params, 0.0)));
    let mut energy = vec![0.0; rows];
    let mut poses = Vec::new();
    for body in &model.bodies {
        let n = &body.name;
        let m = body.mass.eval(params, 0.0);
        let i: Vec<f64> = body.inertia.iter().map(|e| e.eval(params, 0.0)).collect();
        let inertia = Matrix3::new(i[0], i[3], i[4], i[3], i[1], i[5], i[4], i[5], i[2]);
        let v3 = |a: &str, b: &str, cc: &str| {
            let (x, y, z) = (
                c(&format!("{n}.{a}")),
                c(&format!("{n}.{b}")),
                c(&format!("{n}.{cc}")),
            );
            (0..rows)
                .map(|k| Vector3::new(x[k], y[k], z[k]))
                .collect::<Vec<_>>()
        };
        let (r, v) = (
            v3("x[m]", "y[m]", "z[m]"),
            v3("vx[m/s]", "vy[m/s]", "vz[m/s]"),
        );
        let (w, ang) = (
            v3("wx[rad/s]", "wy[rad/s]", "wz[rad/s]"),
            v3("rx[rad]", "ry[rad]", "rz[rad]"),
        );
        let rot: Vec<Rotation3<f64>> = ang
            .iter()
            .map(|a| {
                // xyz Cardan angles: R = Rx Ry Rz.
                Rotation3::from_axis_angle(&Vector3::x_axis(), a.x)
                    * Rotation3::from_axis_angle(&Vector3::y_axis(), a.y)
                    * Rotation3::from_axis_angle(&Vector3::z_axis(), a.z)
            })
            .collect();
        for k in 0..rows {
            let wb = rot[k].transpose() * w[k];
            energy[k] +=
                0.5 * m * v[k].norm_squared() + 0.5 * wb.dot(&(inertia * wb)) - m * g.dot(&r[k]);
        }
        poses.push((r, rot));
    }
    // Constant forces given in SC0 (dead loads): potential −F·r of their point.
    for f in &model.forces {
        if let ForceKind::Applied(railmbs_models::forces::Applied {
            body,
            point,
            force,
            torque,
            frame: VectorFrame::Global,
        }) = &f.kind
        {
            let ev = |e: &[railmbs_models::Expr; 3]| {
                Vector3::new(
                    e[0].eval(params, 0.0),
                    e[1].eval(params, 0.0),
                    e[2].eval(params, 0.0),
                )
            };
            assert!(
                [force, torque]
                    .iter()
                    .all(|e| !e.iter().any(|x| x.has_time()))
                    && ev(torque) == Vector3::zeros(),
                "{}: only constant forces have a potential",
                f.name
            );
            let (r, rot) = &poses[*body];
            for k in 0..rows {
                energy[k] -= ev(force).dot(&(r[k] + rot[k] * ev(point)));
            }
        }
    }
    let mut power = vec![0.0; rows];
    for h in &out.header {
        if h.ends_with(".E[J]") || h.ends_with(".Eel [J]") {
            for (e, x) in energy.iter_mut().zip(c(h)) {
                *e += x;
            }
        }
        if h.ends_with(".P[W]") || h.ends_with(".P [W]") {
            for (p, x) in power.iter_mut().zip(c(h)) {
                *p += x;
            }
        }
    }
    (energy, power)
}

/// Checks an energy balance (lost, dissipated, largest gap, J): at least
/// `min` J dissipated, the net gap below `net` and the largest below `worst`
/// (fractions of the dissipated energy).
pub(crate) fn assert_balance(
    name: &str,
    (lost, dissipated, gap): (f64, f64, f64),
    (min, net, worst): (f64, f64, f64),
) {
    println!(
        "{name}: energy lost {lost:.3} J, dissipated {dissipated:.3} J, largest gap {gap:.3} J"
    );
    assert!(dissipated > min, "{name}: dissipated {dissipated} J");
    assert!(
        (lost - dissipated).abs() < net * dissipated,
        "{name}: energy lost {lost} J, dissipated {dissipated} J"
    );
    assert!(
        gap < worst * dissipated,
        "{name}: largest gap {gap} J of {dissipated} J"
    );
}

/// Runs `scenario` with all bodies and elements written and returns (energy
/// lost, energy dissipated, largest gap between them on the way) from `t0`
/// to the end ([`energy_and_dissipation`]).
pub(crate) fn energy_balance(mut scenario: railmbs_models::Scenario, t0: f64) -> (f64, f64, f64) {
    // From the given state: a coasting vehicle has no steady state.
    scenario.initial_kind = railmbs_models::InitialStateKind::Given;
    let model = railmbs_models::load_model(&scenario.model).unwrap();
    scenario.output.bodies = vec!["*".into()];
    scenario.output.forces = vec!["*".into()];
    let params = scenario.parameter_values(&model).unwrap();
    let out = run_to_table(&scenario, &model, Box::new(NumericEquations::new(&model)));
    let t = out.col("time");
    let (energy, power) = energy_and_dissipation(&model, &params, &out);
    let i0 = t.iter().position(|&x| x >= t0).unwrap();
    let (mut dissipated, mut worst) = (0.0, 0.0_f64);
    for k in i0 + 1..t.len() {
        dissipated += 0.5 * (power[k] + power[k - 1]) * (t[k] - t[k - 1]);
        worst = worst.max((energy[i0] - energy[k] - dissipated).abs());
    }
    (energy[i0] - energy[t.len() - 1], dissipated, worst)
}

/// [`energy_balance`] of `scenario` coasting (speed hold off: `k_traction =
/// c_traction = 0`) at 30 m/s on perfect straight track, written every 2 ms.
fn coasting_balance(mut scenario: railmbs_models::Scenario, t0: f64) -> (f64, f64, f64) {
    let track = scenario.track.as_mut().unwrap();
    track.load_file(&model_path("tracks/straight.ron")).unwrap();
    track.speed_profile.clear();
    track.speed = 30.0;
    for (name, value) in [("v0", "30"), ("k_traction", "0"), ("c_traction", "0")] {
        scenario.parameters.push((name.into(), value.into()));
    }
    scenario.integrator = railmbs_models::IntegratorSpec::Park {
        rtol: 1e-6,
        atol: 1e-8,
        max_step: 0.002,
        initial_step: None,
        jacobian: railmbs_models::JacobianKind::Analytic,
        solver: Default::default(),
    };
    scenario.output.interval = 0.002;
    energy_balance(scenario, t0)
}

/// A coasting vehicle loses energy only through damping and creep: the drop
/// of its mechanical energy (kinetic energy of all bodies, potential energy of
/// gravity and of constant dead loads, elastic energy of the suspension —
/// ½δᵀCδ + W₀ᵀδ of the 6×6 elements, ∫f of the bump stops — and of the Hertz
/// contacts) equals the integral of the power the dampers (δ̇ᵀDδ̇) and the
/// wheel–rail contacts (creep and normal damper) report as dissipated.
/// Manchester Vehicle 1's bogie (half the car body as a dead load) and the
/// whole Vehicle 1, released 3 mm off centre at 30 m/s, speed hold off.
///
/// What is not exact: the contact points' jumps across the tread (see the
/// free wheelset's balance), the suspension's small-rotation elastic energy,
/// the trapezoidal rule over 2 ms rows. Measured over 2.5 s: bogie 36.3 J
/// lost against 36.5 J dissipated (0.5 %), 1.5 % at worst on the way;
/// Vehicle 1 48.8 J against 49.3 J (1.1 %), 1.1 % at worst. The bounds leave
/// room for other step sequences.
#[test]
fn coasting_vehicles_lose_energy_only_through_damping_and_creep() {
    let bogie = railmbs_models::load_scenario(&model_path("scenarios/bogie_critical.ron")).unwrap();
    let mut bogie = bogie;
    bogie.end_time = 3.0;
    let mut vehicle =
        railmbs_models::load_scenario(&model_path("scenarios/vehicle1_tc1.ron")).unwrap();
    vehicle.end_time = 3.0;
    for ws in ["Bogie1.WS1", "Bogie1.WS2", "Bogie2.WS1", "Bogie2.WS2"] {
        vehicle.initial.push(railmbs_models::InitialOverride {
            coordinate: format!("{ws}.ws.y"),
            value: Some(0.003),
            velocity: None,
        });
    }
    for (name, scenario) in [("bogie", bogie), ("Vehicle 1", vehicle)] {
        assert_balance(name, coasting_balance(scenario, 0.5), (10.0, 0.02, 0.03));
    }
}
