//! Accelerometer outputs (`output: (accelerometers: {name: (body, point)})`):
//! the kinematic acceleration of a body point in the body's frame, against
//! the centripetal acceleration of a spinning body, the spring force of an
//! oscillator, and the lateral acceleration v²/R of a body carried round a
//! curve by its track-following frame.

use railmbs_runtime::NumericEquations;
use railmbs_runtime::run::run_scenario;

/// Runs `scenario` (text) with `model` (text) written beside it; returns the
/// header and rows of the output.
fn run(model: &str, scenario: &str, extra: &[(&str, &str)]) -> (Vec<String>, Vec<Vec<f64>>) {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("model.ron"), model).unwrap();
    for (name, text) in extra {
        std::fs::write(dir.path().join(name), text).unwrap();
    }
    let path = dir.path().join("run.ron");
    std::fs::write(&path, scenario).unwrap();
    let sc = railmbs_models::load_scenario(&path).unwrap_or_else(|e| panic!("{e}"));
    let m = railmbs_models::load_model(&sc.model).unwrap_or_else(|e| panic!("{e}"));
    let out = dir.path().join("out.csv");
    let summary = run_scenario(
        &sc,
        &m,
        Box::new(NumericEquations::new(&m)),
        Some(&out),
        |_| {},
    )
    .unwrap_or_else(|e| panic!("{e}"));
    assert!(summary.error.is_none(), "{:?}", summary.error);
    let text = std::fs::read_to_string(&out).unwrap();
    let mut lines = text.lines();
    let header = lines.next().unwrap().split(',').map(String::from).collect();
    let rows = lines
        .map(|l| l.split(',').map(|x| x.parse().unwrap()).collect())
        .collect();
    (header, rows)
}

fn col(header: &[String], name: &str) -> usize {
    header
        .iter()
        .position(|h| h == name)
        .unwrap_or_else(|| panic!("no column {name} in {header:?}"))
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
    let (h, rows) = run(model, scenario, &[]);
    assert_eq!(
        h[h.len() - 9..],
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
        col(&h, "rim.ax[m/s2]"),
        col(&h, "axis.ax[m/s2]"),
        col(&h, "m.ax[m/s2]"),
        col(&h, "x"),
    );
    for r in &rows {
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
    let (h, rows) = run(model, scenario, &[("track.ron", track)]);
    let (c, f) = (col(&h, "c.ax[m/s2]"), col(&h, "front.ax[m/s2]"));
    for r in &rows {
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
