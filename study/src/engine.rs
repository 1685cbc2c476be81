//! The engine of a study: the model's plugin, built and loaded once, and the
//! run of one case to a result row.

use crate::format::{EngineKind, Study, StudyScenario};
use crate::reduce::{CaseReducer, Cell};
use crate::{Case, StudyError};
use railmbs_models::Model;
use railmbs_runtime::forces::ContactTableCache;
use railmbs_runtime::run::{Interruptible, OutputSink, RunError, run_scenario_with};
use railmbs_runtime::{Equations, NumericEquations, Plugin, PluginEquations};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::AtomicBool;
use std::time::Instant;

/// How often a study engine derived and compiled the model's plugin.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct PluginBuilds {
    /// Derivations of the symbolic equations (1 per model of a symbolic
    /// study whose plugin the plugin index did not know; 0 for a numeric
    /// study or a plugin given).
    pub derived: usize,
    /// Plugins found through the plugin index, without deriving
    /// (`railmbs_codegen::find_or_build_plugin`).
    pub indexed: usize,
    /// Compilations by rustc (the plugin was not in the cache).
    pub compiled: usize,
    /// Libraries loaded (the cases share the loaded library).
    pub loaded: usize,
}

/// The model's equations, ready for every case of a study: the plugin is
/// built (through the content-hash cache) and loaded once; each case gets
/// its own engine state on the shared library. `Sync`: one engine serves
/// the threads of a pool.
#[derive(Debug)]
pub struct StudyEngine {
    kind: EngineKind,
    /// One per model of the study (symbolic), none (numeric).
    plugins: Vec<Plugin>,
    builds: PluginBuilds,
    /// The wheel–rail contact tables, built by the first case that needs
    /// them and shared by the others (same model and track).
    tables: ContactTableCache,
}

/// Options of one case's run.
#[derive(Debug, Clone, Default)]
pub struct CaseOptions {
    /// Write the case's output rows as `<case id>.csv` (or `.parquet`, the
    /// study's [`series_format`](Study::series_format)) in this folder.
    pub series_dir: Option<PathBuf>,
    /// Stop the run at its next output row when set (Ctrl-C).
    pub stop: Option<Arc<AtomicBool>>,
}

/// How a case ended.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CaseStatus {
    /// It ran to its end time.
    Ok,
    /// It failed (diverged, a non-finite value, a bad parameter value…).
    Failed,
}

impl CaseStatus {
    /// `ok` or `failed`, as in the result table.
    pub fn name(self) -> &'static str {
        match self {
            CaseStatus::Ok => "ok",
            CaseStatus::Failed => "failed",
        }
    }
}

/// The result of one case: a row of the result table.
#[derive(Debug, Clone, PartialEq)]
pub struct CaseResult {
    /// The case's index in the study.
    pub index: usize,
    /// The case's id.
    pub id: String,
    /// Its inputs as text, one per variable.
    pub inputs: Vec<String>,
    /// How it ended.
    pub status: CaseStatus,
    /// Why it failed.
    pub error: Option<String>,
    /// Accepted steps.
    pub steps: usize,
    /// Rejected step attempts.
    pub rejected_steps: usize,
    /// Simulated time reached, s.
    pub t_end: f64,
    /// Time of the integration by the runner's clock (the CPU time of the
    /// case's thread; wall-clock time where the platform has no thread
    /// clock), s.
    pub integration_time: f64,
    /// CPU time of the case's thread (set-up, run, reductions), s.
    pub cpu_time: f64,
    /// Wall-clock time of the whole case, s.
    pub wall_time: f64,
    /// The reductions' cells (in [`Study::result_header`] order; empty
    /// cells for a failed case).
    pub values: Vec<Cell>,
}

impl CaseResult {
    /// The row as CSV cells, in [`Study::result_header`] order.
    pub fn record(&self) -> Vec<String> {
        let mut r = vec![self.index.to_string(), self.id.clone()];
        r.extend(self.inputs.iter().cloned());
        r.push(self.status.name().into());
        // One line per row: a message's line breaks become "; ".
        r.push(
            self.error
                .as_deref()
                .unwrap_or_default()
                .replace('\n', "; "),
        );
        r.push(self.steps.to_string());
        r.push(self.rejected_steps.to_string());
        for x in [
            self.t_end,
            self.integration_time,
            self.cpu_time,
            self.wall_time,
        ] {
            r.push(Cell::num(x).text());
        }
        r.extend(self.values.iter().map(Cell::text));
        r
    }
}

/// CPU time of this thread, s (0 where the platform has no thread clock).
fn thread_cpu() -> Option<cpu_time::ThreadTime> {
    cpu_time::ThreadTime::try_now().ok()
}

impl StudyEngine {
    /// The engine of `study`: for a symbolic study, derives the equations of
    /// each of its models (one; a train's distinct model files) and builds
    /// the plugin through the cache (`cache_dir`, else `RAILMBS_CACHE_DIR`,
    /// else the platform cache directory) and loads it.
    ///
    /// # Errors
    /// [`StudyError::Plugin`] when a plugin cannot be built or loaded.
    pub fn prepare(study: &Study, cache_dir: Option<PathBuf>) -> Result<StudyEngine, StudyError> {
        let mut builds = PluginBuilds::default();
        let mut plugins = Vec::new();
        if study.engine == EngineKind::Symbolic {
            for model in &study.models {
                let opts = railmbs_codegen::GenerateOptions::new();
                let built = railmbs_codegen::find_or_build_plugin(model, &opts, cache_dir.clone())
                    .map_err(|e| plugin_error(model, e))?;
                builds.derived += usize::from(!built.indexed);
                builds.indexed += usize::from(built.indexed);
                builds.compiled += usize::from(!built.cache_hit);
                let plugin =
                    Plugin::load_for(&built.path, model).map_err(|e| plugin_error(model, e))?;
                builds.loaded += 1;
                plugins.push(plugin);
            }
        }
        Ok(StudyEngine {
            kind: study.engine,
            plugins,
            builds,
            tables: ContactTableCache::new(),
        })
    }

    /// The engine of a symbolic `study` on plugins built elsewhere (by the
    /// client of a distributed study, say): `paths` has one per model of
    /// [`Study::models`], in order, each checked against its model.
    ///
    /// # Errors
    /// [`StudyError::Plugin`] when one cannot be loaded, is of another
    /// model, or the number of paths is not the number of models.
    pub fn from_plugins(study: &Study, paths: &[&Path]) -> Result<StudyEngine, StudyError> {
        if paths.len() != study.models.len() {
            return Err(StudyError::Plugin {
                model: study
                    .models
                    .iter()
                    .map(|m| m.name.as_str())
                    .collect::<Vec<_>>()
                    .join(", "),
                message: format!(
                    "{} plugin file(s) given for {} model(s)",
                    paths.len(),
                    study.models.len()
                ),
            });
        }
        let plugins = study
            .models
            .iter()
            .zip(paths)
            .map(|(m, p)| Plugin::load_for(p, m).map_err(|e| plugin_error(m, e)))
            .collect::<Result<Vec<_>, _>>()?;
        Ok(StudyEngine {
            kind: EngineKind::Symbolic,
            builds: PluginBuilds {
                loaded: plugins.len(),
                ..PluginBuilds::default()
            },
            plugins,
            tables: ContactTableCache::new(),
        })
    }

    /// The loaded plugins' files, one per model (symbolic studies): what a
    /// worker on the same machine or a shared file system gives
    /// [`StudyEngine::from_plugins`].
    pub fn plugin_paths(&self) -> Vec<&Path> {
        self.plugins.iter().map(Plugin::path).collect()
    }

    /// Wheel–rail contact tables built so far (shared by the cases of the
    /// study, and by the vehicles of a train).
    pub fn contact_tables(&self) -> usize {
        self.tables.len()
    }

    /// How often this engine derived, compiled and loaded plugins.
    pub fn builds(&self) -> PluginBuilds {
        self.builds
    }

    /// A fresh engine state for model `k` of the study.
    fn equations(&self, study: &Study, k: usize) -> Box<dyn Equations> {
        match (self.kind, self.plugins.get(k)) {
            (EngineKind::Symbolic, Some(p)) => Box::new(PluginEquations::new(p.clone())),
            _ => Box::new(NumericEquations::new(&study.models[k])),
        }
    }

    /// Runs `case` of `study` to its result row. A run that fails (diverges,
    /// a bad parameter value) is a result with status
    /// [`CaseStatus::Failed`] and its error.
    ///
    /// # Errors
    /// [`StudyError::Interrupted`] when `options.stop` was set (nothing to
    /// record); [`StudyError::Results`] when a reduction does not fit the
    /// run's output columns (a fault of the study, the same for every case).
    pub fn run_case(
        &self,
        study: &Study,
        case: &Case,
        options: &CaseOptions,
    ) -> Result<CaseResult, StudyError> {
        let wall = Instant::now();
        let cpu = thread_cpu();
        let mut result = CaseResult {
            index: case.index,
            id: case.id.clone(),
            inputs: case.input_texts(),
            status: CaseStatus::Ok,
            error: None,
            steps: 0,
            rejected_steps: 0,
            t_end: 0.0,
            integration_time: 0.0,
            cpu_time: 0.0,
            wall_time: 0.0,
            values: Vec::new(),
        };
        let empty = |study: &Study| {
            let n: usize = study
                .reductions
                .iter()
                .map(|r| r.columns().len())
                .sum::<usize>()
                + study
                    .analyses
                    .iter()
                    .map(|a| a.columns().len())
                    .sum::<usize>();
            vec![Cell::Empty; n]
        };
        let finish = |mut r: CaseResult| {
            r.cpu_time = cpu.map_or(0.0, |c| c.elapsed().as_secs_f64());
            r.wall_time = wall.elapsed().as_secs_f64();
            r
        };
        let scenario = match study.case_scenario(case) {
            Ok(s) => s,
            Err(e) => {
                result.status = CaseStatus::Failed;
                result.error = Some(e);
                result.values = empty(study);
                return Ok(finish(result));
            }
        };
        if study.time_run() {
            self.time_run(study, case, &scenario, options, &mut result)?;
        }
        if result.status == CaseStatus::Ok && !study.analyses.is_empty() {
            if options
                .stop
                .as_ref()
                .is_some_and(|f| f.load(std::sync::atomic::Ordering::Relaxed))
            {
                return Err(StudyError::Interrupted);
            }
            match self.analyses(study, &scenario) {
                Ok(cells) => result.values.extend(cells),
                Err(e) => {
                    result.status = CaseStatus::Failed;
                    result.error = Some(e);
                }
            }
        }
        if result.status == CaseStatus::Failed {
            result.values = empty(study);
        }
        Ok(finish(result))
    }

    /// The cells of the study's analyses of the case scenario `scenario`
    /// (a single vehicle: checked at load), each on fresh engines of the
    /// study's plugin, sharing the study's contact tables.
    fn analyses(&self, study: &Study, scenario: &StudyScenario) -> Result<Vec<Cell>, String> {
        let StudyScenario::Single(s) = scenario else {
            return Err("the analyses apply to a single-vehicle scenario".into());
        };
        let mut engine = || Ok(self.equations(study, 0));
        let mut cells = Vec::new();
        for a in &study.analyses {
            cells.extend(a.cells(s, &study.models[0], &mut engine, &self.tables)?);
        }
        Ok(cells)
    }

    /// The time run of a case into `result` (its steps, time, status and
    /// the run reductions' cells).
    fn time_run(
        &self,
        study: &Study,
        case: &Case,
        scenario: &StudyScenario,
        options: &CaseOptions,
        result: &mut CaseResult,
    ) -> Result<(), StudyError> {
        let mut series = options
            .series_dir
            .as_ref()
            .map(|d| study.series_format.sink(d, &case.id));
        let inner = series.as_mut().map(|s| s.as_mut() as &mut dyn OutputSink);
        let mut reducer = CaseReducer::new(&study.reductions, inner);
        let flag = options.stop.clone().unwrap_or_default();
        let run = {
            let mut sink = Interruptible::new(&mut reducer, flag);
            match &scenario {
                StudyScenario::Single(s) => {
                    let equations = self.equations(study, 0);
                    run_scenario_with(
                        s,
                        &study.models[0],
                        equations,
                        &mut sink,
                        |_| {},
                        &self.tables,
                    )
                }
                StudyScenario::Train(t) => {
                    let models: Vec<&Model> = study
                        .vehicle_models
                        .iter()
                        .map(|&k| &study.models[k])
                        .collect();
                    let engines = study
                        .vehicle_models
                        .iter()
                        .map(|&k| self.equations(study, k))
                        .collect();
                    railmbs_runtime::train::run_train_with(
                        t,
                        &models,
                        engines,
                        &mut sink,
                        |_| {},
                        &self.tables,
                    )
                }
            }
        };
        match run {
            Ok(summary) => {
                result.steps = summary.steps;
                result.rejected_steps = summary.rejected_steps;
                result.t_end = summary.t_end;
                result.integration_time = summary.cpu_time;
                match &summary.error {
                    Some(e) => {
                        result.status = CaseStatus::Failed;
                        result.error = Some(e.to_string());
                    }
                    None => result.values = reducer.cells(&summary.assessment),
                }
            }
            Err(RunError::Interrupted { .. }) => return Err(StudyError::Interrupted),
            Err(e) => {
                if let Some(message) = reducer.setup_error.take() {
                    return Err(StudyError::Results {
                        path: study.source.clone(),
                        message,
                    });
                }
                result.status = CaseStatus::Failed;
                result.error = Some(e.to_string());
            }
        }
        Ok(())
    }
}

fn plugin_error(model: &Model, e: impl std::fmt::Display) -> StudyError {
    StudyError::Plugin {
        model: model.name.clone(),
        message: e.to_string(),
    }
}
