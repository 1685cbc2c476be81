//! Track cases: the documented data are what the constructors build.
#![allow(clippy::needless_range_loop)] // index loops mirror the vector formulas

use railmbs_track::cases::*;
use railmbs_track::{STANDARD_GRAVITY, balancing_speed, uncompensated_lateral_acceleration};

#[test]
fn manchester_track_case_1() {
    let t = manchester_tc1().unwrap();
    assert!((t.length() - 275.0).abs() < 1e-12);
    let a = t.alignment();
    assert!(
        (a.section_end(3).unwrap() - 175.0).abs() < 1e-12,
        "end of the leaving transition"
    );
    // Right curve of 150 m with 100 mm cant, outer (left) rail raised.
    let p = t.point(100.0).unwrap();
    assert!((p.plan.curvature + 1.0 / 150.0).abs() < 1e-15);
    assert!((p.plan.cant - 0.1).abs() < 1e-15 && p.roll > 0.0);
    // Cant ramps linearly with curvature on the transitions.
    let p = t.point(50.0).unwrap();
    assert!((p.plan.cant - 0.05).abs() < 1e-15);
    assert!((p.plan.curvature + 0.5 / 150.0).abs() < 1e-15);
    // The curve turns the track through (50 + 2·25)/150 rad to the right.
    let p = t.point(275.0).unwrap();
    assert!((p.plan.heading + 100.0 / 150.0).abs() < 1e-13);
    // 20 mm linear dip in the left rail centred at s = 175 m, 10 m long.
    let d = |s| t.deviation(s).unwrap();
    assert!((d(175.0).left_vertical + 0.020).abs() < 1e-15);
    assert!((d(172.5).left_vertical + 0.010).abs() < 1e-15);
    assert_eq!(d(170.0).left_vertical, 0.0);
    assert_eq!(d(180.0).left_vertical, 0.0);
    assert_eq!(d(175.0).right_vertical, 0.0);
    // The suggested start keeps Vehicle 1's rear wheelset (10.78 m behind the
    // body centre) on the track, and 42 s at 4.4 m/s takes it past the dip.
    let rear = TC1_BODY_START - (9.5 + 1.28);
    assert!(rear >= 0.0);
    assert!(rear + TC1_SPEED * TC1_DURATION > 180.0);
    // Balancing speed √(g R tan φ), tan(asin(1/15)) = 1/√224: 9.914 m/s, so at
    // 4.4 m/s the curve has cant excess (a_q < 0).
    let veq = balancing_speed(150.0, p_roll(&t), STANDARD_GRAVITY).unwrap();
    assert!((veq - (STANDARD_GRAVITY * 150.0 / 224f64.sqrt()).sqrt()).abs() < 1e-12);
    assert!(
        uncompensated_lateral_acceleration(TC1_SPEED, 150.0, 0.1, 1.5, STANDARD_GRAVITY).unwrap()
            < 0.0
    );
}

fn p_roll(t: &railmbs_track::Track) -> f64 {
    t.point(100.0).unwrap().roll
}

#[test]
fn manchester_track_case_3() {
    let t = manchester_tc3(1000.0).unwrap();
    for s in [0.0, 300.0, 1000.0] {
        assert!((t.deviation(s).unwrap().gauge() - 0.0254).abs() < 1e-15);
    }
    let x = t.deviation(50.0 + 6.25).unwrap();
    assert!(
        (x.alignment() - 0.005).abs() < 1e-15,
        "5 mm at a quarter wave"
    );
    assert!(t.deviation(50.0).unwrap().alignment().abs() < 1e-15);
    assert!(t.deviation(550.0).unwrap().alignment().abs() < 1e-15);
    assert_eq!(t.deviation(600.0).unwrap().alignment(), 0.0);
    assert_eq!(t.point(500.0).unwrap().plan.curvature, 0.0);
    assert!(manchester_tc3(100.0).is_err());
    assert!(manchester_tc3(f64::NAN).is_err());
}

#[test]
fn high_speed_curve_case() {
    let t = high_speed_curve().unwrap();
    assert!((t.length() - 1300.0).abs() < 1e-12);
    let p = t.point(600.0).unwrap();
    assert!((p.plan.curvature - 1.0 / 1200.0).abs() < 1e-15);
    assert!(
        (p.plan.cant + 0.15).abs() < 1e-15 && p.roll < 0.0,
        "left curve: right rail up"
    );
    // v_eq = √(g R tan(asin 0.1)) = 34.39 m/s; a_q(45 m/s) = 0.7068 m/s².
    let veq = balancing_speed(1200.0, p.roll, STANDARD_GRAVITY).unwrap();
    assert!((veq - (STANDARD_GRAVITY * 1200.0 * 0.1 / 0.99f64.sqrt()).sqrt()).abs() < 1e-12);
    assert!((veq - 34.39).abs() < 0.01);
    let aq =
        uncompensated_lateral_acceleration(HS_SPEED, 1200.0, 0.15, 1.5, STANDARD_GRAVITY).unwrap();
    assert!((aq - (2025.0 / 1200.0 - STANDARD_GRAVITY * 0.1)).abs() < 1e-14);
    // Frame at speed: the specific force a − g_vec along the canted frame's y
    // axis (−sψ cφ, cψ cφ, sφ) is (v²/R) cos φ + g sin φ with sin φ = −h/2e0:
    // the uncompensated acceleration in the rail plane, toward the centre.
    let f = t.frame(600.0, HS_SPEED, 0.0).unwrap();
    let r = f.rotation;
    let spec = [
        f.acceleration[0],
        f.acceleration[1],
        f.acceleration[2] + STANDARD_GRAVITY,
    ];
    let lat: f64 = (0..3).map(|i| r[i][1] * spec[i]).sum();
    let expected = 2025.0 / 1200.0 * 0.99f64.sqrt() - STANDARD_GRAVITY * 0.1;
    assert!((lat - expected).abs() < 1e-12, "{lat} vs {expected}");
}

#[test]
fn straight_lateral_irregularity_case() {
    let t = straight_lateral_irregularity(600.0, 42).unwrap();
    assert_eq!(t.deviation(40.0).unwrap().alignment(), 0.0);
    let x = t.deviation(300.0).unwrap();
    assert!(x.alignment() != 0.0 && x.gauge() == 0.0 && x.level() == 0.0);
    let u = straight_lateral_irregularity(600.0, 42).unwrap();
    assert_eq!(u.deviation(234.5).unwrap(), t.deviation(234.5).unwrap());
    assert!(straight_lateral_irregularity(100.0, 1).is_err());
}
