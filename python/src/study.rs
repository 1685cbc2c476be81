//! Parameter studies in process: `railmbs._railmbs.Study`, `StudyEngine`
//! and `ResultStore`, the pieces of the `railmbs-study` crate that a Python
//! front end (`railmbs.study`: the local pool, Dask) drives.
//!
//! A study file is loaded with located errors (`railmbs.ModelError`); the
//! engine builds the model's plugin once (or loads plugins built by the
//! client of a distributed study) and runs one case at a time to its result
//! row, with the GIL released; the result store is the append-only table
//! that resumes. Rows cross the Python boundary as lists of the table's CSV
//! cells (strings), exactly what `umsim study` writes, so that a row
//! computed on a Dask worker is pickled as plain text and appended on the
//! client unchanged.
//!
//! Long calls (a case, the local pool) run on a thread of their own while
//! the calling thread polls Python's signal handlers every 50 ms: Ctrl-C
//! (KeyboardInterrupt) stops them at their next output row.

use crate::errors;
use pyo3::prelude::*;
use pyo3::types::{PyDict, PyList};
use railmbs_study::{
    CaseOptions, PoolOptions, ResultStore as Store, Study as StudyFile, StudyEngine as Engine,
    StudyError,
};
use std::collections::HashSet;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};

/// A study error as a Python exception: a bad file is `ModelError`
/// (located), a plugin problem `PluginError`, an interruption
/// `KeyboardInterrupt`, a result table or file problem `StudyError`.
fn study_error(py: Python<'_>, e: StudyError) -> PyErr {
    match e {
        StudyError::File(errs) => errors::model_errors(py, &errs),
        StudyError::Plugin { .. } => errors::plain(py, "PluginError", e),
        StudyError::Interrupted => {
            pyo3::exceptions::PyKeyboardInterrupt::new_err("the study was interrupted")
        }
        StudyError::Results { .. } | StudyError::Io { .. } => errors::plain(py, "StudyError", e),
    }
}

/// Runs `work` on a thread of its own with the GIL released, polling
/// Python's signal handlers every 50 ms on the calling thread; a raised
/// signal (KeyboardInterrupt) sets `stop` and is returned beside the
/// work's value (which then ends at its next output row).
fn run_watched<T: Send>(
    py: Python<'_>,
    stop: &Arc<AtomicBool>,
    work: impl FnOnce() -> T + Send,
) -> (T, Option<PyErr>) {
    py.detach(|| {
        std::thread::scope(|scope| {
            let handle = scope.spawn(work);
            let mut raised = None;
            while !handle.is_finished() {
                std::thread::sleep(std::time::Duration::from_millis(50));
                if raised.is_none()
                    && let Err(e) = Python::attach(|py| py.check_signals())
                {
                    stop.store(true, Ordering::Relaxed);
                    raised = Some(e);
                }
            }
            let value = match handle.join() {
                Ok(v) => v,
                Err(panic) => std::panic::resume_unwind(panic),
            };
            (value, raised)
        })
    })
}

/// A study file (`Study(...)`, RON; the format is documented in the
/// `railmbs-study` crate): its scenario, models, cases and result columns.
#[pyclass(module = "railmbs._railmbs", frozen)]
pub struct Study {
    inner: Arc<StudyFile>,
}

impl Study {
    /// The case of `case`: its index (int) or id (str).
    fn case(&self, case: &Bound<'_, PyAny>) -> PyResult<&railmbs_study::Case> {
        let cases = self.inner.cases();
        let found = if let Ok(k) = case.extract::<usize>() {
            cases.get(k)
        } else if let Ok(id) = case.extract::<String>() {
            self.inner.case_by_id(&id)
        } else {
            return Err(pyo3::exceptions::PyTypeError::new_err(
                "a case is its index (int) or its id (str)",
            ));
        };
        found.ok_or_else(|| {
            pyo3::exceptions::PyKeyError::new_err(format!(
                "{}: no case {} (the study has {} cases)",
                self.inner.source.display(),
                case.repr().map_or_else(|_| "?".into(), |r| r.to_string()),
                cases.len()
            ))
        })
    }
}

/// A case's input text as a float when it is a number, else the text (an
/// expression or a macro name).
fn input_value<'py>(py: Python<'py>, text: &str) -> PyResult<Bound<'py, PyAny>> {
    match text.parse::<f64>() {
        Ok(x) => Ok(x.into_pyobject(py)?.into_any()),
        Err(_) => Ok(text.into_pyobject(py)?.into_any()),
    }
}

#[pymethods]
impl Study {
    /// Reads and checks a study file, its scenario and model(s). Errors:
    /// `railmbs.ModelError` naming the file, the element, the line and the
    /// column of every problem.
    #[staticmethod]
    fn load(py: Python<'_>, path: PathBuf) -> PyResult<Self> {
        let study = StudyFile::load(&path).map_err(|e| errors::model_errors(py, &e))?;
        Ok(Self {
            inner: Arc::new(study),
        })
    }

    /// Reads study text; `path` names it in errors and resolves the
    /// scenario (and a case table) relative to its folder.
    #[staticmethod]
    #[pyo3(signature = (text, path = PathBuf::from("study.ron")))]
    fn from_string(py: Python<'_>, text: &str, path: PathBuf) -> PyResult<Self> {
        let study = StudyFile::parse(text, &path).map_err(|e| errors::model_errors(py, &e))?;
        Ok(Self {
            inner: Arc::new(study),
        })
    }

    /// The study file.
    #[getter]
    fn path(&self) -> PathBuf {
        self.inner.source.clone()
    }

    /// `"symbolic"` (one compiled plugin for all cases) or `"numeric"`.
    #[getter]
    fn engine(&self) -> &'static str {
        self.inner.engine.name()
    }

    /// The names of the models (one; a train's distinct model files), in
    /// the order of `StudyEngine.plugin_paths`.
    #[getter]
    fn models(&self) -> Vec<String> {
        self.inner.models.iter().map(|m| m.name.clone()).collect()
    }

    /// The case variables, in the study's order.
    #[getter]
    fn variables(&self) -> Vec<String> {
        self.inner.variables.clone()
    }

    /// Whether each case's output is written as `series/<case id>.csv`
    /// (or `.parquet`: `series_format`).
    #[getter]
    fn time_series(&self) -> bool {
        self.inner.time_series
    }

    /// The format of the time series files: `"csv"` or `"parquet"` (the
    /// file extension).
    #[getter]
    fn series_format(&self) -> &'static str {
        self.inner.series_format.extension()
    }

    /// The cases in index order, each a dict: `index` (int), `id` (16 hex
    /// digits, stable), `inputs` (variable → value: a float, or the text of
    /// an expression or a macro name).
    fn cases<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        let list = PyList::empty(py);
        for c in self.inner.cases() {
            let d = PyDict::new(py);
            d.set_item("index", c.index)?;
            d.set_item("id", &c.id)?;
            let inputs = PyDict::new(py);
            for (name, text) in self.inner.variables.iter().zip(c.input_texts()) {
                inputs.set_item(name, input_value(py, &text)?)?;
            }
            d.set_item("inputs", inputs)?;
            list.append(d)?;
        }
        Ok(list)
    }

    /// The number of cases.
    fn __len__(&self) -> usize {
        self.inner.cases().len()
    }

    /// The columns of the result table: `index`, `case_id`, the variables,
    /// `status`, `error`, `steps`, `rejected_steps`, `t_end[s]`,
    /// `integration_time[s]`, `cpu_time[s]`, `wall_time[s]`, then the
    /// reductions' columns.
    fn result_header(&self) -> Vec<String> {
        self.inner.result_header()
    }

    fn __repr__(&self) -> String {
        format!(
            "Study({:?}: {} cases of {} variable(s), engine {})",
            self.inner.source.display().to_string(),
            self.inner.cases().len(),
            self.inner.variables.len(),
            self.inner.engine.name()
        )
    }
}

/// The engine of a study: the model's plugin built (through the
/// content-hash cache) and loaded once, shared by every case this process
/// runs.
#[pyclass(module = "railmbs._railmbs", frozen)]
pub struct StudyEngine {
    inner: Arc<Engine>,
    study: Arc<StudyFile>,
}

/// The engine's build counters as a dict.
fn builds_dict<'py>(py: Python<'py>, engine: &Engine) -> PyResult<Bound<'py, PyDict>> {
    let b = engine.builds();
    let d = PyDict::new(py);
    d.set_item("derived", b.derived)?;
    d.set_item("indexed", b.indexed)?;
    d.set_item("compiled", b.compiled)?;
    d.set_item("loaded", b.loaded)?;
    Ok(d)
}

#[pymethods]
impl StudyEngine {
    /// The engine of `study`: for a symbolic study, derives the equations
    /// and builds the plugin through the cache (`cache_dir`, else
    /// `$RAILMBS_CACHE_DIR`, else the platform cache directory) unless the
    /// plugin index knows it, and loads it; nothing for a numeric study.
    /// The GIL is released while it works. Errors: `railmbs.PluginError`.
    #[staticmethod]
    #[pyo3(signature = (study, cache_dir = None))]
    fn prepare(py: Python<'_>, study: &Study, cache_dir: Option<PathBuf>) -> PyResult<Self> {
        let s = study.inner.clone();
        let engine = py
            .detach(|| Engine::prepare(&s, cache_dir))
            .map_err(|e| study_error(py, e))?;
        Ok(Self {
            inner: Arc::new(engine),
            study: study.inner.clone(),
        })
    }

    /// The engine of a symbolic `study` on plugins built elsewhere (by the
    /// client of a distributed study): `paths` has one plugin file per
    /// model of `study.models`, in order, each checked against its model.
    /// Nothing is derived or compiled. Errors: `railmbs.PluginError`.
    #[staticmethod]
    fn from_plugins(py: Python<'_>, study: &Study, paths: Vec<PathBuf>) -> PyResult<Self> {
        let refs: Vec<&Path> = paths.iter().map(PathBuf::as_path).collect();
        let engine = Engine::from_plugins(&study.inner, &refs).map_err(|e| study_error(py, e))?;
        Ok(Self {
            inner: Arc::new(engine),
            study: study.inner.clone(),
        })
    }

    /// The loaded plugins' files, one per model (empty for a numeric
    /// study): what a worker on this machine (or a shared file system)
    /// gives `StudyEngine.from_plugins`.
    #[getter]
    fn plugin_paths(&self) -> Vec<PathBuf> {
        self.inner
            .plugin_paths()
            .into_iter()
            .map(Path::to_path_buf)
            .collect()
    }

    /// How often this engine derived the equations, found the plugin
    /// through the plugin index, compiled it (rustc) and loaded it: a dict
    /// with `derived`, `indexed`, `compiled`, `loaded`.
    fn builds<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        builds_dict(py, &self.inner)
    }

    /// Runs one case of the engine's study, given by its index (int) or id
    /// (str), and returns its result row: the cells of the result table as
    /// text, in `Study.result_header()` order (times in s). A run that fails
    /// (diverges, a bad parameter value) is a row with status `failed` and
    /// its error, not an exception. `series_dir`: write the case's output
    /// as `<case id>.csv` (or `.parquet`: `Study.series_format`) there.
    /// The GIL is released during the run; Ctrl-C stops it
    /// (KeyboardInterrupt). Errors: `railmbs.StudyError` when a reduction
    /// fits no output column (a fault of the study file).
    #[pyo3(signature = (case, series_dir = None))]
    fn run_case(
        &self,
        py: Python<'_>,
        case: &Bound<'_, PyAny>,
        series_dir: Option<PathBuf>,
    ) -> PyResult<Vec<String>> {
        let study = Study {
            inner: self.study.clone(),
        };
        let case = study.case(case)?;
        let stop = Arc::new(AtomicBool::new(false));
        let options = CaseOptions {
            series_dir,
            stop: Some(stop.clone()),
        };
        let (result, raised) = run_watched(py, &stop, || {
            self.inner.run_case(&self.study, case, &options)
        });
        if let Some(e) = raised {
            return Err(e);
        }
        result.map(|r| r.record()).map_err(|e| study_error(py, e))
    }

    /// Runs the cases of the study that `store` does not hold yet on a pool
    /// of `jobs` threads of this process (0: one per core) and appends each
    /// row to `store` as it finishes. `on_result(row)` is called with each
    /// row (the table's cells as text) after it is written; an exception it
    /// raises (or Ctrl-C) stops the study: running cases stop and are not
    /// recorded, no new case starts, and the exception is raised once the
    /// pool has ended. Returns a dict: `skipped` (cases in the table
    /// before), `recorded`, `failed`, `interrupted` (bool). The GIL is
    /// released except for the callback.
    #[pyo3(signature = (store, jobs = 0, on_result = None))]
    fn run_local<'py>(
        &self,
        py: Python<'py>,
        store: &ResultStore,
        jobs: usize,
        on_result: Option<Py<PyAny>>,
    ) -> PyResult<Bound<'py, PyDict>> {
        let stop = Arc::new(AtomicBool::new(false));
        let options = PoolOptions {
            jobs,
            series_dir: self
                .study
                .time_series
                .then(|| store_dir(&store.path).join("series")),
            stop: Some(stop.clone()),
        };
        let callback_error: Mutex<Option<PyErr>> = Mutex::new(None);
        let mut guard = store.inner.lock().expect("not poisoned");
        let table: &mut Store = &mut guard;
        let (summary, raised) = run_watched(py, &stop, || {
            railmbs_study::run_local(&self.study, &self.inner, table, &options, |r| {
                let Some(cb) = &on_result else { return };
                if stop.load(Ordering::Relaxed) {
                    return;
                }
                Python::attach(|py| {
                    if let Err(e) = cb.call1(py, (r.record(),)) {
                        *callback_error.lock().expect("not poisoned") = Some(e);
                        stop.store(true, Ordering::Relaxed);
                    }
                });
            })
        });
        drop(guard);
        let summary = summary.map_err(|e| study_error(py, e))?;
        if let Some(e) = raised.or_else(|| callback_error.lock().expect("not poisoned").take()) {
            return Err(e);
        }
        let d = PyDict::new(py);
        d.set_item("skipped", summary.skipped)?;
        d.set_item("recorded", summary.recorded)?;
        d.set_item("failed", summary.failed)?;
        d.set_item("interrupted", summary.interrupted)?;
        Ok(d)
    }

    fn __repr__(&self) -> String {
        let b = self.inner.builds();
        format!(
            "StudyEngine({} plugin(s); derived {}, indexed {}, compiled {}, loaded {})",
            self.inner.plugin_paths().len(),
            b.derived,
            b.indexed,
            b.compiled,
            b.loaded
        )
    }
}

/// The folder of a result table (its output folder).
fn store_dir(path: &Path) -> PathBuf {
    path.parent().map(Path::to_path_buf).unwrap_or_default()
}

/// The append-only result table of a study (`results.csv`, one CSV line per
/// finished case, flushed per row). Opening an existing table resumes it.
#[pyclass(module = "railmbs._railmbs", frozen)]
pub struct ResultStore {
    inner: Mutex<Store>,
    path: PathBuf,
}

#[pymethods]
impl ResultStore {
    /// Opens (or creates, with its folder) the table at `path` with the
    /// columns `header` (`Study.result_header()`). A last line without its
    /// line break (a process killed while writing it) is dropped. Errors:
    /// `railmbs.StudyError` when the file has other columns (another study,
    /// or the study file changed) or a damaged line.
    #[staticmethod]
    fn open(py: Python<'_>, path: PathBuf, header: Vec<String>) -> PyResult<Self> {
        let store = Store::open(&path, header).map_err(|e| study_error(py, e))?;
        Ok(Self {
            inner: Mutex::new(store),
            path,
        })
    }

    /// The table's file.
    #[getter]
    fn path(&self) -> PathBuf {
        self.path.clone()
    }

    /// The ids of the cases in the table.
    fn finished(&self) -> HashSet<String> {
        self.inner.lock().expect("not poisoned").finished().clone()
    }

    /// Whether opening dropped a partly written last line.
    #[getter]
    fn dropped_partial_line(&self) -> bool {
        self.inner
            .lock()
            .expect("not poisoned")
            .dropped_partial_line()
    }

    /// Appends a row (the cells of `StudyEngine.run_case`) and flushes it
    /// to the file. Errors: `railmbs.StudyError` for a row of another
    /// length, or when the file cannot be written.
    fn append(&self, py: Python<'_>, row: Vec<String>) -> PyResult<()> {
        self.inner
            .lock()
            .expect("not poisoned")
            .append_record(&row)
            .map_err(|e| study_error(py, e))
    }
}
