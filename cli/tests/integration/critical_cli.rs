//! `umsim critical-speed` and `umsim modes --plot/--sweep`: bad input gets
//! a clear error before anything runs.

use crate::common::{text, umsim};

#[test]
fn a_continuation_longer_than_the_track_is_refused_before_it_runs() {
    // 191 plateaus from 200 down to 10 m/s, 10 s each: about 200 km on
    // the 5 km straight track.
    let out = umsim(&[
        "critical-speed",
        "models/scenarios/wheelset_on_springs_critical.ron",
        "--bifurcation",
        "10:200:1",
        "--hold",
        "10",
        "--signal",
        "ws.y",
    ]);
    assert!(!out.status.success());
    let err = text(&out.stderr);
    assert!(
        err.contains("wheelset_on_springs_critical.ron")
            && err.contains("the track")
            && err.contains("longer track"),
        "{err}"
    );
}

#[test]
fn bad_detection_settings_and_plots_without_a_locus_are_named() {
    let out = umsim(&[
        "critical-speed",
        "models/scenarios/wheelset_on_springs_critical.ron",
        "--window",
        "0",
        "--signal",
        "ws.y",
    ]);
    assert!(!out.status.success());
    assert!(
        text(&out.stderr).contains("window must be positive"),
        "{}",
        text(&out.stderr)
    );
    let out = umsim(&[
        "modes",
        "models/scenarios/spring_mass.ron",
        "--plot",
        "never.svg",
    ]);
    assert!(!out.status.success());
    assert!(
        text(&out.stderr).contains("--plot needs --speed, --sweep or --conicity"),
        "{}",
        text(&out.stderr)
    );
}
