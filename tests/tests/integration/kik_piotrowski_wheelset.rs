//! The non-elliptic Kik–Piotrowski contact in the wheel–rail element
//! (`contact: KikPiotrowski(..)`, runtime/src/forces/wheel_rail/non_elliptic.rs)
//! on the Manchester wheelset on its primary suspension
//! (models/vehicles/wheelset_on_springs.ron, S1002 on UIC60 1:40), written
//! here with a lateral offset `yc` of its axlebox springs and the contact
//! model to choose.

use railmbs_models::{InitialStateKind, Model, Scenario, load_model, load_scenario};
use railmbs_runtime::run::scenario::scenario_system;
use railmbs_runtime::{Equations, NumericEquations};
use railmbs_testkit::*;
use railmbs_wheelrail::geometry::{ContactGeometry, SearchSettings, Track, Wheelset};
use railmbs_wheelrail::kik_piotrowski::KikPiotrowski;
use railmbs_wheelrail::profile::{Profile, ProfileKind, ProfileSettings};

/// The wheelset on springs (parameters of the bundled model) with the
/// contact `contact` (RON text of the element's fields after `normal_damping`)
/// and wheel profile `wheel`, rail profile `rail` (files under
/// models/profiles).
fn model_text(contact: &str, wheel: &str, rail: &str) -> String {
    let profile = |f: &str| model_path(&format!("profiles/{f}")).display().to_string();
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
        "mu": (value: 0.4), "cn": (value: 2e5),
    }},
    bodies: [
        Body(name: "frame", mass: 1.0, inertia: (ixx: 1.0, iyy: 1.0, izz: 1.0),
             joint: Rigid(parent: "ground", track: Some(0))),
        Body(name: "ws", mass: "m", inertia: (ixx: "Ixx", iyy: "Iyy", izz: "Izz"),
             joint: SixDof(parent: "ground", order: "zxy", track: Some(0),
                           init: (0, "y0", "r0 - 1e-4", 0, 0, 0), vel: (0, 0, 0, 0, "v0/r0", 0))),
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

/// Exploratory: a short run with each contact.
#[test]
fn kp_explore() {
    let dir = tempfile::tempdir().unwrap();
    for (name, contact) in [("hertz", HERTZ_STRIP), ("kp", KP)] {
        let (s, m) = case(dir.path(), &s1002(contact), "", 0.1, false);
        let t0 = std::time::Instant::now();
        let t = run_to_table(&s, &m, Box::new(NumericEquations::new(&m)));
        println!("{name}: {:?}", t0.elapsed());
        for c in ["contact.L.Q [N]", "contact.R.Q [N]", "contact.L.Fy [N]", "contact.L.contacts [-]"] {
            let v = t.col(c);
            println!("  {c}: {:?}", &v[..5.min(v.len())]);
            println!("  {c} end: {:?}", v.last());
        }
    }
}
