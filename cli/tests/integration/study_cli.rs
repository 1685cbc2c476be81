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
