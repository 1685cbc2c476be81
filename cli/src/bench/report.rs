//! The report of `umsim bench`: its measurements, the JSON object of
//! `--json` (the keys are part of the command's interface) and the table.

use std::path::PathBuf;

/// The measurements of one engine.
#[derive(Debug, Clone, Default)]
pub struct EngineTimes {
    /// M and k, ns per evaluation.
    pub eval_ns: Option<f64>,
    /// `ModelSystem::dynamics`, ns per call.
    pub dynamics_ns: Option<f64>,
    /// Scenario run (`run_scenario` without CSV output), s.
    pub run_s: Option<f64>,
    /// Integration steps of the scenario run.
    pub run_steps: Option<usize>,
    /// Wall time of the scenario run, s, for a train whose vehicles step on
    /// worker threads (`threads` > 1); its `run_s` is then the process's CPU
    /// time over all threads.
    pub run_wall_s: Option<f64>,
    /// CPU time of a whole `umsim run` process of the scenario, caches warm
    /// (start-up, run, CSV output), s.
    pub process_s: Option<f64>,
    /// Why something is missing.
    pub note: Option<String>,
}

/// Everything `umsim bench` measures.
#[derive(Debug, Clone)]
pub struct BenchReport {
    /// Name of the model (for a train file, the train's name and its number
    /// of vehicles).
    pub model: String,
    /// The model (or train) file given on the command line.
    pub model_file: PathBuf,
    /// Number of degrees of freedom (for a train, summed over its vehicles).
    pub dof: usize,
    /// Number of bodies (for a train, summed over its vehicles).
    pub bodies: usize,
    /// Number of random states evaluated at (`--states`).
    pub states: usize,
    /// The scenario file that was run, if any (a train file is its own
    /// scenario).
    pub scenario: Option<PathBuf>,
    /// Why no scenario was run.
    pub scenario_note: Option<String>,
    /// Measurements of the numeric-iterative engine.
    pub numeric: EngineTimes,
    /// Measurements of the compiled symbolic plugin; what was not measured
    /// is `None` and its `note` says why.
    pub symbolic: EngineTimes,
    /// Symbolic derivation, s.
    pub derive_s: Option<f64>,
    /// Plugin build beyond derivation and emission (compilation or cache), s.
    pub compile_s: Option<f64>,
    /// The `--creep` override, if any.
    pub creep: Option<String>,
    /// The integrators' linear solves on the model's M
    /// ([`time_linear_solves`](super::workload::time_linear_solves)), ns per
    /// call: the q̈ solve (Cholesky of M and its solve), Park's LU
    /// factorization of an n×n iteration matrix and one Newton solve with
    /// it. `None` for a train (not measured) or when M could not be evaluated.
    pub linear_ns: Option<[f64; 3]>,
    /// A train's linear solves, dense and bordered block-diagonal
    /// (`time_train_linear_solves` in the bench's train module);
    /// `None` for a model file or when they could not be set up.
    pub train_linear: Option<TrainLinear>,
}

/// Park's linear solves of a train at its initial state, ns per call: the
/// q̈ solve with M (dense Cholesky; the bordered LU of M), the LU
/// factorization of the iteration matrix M − β ∂f/∂q̇ − β² ∂f/∂q and one
/// Newton solve with it, dense and bordered block-diagonal.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct TrainLinear {
    /// Coordinates on the border (the coupled bodies').
    pub border: usize,
    /// Dense: q̈ solve, LU factorization, Newton solve.
    pub dense_ns: [f64; 3],
    /// Bordered block-diagonal: q̈ solve, factorization, Newton solve;
    /// `None` when the train has no block pattern that pays.
    pub block_ns: Option<[f64; 3]>,
}

fn ratio(a: Option<f64>, b: Option<f64>) -> Option<f64> {
    match (a, b) {
        (Some(a), Some(b)) if b > 0.0 => Some(a / b),
        _ => None,
    }
}

impl BenchReport {
    /// numeric / symbolic time of one (M, k) evaluation.
    pub fn eval_ratio(&self) -> Option<f64> {
        ratio(self.numeric.eval_ns, self.symbolic.eval_ns)
    }
    /// numeric / symbolic time of one `dynamics` call.
    pub fn dynamics_ratio(&self) -> Option<f64> {
        ratio(self.numeric.dynamics_ns, self.symbolic.dynamics_ns)
    }
    /// numeric / symbolic time of the scenario run.
    pub fn run_ratio(&self) -> Option<f64> {
        ratio(self.numeric.run_s, self.symbolic.run_s)
    }

    /// The JSON object printed by `--json`.
    pub fn to_json(&self) -> serde_json::Value {
        serde_json::json!({
            "model": self.model,
            "model_file": self.model_file.display().to_string(),
            "dof": self.dof,
            "bodies": self.bodies,
            "states": self.states,
            "scenario": self.scenario.as_ref().map(|p| p.display().to_string()),
            "scenario_note": self.scenario_note,
            "numeric_eval_ns": self.numeric.eval_ns,
            "symbolic_eval_ns": self.symbolic.eval_ns,
            "eval_ratio": self.eval_ratio(),
            "numeric_dynamics_ns": self.numeric.dynamics_ns,
            "symbolic_dynamics_ns": self.symbolic.dynamics_ns,
            "dynamics_ratio": self.dynamics_ratio(),
            "numeric_run_s": self.numeric.run_s,
            "symbolic_run_s": self.symbolic.run_s,
            "run_ratio": self.run_ratio(),
            "numeric_run_steps": self.numeric.run_steps,
            "numeric_run_wall_s": self.numeric.run_wall_s,
            "symbolic_run_wall_s": self.symbolic.run_wall_s,
            "numeric_process_s": self.numeric.process_s,
            "symbolic_process_s": self.symbolic.process_s,
            "symbolic_run_steps": self.symbolic.run_steps,
            "creep": self.creep,
            "derive_s": self.derive_s,
            "compile_s": self.compile_s,
            "qdd_solve_ns": self.linear_ns.map(|t| t[0]),
            "lu_factorization_ns": self.linear_ns.map(|t| t[1]),
            "lu_solve_ns": self.linear_ns.map(|t| t[2]),
            "train_border": self.train_linear.map(|t| t.border),
            "train_dense_qdd_solve_ns": self.train_linear.map(|t| t.dense_ns[0]),
            "train_dense_lu_factorization_ns": self.train_linear.map(|t| t.dense_ns[1]),
            "train_dense_lu_solve_ns": self.train_linear.map(|t| t.dense_ns[2]),
            "train_block_qdd_solve_ns": self.train_linear.and_then(|t| t.block_ns.map(|b| b[0])),
            "train_block_factorization_ns": self.train_linear.and_then(|t| t.block_ns.map(|b| b[1])),
            "train_block_solve_ns": self.train_linear.and_then(|t| t.block_ns.map(|b| b[2])),
            "numeric_note": self.numeric.note,
            "symbolic_note": self.symbolic.note,
        })
    }

    /// The human-readable table.
    pub fn table(&self) -> String {
        use std::fmt::Write as _;
        let mut s = String::new();
        let _ = writeln!(
            s,
            "model {} ({}): {} coordinates, {} bodies, {} random states",
            self.model,
            self.model_file.display(),
            self.dof,
            self.bodies,
            self.states
        );
        match (&self.scenario, &self.scenario_note) {
            (Some(p), _) => {
                let _ = writeln!(s, "scenario {}", p.display());
                if let Some(c) = &self.creep {
                    let _ = writeln!(s, "creep law of every wheel–rail element: {c}");
                }
            }
            (None, Some(n)) => {
                let _ = writeln!(s, "scenario: none ({n})");
            }
            (None, None) => {}
        }
        let ns = |x: Option<f64>| x.map_or("-".to_string(), |v| format!("{v:.1} ns"));
        let sec = |x: Option<f64>| x.map_or("-".to_string(), |v| format!("{v:.4} s"));
        let r = |x: Option<f64>| x.map_or("-".to_string(), |v| format!("{v:.2}"));
        let per_step = |t: Option<f64>, n: Option<usize>| match (t, n) {
            (Some(t), Some(n)) if n > 0 => format!("{:.1} µs", 1e6 * t / n as f64),
            _ => "-".to_string(),
        };
        let _ = writeln!(
            s,
            "{:<28} {:>14} {:>14} {:>18}",
            "", "numeric", "symbolic", "numeric/symbolic"
        );
        let rows = [
            (
                "M, k per evaluation",
                ns(self.numeric.eval_ns),
                ns(self.symbolic.eval_ns),
                r(self.eval_ratio()),
            ),
            (
                "dynamics per evaluation",
                ns(self.numeric.dynamics_ns),
                ns(self.symbolic.dynamics_ns),
                r(self.dynamics_ratio()),
            ),
            (
                "scenario run",
                sec(self.numeric.run_s),
                sec(self.symbolic.run_s),
                r(self.run_ratio()),
            ),
            (
                "whole umsim run process",
                sec(self.numeric.process_s),
                sec(self.symbolic.process_s),
                r(ratio(self.numeric.process_s, self.symbolic.process_s)),
            ),
            (
                "steps of the run",
                self.numeric.run_steps.map_or("-".into(), |n| n.to_string()),
                self.symbolic
                    .run_steps
                    .map_or("-".into(), |n| n.to_string()),
                String::new(),
            ),
            (
                "CPU time per step",
                per_step(self.numeric.run_s, self.numeric.run_steps),
                per_step(self.symbolic.run_s, self.symbolic.run_steps),
                String::new(),
            ),
        ];
        for (label, a, b, c) in rows {
            let _ = writeln!(s, "{label:<28} {a:>14} {b:>14} {c:>18}");
        }
        if self.numeric.run_wall_s.is_some() || self.symbolic.run_wall_s.is_some() {
            let _ = writeln!(
                s,
                "{:<28} {:>14} {:>14} {:>18}",
                "wall time per step",
                per_step(self.numeric.run_wall_s, self.numeric.run_steps),
                per_step(self.symbolic.run_wall_s, self.symbolic.run_steps),
                ""
            );
            let _ = writeln!(
                s,
                "(the vehicles step on worker threads: CPU time is the process's, summed over \
                 its threads)"
            );
        }
        if let Some([chol, factor, solve]) = self.linear_ns {
            let _ = writeln!(
                s,
                "linear algebra (either engine): q̈ solve (Cholesky of M, solve) {chol:.1} ns; \
                 Park: LU factorization {factor:.1} ns, Newton solve {solve:.1} ns"
            );
        }
        if let Some(t) = &self.train_linear {
            let [q, f, v] = t.dense_ns;
            let _ = writeln!(
                s,
                "train linear algebra, dense: q̈ solve (Cholesky of M) {q:.1} ns; Park: LU \
                 factorization {f:.1} ns, Newton solve {v:.1} ns"
            );
            match t.block_ns {
                Some([q, f, v]) => {
                    let _ = writeln!(
                        s,
                        "train linear algebra, block-bordered ({} border coordinates): q̈ solve \
                         {q:.1} ns; Park: factorization {f:.1} ns, Newton solve {v:.1} ns",
                        t.border
                    );
                }
                None => {
                    let _ = writeln!(
                        s,
                        "train linear algebra, block-bordered: no pattern that pays"
                    );
                }
            }
        }
        if self.numeric.dynamics_ns.is_none() && self.numeric.eval_ns.is_some() {
            let _ = writeln!(
                s,
                "dynamics: not timed alone for a model on the track (its wheel–rail forces \
                 need the scenario's track); the scenario run includes it"
            );
        }
        let _ = writeln!(
            s,
            "symbolic derivation {}, plugin compilation {}",
            sec(self.derive_s),
            sec(self.compile_s)
        );
        for (name, t) in [("numeric", &self.numeric), ("symbolic", &self.symbolic)] {
            if let Some(n) = &t.note {
                let _ = writeln!(s, "{name}: {n}");
            }
        }
        s
    }
}
