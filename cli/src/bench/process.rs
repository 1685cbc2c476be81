//! What the user waits for: the CPU time of a whole `umsim run` process
//! (start-up, plugin and contact-table lookup in their caches, the run and
//! the CSV output), measured by running this program as a child and reading
//! the `process CPU time` line of its summary.

use super::Args;
use super::report::EngineTimes;
use super::timing::{MAX_RUNS, RUN_SECONDS};
use crate::engine::Engine;
use crate::run::PROCESS_CPU_LABEL;
use std::path::Path;
use std::process::Command;

/// Median process CPU time (s) of `umsim run SCENARIO --engine ENGINE` with
/// its CSV written to a temporary file, after one run that fills the caches
/// (the plugin and contact tables are built once per model, not per run);
/// repeated up to three times within [`RUN_SECONDS`] in all.
pub fn process_cpu(scenario: &Path, engine: Engine) -> Result<f64, String> {
    let exe = std::env::current_exe().map_err(|e| format!("umsim's own path: {e}"))?;
    let dir = tempfile::tempdir().map_err(|e| format!("temporary folder: {e}"))?;
    let output = dir.path().join("run.csv");
    let engine = match engine {
        Engine::Numeric => "numeric",
        Engine::Symbolic => "symbolic",
        Engine::NumericAba => "numeric-aba",
    };
    let once = || -> Result<f64, String> {
        let out = Command::new(&exe)
            .arg("run")
            .arg(scenario)
            .args(["--engine", engine, "-o"])
            .arg(&output)
            .output()
            .map_err(|e| format!("{}: {e}", exe.display()))?;
        let stdout = String::from_utf8_lossy(&out.stdout);
        if !out.status.success() {
            return Err(format!(
                "umsim run {} failed: {}",
                scenario.display(),
                String::from_utf8_lossy(&out.stderr).trim()
            ));
        }
        stdout
            .lines()
            .find_map(|l| l.strip_prefix(PROCESS_CPU_LABEL))
            .and_then(|rest| rest.split_whitespace().next())
            .and_then(|x| x.parse::<f64>().ok())
            .ok_or_else(|| "umsim run printed no process CPU time".to_owned())
    };
    once()?;
    let mut times = Vec::new();
    while times.is_empty()
        || (times.len() < MAX_RUNS.min(3) && times.iter().sum::<f64>() < RUN_SECONDS)
    {
        times.push(once()?);
    }
    times.sort_by(f64::total_cmp);
    Ok(times[times.len() / 2])
}

/// [`EngineTimes::process_s`] of the scenario (or train) file `scenario`
/// with `engine`, unless the options make the measured runs differ from what
/// `umsim run` does (`--creep`, `--portable`), which the note then says.
pub(super) fn whole_process(scenario: &Path, engine: Engine, args: &Args, times: &mut EngineTimes) {
    if args.creep.is_some() || args.portable {
        let why = "whole process not measured: `umsim run` has no --creep or --portable";
        times.note.get_or_insert_with(|| why.to_owned());
        return;
    }
    match process_cpu(scenario, engine) {
        Ok(t) => times.process_s = Some(t),
        Err(e) => {
            times.note.get_or_insert(e);
        }
    }
}
