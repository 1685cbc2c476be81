//! `umsim info FILE`: a model's (or a scenario's model's) parameters,
//! macros, coordinates, bodies, force elements and output columns.

use crate::common::{text, umsim};

#[test]
fn info_lists_what_a_model_offers() {
    let o = umsim(&["info", "models/scenarios/double_pendulum.ron"]);
    let out = text(&o.stdout);
    assert!(o.status.success(), "{}", text(&o.stderr));
    // The model file says l2 = 0.7 m, m2 = 0.5 kg, g = 9.81 m/s² and a macro.
    for line in [
        "model \"double_pendulum\"",
        "2 bodies, 2 coordinates, 0 cut joints, 0 force elements",
        "scenario models/scenarios/double_pendulum.ron: end time 10 s, output every 0.01 s",
        "  l2 = 0.7",
        "  g = 9.81",
        "  equal_rods: l2 = l1, m2 = m1",
        "  q2 (rod2)",
        "  rod2, 0.5",
    ] {
        assert!(out.contains(line), "no {line:?} in\n{out}");
    }
    // A vehicle: the wheel-rail element's columns, as the runner names them.
    let o = umsim(&["info", "models/vehicles/vehicle1.ron"]);
    let out = text(&o.stdout);
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(out.contains("8 bodies, 42 coordinates"), "{out}");
    assert!(
        out.contains("  mc = 32000 [kg]  car body mass, kg"),
        "{out}"
    );
    // The unit column: from the doc's last ", UNIT" (before a remark), "-"
    // for a parameter whose doc gives none (the friction coefficient).
    for line in [
        "  Bogie1.WS1.Iyy = 112 [kg m2]  spin inertia, kg m2",
        "  kyaw2 = 10500 [N m/rad]  ",
        "  Bogie1.WS1.penetration = 0.000236 [m]  ",
        "  mu = 0.4 [-]  wheel–rail coefficient of friction",
    ] {
        assert!(out.contains(line), "no {line:?} in\n{out}");
    }
    assert!(
        out.contains("  Bogie1.WS1.contact (WheelRail): L.Q [N], L.Y [N], L.Y/Q [-]"),
        "{out}"
    );
    // Not a model or scenario.
    let o = umsim(&["info", "models/tracks/straight.ron"]);
    assert_eq!(o.status.code(), Some(1));
    assert!(
        text(&o.stderr).contains("expected a Model(...) or Scenario(...) file"),
        "{}",
        text(&o.stderr)
    );
}

/// Units in every `--help` (issue 18): each option with a physical quantity
/// names its unit, in its value name or its help text, command by command.
#[test]
fn every_help_names_the_units_of_its_quantities() {
    let cases: [(&str, &[&str]); 6] = [
        (
            "run",
            &["--end-time <SECONDS>", "in the parameter's own unit, SI"],
        ),
        (
            "conicity",
            &[
                "--gauge <MM>",
                "--flange-back <MM>",
                "--diameters <MM,MM>",
                "--smoothing <MM>",
            ],
        ),
        (
            "creep",
            &[
                "contact semi-axes, m",
                "combined shear modulus, Pa",
                "normal force, N",
                "spin creepage, 1/m",
                "Mz in N·m",
            ],
        ),
        (
            "curving",
            &["--radius <M>", "--cant <M>", "--speed <M/S|FROM:TO:STEP>"],
        ),
        ("modes", &["`FROM:TO:STEP` (m/s)"]),
        (
            "plot",
            &[
                "--width <PIXELS>",
                "--height <PIXELS>",
                "s for time, m for `s[m]`",
            ],
        ),
    ];
    for (command, needles) in cases {
        let o = umsim(&[command, "--help"]);
        let out = text(&o.stdout);
        assert!(o.status.success(), "{command}: {}", text(&o.stderr));
        for needle in needles {
            assert!(
                out.contains(needle),
                "umsim {command} --help lacks {needle:?}:\n{out}"
            );
        }
    }
}
