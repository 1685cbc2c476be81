//! Included subsystems: long names, parameter overrides that follow the
//! includer's parameters, track offsets, connection points, re-attachment,
//! equality with a hand-written flat model, and located errors.

use crate::common::{S1002_PRW, UIC60_BAN};
use railmbs_models::*;
use railmbs_testkit::model_path;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

fn example(name: &str) -> PathBuf {
    model_path("mechanisms/subsystems").join(name)
}

fn vehicle() -> Model {
    load_model(&example("vehicle.ron")).unwrap_or_else(|e| panic!("{e}"))
}

fn s(x: &str) -> String {
    x.to_string()
}

fn names<T>(items: &[T], name: impl Fn(&T) -> &str) -> Vec<&str> {
    items.iter().map(name).collect()
}

/// A fresh folder with these files; removed when dropped.
struct Files(PathBuf);

impl Files {
    fn new(files: &[(&str, &str)]) -> Files {
        static N: AtomicUsize = AtomicUsize::new(0);
        let dir = std::env::temp_dir().join(format!(
            "railmbs-subsystems-{}-{}",
            std::process::id(),
            N.fetch_add(1, Ordering::Relaxed)
        ));
        for (name, text) in files {
            let path = dir.join(name);
            std::fs::create_dir_all(path.parent().unwrap()).unwrap();
            std::fs::write(path, text).unwrap();
        }
        Files(dir)
    }

    fn path(&self, name: &str) -> PathBuf {
        self.0.join(name)
    }

    fn load(&self, name: &str) -> Result<Model, ModelErrors> {
        load_model(&self.path(name))
    }

    fn errors(&self, name: &str) -> ModelErrors {
        match self.load(name) {
            Ok(_) => panic!("{name} should not load"),
            Err(e) => e,
        }
    }
}

impl Drop for Files {
    fn drop(&mut self) {
        std::fs::remove_dir_all(&self.0).ok();
    }
}

/// 1-based (line, column) of the first occurrence of `needle` in `text`.
fn position(text: &str, needle: &str) -> (usize, usize) {
    let off = text
        .find(needle)
        .unwrap_or_else(|| panic!("{needle:?} not found"));
    let before = &text[..off];
    let line = before.matches('\n').count() + 1;
    let col = off - before.rfind('\n').map_or(0, |p| p + 1) + 1;
    (line, col)
}

/// The single error whose display contains `needle`; checks that it starts
/// with `file:line:col: element: ` for the position of `at` in `text`.
fn located<'a>(
    errors: &'a ModelErrors,
    file: &Path,
    text: &str,
    at: &str,
    element: &str,
    needle: &str,
) -> &'a ModelError {
    let found: Vec<&ModelError> = errors
        .iter()
        .filter(|e| e.to_string().contains(needle))
        .collect();
    assert_eq!(found.len(), 1, "one error with {needle:?} in:\n{errors}");
    let e = found[0];
    let (line, col) = position(text, at);
    let prefix = format!("{}:{line}:{col}: {element}: ", file.display());
    assert!(
        e.to_string().starts_with(&prefix),
        "{e}\nshould start with\n{prefix}"
    );
    e
}

#[test]
fn two_levels_give_long_names() {
    let m = vehicle();
    assert_eq!(m.name, "vehicle");
    assert_eq!(m.source.as_deref(), Some(example("vehicle.ron").as_path()));
    assert_eq!(
        names(&m.bodies, |b| &b.name),
        [
            "carbody",
            "Bogie1.frame",
            "Bogie1.WS1.axle",
            "Bogie1.WS2.axle",
            "Bogie2.frame",
            "Bogie2.WS1.axle",
            "Bogie2.WS2.axle",
            "Absorber.mass",
        ]
    );
    // Six coordinates per SixDof body, then the absorber's.
    assert_eq!(m.coordinates.len(), 7 * 6 + 1);
    for name in [
        "carbody.x",
        "Bogie1.frame.rz",
        "Bogie1.WS2.axle.ry",
        "Bogie2.WS1.axle.y",
        "Absorber.y",
    ] {
        assert!(m.coordinate_index(name).is_some(), "{name}");
    }
    for name in [
        "Secondary1Left",
        "AbsorberSpring",
        "Bogie1.Primary1Left",
        "Bogie2.Guide2",
    ] {
        assert!(m.force_index(name).is_some(), "{name}");
    }
    assert_eq!(m.forces.len(), 7 + 2 * 6);
    for name in [
        "lb",
        "Bogie1.offset",
        "Bogie1.WS1.m",
        "Bogie2.WS2.offset",
        "Absorber.z0",
    ] {
        assert!(m.parameter_index(name).is_some(), "{name}");
    }
    assert_eq!(
        names(&m.macros, |x| &x.name),
        [
            "loaded",
            "Bogie1.WS1.worn",
            "Bogie1.WS2.worn",
            "Bogie2.WS1.worn",
            "Bogie2.WS2.worn"
        ]
    );
    // Parents before children, coordinates in body order.
    for (i, b) in m.bodies.iter().enumerate() {
        if let BodyRef::Body(p) = b.parent {
            assert!(p < i, "{}", b.name);
        }
    }
    let bodies: Vec<usize> = m.coordinates.iter().map(|c| c.body).collect();
    assert!(bodies.windows(2).all(|w| w[0] <= w[1]));
    for (i, c) in m.coordinates.iter().enumerate() {
        assert_eq!(
            m.bodies[c.body].joint[c.elementary].motion,
            Motion::Coordinate(i)
        );
    }
}

#[test]
fn overridden_defaults_follow_the_includer() {
    let m = vehicle();
    let i = |n: &str| m.parameter_index(n).unwrap_or_else(|| panic!("{n}"));
    let p = m.default_parameter_values();
    // Bogie1: mw from the vehicle (1250) for both wheelsets (WS2.m = "WS1.m").
    assert_eq!(p[i("Bogie1.mw")], 1250.0);
    assert_eq!(p[i("Bogie1.WS1.m")], 1250.0);
    assert_eq!(p[i("Bogie1.WS2.m")], 1250.0);
    // Bogie2: its own mw (1500); WS2.m overridden by the vehicle.
    assert_eq!(p[i("Bogie2.WS1.m")], 1500.0);
    assert_eq!(p[i("Bogie2.WS2.m")], 1000.0);
    assert_eq!(p[i("Absorber.m")], 300.0);
    // The overridden defaults are expressions over the includer's parameters.
    assert_eq!(
        m.parameters[i("Bogie1.offset")].default,
        Expr::Param(i("lb"))
    );
    assert_eq!(
        m.parameters[i("Bogie1.WS2.m")].default,
        Expr::Param(i("Bogie1.WS1.m"))
    );
    assert_eq!(m.parameters[i("Bogie1.WS1.m")].doc, "mass, kg");

    // Changing the vehicle's parameters changes the subsystems' too.
    let over = [
        (s("mw"), s("1400")),
        (s("lb"), s("10")),
        (s("mc"), s("20000")),
    ];
    let p = m.parameter_values(&[], &over).unwrap();
    assert_eq!(p[i("Bogie1.WS1.m")], 1400.0);
    assert_eq!(p[i("Bogie1.WS2.m")], 1400.0);
    assert_eq!(p[i("Bogie2.WS1.m")], 1500.0);
    assert_eq!(p[i("Bogie1.WS1.offset")], 11.25);
    assert_eq!(p[i("Bogie2.WS2.offset")], -11.25);
    assert_eq!(p[i("Absorber.m")], 200.0);
    // A subsystem parameter may still be overridden directly; its dependents follow.
    let over = [
        (s("Bogie1.WS1.m"), s("999")),
        (s("Bogie2.offset"), s("-20")),
    ];
    let p = m.parameter_values(&[], &over).unwrap();
    assert_eq!(p[i("Bogie1.WS1.m")], 999.0);
    assert_eq!(p[i("Bogie1.WS2.m")], 999.0);
    assert_eq!(p[i("Bogie2.WS1.offset")], -18.75);
    // Macros of subsystems under their long names.
    let p = m
        .parameter_values(&[s("Bogie2.WS1.worn"), s("loaded")], &[])
        .unwrap();
    assert_eq!(p[i("Bogie2.WS1.r0")], 0.46875);
    assert_eq!(p[i("Bogie1.WS1.r0")], 0.5);
    assert_eq!(p[i("Absorber.m")], 450.0);
}

#[test]
fn scenario_overrides_reach_subsystem_parameters() {
    let model = example("vehicle.ron");
    let scenario = format!(
        r#"Scenario(
    model: "{}",
    macros: ["Bogie1.WS2.worn"],
    parameters: {{ "lb": 8, "Bogie2.WS1.offset": "lb/2" }},
    initial: [(coord: "Bogie1.WS1.axle.y", value: 0.001)],
    end_time: 1.0,
    integrator: Rk4(step: 0.001),
    output: (interval: 0.01),
)
"#,
        model.display()
    );
    let files = Files::new(&[("scenario.ron", &scenario)]);
    let sc = load_scenario(&files.path("scenario.ron")).unwrap_or_else(|e| panic!("{e}"));
    let m = load_model(&sc.model).unwrap_or_else(|e| panic!("{e}"));
    let p = sc.parameter_values(&m).unwrap_or_else(|e| panic!("{e}"));
    let i = |n: &str| m.parameter_index(n).unwrap();
    assert_eq!(p[i("Bogie1.WS1.offset")], 9.25);
    assert_eq!(p[i("Bogie1.WS2.offset")], 6.75);
    assert_eq!(p[i("Bogie2.WS1.offset")], 4.0);
    assert_eq!(p[i("Bogie1.WS2.r0")], 0.46875);
    let (q, _) = sc.initial_state(&m, &p).unwrap();
    assert_eq!(q[m.coordinate_index("Bogie1.WS1.axle.y").unwrap()], 0.001);
}

#[test]
fn track_offsets_add_up() {
    let m = vehicle();
    let frames: Vec<&str> = m
        .track_frames
        .iter()
        .map(|t| m.bodies[t.body].name.as_str())
        .collect();
    assert_eq!(
        frames,
        [
            "carbody",
            "Bogie1.frame",
            "Bogie1.WS1.axle",
            "Bogie1.WS2.axle",
            "Bogie2.frame",
            "Bogie2.WS1.axle",
            "Bogie2.WS2.axle",
        ]
    );
    let offsets = |p: &[f64]| -> Vec<f64> {
        m.track_frames
            .iter()
            .map(|t| t.offset.eval(p, 0.0))
            .collect()
    };
    let p = m.default_parameter_values();
    assert_eq!(offsets(&p), [0.0, 9.5, 10.75, 8.25, -9.5, -8.25, -10.75]);
    let p = m.parameter_values(&[], &[(s("lb"), s("6"))]).unwrap();
    assert_eq!(offsets(&p), [0.0, 6.0, 7.25, 4.75, -6.0, -4.75, -7.25]);
    // Frame k supplies inputs 6k..6k+6 to its body's joint, in order.
    for (k, t) in m.track_frames.iter().enumerate() {
        let inputs: Vec<Motion> = m.bodies[t.body].joint[..6]
            .iter()
            .map(|e| e.motion.clone())
            .collect();
        let expected: Vec<Motion> = (0..6).map(|c| Motion::Input(6 * k + c)).collect();
        assert_eq!(inputs, expected);
    }
    let inputs = m
        .bodies
        .iter()
        .flat_map(|b| &b.joint)
        .filter(|e| matches!(e.motion, Motion::Input(_)))
        .count();
    assert_eq!(inputs, 6 * m.track_frames.len());
}

fn eval3(e: &[Expr; 3], p: &[f64]) -> [f64; 3] {
    e.each_ref().map(|x| x.eval(p, 0.0))
}

#[test]
fn forces_reach_subsystem_bodies_and_connection_points() {
    let m = vehicle();
    let p = m.default_parameter_values();
    let body = |n: &str| BodyRef::Body(m.body_index(n).unwrap());
    let bipolar = |name: &str| match &m.forces[m.force_index(name).unwrap()].kind {
        ForceKind::Bipolar(railmbs_models::forces::Bipolar {
            ends:
                railmbs_models::forces::PointPair {
                    body1,
                    point1,
                    body2,
                    point2,
                },
            ..
        }) => (*body1, eval3(point1, &p), *body2, eval3(point2, &p)),
        other => panic!("{name}: {other:?}"),
    };
    // The vehicle to a bogie's connection point: its body and point.
    let (b1, p1, b2, p2) = bipolar("Secondary1Left");
    assert_eq!((b1, p1), (body("carbody"), [9.5, 1.0, -0.5]));
    assert_eq!((b2, p2), (body("Bogie1.frame"), [0.0, 1.0, 0.25]));
    // With an offset added to the connection point.
    let (_, _, b2, p2) = bipolar("Secondary2Right");
    assert_eq!((b2, p2), (body("Bogie2.frame"), [0.0, -1.0, 0.125]));
    // Inside a bogie: to the wheelsets' connection points.
    let (b1, p1, b2, p2) = bipolar("Bogie2.Primary2Left");
    assert_eq!((b1, p1), (body("Bogie2.frame"), [-1.25, 1.0, -0.125]));
    assert_eq!((b2, p2), (body("Bogie2.WS2.axle"), [0.0, 1.0, 0.125]));
    // The absorber, re-attached to the car body.
    let (b1, _, b2, _) = bipolar("AbsorberSpring");
    assert_eq!((b1, b2), (body("carbody"), body("Absorber.mass")));
    // By long body name.
    match &m.forces[m.force_index("Traction2").unwrap()].kind {
        ForceKind::Linear6(railmbs_models::forces::Linear6 { body2, frame2, .. }) => {
            assert_eq!(*body2, body("Bogie2.frame"));
            assert_eq!(eval3(&frame2.origin, &p), [0.0, 0.0, 0.25]);
        }
        other => panic!("{other:?}"),
    }
    match &m.forces[m.force_index("Bogie1.Guide2").unwrap()].kind {
        ForceKind::Linear6(railmbs_models::forces::Linear6 { body1, body2, .. }) => {
            assert_eq!(*body1, body("Bogie1.frame"));
            assert_eq!(*body2, body("Bogie1.WS2.axle"));
        }
        other => panic!("{other:?}"),
    }
}

#[test]
fn parent_reattaches_ground_bodies() {
    let m = vehicle();
    let absorber = &m.bodies[m.body_index("Absorber.mass").unwrap()];
    assert_eq!(
        absorber.parent,
        BodyRef::Body(m.body_index("carbody").unwrap())
    );
    // The included file alone hangs it on ground.
    let alone = load_model(&example("absorber.ron")).unwrap();
    assert_eq!(alone.bodies[0].parent, BodyRef::Ground);
    // The re-attached body may come before its new parent among the
    // includer's subsystems: it is still sorted after it.
    let files = Files::new(&[
        (
            "absorber.ron",
            &std::fs::read_to_string(example("absorber.ron")).unwrap(),
        ),
        (
            "rig.ron",
            r#"Model(
    name: "rig",
    subsystems: [
        Subsystem(name: "A", file: "absorber.ron", parent: "B.mass"),
        Subsystem(name: "B", file: "absorber.ron"),
    ],
    bodies: [],
)"#,
        ),
    ]);
    let m = files.load("rig.ron").unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(names(&m.bodies, |b| &b.name), ["B.mass", "A.mass"]);
    assert_eq!(m.bodies[1].parent, BodyRef::Body(0));
    assert_eq!(m.coordinate_names(), ["B.y", "A.y"]);
}

/// The model with every expression (without `t`) replaced by its value with
/// the default parameters, for comparing models that are equal after
/// evaluation (parameter docs removed).
fn evaluated(m: &Model) -> Model {
    let p = m.default_parameter_values();
    let mut e = m.clone();
    for p in &mut e.parameters {
        p.doc.clear();
    }
    e.exprs_mut(&mut |x| {
        if !x.has_time() {
            *x = Expr::Num(x.eval(&p, 0.0));
        }
    });
    e
}

#[test]
fn flattened_model_equals_the_hand_written_flat_model() {
    let sub = evaluated(&vehicle());
    let flat = load_model(&example("vehicle_flat.ron")).unwrap_or_else(|e| panic!("{e}"));
    let flat = evaluated(&flat);
    assert_eq!(sub.parameters, flat.parameters);
    assert_eq!(sub.macros, flat.macros);
    assert_eq!(sub.gravity, flat.gravity);
    assert_eq!(sub.bodies, flat.bodies);
    assert_eq!(sub.coordinates, flat.coordinates);
    for (a, b) in sub.forces.iter().zip(&flat.forces) {
        assert_eq!(a, b);
    }
    assert_eq!(sub.forces.len(), flat.forces.len());
    assert_eq!(sub.cut_joints, flat.cut_joints);
    assert_eq!(sub.track_frames, flat.track_frames);
}

#[test]
fn structural_hash_is_deterministic() {
    let a = vehicle();
    let b = vehicle();
    assert_eq!(a, b);
    assert_eq!(a.structural_hash(), b.structural_hash());
    // The flat file has the same structure (same expressions over the same
    // parameters); only the parameters' default values differ.
    let flat = load_model(&example("vehicle_flat.ron")).unwrap();
    assert_eq!(a.structural_hash(), flat.structural_hash());
    // Different overrides that change no structure keep the hash.
    let text = std::fs::read_to_string(example("vehicle.ron"))
        .unwrap()
        .replace("\"offset\": \"-lb\"", "\"offset\": -9");
    let files = Files::new(&[
        ("vehicle.ron", &text),
        (
            "bogie.ron",
            &std::fs::read_to_string(example("bogie.ron")).unwrap(),
        ),
        (
            "wheelset.ron",
            &std::fs::read_to_string(example("wheelset.ron")).unwrap(),
        ),
        (
            "absorber.ron",
            &std::fs::read_to_string(example("absorber.ron")).unwrap(),
        ),
    ]);
    let c = files.load("vehicle.ron").unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(a.structural_hash(), c.structural_hash());
    assert_ne!(a, c);
}

const WHEELSET: &str = r#"Model(
    name: "ws",
    parameters: { "m": 1500, "r0": 0.46, "offset": 0 },
    bodies: [
        Body(name: "axle", mass: "m", inertia: (ixx: 800, iyy: 100, izz: 800),
             joint: SixDof(parent: "ground", at: (0, 0, "r0"), order: "zxy", track: Some("offset"))),
    ],
    connections: { "BoxLeft": (body: "axle", point: (0, 1, 0)) },
    forces: [
        WheelRail(name: "Contact", wheelset: "axle", wheel_profile: "../profiles/wheel.prw",
                  rail_profile: "../profiles/rail.ban", radius: "r0"),
    ],
)
"#;

#[test]
fn wheel_rail_profiles_are_relative_to_the_included_file() {
    let files = Files::new(&[
        ("profiles/wheel.prw", S1002_PRW),
        ("profiles/rail.ban", UIC60_BAN),
        ("wheelsets/ws.ron", WHEELSET),
        (
            "vehicles/car.ron",
            r#"Model(
    name: "car",
    parameters: { "lw": 1.5 },
    subsystems: [
        Subsystem(name: "WS1", file: "../wheelsets/ws.ron", parameters: { "offset": "lw" }),
        Subsystem(name: "WS2", file: "../wheelsets/ws.ron", parameters: { "offset": "-lw" }),
    ],
    bodies: [],
)"#,
        ),
    ]);
    let m = files
        .load("vehicles/car.ron")
        .unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(m.forces.len(), 2);
    for (k, f) in m.forces.iter().enumerate() {
        assert_eq!(f.name, format!("WS{}.Contact", k + 1));
        let ForceKind::WheelRail(w) = &f.kind else {
            panic!("{f:?}")
        };
        assert_eq!(
            w.wheelset,
            m.body_index(&format!("WS{}.axle", k + 1)).unwrap()
        );
        let canonical = |f: &str| std::fs::canonicalize(files.path(f)).unwrap();
        assert_eq!(w.wheel_profiles[0].path, canonical("profiles/wheel.prw"));
        assert_eq!(w.wheel_profiles[1].path, canonical("profiles/wheel.prw"));
        assert_eq!(w.rail_profiles[0].path, canonical("profiles/rail.ban"));
        assert_eq!(w.rail_profiles[1].path, canonical("profiles/rail.ban"));
        assert!(w.wheel_profiles[0].path.is_absolute());
        let p = m.default_parameter_values();
        assert_eq!(w.radius.eval(&p, 0.0), 0.46);
    }
}

#[test]
fn cut_joints_use_connection_points_and_long_names() {
    let files = Files::new(&[
        (
            "ws.ron",
            WHEELSET
                .replace("WheelRail(", "Applied(")
                .replace(
                    r#"wheelset: "axle", wheel_profile: "../profiles/wheel.prw",
                  rail_profile: "../profiles/rail.ban", radius: "r0""#,
                    r#"body: "BoxLeft", point: (0, 0, 0.5), force: (0, 0, "-m")"#,
                )
                .as_str(),
        ),
        (
            "frame.ron",
            r#"Model(
    name: "frame",
    subsystems: [ Subsystem(name: "WS", file: "ws.ron") ],
    bodies: [
        Body(name: "beam", mass: 10, inertia: (ixx: 1, iyy: 1, izz: 1),
             joint: Revolute(parent: "WS.axle", axis: Y, at: (0, 0, 0.5))),
    ],
    connections: { "Top": (body: "WS.BoxLeft", point: (0, 0, 0.25)) },
    cut_joints: [
        CutJoint(name: "pin", body1: "Top", point1: (1, 0, 0), body2: "beam", constrain: [Tx, Tz]),
    ],
)"#,
        ),
    ]);
    let m = files.load("frame.ron").unwrap_or_else(|e| panic!("{e}"));
    let p = m.default_parameter_values();
    assert_eq!(names(&m.bodies, |b| &b.name), ["WS.axle", "beam"]);
    assert_eq!(m.bodies[1].parent, BodyRef::Body(0));
    let c = &m.cut_joints[0];
    assert_eq!(c.body1, BodyRef::Body(0));
    // Connection of a connection: (0, 1, 0) + (0, 0, 0.25) + (1, 0, 0).
    assert_eq!(eval3(&c.frame1.origin, &p), [1.0, 1.0, 0.25]);
    // The wheelset's applied force at its own connection point.
    match &m.forces[0].kind {
        ForceKind::Applied(railmbs_models::forces::Applied {
            body, point, force, ..
        }) => {
            assert_eq!(*body, 0);
            assert_eq!(eval3(point, &p), [0.0, 1.0, 0.5]);
            assert_eq!(eval3(force, &p), [0.0, 0.0, -1500.0]);
        }
        other => panic!("{other:?}"),
    }
}

// ---- errors ----

const BOGIE: &str = r#"Model(
    name: "bogie",
    parameters: { "offset": 0, "a": 1.25 },
    subsystems: [
        Subsystem(name: "WS1", file: "ws.ron", parameters: { "offset": "offset + a" }),
        Subsystem(name: "WS2", file: "ws.ron", parameters: { "offset": "offset - a" }),
    ],
    bodies: [
        Body(name: "frame", mass: 2000, inertia: (ixx: 1000, iyy: 1000, izz: 1000),
             joint: SixDof(parent: "ground", track: Some("offset"))),
    ],
    forces: [
        Spring(name: "Primary1", body1: "frame", body2: "WS1.BoxLeft", c: 1e6),
    ],
)
"#;

const VEHICLE: &str = r#"Model(
    name: "vehicle",
    parameters: { "lb": 9.5 },
    subsystems: [
        Subsystem(name: "Bogie1", file: "bogie.ron", parameters: { "offset": "lb" }),
    ],
    bodies: [
        Body(name: "carbody", mass: 30000, inertia: (ixx: 5e4, iyy: 1e6, izz: 1e6),
             joint: SixDof(parent: "ground", track: Some(0))),
    ],
    forces: [
        Spring(name: "Secondary1", body1: "carbody", body2: "Bogie1.frame", c: 1e6),
    ],
)
"#;

/// Loads `vehicle` over the standard bogie and wheelset files: its one error
/// containing `needle` must be located at `at` and name `element`.
fn vehicle_error(vehicle: &str, at: &str, element: &str, needle: &str) -> ModelError {
    let files = tree(vehicle, BOGIE, WHEELSET);
    let errors = files.errors("vehicle.ron");
    located(
        &errors,
        &files.path("vehicle.ron"),
        vehicle,
        at,
        element,
        needle,
    )
    .clone()
}

fn tree(vehicle: &str, bogie: &str, ws: &str) -> Files {
    let ws = ws.replace(
        "    forces: [\n        WheelRail(name: \"Contact\", wheelset: \"axle\", wheel_profile: \"../profiles/wheel.prw\",\n                  rail_profile: \"../profiles/rail.ban\", radius: \"r0\"),\n    ],\n",
        "",
    );
    assert!(!ws.contains("WheelRail"));
    Files::new(&[
        ("vehicle.ron", vehicle),
        ("bogie.ron", bogie),
        ("ws.ron", &ws),
    ])
}

#[test]
fn the_error_test_tree_is_valid() {
    let files = tree(VEHICLE, BOGIE, WHEELSET);
    let m = files.load("vehicle.ron").unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(
        names(&m.bodies, |b| &b.name),
        [
            "carbody",
            "Bogie1.frame",
            "Bogie1.WS1.axle",
            "Bogie1.WS2.axle"
        ]
    );
}

#[test]
fn missing_subsystem_file() {
    let bogie = BOGIE.replacen("file: \"ws.ron\"", "file: \"nope.ron\"", 1);
    let files = tree(VEHICLE, &bogie, WHEELSET);
    let errors = files.errors("vehicle.ron");
    let e = located(
        &errors,
        &files.path("bogie.ron"),
        &bogie,
        "\"nope.ron\"",
        "subsystem \"WS1\"",
        "cannot read the subsystem file",
    );
    let (line, col) = position(VEHICLE, "Subsystem(name: \"Bogie1\"");
    assert!(
        e.message
            .contains(&format!("{}: ", files.path("nope.ron").display())),
        "{e}"
    );
    assert!(
        e.message.ends_with(&format!(
            "(included as \"Bogie1\" from {}:{line}:{col})",
            files.path("vehicle.ron").display()
        )),
        "{e}"
    );
    assert_eq!(errors.len(), 1, "{errors}");
}

#[test]
fn include_cycle_names_the_chain() {
    let ws = WHEELSET.replacen(
        "    bodies: [",
        "    subsystems: [ Subsystem(name: \"Loop\", file: \"vehicle.ron\") ],\n    bodies: [",
        1,
    );
    let files = tree(VEHICLE, BOGIE, &ws);
    let errors = files.errors("vehicle.ron");
    let ws_text = std::fs::read_to_string(files.path("ws.ron")).unwrap();
    let e = located(
        &errors,
        &files.path("ws.ron"),
        &ws_text,
        "\"vehicle.ron\"",
        "subsystem \"Loop\"",
        "include cycle",
    );
    let [v, b, w] =
        ["vehicle.ron", "bogie.ron", "ws.ron"].map(|f| files.path(f).display().to_string());
    assert!(
        e.message
            .starts_with(&format!("include cycle: {v} -> {b} -> {w} -> {v}")),
        "{e}"
    );
    // Reported once although the bogie includes ws.ron twice.
    assert_eq!(errors.len(), 1, "{errors}");
    // Through both levels.
    let (l1, c1) = position(VEHICLE, "Subsystem(name: \"Bogie1\"");
    let (l2, c2) = position(BOGIE, "Subsystem(name: \"WS1\"");
    assert!(
        e.message.ends_with(&format!(
            "(included as \"Bogie1.WS1\" from {v}:{l1}:{c1} via {b}:{l2}:{c2})"
        )),
        "{e}"
    );

    // A file including itself.
    let selfish = VEHICLE.replacen("file: \"bogie.ron\"", "file: \"./vehicle.ron\"", 1);
    let files = tree(&selfish, BOGIE, WHEELSET);
    let errors = files.errors("vehicle.ron");
    let v = files.path("vehicle.ron").display().to_string();
    located(
        &errors,
        &files.path("vehicle.ron"),
        &selfish,
        "\"./vehicle.ron\"",
        "subsystem \"Bogie1\"",
        &format!("include cycle: {v} -> {v}"),
    );
}

#[test]
fn unknown_override_names_subsystem_file_and_parameter() {
    let vehicle = VEHICLE.replacen("\"offset\": \"lb\"", "\"offset\": \"lb\", \"ofset\": 2", 1);
    let files = tree(&vehicle, BOGIE, WHEELSET);
    let errors = files.errors("vehicle.ron");
    let e = located(
        &errors,
        &files.path("vehicle.ron"),
        &vehicle,
        "\"ofset\"",
        "subsystem \"Bogie1\"",
        "unknown parameter \"ofset\"",
    );
    assert!(
        e.message
            .contains(&files.path("bogie.ron").display().to_string()),
        "{e}"
    );
    assert!(e.message.contains("close matches: \"offset\""), "{e}");
    assert_eq!(errors.len(), 1, "{errors}");
}

#[test]
fn bad_override_values_are_located_at_the_override() {
    // Unknown identifier in the includer's namespace.
    let vehicle = VEHICLE.replacen("\"offset\": \"lb\"", "\"offset\": \"lb + a\"", 1);
    vehicle_error(
        &vehicle,
        "\"lb + a\"",
        "subsystem \"Bogie1\"",
        "unknown identifier \"a\" in the override of \"offset\"",
    );
    // A cycle through an override.
    let vehicle = VEHICLE.replacen("\"lb\": 9.5", "\"lb\": \"Bogie1.offset\"", 1);
    vehicle_error(
        &vehicle,
        "\"lb\": \"Bogie1",
        "parameter \"lb\"",
        "cycle in parameter default values: lb -> Bogie1.offset -> lb",
    );
    // A mass that the override makes negative.
    let bogie = BOGIE.replacen(
        "\"offset\": \"offset + a\"",
        "\"offset\": \"offset + a\", \"m\": \"-a\"",
        1,
    );
    let files = tree(VEHICLE, &bogie, WHEELSET);
    let errors = files.errors("bogie.ron");
    let e = located(
        &errors,
        &files.path("bogie.ron"),
        &bogie,
        "Subsystem(name: \"WS1\"",
        "subsystem \"WS1\"",
        "mass must be positive",
    );
    assert!(
        e.message.starts_with(
            "body \"WS1.axle\", with this instance's parameters: mass must be positive, got -1.25"
        ),
        "{e}"
    );
}

#[test]
fn unknown_long_names_list_close_matches() {
    let vehicle = VEHICLE.replacen("body2: \"Bogie1.frame\"", "body2: \"Bogie1.fram\"", 1);
    let files = tree(&vehicle, BOGIE, WHEELSET);
    let errors = files.errors("vehicle.ron");
    let e = located(
        &errors,
        &files.path("vehicle.ron"),
        &vehicle,
        "\"Bogie1.fram\"",
        "force \"Secondary1\"",
        "unknown body \"Bogie1.fram\" in body2",
    );
    assert!(
        e.message.ends_with("; close matches: \"Bogie1.frame\""),
        "{e}"
    );

    // A short name of a subsystem body: the long names ending with it.
    let vehicle = VEHICLE.replacen("body2: \"Bogie1.frame\"", "body2: \"axle\"", 1);
    let files = tree(&vehicle, BOGIE, WHEELSET);
    let errors = files.errors("vehicle.ron");
    let e = located(
        &errors,
        &files.path("vehicle.ron"),
        &vehicle,
        "\"axle\"",
        "force \"Secondary1\"",
        "unknown body \"axle\" in body2",
    );
    assert!(
        e.message
            .ends_with("close matches: \"Bogie1.WS1.axle\", \"Bogie1.WS2.axle\""),
        "{e}"
    );

    // A connection point where a body is needed.
    let vehicle = VEHICLE.replacen(
        "joint: SixDof(parent: \"ground\", track: Some(0))",
        "joint: Rigid(parent: \"Bogie1.WS1.BoxLeft\")",
        1,
    );
    vehicle_error(
        &vehicle,
        "\"Bogie1.WS1.BoxLeft\"",
        "body \"carbody\"",
        "\"Bogie1.WS1.BoxLeft\" is a connection point, not a body",
    );
}

#[test]
fn reattaching_a_track_body_is_an_error() {
    let vehicle = VEHICLE.replacen(
        "parameters: { \"offset\": \"lb\" }",
        "parameters: { \"offset\": \"lb\" }, parent: \"carbody\"",
        1,
    );
    let files = tree(&vehicle, BOGIE, WHEELSET);
    let errors = files.errors("vehicle.ron");
    let path = files.path("vehicle.ron");
    for body in ["Bogie1.frame", "Bogie1.WS1.axle", "Bogie1.WS2.axle"] {
        located(
            &errors,
            &path,
            &vehicle,
            "\"carbody\"),",
            "subsystem \"Bogie1\"",
            &format!(
                "cannot re-attach body \"{body}\" to \"carbody\": it hangs on a track-following frame"
            ),
        );
    }
    assert_eq!(errors.len(), 3, "{errors}");
    // An unknown parent.
    let vehicle = VEHICLE.replacen(
        "parameters: { \"offset\": \"lb\" }",
        "parameters: { \"offset\": \"lb\" }, parent: \"carbdy\"",
        1,
    );
    vehicle_error(
        &vehicle,
        "\"carbdy\"",
        "subsystem \"Bogie1\"",
        "unknown body \"carbdy\" as parent; close matches: \"carbody\"",
    );
}

#[test]
fn errors_inside_included_files_name_that_file_and_the_instance() {
    let ws = WHEELSET.replacen("mass: \"m\"", "mass: \"m + q\"", 1);
    let files = tree(VEHICLE, BOGIE, &ws);
    let errors = files.errors("vehicle.ron");
    let ws_text = std::fs::read_to_string(files.path("ws.ron")).unwrap();
    let e = located(
        &errors,
        &files.path("ws.ron"),
        &ws_text,
        "\"m + q\"",
        "body \"axle\"",
        "unknown identifier \"q\" in mass",
    );
    let [v, b] = ["vehicle.ron", "bogie.ron"].map(|f| files.path(f).display().to_string());
    let (l1, c1) = position(VEHICLE, "Subsystem(name: \"Bogie1\"");
    let (l2, c2) = position(BOGIE, "Subsystem(name: \"WS1\"");
    assert!(
        e.message.ends_with(&format!(
            "(included as \"Bogie1.WS1\" from {v}:{l1}:{c1} via {b}:{l2}:{c2})"
        )),
        "{e}"
    );
    // Once, although ws.ron is included twice.
    assert_eq!(errors.len(), 1, "{errors}");

    // A RON syntax error in an included file.
    let bogie = BOGIE.replacen("\"a\": 1.25", "\"a\" 1.25", 1);
    let files = tree(VEHICLE, &bogie, WHEELSET);
    let errors = files.errors("vehicle.ron");
    assert_eq!(errors.len(), 1, "{errors}");
    let e = &errors.0[0];
    assert_eq!(e.file, files.path("bogie.ron"));
    assert_eq!(e.line(), Some(position(&bogie, "\"a\" 1.25").0));
    assert!(e.message.contains("(included as \"Bogie1\" from "), "{e}");
}

#[test]
fn names_must_not_clash() {
    // A body of the includer with a subsystem body's long name.
    let vehicle = VEHICLE.replacen("name: \"carbody\"", "name: \"Bogie1.frame\"", 1);
    vehicle_error(
        &vehicle,
        "name: \"Bogie1.frame\"",
        "body \"Bogie1.frame\"",
        "duplicate body name: subsystem \"Bogie1\" has a body \"frame\"",
    );
    // Two instances with one name; an instance name with a dot.
    let vehicle = VEHICLE.replacen(
        "    ],\n    bodies",
        "        Subsystem(name: \"Bogie1\", file: \"bogie.ron\"),\n        Subsystem(name: \"B.2\", file: \"bogie.ron\"),\n    ],\n    bodies",
        1,
    );
    let files = tree(&vehicle, BOGIE, WHEELSET);
    let errors = files.errors("vehicle.ron");
    assert!(
        errors
            .iter()
            .any(|e| e.message == "duplicate subsystem name" && e.element == "subsystem \"Bogie1\""),
        "{errors}"
    );
    assert!(
        errors.iter().any(|e| e
            .message
            .contains("instance name \"B.2\" is not a valid name")),
        "{errors}"
    );
    // A connection point named like a body.
    let vehicle = VEHICLE.replacen(
        "    forces: [",
        "    connections: { \"carbody\": (body: \"carbody\") },\n    forces: [",
        1,
    );
    vehicle_error(
        &vehicle,
        "\"carbody\": (",
        "connection \"carbody\"",
        "duplicate name: a body is already called \"carbody\"",
    );
}

#[test]
fn a_failed_subsystem_hides_only_its_own_names() {
    // The bogie file is missing: references to Bogie1's bodies and parameters
    // raise no further errors, but the vehicle's other problems are reported.
    let vehicle = VEHICLE
        .replacen("file: \"bogie.ron\"", "file: \"bogi.ron\"", 1)
        .replacen("\"lb\": 9.5", "\"lb\": 9.5, \"h\": \"Bogie1.a + 1\"", 1)
        .replacen("c: 1e6),\n    ],\n)", "c: 1e6),\n        Spring(name: \"S2\", body1: \"carbdy\", body2: \"Bogie1.WS1.BoxLeft\", c: 1),\n    ],\n)", 1);
    let files = tree(&vehicle, BOGIE, WHEELSET);
    let errors = files.errors("vehicle.ron");
    let path = files.path("vehicle.ron");
    located(
        &errors,
        &path,
        &vehicle,
        "\"bogi.ron\"",
        "subsystem \"Bogie1\"",
        "cannot read the subsystem file",
    );
    located(
        &errors,
        &path,
        &vehicle,
        "\"carbdy\"",
        "force \"S2\"",
        "unknown body \"carbdy\" in body1; close matches: \"carbody\"",
    );
    assert_eq!(errors.len(), 2, "{errors}");
}

#[test]
fn the_includer_uses_subsystem_parameters_by_long_name() {
    let vehicle = VEHICLE
        .replacen(
            "\"lb\": 9.5 }",
            "\"lb\": 9.5, \"hc\": \"Bogie1.WS1.r0 + 1.5\" },\n    macros: { \"heavy\": { \"Bogie1.WS2.m\": \"2*Bogie1.WS1.m\" } }",
            1,
        )
        .replacen(
            "joint: SixDof(parent: \"ground\", track: Some(0))",
            "joint: SixDof(parent: \"ground\", at: (0, 0, \"hc\"), track: Some(0))",
            1,
        );
    let files = tree(&vehicle, BOGIE, WHEELSET);
    let m = files.load("vehicle.ron").unwrap_or_else(|e| panic!("{e}"));
    let i = |n: &str| m.parameter_index(n).unwrap();
    assert_eq!(m.default_parameter_values()[i("hc")], 0.46 + 1.5);
    let p = m
        .parameter_values(&[s("heavy")], &[(s("Bogie1.WS1.r0"), s("0.5"))])
        .unwrap();
    assert_eq!(p[i("hc")], 2.0);
    assert_eq!(p[i("Bogie1.WS2.m")], 3000.0);
    assert_eq!(p[i("Bogie1.WS1.m")], 1500.0);
}

#[test]
fn unknown_identifiers_list_close_long_names() {
    let vehicle = VEHICLE.replacen("\"offset\": \"lb\"", "\"offset\": \"Bogie1.WS1.ofset\"", 1);
    let files = tree(&vehicle, BOGIE, WHEELSET);
    let errors = files.errors("vehicle.ron");
    let e = located(
        &errors,
        &files.path("vehicle.ron"),
        &vehicle,
        "\"Bogie1.WS1.ofset\"",
        "subsystem \"Bogie1\"",
        "unknown identifier \"Bogie1.WS1.ofset\" in the override of \"offset\"",
    );
    assert!(
        e.message
            .ends_with("; close matches: \"Bogie1.WS1.offset\", \"Bogie1.WS2.offset\""),
        "{e}"
    );
}

#[test]
fn values_made_non_finite_by_an_override_are_errors() {
    let ws = WHEELSET.replacen("radius: \"r0\"", "radius: \"sqrt(r0)\"", 1);
    let bogie = BOGIE.replacen(
        "\"offset\": \"offset - a\"",
        "\"offset\": \"offset - a\", \"r0\": \"-a\"",
        1,
    );
    let files = Files::new(&[
        ("profiles/wheel.prw", S1002_PRW),
        ("profiles/rail.ban", UIC60_BAN),
        ("wheelsets/ws.ron", &ws),
        ("wheelsets/bogie.ron", &bogie.replace("ws.ron", "./ws.ron")),
    ]);
    let errors = files.errors("wheelsets/bogie.ron");
    let text = std::fs::read_to_string(files.path("wheelsets/bogie.ron")).unwrap();
    located(
        &errors,
        &files.path("wheelsets/bogie.ron"),
        &text,
        "Subsystem(name: \"WS2\"",
        "subsystem \"WS2\"",
        "force \"WS2.Contact\", with this instance's parameters: a value is not finite: NaN",
    );
    assert_eq!(errors.len(), 1, "{errors}");

    // Range checks of force elements, with the instance's parameters.
    let files = Files::new(&[
        ("profiles/wheel.prw", S1002_PRW),
        ("profiles/rail.ban", UIC60_BAN),
        ("wheelsets/ws.ron", WHEELSET),
        ("wheelsets/bogie.ron", &bogie.replace("ws.ron", "./ws.ron")),
    ]);
    let errors = files.errors("wheelsets/bogie.ron");
    located(
        &errors,
        &files.path("wheelsets/bogie.ron"),
        &text,
        "Subsystem(name: \"WS2\"",
        "subsystem \"WS2\"",
        "force \"WS2.Contact\", with this instance's parameters: radius must be positive, got -1.25",
    );
    assert_eq!(errors.len(), 1, "{errors}");
}

#[test]
fn edge_cases_of_overrides_and_parents() {
    let absorber = std::fs::read_to_string(example("absorber.ron")).unwrap();
    let rig = |subsystems: &str| {
        format!(
            "Model(\n    name: \"rig\",\n    subsystems: [\n        {subsystems}\n    ],\n    bodies: [],\n)\n"
        )
    };
    // parent: "ground" changes nothing.
    let text = rig(r#"Subsystem(name: "A", file: "absorber.ron", parent: "ground"),"#);
    let files = Files::new(&[("absorber.ron", &absorber), ("rig.ron", &text)]);
    let m = files.load("rig.ron").unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(m.bodies[0].parent, BodyRef::Ground);

    // The same parameter overridden twice.
    let text =
        rig(r#"Subsystem(name: "A", file: "absorber.ron", parameters: { "m": 1, "m": 2 }),"#);
    let files = Files::new(&[("absorber.ron", &absorber), ("rig.ron", &text)]);
    let errors = files.errors("rig.ron");
    assert!(
        errors
            .iter()
            .any(|e| e.message == "overrides \"m\" twice" && e.element == "subsystem \"A\""),
        "{errors}"
    );

    // A subsystem re-attached to its own body: a loop.
    let text = rig(r#"Subsystem(name: "A", file: "absorber.ron", parent: "A.mass"),"#);
    let files = Files::new(&[("absorber.ron", &absorber), ("rig.ron", &text)]);
    let errors = files.errors("rig.ron");
    located(
        &errors,
        &files.path("rig.ron"),
        &text,
        "parent: \"A.mass\"",
        "subsystem \"A\"",
        "loop in the body tree (body -> its parent): A.mass -> A.mass",
    );

    // An empty file name; a file that is not a model.
    let text = rig(r#"Subsystem(name: "A", file: ""),
        Subsystem(name: "B", file: "notes.txt"),"#);
    let files = Files::new(&[("notes.txt", "hello"), ("rig.ron", &text)]);
    let errors = files.errors("rig.ron");
    located(
        &errors,
        &files.path("rig.ron"),
        &text,
        "\"\")",
        "subsystem \"A\"",
        "cannot read the subsystem file",
    );
    let e = errors
        .iter()
        .find(|e| e.file == files.path("notes.txt"))
        .unwrap_or_else(|| panic!("{errors}"));
    assert!(e.message.contains("(included as \"B\" from "), "{e}");
}

#[test]
fn cut_joints_of_subsystems_get_long_names() {
    let fourbar = model_path("mechanisms/fourbar.ron");
    let original = load_model(&fourbar).unwrap();
    assert!(!original.cut_joints.is_empty());
    let text = format!(
        "Model(\n    name: \"two\",\n    subsystems: [\n        Subsystem(name: \"L\", file: \"{0}\"),\n        Subsystem(name: \"R\", file: \"{0}\"),\n    ],\n    bodies: [],\n)\n",
        fourbar.display()
    );
    let files = Files::new(&[("two.ron", &text)]);
    let m = files.load("two.ron").unwrap_or_else(|e| panic!("{e}"));
    let n = original.bodies.len();
    assert_eq!(m.bodies.len(), 2 * n);
    assert_eq!(m.cut_joints.len(), 2 * original.cut_joints.len());
    let body_name = |m: &Model, b: BodyRef| match b {
        BodyRef::Ground => "ground".to_string(),
        BodyRef::Body(i) => m.bodies[i].name.clone(),
    };
    let (pm, po) = (
        m.default_parameter_values(),
        original.default_parameter_values(),
    );
    for (k, prefix) in ["L.", "R."].iter().enumerate() {
        for (j, c) in original.cut_joints.iter().enumerate() {
            let f = &m.cut_joints[k * original.cut_joints.len() + j];
            assert_eq!(f.name, format!("{prefix}{}", c.name));
            for (a, b) in [(f.body1, c.body1), (f.body2, c.body2)] {
                let expected = match b {
                    BodyRef::Ground => "ground".to_string(),
                    _ => format!("{prefix}{}", body_name(&original, b)),
                };
                assert_eq!(body_name(&m, a), expected);
            }
            assert_eq!(eval3(&f.frame1.origin, &pm), eval3(&c.frame1.origin, &po));
            assert_eq!(eval3(&f.frame2.origin, &pm), eval3(&c.frame2.origin, &po));
            assert_eq!(f.constrained, c.constrained);
        }
    }
}
