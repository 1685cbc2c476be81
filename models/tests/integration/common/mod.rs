//! The model texts of the models crate's tests and the checks of located
//! errors in them; models from text come from the test kit
//! ([`railmbs_testkit::try_parse`], said to be in [`FILE`]).
#![allow(dead_code)]

use railmbs_models::{Model, ModelError, ModelErrors};

pub use railmbs_testkit::{TEXT_FILE as FILE, try_parse as load};

/// The bundled S1002 wheel profile (SIMPACK `.prw`), for tests that write
/// their own profile files (profiles are read when a model loads).
pub const S1002_PRW: &str = include_str!("../../../profiles/MBench_S1002_v3.prw");

/// The bundled UIC60 rail profile (MiniProf `.ban`).
pub const UIC60_BAN: &str = include_str!("../../../profiles/MBench_UIC60_v3.ban");

/// A model using every construct of the language.
pub const FULL: &str = r#"// A model using every construct.
Model(
    name: "everything",
    description: "test model",
    parameters: {
        "l1": 1.0,
        "m1": 1.0,
        "l2": "l1",
        "m2": (value: 2, doc: "kg"),
        "g": 9.81,
        "k": 100,
        "d": 1.5,
        "L0": 0.5,
        "WS1.r0": 0.46,
    },
    macros: { "heavy": { "m1": 2.0, "m2": "2*m1" }, "long": { "l1": 3 } },
    gravity: (0, "-g", 0),
    bodies: [
        Body(
            name: "link2", mass: "m2", inertia: (ixx: 0.1, iyy: 0.1, izz: 0.1),
            joint: Joint(parent: "link1", transforms: [
                Ty("-l1/2"),
                Rz((coord: "q1", init: "0.1*l1", vel: 2)),
                Rx("0.1*sin(2*pi*t)"),
                Ty("-l2/2"),
                Tx(0),
                Rz((coord: "q2")),
            ]),
        ),
        Body(
            name: "link1",
            mass: "m1",
            inertia: (ixx: "m1*l1^2/12", iyy: 1e-4, izz: "m1*l1^2/12"),
            joint: Revolute(parent: "ground", at: (0, 0, 0), axis: Z,
                            coord: "q0", init: 0.5, vel: 0.0, to_com: (0, "-l1/2", 0)),
        ),
        Body(name: "Bogie1.WS1", mass: 1200, inertia: (ixx: 700, iyy: 100, izz: 700, ixy: 1),
             joint: SixDof(parent: "ground", at: (1, 2, "WS1.r0"), order: "zxy",
                           init: (0.1, 0.2, 0.3, 0.4, 0.5, 0.6), vel: (1, 0, 0, 0, "1/WS1.r0", 0))),
        Body(name: "fix", mass: 1, inertia: (ixx: 1, iyy: 1, izz: 1),
             joint: Rigid(parent: "Bogie1.WS1", at: (1, 0, 0), rotation: (0, 0.5, 0))),
        Body(name: "slider", mass: 1, inertia: (ixx: 1, iyy: 1, izz: 1),
             joint: Prismatic(parent: "ground", axis: X, to_com: (0, 0, 0.25))),
    ],
    cut_joints: [
        CutJoint(name: "closure", body1: "link2", point1: (0, "-l2/2", 0), rotation1: (0, 0, 0),
                 body2: "ground", point2: (2.0, 0, 0), constrain: [Tx, Ty]),
    ],
    forces: [
        Spring(name: "k1", body1: "ground", point1: (0, 0, 0), body2: "slider", point2: (0, 0, 0),
               c: "k", d: "d", f0: 0, x0: "L0"),
        Linear6(name: "bush", body1: "Bogie1.WS1", point1: (0, 0, 0), rotation1: (0, 0, 0),
                body2: "fix", point2: (0, 0, 0), rotation2: (0, 0, 0),
                stiffness: Diag((1e6, 1e6, 1e6, 1e3, 1e3, 1e3)),
                damping: Full([1,0,0,0,0,0, 0,1,0,0,0,0, 0,0,1,0,0,0, 0,0,0,1,0,0, 0,0,0,0,1,0, 0,0,0,0,0,"k"]),
                preload: (0, 0, "m1*g", 0, 0, 0)),
        Applied(name: "push", body: "slider", point: (0, 0, 0), force: ("10*sin(t)", 0, 0),
                torque: (0, 0, 0), frame: Body),
        Applied(name: "pull", body: "slider", force: (0, 0, -1)),
    ],
)
"#;

/// A small valid model for validation tests; errors are made by replacing text.
pub const BASE: &str = r#"Model(
    name: "base",
    parameters: { "m": 2.0, "l": 1.0, "k": 10 },
    bodies: [
        Body(
            name: "a",
            mass: "m",
            inertia: (ixx: 1, iyy: 1, izz: 1),
            joint: Revolute(parent: "ground", axis: Z, coord: "qa"),
        ),
        Body(
            name: "b",
            mass: 1,
            inertia: (ixx: 1, iyy: 1, izz: 1),
            joint: Joint(parent: "a", transforms: [Ty("-l"), Rz((coord: "qb"))]),
        ),
    ],
    cut_joints: [
        CutJoint(name: "cj", body1: "b", point1: (0, 0, 0), body2: "ground", point2: (1, 0, 0), constrain: [Tx]),
    ],
    forces: [
        Spring(name: "s", body1: "ground", point1: (0, 0, 0), body2: "b", point2: (0, 0, 0), c: "k"),
    ],
)
"#;

pub fn full() -> Model {
    load(FULL).unwrap_or_else(|e| panic!("{e}"))
}

/// Replaces `from` (which must occur) by `to` in BASE and returns the errors.
pub fn base_errors(from: &str, to: &str) -> ModelErrors {
    assert!(BASE.contains(from), "BASE does not contain {from:?}");
    match load(&BASE.replacen(from, to, 1)) {
        Ok(_) => panic!("replacing {from:?} by {to:?} should be an error"),
        Err(e) => e,
    }
}

/// The error naming `element` whose message contains `needle`; checks that
/// its display names the file, line and column, the element and the message.
pub fn find<'a>(errors: &'a ModelErrors, element: &str, needle: &str) -> &'a ModelError {
    let e = errors
        .iter()
        .find(|e| e.element == element && e.message.contains(needle))
        .unwrap_or_else(|| panic!("no error for {element} containing {needle:?} in:\n{errors}"));
    let (line, col) = e
        .position
        .unwrap_or_else(|| panic!("error without a position: {e}"));
    let shown = e.to_string();
    let prefix = if element.is_empty() {
        format!("{FILE}:{line}:{col}: ")
    } else {
        format!("{FILE}:{line}:{col}: {element}: ")
    };
    assert!(
        shown.starts_with(&prefix),
        "{shown} should start with {prefix}"
    );
    assert!(shown.contains(needle), "{shown}");
    e
}

/// 1-based line of the first occurrence of `text` in `src`.
pub fn line_of(src: &str, text: &str) -> usize {
    let off = src
        .find(text)
        .unwrap_or_else(|| panic!("{text:?} not found"));
    src[..off].matches('\n').count() + 1
}
