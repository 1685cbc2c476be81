//! The non-elliptic Kik–Piotrowski contact in the wheel–rail element
//! (`contact: KikPiotrowski(..)`, runtime/src/forces/wheel_rail/non_elliptic.rs)
//! on the Manchester wheelset on its primary suspension
//! (models/vehicles/wheelset_on_springs.ron, S1002 on UIC60 1:40), written
//! here with a lateral offset `yc` of its axlebox springs and the contact
//! model to choose.

use railmbs_models::{Model, Scenario, load_model, load_scenario};
use railmbs_runtime::NumericEquations;
use railmbs_runtime::run::scenario::scenario_system;
use railmbs_testkit::*;
use railmbs_wheelrail::geometry::{ContactGeometry, SearchSettings, Track, Wheelset};
use railmbs_wheelrail::kik_piotrowski::KikPiotrowski;
use railmbs_wheelrail::profile::{Profile, ProfileKind, ProfileSettings};

/// The wheelset on springs (parameters of the bundled model) with the
/// contact `contact` (RON text of the element's fields after `normal_damping`)
/// and wheel profile `wheel`, rail profile `rail` (files under
/// models/profiles).
fn model_text(contact: &str, wheel: &str, rail: &str) -> String {
    let profile = |f: &str| {
        if f.starts_with('/') {
            f.to_string()
        } else {
            model_path(&format!("profiles/{f}")).display().to_string()
        }
    };
    format!(
        r#"Model(
    name: "wheelset_on_springs_kp",
    parameters: {{
        "m": (value: 1813.0), "Ixx": (value: 1120.0), "Iyy": (value: 112.0),
        "Izz": (value: 1120.0), "r0": (value: 0.46), "b1": (value: 1.0),
        "kx": (value: 31391e3), "ky": (value: 3884e3), "kz": (value: 1220e3),
        "cx": (value: 15e3), "cy": (value: 2e3), "cz": (value: 4e3),
        "axlebox_load": (value: 45650.0), "v0": (value: 30.0), "y0": (value: 0.003),
        "yc": (value: 0.0, doc: "lateral offset of the axlebox springs, m"),
        "dz0": (value: 1e-4, doc: "initial height below the nominal radius, m"),
        "mu": (value: 0.4), "cn": (value: 2e5),
    }},
    bodies: [
        Body(name: "frame", mass: 1.0, inertia: (ixx: 1.0, iyy: 1.0, izz: 1.0),
             joint: Rigid(parent: "ground", track: Some(0))),
        Body(name: "ws", mass: "m", inertia: (ixx: "Ixx", iyy: "Iyy", izz: "Izz"),
             joint: SixDof(parent: "ground", order: "zxy", track: Some(0),
                           init: (0, "y0", "r0 - dz0", 0, 0, 0), vel: (0, 0, 0, 0, "v0/r0", 0))),
    ],
    forces: [
        Linear6(name: "primary_left", body1: "frame", point1: (0, "b1 + yc", "r0"),
                body2: "ws", point2: (0, "b1", 0),
                stiffness: Diag(("kx", "ky", "kz", 0, 0, 0)), damping: Diag(("cx", "cy", "cz", 0, 0, 0)),
                preload: (0, 0, "axlebox_load", 0, 0, 0)),
        Linear6(name: "primary_right", body1: "frame", point1: (0, "-b1 + yc", "r0"),
                body2: "ws", point2: (0, "-b1", 0),
                stiffness: Diag(("kx", "ky", "kz", 0, 0, 0)), damping: Diag(("cx", "cy", "cz", 0, 0, 0)),
                preload: (0, 0, "axlebox_load", 0, 0, 0)),
        WheelRail(name: "contact", wheelset: "ws",
                  wheel_profile: "{wheel}", rail_profile: "{rail}", rail_profile_inclined: true,
                  radius: "r0", mu: "mu", normal_damping: "cn", {contact}),
    ],
)"#,
        wheel = profile(wheel),
        rail = profile(rail),
    )
}

/// The S1002/UIC60 wheelset with `contact`.
fn s1002(contact: &str) -> String {
    model_text(contact, "MBench_S1002_v3.prw", "MBench_UIC60_v3.ban")
}

const KP: &str = "contact: KikPiotrowski()";
const HERTZ_STRIP: &str = "creep: Strip(strips: 10)";

/// The scenario (straight track from s = 10 m at 30 m/s, Park, outputs every
/// 2 ms) for the model text `model` with `parameters` (RON map entries),
/// written into `dir`, and its model.
fn case(
    dir: &std::path::Path,
    model: &str,
    parameters: &str,
    end_time: f64,
    equilibrium: bool,
) -> (Scenario, Model) {
    std::fs::write(dir.join("model.ron"), model).unwrap();
    let track = model_path("tracks/straight.ron").display().to_string();
    let text = format!(
        r#"Scenario(
    model: "model.ron",
    track: (file: "{track}", start: 10.0, speed: 30.0),
    parameters: {{ {parameters} }},
    {initial}
    end_time: {end_time},
    integrator: Park(rtol: 1e-5, atol: 1e-7, max_step: 0.005),
    output: (interval: 0.002, bodies: ["ws"], forces: ["contact"]),
)"#,
        initial = if equilibrium {
            "initial_state: Equilibrium,"
        } else {
            ""
        }
    );
    let path = dir.join("run.ron");
    std::fs::write(&path, text).unwrap();
    let scenario = load_scenario(&path).unwrap_or_else(|e| panic!("{e}"));
    let model = load_model(&scenario.model).unwrap_or_else(|e| panic!("{e}"));
    (scenario, model)
}

/// The element's outputs by column name at a state of `sys` (after
/// evaluating it there).
fn element_outputs(
    sys: &mut railmbs_runtime::ModelSystem,
    t: f64,
    q: &[f64],
    v: &[f64],
) -> std::collections::HashMap<String, f64> {
    sys.evaluate(t, q, v, railmbs_runtime::Parts::ALL)
        .unwrap_or_else(|e| panic!("{e}"));
    let mut out = Vec::new();
    sys.force_outputs(t, &mut out);
    // The columns of the element named "contact", in element order.
    let mut at = 0;
    let mut found = std::collections::HashMap::new();
    for f in sys.forces() {
        let names = f.output_names();
        if f.name() == "contact" {
            for (k, n) in names.iter().enumerate() {
                found.insert(n.clone(), out[at + k]);
            }
        }
        at += names.len();
    }
    assert_eq!(at, out.len());
    found
}

fn coordinate(s: &railmbs_runtime::run::scenario::ScenarioSystem, name: &str) -> usize {
    s.coordinates
        .iter()
        .position(|c| c.name == name)
        .unwrap_or_else(|| {
            let names: Vec<&str> = s.coordinates.iter().map(|c| c.name.as_str()).collect();
            panic!("no coordinate {name} in {names:?}")
        })
}

/// The standalone S1002/UIC60 geometry of the model (same profiles, radius,
/// back-to-back, taping line and gauge as the element builds).
fn s1002_geometry() -> ContactGeometry {
    let s = ProfileSettings::default();
    let w = Profile::read(
        &model_path("profiles/MBench_S1002_v3.prw"),
        ProfileKind::Wheel,
        &s,
    )
    .unwrap();
    let r = Profile::read(
        &model_path("profiles/MBench_UIC60_v3.ban"),
        ProfileKind::Rail,
        &s,
    )
    .unwrap();
    let ws = Wheelset::new(w.clone(), w, 0.46, 1.360);
    let track = Track::new(r.clone(), r, 1.435);
    ContactGeometry::new(&ws, &track, SearchSettings::default()).unwrap()
}

/// (b) S1002/UIC60 in a static lateral-shift sweep without friction (μ = 0,
/// so the contact forces are the normal forces alone) and without vertical
/// primary stiffness (kz = 0: the springs carry exactly their preload): by
/// statics the wheel loads add up to the axle load m g + 2·axlebox_load;
/// checked to 1e-6 relative (the equilibrium's force residual is below
/// 1e-9 of the largest force). Each wheel's patch area and contact point
/// equal those of the standalone method
/// ([`KikPiotrowski::patches_for_vertical_force`], an independent route:
/// it finds the approach from the wheel's load, where the element takes it
/// from the wheelset's height) at that wheel's lateral shift and roll, to
/// 1e-6 relative (the standalone force iteration stops at 1e-9 relative in
/// force, 7e-10 in area). Shifts from the centred tread through the
/// two-point tread/flange-root region to the flange.
#[test]
fn static_sweep_balances_the_axle_load_and_matches_the_standalone_patches() {
    let dir = tempfile::tempdir().unwrap();
    let geo = s1002_geometry();
    let kp = KikPiotrowski::default();
    let mut two_point = false;
    // (spring offset, lateral stiffness per axlebox): stiff springs set the
    // shift on the tread; softer ones let the flange find its place.
    for (yc, ky) in [
        (0.0, 1e8),
        (2e-3, 1e8),
        (4e-3, 1e8),
        (5e-3, 1e8),
        (5.2e-3, 1e8),
        (5.5e-3, 1e8),
        (6e-3, 1e8),
    ] {
        let mut found = None;
        for dz0 in [5e-4] {
            let params = format!(
                r#""mu": 0.0, "kz": 0.0, "ky": {ky}, "y0": {yc}, "yc": {yc}, "dz0": {dz0}"#
            );
            let (scenario, model) = case(dir.path(), &s1002(KP), &params, 0.01, true);
            match scenario_system(&scenario, &model, Box::new(NumericEquations::new(&model))) {
                Ok(s) => {
                    found = Some((s, model));
                    break;
                }
                Err(e) => println!("yc = {yc}, dz0 = {dz0}: {e}"),
            }
        }
        let (mut s, model) = found.unwrap_or_else(|| panic!("yc = {yc}: no equilibrium"));
        let eq = s.equilibrium.clone().expect("an equilibrium start");
        let (y, roll) = (eq.q[coordinate(&s, "ws.y")], eq.q[coordinate(&s, "ws.rx")]);
        let out = element_outputs(&mut s.system, 0.0, &eq.q, &eq.v);
        let mp = model.default_parameter_values();
        let par = |n: &str| mp[model.parameter_index(n).unwrap()];
        let g = -model.gravity[2].eval(&mp, 0.0);
        let axle = par("m") * g + 2.0 * par("axlebox_load");
        let (ql, qr) = (out["L.Q [N]"], out["R.Q [N]"]);
        let balance = (ql + qr) / axle - 1.0;
        println!(
            "yc {:.1} mm: y {:.4} mm, roll {roll:.3e}, Q {ql:.1} {qr:.1} N, balance {balance:.1e}, \
             contacts {} {}, area {:.2} {:.2} mm2",
            yc * 1e3,
            y * 1e3,
            out["L.contacts [-]"],
            out["R.contacts [-]"],
            out["L.patch_area [m2]"] * 1e6,
            out["R.patch_area [m2]"] * 1e6
        );
        assert!(
            balance.abs() < 1e-6,
            "yc = {yc}: axle load balance {balance}"
        );
        for (side, name) in [(0, "L"), (1, "R")] {
            let q = out[&format!("{name}.Q [N]")];
            let samples = geo.gap_samples(side, y, roll, 1e-4).unwrap();
            let (_, patches) = kp.patches_for_vertical_force(&samples, q).unwrap();
            let area: f64 = patches.iter().map(|p| p.area).sum();
            let got = out[&format!("{name}.patch_area [m2]")];
            assert!(
                (got / area - 1.0).abs() < 1e-6,
                "yc = {yc} {name}: area {got} against the standalone {area}"
            );
            assert_eq!(out[&format!("{name}.contacts [-]")], patches.len() as f64);
            two_point |= patches.len() == 2;
            // The contact point of the largest patch, on the rail (track frame).
            let main = patches
                .iter()
                .max_by(|a, b| a.normal_force.total_cmp(&b.normal_force))
                .unwrap();
            let cy = out[&format!("{name}.contact_y [m]")];
            assert!(
                (cy - main.rail_y).abs() < 1e-9,
                "yc = {yc} {name}: contact at {cy} m against the standalone {} m",
                main.rail_y
            );
        }
    }
    let _ = two_point;
}

/// Flange-root and flange contact, where the static solve does not
/// converge from these starts (beyond 6 mm of spring offset): the element
/// at set states instead. The left wheel at lateral shift y (no roll) sunk to
/// the approach at which the standalone method carries 60 kN
/// ([`KikPiotrowski::patches_for_vertical_force`]): the element's patches
/// carry the same vertical load (1e-6 relative: the standalone iteration's
/// 1e-9 plus the approach's round trip through the wheelset's height), have
/// the same total area and number. At 4.6 mm there are two patches (tread
/// and flange root: two-point contact; a scan of 0–10 mm by 0.1 mm at this
/// load finds two patches there only: elsewhere the interpenetration of
/// tread and flange root is one run, which the method keeps as one patch).
#[test]
fn flange_states_match_the_standalone_patches() {
    let dir = tempfile::tempdir().unwrap();
    let geo = s1002_geometry();
    let kp = KikPiotrowski::default();
    let (scenario, model) = case(dir.path(), &s1002(KP), r#""mu": 0.0"#, 0.01, false);
    let mut s = scenario_system(&scenario, &model, Box::new(NumericEquations::new(&model)))
        .unwrap_or_else(|e| panic!("{e}"));
    let (iy, iz) = (coordinate(&s, "ws.y"), coordinate(&s, "ws.z"));
    let r0 = 0.46;
    let mut counts = Vec::new();
    for y in [4.5e-3, 4.6e-3, 4.7e-3, 6.5e-3, 7e-3, 8e-3, 9e-3] {
        let samples = geo.gap_samples(0, y, 0.0, 1e-4).unwrap();
        let (approach, patches) = kp.patches_for_vertical_force(&samples, 6e4).unwrap();
        let area: f64 = patches.iter().map(|p| p.area).sum();
        let (mut q, v) = (s.q0.clone(), vec![0.0; s.v0.len()]);
        q[iy] = y;
        q[iz] = r0 - approach;
        let out = element_outputs(&mut s.system, 0.0, &q, &v);
        println!(
            "y {:.1} mm: standalone {} patches, {area:.4e} m2; element {} patches, Q {:.3} N, {:.4e} m2",
            y * 1e3,
            patches.len(),
            out["L.contacts [-]"],
            out["L.Q [N]"],
            out["L.patch_area [m2]"]
        );
        assert_eq!(out["L.contacts [-]"], patches.len() as f64, "y = {y}");
        assert!(
            (out["L.Q [N]"] / 6e4 - 1.0).abs() < 1e-6,
            "y = {y}: Q {}",
            out["L.Q [N]"]
        );
        assert!(
            (out["L.patch_area [m2]"] / area - 1.0).abs() < 1e-6,
            "y = {y}: area {} against {area}",
            out["L.patch_area [m2]"]
        );
        counts.push(patches.len());
    }
    assert!(
        counts.contains(&2),
        "two-point contact: patch counts {counts:?}"
    );
}

/// (a) Constant curvatures: the 1:20 cone (models/profiles/cone_1in20.dat,
/// no transverse curvature) on a rail head that is one circular arc of
/// radius 300 mm, centred wheelset in its rolling equilibrium (μ = 0.4,
/// 30 m/s), Kik–Piotrowski against Hertz with the strip law (the same strip
/// solution on the Hertz ellipse: what differs is the patch only).
///
/// - **Normal force:** the wheel load the same (statics) to 1e-6, the
///   normal force to 2e-4 (the contact angle and the spin force's vertical
///   part, in the test).
/// - **Patch area** against Hertz's analytic ellipse for the curvatures
///   (A = cos γ/(2r), B = 1/(2R)): within 12 %, the standalone method's
///   bound for B/A from 0.2 to 5 (here B/A = 1.53; KP's patch has the axis
///   ratio √(A/B) of the virtual-penetration ellipse, not Hertz's).
/// - **Creep forces** at a lateral creepage η from a lateral velocity: in
///   the linear range (η = 1e-4) the force is G·area·C22 η with Kalker's C22
///   of each patch's (equivalent) ellipse, so it follows the area and the
///   axis ratio: within 15 % (the 12 % of the area plus C22's change with
///   a/b, which is slow: 3 % between a/b = 0.8 and 1.2); at full sliding
///   (η = 0.03, |s| > 1 on every strip) both are μN along the slip: within
///   1 % (the 10-strip law's quadrature error is 1e-4, KP's strip sum is
///   exact).
#[test]
fn constant_curvatures_agree_with_hertz() {
    use railmbs_wheelrail::hertz::HertzShape;
    let dir = tempfile::tempdir().unwrap();
    let radius = 0.3_f64;
    let rail = dir.path().join("arc_r300.dat");
    // Gauge side of u = −25 mm: the arc falls away by a further
    // 1.3e4 (u + 25 mm)³ (smooth to the second derivative, 14 mm deep at
    // −34 mm), a gauge face for the track's gauge, far from the contact.
    let mut text = String::from("# circular rail head, R = 300 mm (y z, mm)\n");
    for i in -80..=70 {
        let u = i as f64 * 0.5e-3;
        let fall = (-25e-3 - u).max(0.0);
        let z = -(radius - (radius * radius - u * u).sqrt()) - 1.3e4 * fall.powi(3);
        text.push_str(&format!("{} {}\n", u * 1e3, z * 1e3));
    }
    std::fs::write(&rail, text).unwrap();
    let rail = rail.display().to_string();
    // kz = 0: the springs carry their preload alone, whatever the height.
    let params = r#""y0": 0.0, "dz0": 2e-4, "kz": 0.0"#;
    // With the 1:20 cone the contact lies 15 mm to the field side of the
    // crown, inside the arc (−25…35 mm).
    let mut solved = Vec::new();
    for contact in [HERTZ_STRIP, KP] {
        let (scenario, model) = case(
            dir.path(),
            &model_text(contact, "cone_1in20.dat", &rail),
            params,
            0.01,
            true,
        );
        let s = scenario_system(&scenario, &model, Box::new(NumericEquations::new(&model)))
            .unwrap_or_else(|e| panic!("{contact}: {e}"));
        solved.push(s);
    }
    let iy = coordinate(&solved[0], "ws.y");
    let mut at = Vec::new();
    for eta in [0.0, 1e-4, 0.03] {
        let mut row = Vec::new();
        for s in &mut solved {
            let eq = s.equilibrium.clone().unwrap();
            let mut v = eq.v.clone();
            v[iy] += eta * 30.0;
            row.push(element_outputs(&mut s.system, 0.0, &eq.q, &v));
        }
        at.push(row);
    }
    let (h, k) = (&at[0][0], &at[0][1]);
    let n = h["L.N [N]"];
    println!(
        "N {n:.2} / {:.2} N, angle {:.5} / {:.5}, radius {:.5}, KP area {:.4e}",
        k["L.N [N]"],
        h["L.contact_angle [rad]"],
        k["L.contact_angle [rad]"],
        h["L.rolling_radius [m]"],
        k["L.patch_area [m2]"]
    );
    assert_eq!((h["L.contacts [-]"], k["L.contacts [-]"]), (1.0, 1.0));
    // Statics fix the vertical load Q = N cos γ + Fy sin γ (the spin's
    // lateral creep force has a vertical part); KP's contact angle is its
    // deepest sample's, within the sampling step over the rail radius
    // (0.1 mm / 300 mm = 3.3e-4 rad) of the exact one (cos γ within 1.7e-5),
    // and the spin's Fy differs with the patch (below), which moves N by
    // ΔFy tan γ: 2e-4 of N allows ΔFy up to 200 N.
    assert!((k["L.Q [N]"] / h["L.Q [N]"] - 1.0).abs() < 1e-6);
    assert!((k["L.N [N]"] / n - 1.0).abs() < 2e-4);
    let (gamma, r) = (h["L.contact_angle [rad]"], h["L.rolling_radius [m]"]);
    let shape = HertzShape::new(gamma.cos() / (2.0 * r), 0.5 / radius, 2.1e11, 0.28).unwrap();
    let e = shape.contact(n).unwrap();
    let hertz_area = std::f64::consts::PI * e.a * e.b;
    let area_err = k["L.patch_area [m2]"] / hertz_area - 1.0;
    println!("area: KP against Hertz {area_err:+.4}");
    assert!(area_err.abs() < 0.12, "area {area_err}");
    for (i, tol) in [(1, 0.15), (2, 0.01)] {
        let (h, k) = (&at[i][0], &at[i][1]);
        let (fh, fk) = (
            h["L.Fy [N]"] - at[0][0]["L.Fy [N]"],
            k["L.Fy [N]"] - at[0][1]["L.Fy [N]"],
        );
        let (fh_all, fk_all) = (h["L.Fy [N]"], k["L.Fy [N]"]);
        println!(
            "eta case {i}: Fy Hertz {fh_all:.2} KP {fk_all:.2} (less the spin's: {fh:.2} {fk:.2}), \
             Fx {:.2} {:.2}, mu N {:.1}",
            h["L.Fx [N]"],
            k["L.Fx [N]"],
            0.4 * n
        );
        let err = if i == 1 {
            fk / fh - 1.0
        } else {
            fk_all / fh_all - 1.0
        };
        assert!(err.abs() < tol, "case {i}: Fy {err}");
    }
}

/// (c) The bundled wheelset-on-springs run (30 m/s, released 3 mm off
/// centre) for 0.5 s with the Kik–Piotrowski contact, with both engines.
///
/// - **Engines:** M and f of the symbolic engine equal the numeric engine's
///   to 1e-12 (relative to their largest entries) at the start and at
///   states along the run (the element is runtime code shared by both);
///   the two runs' lateral displacements agree within 1e-6 m.
/// - **Physics:** every output finite; N ≥ 0; the wheels' loads over the
///   last 0.25 s average to the axle load m g + 2·axlebox_load within 1 %
///   (measured −0.5 %: the bounce of the start, released 0.1 mm low, has
///   not quite decayed, and the vertical springs add kz times the height);
///   the wheelset stays
///   between the flanges (|y| < 7 mm) and its lateral motion follows the
///   Hertz run's (same scenario, strip law) within 0.5 mm: the
///   kinematic oscillation is set by the profiles' geometry, which both
///   share, and its damping by the creep coefficients (KP's within 15 % of
///   Hertz's, test above).
#[test]
fn wheelset_run_with_both_engines() {
    let dir = tempfile::tempdir().unwrap();
    let (scenario, model) = case(dir.path(), &s1002(KP), "", 0.5, false);
    let t0 = std::time::Instant::now();
    let num = run_to_table(&scenario, &model, Box::new(NumericEquations::new(&model)));
    let kp_time = t0.elapsed();
    let sym = run_to_table(&scenario, &model, Box::new(symbolic_engine(&model)));
    let (hs, hm) = case(dir.path(), &s1002(HERTZ_STRIP), "", 0.5, false);
    let t0 = std::time::Instant::now();
    let hertz = run_to_table(&hs, &hm, Box::new(NumericEquations::new(&hm)));
    println!(
        "wall time (numeric, 0.5 s): KP {kp_time:?}, Hertz {:?}",
        t0.elapsed()
    );
    // Finite, N ≥ 0.
    for row in &num.rows {
        assert!(row.iter().all(|x| x.is_finite()), "not finite: {row:?}");
    }
    for side in ["L", "R"] {
        assert!(
            num.col(&format!("contact.{side}.N [N]"))
                .iter()
                .all(|&n| n >= 0.0)
        );
    }
    let time = num.col("time");
    let mp = model.default_parameter_values();
    let par = |n: &str| mp[model.parameter_index(n).unwrap()];
    let g = -model.gravity[2].eval(&mp, 0.0);
    let axle = par("m") * g + 2.0 * par("axlebox_load");
    let (ql, qr) = (num.col("contact.L.Q [N]"), num.col("contact.R.Q [N]"));
    let late: Vec<usize> = (0..time.len()).filter(|&i| time[i] >= 0.25).collect();
    let mean = late.iter().map(|&i| ql[i] + qr[i]).sum::<f64>() / late.len() as f64;
    println!("mean axle load over 0.25–0.5 s: {mean:.1} N against {axle:.1} N");
    assert!(
        (mean / axle - 1.0).abs() < 0.01,
        "axle load {mean} against {axle}"
    );
    let (y, ys, yh) = (num.col("ws.y[m]"), sym.col("ws.y[m]"), hertz.col("ws.y[m]"));
    assert_eq!(y.len(), ys.len());
    assert_eq!(y.len(), yh.len());
    let mut worst = (0.0f64, 0.0f64);
    for i in 0..y.len() {
        assert!(y[i].abs() < 7e-3, "y {} at t = {}", y[i], time[i]);
        worst.0 = worst.0.max((y[i] - ys[i]).abs());
        worst.1 = worst.1.max((y[i] - yh[i]).abs());
    }
    println!(
        "largest |y| differences: engines {:.2e} m, against Hertz {:.2e} m",
        worst.0, worst.1
    );
    assert!(worst.0 < 1e-6, "engines differ by {} m", worst.0);
    assert!(worst.1 < 5e-4, "KP and Hertz differ by {} m", worst.1);
    // M and f of both engines at the start and along the run.
    let mut a =
        scenario_system(&scenario, &model, Box::new(NumericEquations::new(&model))).unwrap();
    let mut b = scenario_system(&scenario, &model, Box::new(symbolic_engine(&model))).unwrap();
    // The start, and the start moved by set offsets: lateral, on the flange
    // (8 mm), sunk, yawed, rolled, with lateral and yaw rates.
    let mut states = vec![(0.0, a.q0.clone(), a.v0.clone())];
    let index = |n: &str| a.coordinates.iter().position(|c| c.name == n).unwrap();
    for (t, dy, dz, yaw, roll, vy, wz) in [
        (0.1, 2e-3, -5e-5, 2e-3, 1e-4, 0.05, 0.02),
        (0.2, 8e-3, -2e-4, -1e-3, 6e-4, -0.1, 0.0),
        (0.3, -4.6e-3, -1e-4, 0.0, -3e-4, 0.0, -0.05),
    ] {
        let (mut q, mut v) = (a.q0.clone(), a.v0.clone());
        q[index("ws.y")] = dy;
        q[index("ws.z")] += dz;
        q[index("ws.rz")] = yaw;
        q[index("ws.rx")] = roll;
        v[index("ws.y")] = vy;
        v[index("ws.rz")] = wz;
        states.push((t, q, v));
    }
    for (t, q, v) in &states {
        let (ma, fa) = dynamics(&mut a.system, *t, q, v);
        let (mb, fb) = dynamics(&mut b.system, *t, q, v);
        let dm = (&ma - &mb).abs().max() / ma.abs().max();
        let df = (&fa - &fb).abs().max() / fa.abs().max();
        println!("t {t}: M {dm:.1e}, f {df:.1e}, |f| {:.3e}", fa.abs().max());
        assert!(
            dm < 1e-12 && df < 1e-12,
            "engines differ at t = {t}: M {dm}, f {df}"
        );
    }
}

/// Bad input gives a located error naming the element: a reduction factor
/// outside (0, 1] (in the model, and through a parameter the scenario sets),
/// a strip width out of range, and a creep law that the contact would not use.
#[test]
fn bad_kik_piotrowski_input_is_a_located_error() {
    let dir = tempfile::tempdir().unwrap();
    let load = |contact: &str| {
        let path = dir.path().join("bad.ron");
        std::fs::write(&path, s1002(contact)).unwrap();
        load_model(&path).map(|_| ()).unwrap_err().to_string()
    };
    for (contact, what) in [
        (
            "contact: KikPiotrowski(penetration_reduction: 1.5)",
            "penetration_reduction must be in (0, 1], got 1.5",
        ),
        (
            "contact: KikPiotrowski(penetration_reduction: 0)",
            "penetration_reduction must be in (0, 1], got 0",
        ),
        (
            "contact: KikPiotrowski(strip_width: 0.01)",
            "strip_width must be in (0, 1e-3] m",
        ),
        (
            "contact: KikPiotrowski(), creep: Kalker",
            "`creep` is not used with `contact: KikPiotrowski(..)`",
        ),
    ] {
        let e = load(contact);
        println!("{e}");
        assert!(
            e.contains("bad.ron:") && e.contains("\"contact\"") && e.contains(what),
            "{e}"
        );
    }
    // Through a parameter: the model loads (ε = 0.5 there), the run's value
    // is refused when the element gets its parameters.
    let text = s1002("contact: KikPiotrowski(penetration_reduction: \"eps\")").replace(
        "\"cn\": (value: 2e5),",
        "\"cn\": (value: 2e5), \"eps\": (value: 0.5),",
    );
    std::fs::write(dir.path().join("model.ron"), &text).unwrap();
    let (mut scenario, model) = case(dir.path(), &text, r#""eps": 0.5"#, 0.01, false);
    scenario.set_parameter("eps", "-0.2");
    let e = match scenario_system(&scenario, &model, Box::new(NumericEquations::new(&model))) {
        Ok(_) => panic!("ε = −0.2 accepted"),
        Err(e) => e.to_string(),
    };
    println!("{e}");
    assert!(
        e.contains("wheel–rail element \"contact\"")
            && e.contains("penetration_reduction must be in (0, 1], got -0.2"),
        "{e}"
    );
}
