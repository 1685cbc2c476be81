//! `umsim conicity` end to end on the bundled EN 15302 profiles against the EN 15302 Annex E
//! reference case E1 (wheels A/A on rail A, diameters 920 mm, gauge 1435.16 mm), tolerance
//! min(0.05, 0.5 tan γe) (Annex F).

use railmbs_testkit::{model_path, reference_path};
use std::process::Command;

#[test]
fn conicity_e1_matches_en15302_reference() {
    let out = Command::new(env!("CARGO_BIN_EXE_umsim"))
        .args(["conicity", "--wheel"])
        .arg(model_path("profiles/en15302/RUIC519A.dat"))
        .arg("--rail")
        .arg(model_path("profiles/en15302/SUIC519A.dat"))
        .args(["--gauge", "1435.16", "--diameters", "920,920"])
        .output()
        .unwrap();
    assert!(
        out.status.success(),
        "{}",
        String::from_utf8_lossy(&out.stderr)
    );
    let text = String::from_utf8(out.stdout).unwrap();
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("amplitude_mm,tan_gamma_e"));
    let rows: Vec<(f64, f64)> = lines
        .map(|l| {
            let (a, t) = l.split_once(',').unwrap();
            (a.parse().unwrap(), t.parse().unwrap())
        })
        .collect();
    assert_eq!(rows.len(), 20);
    assert!((rows[0].0 - 0.5).abs() < 1e-9 && (rows[19].0 - 10.0).abs() < 1e-9);
    let reference = std::fs::read_to_string(reference_path("conicity/ben_E1.dat")).unwrap();
    let mut compared = 0;
    for l in reference.lines().filter(|l| !l.trim().is_empty()) {
        let v: Vec<f64> = l.split_whitespace().map(|x| x.parse().unwrap()).collect();
        if let Some(&(_, t)) = rows.iter().find(|r| (r.0 - v[0]).abs() < 1e-6) {
            let tol = (0.5 * v[1]).min(0.05) + 1e-9;
            assert!((t - v[1]).abs() <= tol, "ŷ {} mm: {t} vs {}", v[0], v[1]);
            compared += 1;
        }
    }
    assert_eq!(compared, 14); // 1.0, 1.5, …, 7.5 mm
}

#[test]
fn conicity_writes_file_and_reports_bad_input() {
    let dir = std::env::temp_dir().join(format!("umsim-conicity-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let out_csv = dir.join("c.csv");
    let st = Command::new(env!("CARGO_BIN_EXE_umsim"))
        .args(["conicity", "--wheel"])
        .arg(model_path("profiles/en15302/RUIC519B.dat"))
        .arg("--rail")
        .arg(model_path("profiles/en15302/SUIC519A.dat"))
        .args(["--gauge", "1435.16", "-o"])
        .arg(&out_csv)
        .status()
        .unwrap();
    assert!(st.success());
    let text = std::fs::read_to_string(&out_csv).unwrap();
    assert!(text.starts_with("amplitude_mm,tan_gamma_e\n0.5,"));
    // a malformed profile: the error names the file and line, exit status 1
    let bad = dir.join("bad_wheel.dat");
    std::fs::write(&bad, "-70 -9\n0 0\n10 abc\n20 0.2\n").unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_umsim"))
        .args(["conicity", "--wheel"])
        .arg(&bad)
        .arg("--rail")
        .arg(model_path("profiles/en15302/SUIC519A.dat"))
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
    let err = String::from_utf8_lossy(&out.stderr);
    assert!(err.contains("bad_wheel.dat:3:"), "{err}");
    // a rail given as wheel is refused by its extension
    let out = Command::new(env!("CARGO_BIN_EXE_umsim"))
        .args(["conicity", "--wheel"])
        .arg(model_path("profiles/MBench_UIC60_v3.prr"))
        .arg("--rail")
        .arg(model_path("profiles/en15302/SUIC519A.dat"))
        .output()
        .unwrap();
    assert_eq!(out.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&out.stderr).contains("rail profile"));
    std::fs::remove_dir_all(&dir).unwrap();
}

/// A wheel profile given as the rail (a two-column file says nothing about its
/// kind) is an error with a message, not a panic (exit code 101).
#[test]
fn a_wheel_profile_as_the_rail_is_an_error() {
    let out = Command::new(env!("CARGO_BIN_EXE_umsim"))
        .args(["conicity", "--wheel"])
        .arg(model_path("profiles/en15302/RUIC519A.dat"))
        .arg("--rail")
        .arg(model_path("profiles/en15302/RUIC519A.dat"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("no contact between left wheel and rail"),
        "{stderr}"
    );
}
