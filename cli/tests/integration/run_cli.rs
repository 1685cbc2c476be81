//! `umsim run` end to end: output file layout, summary, and the errors a user
//! meets (missing file, unknown parameter, a simulation that blows up).

use crate::common::{text, umsim};
use railmbs_testkit::{Table, repo_path};
use std::path::Path;
use std::process::Command;

/// Header (joined by commas) and rows of a CSV output file.
fn read_csv(path: &Path) -> (String, Vec<Vec<f64>>) {
    let table = Table::read(path);
    (table.header.join(","), table.rows)
}

#[test]
fn chain3_rk4_run_writes_the_output_grid_and_a_summary() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.csv");
    let o = umsim(&[
        "run",
        "models/scenarios/chain3_rk4.ron",
        "-o",
        out.to_str().unwrap(),
    ]);
    let stdout = text(&o.stdout);
    assert!(
        o.status.success(),
        "umsim run failed:\n{stdout}\n{}",
        text(&o.stderr)
    );
    let (header, rows) = read_csv(&out);
    assert_eq!(header, "time,q0,q1,q2");
    // 10 s at an output interval of 0.01 s: rows at 0, 0.01, ..., 10.
    assert_eq!(rows.len(), 1001);
    assert_eq!(rows[0][0], 0.0);
    assert_eq!(rows[1000][0], 10.0);
    // Initial state of models/mechanisms/chain3.ron: q0 = 0.5 rad, q1 = q2 = 0.
    assert_eq!(&rows[0][1..], &[0.5, 0.0, 0.0]);
    for (k, r) in rows.iter().enumerate() {
        assert_eq!(r.len(), 4, "row {k}");
        // Output times are k·0.01 s (to the rounding of the product).
        assert!(
            (r[0] - k as f64 * 0.01).abs() < 1e-12,
            "row {k} at t = {}",
            r[0]
        );
        assert!(r.iter().all(|x| x.is_finite()), "row {k}: {r:?}");
    }
    // RK4 with h = 1 ms over 10 s takes exactly 10 000 steps.
    let steps = stdout
        .lines()
        .find(|l| l.starts_with("steps"))
        .unwrap_or_else(|| panic!("no steps line in the summary:\n{stdout}"));
    assert_eq!(steps.split_whitespace().last(), Some("10000"), "{steps}");
    assert!(
        stdout.contains("CPU time"),
        "no CPU time in the summary:\n{stdout}"
    );
}

#[test]
fn missing_scenario_file_is_named_in_the_error() {
    let o = umsim(&["run", "models/scenarios/no_such_scenario.ron"]);
    assert!(!o.status.success());
    let err = text(&o.stderr);
    assert!(err.contains("no_such_scenario.ron"), "{err}");
}

#[test]
fn unknown_scenario_parameter_is_named_with_the_file() {
    let dir = tempfile::tempdir().unwrap();
    let model = repo_path("models/mechanisms/chain3.ron");
    let scenario = dir.path().join("bad_parameter.ron");
    std::fs::write(
        &scenario,
        format!(
            "Scenario(\n    model: {:?},\n    parameters: {{ \"no_such_stiffness\": 5.0 }},\n    \
             end_time: 1.0,\n    integrator: Rk4(step: 0.001),\n    output: (interval: 0.01),\n)\n",
            model.canonicalize().unwrap().display().to_string()
        ),
    )
    .unwrap();
    let o = umsim(&[
        "run",
        scenario.to_str().unwrap(),
        "-o",
        dir.path().join("o.csv").to_str().unwrap(),
    ]);
    assert!(!o.status.success());
    let err = text(&o.stderr);
    assert!(err.contains("bad_parameter.ron"), "{err}");
    assert!(err.contains("no_such_stiffness"), "{err}");
}

/// A 1 kg slider on a prismatic x joint pushed by F(t) = 1/(1 − t) N, which
/// blows up at t = 1 s. From rest at x = 0: v = −ln(1 − t),
/// x = (1 − t) ln(1 − t) + t.
const BLOWUP_MODEL: &str = r#"Model(
    name: "blowup",
    bodies: [
        Body(
            name: "slider",
            mass: 1.0,
            inertia: (ixx: 0.01, iyy: 0.01, izz: 0.01),
            joint: Prismatic(parent: "ground", axis: X, coord: "x"),
        ),
    ],
    forces: [
        Applied(name: "push", body: "slider", force: ("1/(1-t)", 0, 0)),
    ],
)
"#;

const BLOWUP_SCENARIO: &str = r#"Scenario(
    model: "blowup.ron",
    end_time: 2.0,
    integrator: Rk4(step: 0.001),
    output: (interval: 0.01),
)
"#;

#[test]
fn diverging_run_fails_with_the_time_and_keeps_the_rows_before_it() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(dir.path().join("blowup.ron"), BLOWUP_MODEL).unwrap();
    let scenario = dir.path().join("blowup_rk4.ron");
    std::fs::write(&scenario, BLOWUP_SCENARIO).unwrap();
    let out = dir.path().join("blowup.csv");
    let o = umsim(&[
        "run",
        scenario.to_str().unwrap(),
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(
        !o.status.success(),
        "a run through a singular force succeeded"
    );
    let err = text(&o.stderr);
    // RK4 steps land on t = 1000 · 1 ms = 1 s, where the force is 1/0.
    assert!(err.contains("t = 1 s"), "{err}");
    assert!(
        err.contains("push"),
        "the force element is not named: {err}"
    );
    assert!(
        err.contains("blowup_rk4.ron"),
        "the scenario is not named: {err}"
    );

    let (header, rows) = read_csv(&out);
    assert_eq!(header, "time,x");
    // Rows at 0, 0.01, ..., 0.99 s were written before the failure.
    assert_eq!(rows.len(), 100, "rows: {}", rows.len());
    assert!((rows[99][0] - 0.99).abs() < 1e-12);
    for r in &rows {
        let t = r[0];
        let exact = (1.0 - t) * (1.0 - t).ln() + t;
        // RK4's global error is about h⁴ · max|x⁽⁵⁾| · t with
        // x⁽⁵⁾ = 6/(1 − t)⁴ ≤ 6e4 m/s⁵ up to t = 0.9 s: 1e-12 · 6e4 · 0.9
        // ≈ 5e-8 m, so 1e-6 m leaves a wide margin.
        if t <= 0.9 {
            assert!((r[1] - exact).abs() < 1e-6, "x({t}) = {} vs {exact}", r[1]);
        }
        assert!(r[1].is_finite());
    }
}

#[test]
fn symbolic_engine_runs_or_says_why_not() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.csv");
    let o = umsim(&[
        "run",
        "models/scenarios/chain3_rk4.ron",
        "--engine",
        "symbolic",
        "-o",
        out.to_str().unwrap(),
    ]);
    if o.status.success() {
        let (header, rows) = read_csv(&out);
        assert_eq!(header, "time,q0,q1,q2");
        assert_eq!(rows.len(), 1001);
        assert!(text(&o.stdout).contains("symbolic"));
    } else {
        let err = text(&o.stderr);
        assert!(err.contains("symbolic"), "unclear error: {err}");
    }
}

/// `-o` naming one of the run's inputs is refused before anything is written.
#[test]
fn output_over_an_input_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let models = repo_path("models");
    let model = std::fs::read_to_string(models.join("mechanisms/chain3.ron")).unwrap();
    std::fs::write(dir.path().join("chain3.ron"), &model).unwrap();
    let scenario = "Scenario(model: \"chain3.ron\", end_time: 0.1, integrator: Rk4(step: 1e-3), output: (interval: 0.01))";
    let run = dir.path().join("run.ron");
    std::fs::write(&run, scenario).unwrap();
    for (target, what) in [("run.ron", "scenario file"), ("chain3.ron", "model file")] {
        let path = dir.path().join(target);
        let before = std::fs::read_to_string(&path).unwrap();
        let o = umsim(&["run", run.to_str().unwrap(), "-o", path.to_str().unwrap()]);
        let stderr = text(&o.stderr);
        assert!(!o.status.success(), "{stderr}");
        assert!(
            stderr.contains(&format!("the output file is the run's {what}")),
            "{stderr}"
        );
        assert_eq!(
            std::fs::read_to_string(&path).unwrap(),
            before,
            "{target} changed"
        );
    }
}

/// `--plugin NAME.so` finds the file in the working directory (as the README
/// writes it), and a truncated plugin is refused with its reason instead of
/// crashing the process (SIGBUS) when the loader maps it.
#[test]
fn plugin_by_bare_name_and_truncated_plugins() {
    let dir = tempfile::tempdir().unwrap();
    let models = repo_path("models");
    let built = Command::new(env!("CARGO_BIN_EXE_umgen"))
        .arg(models.join("mechanisms/chain3.ron"))
        .args(["-o", "chain3.so"])
        .current_dir(dir.path())
        .output()
        .unwrap();
    assert!(built.status.success(), "{}", text(&built.stderr));
    let scenario = models.join("scenarios/chain3_rk4.ron");
    let run = |plugin: &str| {
        Command::new(env!("CARGO_BIN_EXE_umsim"))
            .arg("run")
            .arg(&scenario)
            .args(["--plugin", plugin, "--quiet", "-o", "out.csv"])
            .current_dir(dir.path())
            .output()
            .unwrap()
    };
    let o = run("chain3.so");
    assert!(o.status.success(), "{}", text(&o.stderr));
    let whole = std::fs::read(dir.path().join("chain3.so")).unwrap();
    std::fs::write(dir.path().join("cut.so"), &whole[..whole.len() / 2]).unwrap();
    let o = run("cut.so");
    let stderr = text(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("cut.so: not a loadable library"),
        "{stderr}"
    );
    // A missing file names the system's reason.
    let o = run("missing.so");
    let stderr = text(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("No such file"), "{stderr}");
}

/// `--end-time` shortens the run (checked like the file's own end time) and
/// `--set NAME=VALUE` changes a parameter: `g=2*4.905` is the file's own
/// 9.81 m/s² (doubling is exact in binary) and reproduces the run bit for
/// bit; `g=0` changes it.
#[test]
fn end_time_and_set_override_the_scenario() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.csv");
    let run = |extra: &[&str]| {
        let mut args = vec![
            "run",
            "models/scenarios/double_pendulum.ron",
            "--quiet",
            "-o",
            out.to_str().unwrap(),
        ];
        args.extend_from_slice(extra);
        umsim(&args)
    };
    let o = run(&["--end-time", "0.5"]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let (_, rows) = read_csv(&out);
    assert_eq!(rows.len(), 51, "0.5 s at 0.01 s");
    let o = run(&["--end-time", "0.5", "--set", "g=2*4.905"]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert_eq!(read_csv(&out).1, rows, "the same g");
    let o = run(&["--end-time", "0.5", "--set", "g=0"]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    let (_, weightless) = read_csv(&out);
    assert_eq!(weightless[0], rows[0], "the same initial state");
    assert!(
        (weightless[50][1] - rows[50][1]).abs() > 1e-3,
        "gravity matters"
    );
    let o = run(&["--end-time", "1e20"]);
    let stderr = text(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{stderr}");
    assert!(
        stderr.contains("--end-time: RK4 step 0.001 s over end_time 1e20 s"),
        "{stderr}"
    );
    let o = run(&["--set", "gravity=1"]);
    let stderr = text(&o.stderr);
    assert!(
        stderr.contains("parameter \"gravity\": unknown parameter"),
        "{stderr}"
    );
    let o = run(&["--set", "g"]);
    assert!(
        text(&o.stderr).contains("expected NAME=VALUE"),
        "{}",
        text(&o.stderr)
    );
    // A train file: the end time and train-wide parameters.
    let o = umsim(&[
        "run",
        "models/scenarios/train3_straight.ron",
        "--end-time",
        "0.2",
        "--quiet",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert_eq!(read_csv(&out).1.last().unwrap()[0], 0.2);
    let o = umsim(&[
        "run",
        "models/scenarios/train3_straight.ron",
        "--set",
        "nosuch=1",
    ]);
    let stderr = text(&o.stderr);
    assert!(
        stderr.contains("parameter \"nosuch\": no vehicle's model has this parameter"),
        "{stderr}"
    );
}

/// Ctrl-C (SIGINT) stops a run at its next output row with a message naming
/// the rows kept and the file; the CSV is complete up to there.
#[cfg(unix)]
#[test]
fn ctrl_c_stops_the_run_and_says_what_was_kept() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("long.csv");
    let child = Command::new(env!("CARGO_BIN_EXE_umsim"))
        .args([
            "run",
            "models/scenarios/double_pendulum.ron",
            "--end-time",
            "100000",
            "--quiet",
            "-o",
        ])
        .arg(&out)
        .current_dir(repo_path(""))
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // Wait until rows are being written, then interrupt.
    let start = std::time::Instant::now();
    while std::fs::metadata(&out).map_or(0, |m| m.len()) < 10_000 {
        assert!(start.elapsed().as_secs() < 60, "no rows written");
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    let kill = Command::new("kill")
        .args(["-INT", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(kill.success());
    let o = child.wait_with_output().unwrap();
    let stderr = text(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{stderr}");
    assert!(stderr.contains("interrupted after"), "{stderr}");
    assert!(stderr.contains("long.csv keeps them"), "{stderr}");
    let (_, rows) = read_csv(&out);
    let last = rows.last().unwrap()[0];
    assert!(
        stderr.contains(&format!("the last at t = {last} s")),
        "{stderr} (last row {last})"
    );
    assert!(last < 100000.0);
}

/// `--engine numeric` picks the formalism by size for RK4 (issue 19 item 3,
/// `Formalism::for_explicit_integration`): a 40-link chain runs with the
/// articulated-body q̈ (the summary names `numeric-aba`) and gives the same
/// numbers as an explicit `--engine numeric-aba` run, byte for byte; the
/// bundled 30-link chain stays composite-body, and so does a Park run of
/// the 40-link chain (it needs M).
#[test]
fn the_numeric_engine_picks_the_formalism_by_size_for_rk4() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("chain40.ron"),
        railmbs_testkit::model::chain_text(40, false),
    )
    .unwrap();
    let scenario = |name: &str, integrator: &str| {
        let path = dir.path().join(name);
        std::fs::write(
            &path,
            format!(
                "Scenario(model: \"chain40.ron\", end_time: 0.05, integrator: {integrator}, \
                 output: (interval: 0.01))"
            ),
        )
        .unwrap();
        path
    };
    let rk4 = scenario("rk4.ron", "Rk4(step: 0.001)");
    let park = scenario("park.ron", "Park(rtol: 1e-6, atol: 1e-8, max_step: 0.001)");
    let engine_line = |o: &std::process::Output| {
        text(&o.stdout)
            .lines()
            .chain(text(&o.stderr).lines())
            .find(|l| l.starts_with("engine "))
            .map(|l| l.split_whitespace().last().unwrap_or("").to_string())
            .unwrap_or_default()
    };
    let mut csv = Vec::new();
    for (file, engine, expect) in [
        (&rk4, "numeric", "numeric-aba"),
        (&rk4, "numeric-aba", "numeric-aba"),
        (&park, "numeric", "numeric"),
    ] {
        let out = dir.path().join(format!("{engine}-{expect}.csv"));
        let o = umsim(&[
            "run",
            file.to_str().unwrap(),
            "--engine",
            engine,
            "-o",
            out.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", text(&o.stderr));
        assert_eq!(engine_line(&o), expect, "{}", text(&o.stdout));
        csv.push(std::fs::read(&out).unwrap());
    }
    assert_eq!(csv[0], csv[1], "automatic and explicit numeric-aba differ");
    let o = umsim(&[
        "run",
        "models/scenarios/chain30_rk4.ron",
        "--engine",
        "numeric",
        "--end-time",
        "0.01",
        "-o",
        dir.path().join("c30.csv").to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", text(&o.stderr));
    assert_eq!(engine_line(&o), "numeric");
}

/// `--engine numeric-aba` (the articulated-body formalism): an RK4 scenario
/// runs and gives the composite-body run's numbers to rounding (the two q̈
/// differ by κ(M) ε; 1e-9 rad over 10 s of the double pendulum); a Park
/// scenario and an analysis that need M are refused with a message that
/// says why and what to use instead.
#[test]
fn run_with_the_articulated_body_formalism() {
    let dir = tempfile::tempdir().unwrap();
    let (a, c) = (dir.path().join("aba.csv"), dir.path().join("crb.csv"));
    for (engine, out) in [("numeric-aba", &a), ("numeric", &c)] {
        let o = umsim(&[
            "run",
            "models/scenarios/double_pendulum.ron",
            "--engine",
            engine,
            "-o",
            out.to_str().unwrap(),
        ]);
        assert!(o.status.success(), "{}", text(&o.stderr));
    }
    let ((ha, ra), (hc, rc)) = (read_csv(&a), read_csv(&c));
    assert_eq!(ha, hc);
    assert_eq!(ra.len(), rc.len());
    let diff = ra
        .iter()
        .flatten()
        .zip(rc.iter().flatten())
        .fold(0.0_f64, |m, (x, y)| m.max((x - y).abs()));
    assert!(
        diff < 1e-9,
        "numeric-aba and numeric runs differ by {diff:e}"
    );
    let o = umsim(&[
        "run",
        "models/scenarios/fourbar.ron",
        "--engine",
        "numeric-aba",
        "-o",
        dir.path().join("x.csv").to_str().unwrap(),
    ]);
    let err = text(&o.stderr);
    assert!(!o.status.success());
    assert!(
        err.contains("Park's implicit method") && err.contains("--engine numeric"),
        "{err}"
    );
}
