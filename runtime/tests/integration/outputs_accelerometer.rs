//! Accelerometer outputs (`output: (accelerometers: {name: (body, point)})`):
//! the kinematic acceleration of a body point in the body's frame, against
//! the centripetal acceleration of a spinning body, the spring force of an
//! oscillator, and the lateral acceleration v²/R of a body carried round a
//! curve by its track-following frame.

use railmbs_testkit::{Table, run_scenario_files};

/// Runs `scenario` (text) with `model` (text, as `model.ron`) and the
/// `extra` files written beside it; returns the output.
fn run(model: &str, scenario: &str, extra: &[(&str, &str)]) -> Table {
    let mut files = vec![("model.ron", model)];
    files.extend_from_slice(extra);
    run_scenario_files(&files, scenario).unwrap_or_else(|e| panic!("{e}"))
}

#[test]
fn spinning_body_and_oscillator_accelerations() {
    let model = r#"
Model(
    name: "acc",
    gravity: (0, 0, 0),
    bodies: [
        Body(name: "disc", mass: 1, inertia: (ixx: 1, iyy: 1, izz: 1),
             joint: Revolute(parent: "ground", axis: Z, coord: "phi", vel: 2)),
        Body(name: "mass", mass: 2, inertia: (ixx: 1, iyy: 1, izz: 1),
             joint: Prismatic(parent: "ground", axis: X, coord: "x", init: 1.1)),
    ],
    forces: [
        Spring(name: "k", body1: "ground", body2: "mass", c: 800, x0: 1),
    ],
)
"#;
    let scenario = r#"
Scenario(
    model: "model.ron",
    end_time: 1.0,
    integrator: Park(rtol: 1e-9, atol: 1e-10, max_step: 0.01),
    output: (interval: 0.05, accelerometers: {
        "rim": ("disc", (0.5, 0, 0)),
        "axis": ("disc", (0, 0, 0.3)),
        "m": ("mass", (0, 0, 0)),
    }),
)
"#;
    let table = run(model, scenario, &[]);
    assert_eq!(
        table.header[table.header.len() - 9..],
        [
            "rim.ax[m/s2]",
            "rim.ay[m/s2]",
            "rim.az[m/s2]",
            "axis.ax[m/s2]",
            "axis.ay[m/s2]",
            "axis.az[m/s2]",
            "m.ax[m/s2]",
            "m.ay[m/s2]",
            "m.az[m/s2]",
        ]
    );
    let (rim, axis, m, x) = (
        table.index("rim.ax[m/s2]"),
        table.index("axis.ax[m/s2]"),
        table.index("m.ax[m/s2]"),
        table.index("x"),
    );
    for r in &table.rows {
        // Centripetal ω² r towards the axis, in the disc's own frame: the
        // central difference over ε = 1e-5 s has truncation ω²ε²·|a|/6 ≈ 1e-10.
        assert!((r[rim] + 4.0 * 0.5).abs() < 1e-8, "{r:?}");
        assert!(r[rim + 1].abs() < 1e-8 && r[rim + 2].abs() < 1e-8, "{r:?}");
        assert!(r[axis..axis + 3].iter().all(|a| a.abs() < 1e-8), "{r:?}");
        // Spring: m ẍ = −c (x − x0). Between steps, q̈ is the derivative of
        // the velocity interpolant: error O(h²·x⁽⁴⁾) ~ 1e-4 of the 4 m/s²
        // amplitude at rtol 1e-9.
        let exact = -800.0 / 2.0 * (r[x] - 1.0);
        assert!(
            (r[m] - exact).abs() < 1e-3 * 4.0,
            "a = {}, spring {exact}",
            r[m]
        );
    }
}

#[test]
fn body_on_a_curve_feels_the_centripetal_acceleration() {
    // A body fixed to its track-following frame on a 500 m left curve
    // without cant at 20 m/s: the acceleration v²/R = 0.8 m/s² points to the
    // curve's centre, +y (left) in the body's frame; nothing along or up.
    let model = r#"
Model(
    name: "rider",
    gravity: (0, 0, 0),
    bodies: [
        Body(name: "box", mass: 1, inertia: (ixx: 1, iyy: 1, izz: 1),
             joint: Rigid(parent: "ground", track: Some(0))),
        // The integrator needs a degree of freedom; this one just coasts.
        Body(name: "coaster", mass: 1, inertia: (ixx: 1, iyy: 1, izz: 1),
             joint: Prismatic(parent: "ground", axis: X, coord: "u", vel: 1)),
    ],
)
"#;
    let track = r#"
Custom((
    sections: [Curve(length: 400.0, radius: 500.0, direction: Left)],
))
"#;
    let scenario = r#"
Scenario(
    model: "model.ron",
    track: (file: "track.ron", start: 100, speed: 20),
    end_time: 5.0,
    integrator: Park(rtol: 1e-8, atol: 1e-9, max_step: 0.01),
    output: (interval: 0.5, accelerometers: { "c": ("box", (0, 0, 0)), "front": ("box", (3, 0, 0)) }),
)
"#;
    let table = run(model, scenario, &[("track.ron", track)]);
    let (c, f) = (table.index("c.ax[m/s2]"), table.index("front.ax[m/s2]"));
    for r in &table.rows {
        // Turning left: the acceleration points to the left, +y.
        assert!((r[c + 1] - 0.8).abs() < 1e-6, "{r:?}");
        assert!(r[c].abs() < 1e-6 && r[c + 2].abs() < 1e-6, "{r:?}");
        // A point 3 m ahead on the body turning at Ω = v/R: also ω²·3
        // backwards: (−Ω²·3, v²/R) = (−0.0048, 0.8).
        assert!(
            (r[f] + 0.0048).abs() < 1e-6 && (r[f + 1] - 0.8).abs() < 1e-6,
            "{r:?}"
        );
    }
}
