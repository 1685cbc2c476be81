//! `umsim creep` end to end: every method on a small case table, checked
//! against outside references — Kalker's linear theory at small creepage
//! (Kalker 1990 Table E.3 via the library's interpolation is the reference the
//! laws must reproduce there: FASTSIM/FastSim_A within 2 %, Polach exactly) and
//! Coulomb saturation μN at large creepage — and bad input named by row.

use std::process::Command;

const CASES: &str = "a,b,G,nu,mu,N,xi,eta,phi
0.006,0.004,8e10,0.28,0.3,80000,1e-7,0,0
0.006,0.004,8e10,0.28,0.3,80000,0,1e-7,0
0.006,0.004,8e10,0.28,0.3,80000,0.2,0,0
0.006,0.004,8e10,0.28,0.3,80000,0.001,0.002,2.5
";

fn run(args: &[&str], cases: &str) -> (bool, String, String) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("cases.csv");
    std::fs::write(&path, cases).unwrap();
    let out = Command::new(env!("CARGO_BIN_EXE_umsim"))
        .arg("creep")
        .args(args)
        .arg("--cases")
        .arg(&path)
        .output()
        .unwrap();
    (
        out.status.success(),
        String::from_utf8(out.stdout).unwrap(),
        String::from_utf8(out.stderr).unwrap(),
    )
}

fn rows(text: &str) -> Vec<[f64; 3]> {
    let mut lines = text.lines();
    assert_eq!(lines.next(), Some("Fx,Fy,Mz"));
    lines
        .map(|l| {
            let v: Vec<f64> = l.split(',').map(|x| x.parse().unwrap()).collect();
            [v[0], v[1], v[2]]
        })
        .collect()
}

#[test]
fn every_method_reproduces_linear_theory_and_saturation() {
    let (ok, out, err) = run(&["--method", "kalker"], CASES);
    assert!(ok, "{err}");
    let lin = rows(&out);
    let mu_n = 0.3 * 80000.0;
    for (args, tol) in [
        (vec!["--method", "polach"], 1e-6),
        (
            vec!["--method", "fastsim", "--strips", "20", "--elements", "20"],
            0.02,
        ),
        (vec!["--method", "fastsim-a", "--strips", "20"], 0.02),
        (vec!["--method", "fastsim:20"], 0.02),
        (
            vec!["--law", "fastsim-a:strips=20,sliding=integrated,nodes=8"],
            0.02,
        ),
        (vec!["--method", "mueller-kalker-saturated:3"], 1e-6),
        (
            vec![
                "--method",
                "fastsim-a",
                "--strips",
                "20",
                "--sliding",
                "integrated",
            ],
            0.02,
        ),
        (
            vec![
                "--method",
                "fastsim-a",
                "--sliding",
                "picard",
                "--nodes",
                "4",
            ],
            0.02,
        ),
    ] {
        let (ok, out, err) = run(&args, CASES);
        assert!(ok, "{args:?}: {err}");
        let r = rows(&out);
        assert_eq!(r.len(), 4, "{args:?}");
        assert!((r[0][0] / lin[0][0] - 1.0).abs() < tol, "{args:?}: {r:?}");
        assert!((r[1][1] / lin[1][1] - 1.0).abs() < tol, "{args:?}: {r:?}");
        let t = r[2][0].hypot(r[2][1]);
        assert!(t <= mu_n * (1.0 + 1e-9) && t > 0.99 * mu_n, "{args:?}: {t}");
        let t = r[3][0].hypot(r[3][1]);
        assert!(t.is_finite() && t <= mu_n * (1.0 + 1e-9), "{args:?}: {t}");
    }
}

#[test]
fn bad_input_is_named() {
    let (ok, _, err) = run(
        &["--method", "polach"],
        "a,b,G,nu,mu,N,xi,eta,phi\n0.006,0.004,8e10,0.28,0.3,80000,0,0,0\n0.006,0.004,8e10,0.28,-1,80000,0,0,0\n",
    );
    assert!(!ok);
    assert!(err.contains("row 2") && err.contains("mu = -1"), "{err}");
    let (ok, _, err) = run(
        &[
            "--method",
            "fastsim-a",
            "--sliding",
            "integrated",
            "--nodes",
            "0",
        ],
        CASES,
    );
    assert!(!ok);
    assert!(err.contains("nodes"), "{err}");
}

#[test]
fn bad_law_is_named_and_help_gives_the_syntax() {
    let (ok, _, err) = run(&["--method", "fastsim-a:sliding=exact"], CASES);
    assert!(!ok);
    assert!(
        err.contains("\"exact\" is not continuation, integrated or picard"),
        "{err}"
    );
    let out = Command::new(env!("CARGO_BIN_EXE_umsim"))
        .args(["creep", "--help"])
        .output()
        .unwrap();
    let help = String::from_utf8(out.stdout).unwrap();
    assert!(
        help.contains("fastsim-a[:STRIPS]") && help.contains("polach[:ka="),
        "{help}"
    );
}

/// `umsim creep --compare`: each law's forces equal its own `--method` run
/// (same text), the differences are those of the columns (to the last digit
/// written: the differences are computed from the same f64 values), and
/// without laws every registered law is compared against FASTSIM; the bundled
/// sample cases file reads. On the saturated row 3 every law gives μN, so
/// dF/muN < 1e-2 there (the Mueller laws reach μN to O(u⁻²)).
#[test]
fn compare_prints_each_law_and_the_differences() {
    let laws = ["fastsim:20", "fastsim-sa:20", "mueller", "polach"];
    let mut args = vec!["--compare"];
    args.extend(laws);
    let (ok, out, err) = run(&args, CASES);
    assert!(ok, "{err}");
    assert!(
        err.contains("|ΔF|/(μN) against fastsim:nx=20,ny=20"),
        "{err}"
    );
    let mut rd = csv::Reader::from_reader(out.as_bytes());
    let header: Vec<String> = rd.headers().unwrap().iter().map(String::from).collect();
    assert_eq!(header.len(), 1 + 3 * laws.len() + 4 * (laws.len() - 1));
    let table: Vec<Vec<f64>> = rd
        .records()
        .map(|r| r.unwrap().iter().map(|x| x.parse().unwrap()).collect())
        .collect();
    assert_eq!(table.len(), 4);
    let col = |name: &str| {
        header
            .iter()
            .position(|h| h == name)
            .unwrap_or_else(|| panic!("{name}"))
    };
    for law in laws {
        let (ok, single, err) = run(&["--method", law], CASES);
        assert!(ok, "{err}");
        let single = rows(&single);
        let name = law
            .parse::<railmbs_wheelrail::creep::CreepLawSpec>()
            .unwrap()
            .to_string();
        for (r, s) in table.iter().zip(&single) {
            assert_eq!(r[col(&format!("{name}.Fx"))], s[0], "{law}");
            assert_eq!(r[col(&format!("{name}.Fy"))], s[1], "{law}");
        }
    }
    for law in &laws[1..] {
        let name = law
            .parse::<railmbs_wheelrail::creep::CreepLawSpec>()
            .unwrap()
            .to_string();
        for r in &table {
            let d = r[col(&format!("{name}.Fx"))] - r[col("fastsim:nx=20,ny=20.Fx")];
            assert_eq!(r[col(&format!("{name}.dFx"))], d, "{law}");
        }
        assert!(table[2][col(&format!("{name}.dF/muN"))] < 1e-2, "{law}");
    }
    let (ok, out, err) = run(&["--compare"], CASES);
    assert!(ok, "{err}");
    let first = out.lines().next().unwrap();
    for law in [
        "kalker",
        "mueller:",
        "mueller-kalker-saturated:",
        "fastsim-sa:",
        "fastsim-a:",
        "polach:",
        "strip:",
    ] {
        assert!(
            first.contains(&format!(",{law}")) || first.contains(&format!(",\"{law}")),
            "{law}: {first}"
        );
    }
    assert!(
        first.starts_with("row,\"fastsim:nx=10,ny=10.Fx\""),
        "{first}"
    );
    // The sample cases file of the README.
    let sample = std::fs::read_to_string(railmbs_testkit::model_path("creep/cases.csv")).unwrap();
    let (ok, out, err) = run(&["--compare"], &sample);
    assert!(ok, "{err}");
    assert_eq!(out.lines().count(), 1 + 12);
}
