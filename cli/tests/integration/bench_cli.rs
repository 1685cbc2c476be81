//! `umsim bench` end to end: the JSON report.

use crate::common::umsim;
use std::process::Output;

fn json(o: &Output) -> serde_json::Value {
    let stdout = String::from_utf8_lossy(&o.stdout);
    assert!(
        o.status.success(),
        "umsim bench failed:\n{stdout}\n{}",
        String::from_utf8_lossy(&o.stderr)
    );
    serde_json::from_str(&stdout).unwrap_or_else(|e| panic!("not JSON ({e}):\n{stdout}"))
}

const KEYS: [&str; 12] = [
    "model",
    "dof",
    "numeric_eval_ns",
    "symbolic_eval_ns",
    "eval_ratio",
    "numeric_run_s",
    "symbolic_run_s",
    "run_ratio",
    "numeric_process_s",
    "symbolic_process_s",
    "derive_s",
    "compile_s",
];

fn positive(v: &serde_json::Value, key: &str) -> f64 {
    let x = v[key]
        .as_f64()
        .unwrap_or_else(|| panic!("{key} is not a number: {}", v[key]));
    assert!(x > 0.0 && x.is_finite(), "{key} = {x}");
    x
}

#[test]
fn bench_json_has_the_documented_keys() {
    let v = json(&umsim(&[
        "bench",
        "models/mechanisms/chain3.ron",
        "--json",
        "--states",
        "4",
    ]));
    for k in KEYS {
        assert!(v.get(k).is_some(), "key {k} missing in {v}");
    }
    assert_eq!(v["model"], "chain3");
    assert_eq!(v["dof"], 3);
    positive(&v, "numeric_eval_ns");
    positive(&v, "numeric_run_s");
    // The whole `umsim run` process of the scenario, measured in a child.
    positive(&v, "numeric_process_s");
    // models/scenarios/chain3_rk4.ron is the default scenario of chain3.
    assert!(
        v["scenario"].as_str().unwrap().ends_with("chain3_rk4.ron"),
        "{}",
        v["scenario"]
    );
    if v["symbolic_eval_ns"].is_null() {
        assert!(v["eval_ratio"].is_null());
        assert!(v["run_ratio"].is_null());
        assert!(
            v["symbolic_note"].is_string(),
            "no reason for the missing symbolic columns"
        );
    } else {
        let ratio = positive(&v, "eval_ratio");
        let expect = positive(&v, "numeric_eval_ns") / positive(&v, "symbolic_eval_ns");
        assert!((ratio - expect).abs() <= 1e-12 * expect);
        positive(&v, "symbolic_run_s");
        positive(&v, "run_ratio");
        positive(&v, "symbolic_process_s");
    }
}

#[test]
fn bench_numeric_only_leaves_the_symbolic_columns_null() {
    let v = json(&umsim(&[
        "bench",
        "models/mechanisms/pendulum.ron",
        "--json",
        "--engine",
        "numeric",
        "--states",
        "2",
    ]));
    positive(&v, "numeric_eval_ns");
    for k in [
        "symbolic_eval_ns",
        "eval_ratio",
        "symbolic_run_s",
        "run_ratio",
        "derive_s",
        "compile_s",
    ] {
        assert!(v[k].is_null(), "{k} = {}", v[k]);
    }
}

#[test]
fn bench_rejects_zero_states_and_missing_models() {
    let o = umsim(&["bench", "models/mechanisms/chain3.ron", "--states", "0"]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("--states"));
    let o = umsim(&["bench", "models/mechanisms/no_such_model.ron"]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("no_such_model.ron"));
}

#[test]
fn bench_of_a_train_sums_its_vehicles_and_runs_the_train() {
    let v = json(&umsim(&[
        "bench",
        "models/scenarios/train3_straight.ron",
        "--json",
        "--engine",
        "numeric",
        "--states",
        "2",
    ]));
    for k in KEYS {
        assert!(v.get(k).is_some(), "missing {k}");
    }
    // Three coaches of Vehicle 1 (42 coordinates each).
    assert_eq!(v["dof"], 126);
    positive(&v, "numeric_eval_ns");
    positive(&v, "numeric_run_s");
    assert!(v["symbolic_run_s"].is_null());
    // Sequential: the run time is the calling thread's CPU, no wall time.
    assert!(v["numeric_run_wall_s"].is_null());
    // A train is its own scenario.
    let o = umsim(&[
        "bench",
        "models/scenarios/train3_straight.ron",
        "--scenario",
        "models/scenarios/vehicle1_tc1.ron",
    ]);
    assert!(!o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("train file"));
}

/// A train whose vehicles step on two worker threads: its run time is the
/// process's CPU time (all threads) and the wall time is reported beside it;
/// a sequential train has no wall time (the test above).
#[test]
fn bench_of_a_threaded_train_reports_process_cpu_and_wall_time() {
    let repo = railmbs_testkit::repo_path("models");
    let text = std::fs::read_to_string(repo.join("scenarios/train3_straight.ron"))
        .expect("train3_straight.ron")
        .replace("\"../", &format!("\"{}/", repo.display()))
        .replace("end_time: 3.0,", "end_time: 0.2,\n    threads: 2,");
    let dir = tempfile::tempdir().expect("temporary folder");
    let file = dir.path().join("train3_threads2.ron");
    std::fs::write(&file, text).expect("write the train");
    let v = json(&umsim(&[
        "bench",
        file.to_str().expect("UTF-8 path"),
        "--json",
        "--engine",
        "numeric",
        "--states",
        "2",
    ]));
    positive(&v, "numeric_run_s");
    positive(&v, "numeric_run_wall_s");
    assert!(v["symbolic_run_wall_s"].is_null());
}
