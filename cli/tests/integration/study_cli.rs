//! `umsim study`: a study's rows against `umsim run` of the same case,
//! resume, `--list`, `--case` (also from $SLURM_ARRAY_TASK_ID) and
//! `--collect`, and the bundled example study.

use crate::common::{text, umsim};
use std::path::Path;
use std::process::Command;

/// A numeric spring–mass study over k in `dir`, 2 s per case.
fn write_study(dir: &Path) -> String {
    let scenario = railmbs_testkit::model_path("scenarios/spring_mass.ron");
    let path = dir.join("springs.ron");
    std::fs::write(
        &path,
        format!(
            r#"Study(scenario: "{}", engine: Numeric, end_time: Some(2.0),
                     cases: Grid({{ "k": [100, 200, 400] }}),
                     reductions: [Max(column: "z"), Rms(column: "z.v")])"#,
            scenario.display()
        ),
    )
    .unwrap();
    path.display().to_string()
}

fn column(csv: &Path, name: &str) -> Vec<String> {
    let mut r = csv::Reader::from_path(csv).unwrap();
    let k = r.headers().unwrap().iter().position(|h| h == name).unwrap();
    r.records().map(|x| x.unwrap()[k].to_string()).collect()
}

#[test]
fn a_study_row_equals_umsim_run_of_the_same_case_and_a_second_run_resumes() {
    let dir = tempfile::tempdir().unwrap();
    let study = write_study(dir.path());
    let out = dir.path().join("out");
    let o = umsim(&["study", &study, "--list"]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let list = text(&o.stdout);
    assert_eq!(list.lines().count(), 4, "{list}");
    assert!(
        list.lines().nth(2).unwrap().trim_start().starts_with("1 "),
        "{list}"
    );

    let o = umsim(&["study", &study, "-o", out.to_str().unwrap(), "-j", "2"]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(
        text(&o.stdout).contains("3 cases run (0 failed), 0 skipped"),
        "{}",
        text(&o.stdout)
    );
    let results = out.join("results.csv");
    let ks = column(&results, "k");
    let k = ks.iter().position(|k| k == "200").unwrap();

    let single = dir.path().join("single.csv");
    let o = umsim(&[
        "run",
        "models/scenarios/spring_mass.ron",
        "--engine",
        "numeric",
        "--set",
        "k=200",
        "--end-time",
        "2",
        "--quiet",
        "-o",
        single.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let z: Vec<f64> = column(&single, "z")
        .iter()
        .map(|x| x.parse().unwrap())
        .collect();
    let max = z.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let got: f64 = column(&results, "max(z)")[k].parse().unwrap();
    assert_eq!(got, max);
    let v: Vec<f64> = column(&single, "z.v")
        .iter()
        .map(|x| x.parse().unwrap())
        .collect();
    let rms = (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt();
    let got: f64 = column(&results, "rms(z.v)")[k].parse().unwrap();
    // The same sum in another order: a few roundings.
    assert!((got - rms).abs() <= 1e-12 * rms, "{got} against {rms}");

    let o = umsim(&["study", &study, "-o", out.to_str().unwrap()]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(
        text(&o.stdout).contains("0 cases run (0 failed), 3 skipped"),
        "{}",
        text(&o.stdout)
    );
    assert_eq!(column(&results, "k").len(), 3);
}

#[test]
fn single_cases_from_a_job_array_are_collected_into_the_table() {
    let dir = tempfile::tempdir().unwrap();
    let study = write_study(dir.path());
    let out = dir.path().join("out");
    let out = out.to_str().unwrap();
    // As a Slurm job array task: the index from the environment.
    let o = Command::new(env!("CARGO_BIN_EXE_umsim"))
        .args(["study", &study, "-o", out, "--case"])
        .env("SLURM_ARRAY_TASK_ID", "2")
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert!(
        text(&o.stdout).starts_with("case 2 ("),
        "{}",
        text(&o.stdout)
    );
    let o = umsim(&["study", &study, "-o", out, "--case", "0"]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let o = umsim(&["study", &study, "-o", out, "--case", "7"]);
    assert!(
        text(&o.stderr).contains("no case 7 (the study has 3: 0 to 2)"),
        "{}",
        text(&o.stderr)
    );
    let o = umsim(&["study", &study, "-o", out, "--collect"]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let said = text(&o.stdout);
    assert!(
        said.contains("collected 2 case file(s)") && said.contains("missing cases (index): 1"),
        "{said}"
    );
    let index = column(&Path::new(out).join("results.csv"), "index");
    assert_eq!(index, ["0", "2"]);
}

#[test]
fn the_bundled_example_study_runs() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out");
    let o = umsim(&[
        "study",
        "models/studies/vehicle1_yaw_speed.ron",
        "-o",
        out.to_str().unwrap(),
        "--quiet",
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let results = out.join("results.csv");
    assert_eq!(column(&results, "status"), ["ok"; 4]);
    // Y/Q judged against Nadal's limit on every case, below it on this
    // gentle start of the curve.
    for (yq, limit) in column(&results, "YQ.max")
        .iter()
        .zip(column(&results, "YQ.limit"))
    {
        let (yq, limit): (f64, f64) = (yq.parse().unwrap(), limit.parse().unwrap());
        assert!(yq > 0.0 && yq < limit, "{yq} against {limit}");
    }
}

/// Starts `umsim study` on an 8-case study whose cases take a few tenths of
/// a second each, waits for its first row in results.csv and sends it
/// `signal`; returns the rows recorded then and the process's output.
fn interrupt_after_first_row(dir: &Path, signal: &str) -> (usize, std::process::Output) {
    let scenario = railmbs_testkit::model_path("scenarios/spring_mass.ron");
    let study = dir.join("long.ron");
    // 2000 s at steps of at most 0.01 s: 200 000 steps per case.
    std::fs::write(
        &study,
        format!(
            r#"Study(scenario: "{}", engine: Numeric, end_time: Some(2000.0),
                     cases: Grid({{ "k": [100, 110, 120, 130, 140, 150, 160, 170] }}),
                     reductions: [Max(column: "z")])"#,
            scenario.display()
        ),
    )
    .unwrap();
    let out = dir.join("out");
    let args = [
        "study",
        study.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
        "-j",
        "1",
    ];
    let child = Command::new(env!("CARGO_BIN_EXE_umsim"))
        .args(args)
        .stdout(std::process::Stdio::piped())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    let results = out.join("results.csv");
    let rows = || {
        std::fs::read_to_string(&results)
            .map(|t| t.lines().count().saturating_sub(1))
            .unwrap_or(0)
    };
    while rows() == 0 {
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    let kill = Command::new("kill")
        .args([signal, &child.id().to_string()])
        .status()
        .unwrap();
    assert!(kill.success());
    let output = child.wait_with_output().unwrap();
    (rows(), output)
}

#[test]
fn an_interrupted_or_killed_study_resumes_where_it_stopped() {
    for signal in ["-INT", "-KILL"] {
        let dir = tempfile::tempdir().unwrap();
        let (_, o) = interrupt_after_first_row(dir.path(), signal);
        let results = dir.path().join("out/results.csv");
        let kept = column(&results, "case_id").len();
        assert!((1..8).contains(&kept), "{signal}: {kept} rows kept");
        if signal == "-INT" {
            // Ctrl-C: the running case stops at its next row, the message
            // says how many cases are in the table.
            assert_eq!(o.status.code(), Some(1));
            let said = text(&o.stderr);
            assert!(
                said.contains(&format!("interrupted: {kept} of 8 cases")),
                "{said}"
            );
        }
        let study = dir.path().join("long.ron");
        let o = umsim(&[
            "study",
            study.to_str().unwrap(),
            "-o",
            dir.path().join("out").to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", text(&o.stderr));
        let said = text(&o.stdout);
        assert!(
            said.contains(&format!(
                "{} cases run (0 failed), {kept} skipped",
                8 - kept
            )),
            "{signal}: {said}"
        );
        let mut ids = column(&results, "case_id");
        ids.sort();
        ids.dedup();
        assert_eq!(ids.len(), 8, "{signal}: every case once");
    }
}
