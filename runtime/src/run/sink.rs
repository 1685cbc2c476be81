//! Where output rows go: an [`OutputSink`] receives the header once, then
//! every row in time order, then the end of the run. [`CsvFile`] writes what
//! `umsim run` writes; [`Table`] keeps the columns in memory by name;
//! [`Discard`] only counts; [`AssessmentReducer`](super::AssessmentReducer)
//! reduces the accepted steps' wheel loads to the EN 14363 table.

use super::{LoadSample, RunError};
use std::io::Write;
use std::path::{Path, PathBuf};

/// A receiver of a run's output rows.
pub trait OutputSink {
    /// The column names (units in brackets), once, before the first row.
    ///
    /// # Errors
    /// The sink's own (a file that cannot be written).
    fn begin(&mut self, header: &[String]) -> Result<(), RunError>;

    /// One row: a value per column of the header, the first the time (s).
    ///
    /// # Errors
    /// The sink's own; the run then stops and returns the error.
    fn row(&mut self, values: &[f64]) -> Result<(), RunError>;

    /// The wheel loads of an accepted step, one sample per wheel–rail
    /// element (`name` gives an element's long name by key). Ignored by
    /// default; [`AssessmentReducer`](super::AssessmentReducer) reduces them.
    fn accepted_loads(&mut self, _samples: &[LoadSample], _name: &dyn Fn(usize) -> String) {}

    /// The end of the run (also after a simulation error): flush.
    ///
    /// # Errors
    /// The sink's own.
    fn finish(&mut self) -> Result<(), RunError> {
        Ok(())
    }
}

impl<T: OutputSink + ?Sized> OutputSink for &mut T {
    fn begin(&mut self, header: &[String]) -> Result<(), RunError> {
        (**self).begin(header)
    }

    fn row(&mut self, values: &[f64]) -> Result<(), RunError> {
        (**self).row(values)
    }

    fn accepted_loads(&mut self, samples: &[LoadSample], name: &dyn Fn(usize) -> String) {
        (**self).accepted_loads(samples, name);
    }

    fn finish(&mut self) -> Result<(), RunError> {
        (**self).finish()
    }
}

/// Capacity of a [`CsvFile`]'s write buffer, bytes.
const CSV_BUFFER_BYTES: usize = 1 << 18;

/// A CSV file: the header line, then one line per row with each value in
/// Rust's shortest round-trip form (`{}`), comma-separated.
#[derive(Debug)]
pub struct CsvFile {
    path: PathBuf,
    writer: Option<std::io::BufWriter<std::fs::File>>,
    /// Reusable text of one row.
    line: String,
}

impl CsvFile {
    /// A sink that creates `path` (and its folder) at [`OutputSink::begin`].
    pub fn new(path: impl Into<PathBuf>) -> Self {
        Self {
            path: path.into(),
            writer: None,
            line: String::new(),
        }
    }

    /// The file's path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Fails when the output file is one of `inputs` (the scenario, model
    /// or track file a run reads): `-o scenario.ron` must not replace the
    /// scenario by its results.
    ///
    /// # Errors
    /// [`RunError::Setup`] naming the file and what it is.
    pub fn refuse_inputs<'p>(
        &self,
        inputs: impl IntoIterator<Item = (&'p str, &'p Path)>,
    ) -> Result<(), RunError> {
        for (what, input) in inputs {
            // Both must exist to be the same file; a new output is none.
            if same_file::is_same_file(&self.path, input).unwrap_or(false) {
                return Err(RunError::Setup {
                    file: self.path.clone(),
                    message: format!(
                        "the output file is the run's {what} ({}); choose another output file",
                        input.display()
                    ),
                });
            }
        }
        Ok(())
    }

    fn io(&self, source: std::io::Error) -> RunError {
        RunError::Io {
            path: self.path.clone(),
            source,
        }
    }
}

impl OutputSink for CsvFile {
    fn begin(&mut self, header: &[String]) -> Result<(), RunError> {
        let p = &self.path;
        if let Some(dir) = p.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).map_err(|source| RunError::Io {
                path: dir.to_path_buf(),
                source,
            })?;
        }
        let file = std::fs::File::create(p).map_err(|e| self.io(e))?;
        // A row of a vehicle run is a few kB: a larger buffer than the
        // default 8 kB writes it to the file in fewer system calls.
        let mut w = std::io::BufWriter::with_capacity(CSV_BUFFER_BYTES, file);
        writeln!(w, "{}", header.join(",")).map_err(|e| self.io(e))?;
        self.writer = Some(w);
        Ok(())
    }

    fn row(&mut self, values: &[f64]) -> Result<(), RunError> {
        use std::fmt::Write as _;
        let Some(w) = self.writer.as_mut() else {
            return Ok(());
        };
        self.line.clear();
        for (k, x) in values.iter().enumerate() {
            if k > 0 {
                self.line.push(',');
            }
            let _ = write!(self.line, "{x}");
        }
        self.line.push('\n');
        w.write_all(self.line.as_bytes()).map_err(|e| self.io(e))
    }

    fn finish(&mut self) -> Result<(), RunError> {
        if let Some(mut w) = self.writer.take() {
            w.flush().map_err(|e| self.io(e))?;
        }
        Ok(())
    }
}

/// Output columns in memory, by name (for studies and bindings).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Table {
    names: Vec<String>,
    columns: Vec<Vec<f64>>,
}

impl Table {
    /// An empty table; [`OutputSink::begin`] sets its columns.
    pub fn new() -> Self {
        Self::default()
    }

    /// Column names in order (the CSV header).
    pub fn names(&self) -> &[String] {
        &self.names
    }

    /// The column `name` (values in its unit, one per row), if there is one.
    pub fn column(&self, name: &str) -> Option<&[f64]> {
        let k = self.names.iter().position(|n| n == name)?;
        Some(&self.columns[k])
    }

    /// All columns, in header order.
    pub fn columns(&self) -> &[Vec<f64>] {
        &self.columns
    }

    /// The columns, in header order, without copying them (for bindings
    /// that hand them on, e.g. as numpy arrays).
    pub fn into_columns(self) -> Vec<Vec<f64>> {
        self.columns
    }

    /// Number of rows.
    pub fn rows(&self) -> usize {
        self.columns.first().map_or(0, Vec::len)
    }
}

impl OutputSink for Table {
    fn begin(&mut self, header: &[String]) -> Result<(), RunError> {
        self.names = header.to_vec();
        self.columns = vec![Vec::new(); header.len()];
        Ok(())
    }

    fn row(&mut self, values: &[f64]) -> Result<(), RunError> {
        for (c, &x) in self.columns.iter_mut().zip(values) {
            c.push(x);
        }
        Ok(())
    }
}

/// A sink that drops every row (the runner still counts them).
#[derive(Debug, Clone, Copy, Default)]
pub struct Discard;

impl OutputSink for Discard {
    fn begin(&mut self, _header: &[String]) -> Result<(), RunError> {
        Ok(())
    }

    fn row(&mut self, _values: &[f64]) -> Result<(), RunError> {
        Ok(())
    }
}

/// A sink that stops the run at the next row once `flag` is set (by a
/// Ctrl-C handler, say), with [`RunError::Interrupted`] naming the time of
/// the last row written; everything before is kept (the inner sink is
/// finished as after any stop).
#[derive(Debug)]
pub struct Interruptible<S> {
    inner: S,
    flag: std::sync::Arc<std::sync::atomic::AtomicBool>,
    rows: usize,
    last_time: Option<f64>,
}

impl<S: OutputSink> Interruptible<S> {
    /// `inner`, stopped when `flag` becomes true.
    pub fn new(inner: S, flag: std::sync::Arc<std::sync::atomic::AtomicBool>) -> Self {
        Self {
            inner,
            flag,
            rows: 0,
            last_time: None,
        }
    }
}

impl<S: OutputSink> OutputSink for Interruptible<S> {
    fn begin(&mut self, header: &[String]) -> Result<(), RunError> {
        self.inner.begin(header)
    }

    fn row(&mut self, values: &[f64]) -> Result<(), RunError> {
        if self.flag.load(std::sync::atomic::Ordering::Relaxed) {
            return Err(RunError::Interrupted {
                rows: self.rows,
                last_time: self.last_time,
            });
        }
        self.inner.row(values)?;
        self.rows += 1;
        self.last_time = values.first().copied();
        Ok(())
    }

    fn accepted_loads(&mut self, samples: &[LoadSample], name: &dyn Fn(usize) -> String) {
        self.inner.accepted_loads(samples, name);
    }

    fn finish(&mut self) -> Result<(), RunError> {
        self.inner.finish()
    }
}
