//! The result table: an append-only CSV file, one line per finished case,
//! written and flushed as each case finishes; and the per-case files of
//! `umsim study --case` with their collection into the table.

use crate::{CaseResult, Study, StudyError};
use std::collections::HashSet;
use std::io::Write;
use std::path::{Path, PathBuf};

/// The result table of a study, open for appending. Opening an existing
/// table resumes it: its case ids are [`ResultStore::finished`]; a last line
/// without its line break (a process killed while writing it) is dropped.
#[derive(Debug)]
pub struct ResultStore {
    path: PathBuf,
    header: Vec<String>,
    file: std::fs::File,
    finished: HashSet<String>,
    dropped_partial_line: bool,
}

fn io(path: &Path) -> impl Fn(std::io::Error) -> StudyError + '_ {
    move |source| StudyError::Io {
        path: path.to_path_buf(),
        source,
    }
}

/// `cells` as one CSV line (with its line break).
fn csv_line(cells: &[String]) -> Vec<u8> {
    let mut w = csv::Writer::from_writer(Vec::new());
    // Writing to memory cannot fail.
    let _ = w.write_record(cells);
    w.into_inner().unwrap_or_default()
}

/// The records of CSV `text` (complete lines), the first the header.
fn records(text: &[u8], path: &Path) -> Result<Vec<Vec<String>>, StudyError> {
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(false)
        .flexible(true)
        .from_reader(text);
    let mut out = Vec::new();
    for r in reader.records() {
        let r = r.map_err(|e| StudyError::Results {
            path: path.to_path_buf(),
            message: e.to_string(),
        })?;
        out.push(r.iter().map(String::from).collect());
    }
    Ok(out)
}

impl ResultStore {
    /// Opens (or creates, with its folder) the table at `path` with the
    /// columns `header` ([`Study::result_header`]).
    ///
    /// # Errors
    /// [`StudyError::Results`] when the file has other columns (written by
    /// another study or another version of it) or a damaged line before the
    /// last; [`StudyError::Io`].
    pub fn open(path: &Path, header: Vec<String>) -> Result<ResultStore, StudyError> {
        if let Some(dir) = path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).map_err(io(dir))?;
        }
        let mut text = match std::fs::read(path) {
            Ok(t) => t,
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => Vec::new(),
            Err(e) => return Err(io(path)(e)),
        };
        // A last line without its line break was cut by a kill: drop it.
        let complete = text.iter().rposition(|&b| b == b'\n').map_or(0, |k| k + 1);
        let dropped_partial_line = complete < text.len();
        text.truncate(complete);
        let mut finished = HashSet::new();
        let rows = records(&text, path)?;
        if let Some(found) = rows.first() {
            if found != &header {
                return Err(StudyError::Results {
                    path: path.to_path_buf(),
                    message: format!(
                        "the result table has other columns than this study's ({} against {}: \
                         it was written by another study or before the study file changed); \
                         choose another output folder or remove it",
                        found.len(),
                        header.len()
                    ),
                });
            }
            for (k, row) in rows.iter().enumerate().skip(1) {
                if row.len() != header.len() {
                    return Err(StudyError::Results {
                        path: path.to_path_buf(),
                        message: format!(
                            "line {}: {} cells, the header has {}",
                            k + 1,
                            row.len(),
                            header.len()
                        ),
                    });
                }
                finished.insert(row[1].clone());
            }
        }
        let mut file = std::fs::OpenOptions::new()
            .create(true)
            .write(true)
            .truncate(false)
            .open(path)
            .map_err(io(path))?;
        file.set_len(complete as u64).map_err(io(path))?;
        use std::io::Seek;
        file.seek(std::io::SeekFrom::End(0)).map_err(io(path))?;
        if rows.is_empty() {
            file.write_all(&csv_line(&header)).map_err(io(path))?;
            file.flush().map_err(io(path))?;
        }
        Ok(ResultStore {
            path: path.to_path_buf(),
            header,
            file,
            finished,
            dropped_partial_line,
        })
    }

    /// The ids of the cases in the table.
    pub fn finished(&self) -> &HashSet<String> {
        &self.finished
    }

    /// Whether opening dropped a partly written last line.
    pub fn dropped_partial_line(&self) -> bool {
        self.dropped_partial_line
    }

    /// The table's file.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Appends the row of `result` and flushes it to the file.
    ///
    /// # Errors
    /// [`StudyError::Io`].
    pub fn append(&mut self, result: &CaseResult) -> Result<(), StudyError> {
        self.append_record(&result.record())
    }

    /// Appends a row given as cells (from a per-case file) and flushes it.
    ///
    /// # Errors
    /// [`StudyError::Results`] for a row of another length or without id;
    /// [`StudyError::Io`].
    pub fn append_record(&mut self, record: &[String]) -> Result<(), StudyError> {
        if record.len() != self.header.len() {
            return Err(StudyError::Results {
                path: self.path.clone(),
                message: format!(
                    "a row of {} cells for a table of {} columns",
                    record.len(),
                    self.header.len()
                ),
            });
        }
        // One write of the whole line, then to the file.
        self.file
            .write_all(&csv_line(record))
            .map_err(io(&self.path))?;
        self.file.flush().map_err(io(&self.path))?;
        self.finished.insert(record[1].clone());
        Ok(())
    }
}

/// The per-case result file of case `id` in the output folder `dir`:
/// `dir/cases/<id>.csv`.
pub fn case_file(dir: &Path, id: &str) -> PathBuf {
    dir.join("cases").join(format!("{id}.csv"))
}

/// Writes `result` of `study` as its per-case file in `dir` (the header and
/// one row; written to a temporary file and renamed, so a reader never
/// sees half a file). Returns its path.
///
/// # Errors
/// [`StudyError::Io`].
pub fn write_case_file(
    study: &Study,
    dir: &Path,
    result: &CaseResult,
) -> Result<PathBuf, StudyError> {
    let path = case_file(dir, &result.id);
    let folder = path.parent().unwrap_or(dir);
    std::fs::create_dir_all(folder).map_err(io(folder))?;
    let mut text = csv_line(&study.result_header());
    text.extend(csv_line(&result.record()));
    let tmp = path.with_extension(format!("csv.{}.tmp", std::process::id()));
    std::fs::write(&tmp, &text).map_err(io(&tmp))?;
    std::fs::rename(&tmp, &path).map_err(io(&path))?;
    Ok(path)
}

/// The row of a per-case file written for a study with `header`.
///
/// # Errors
/// [`StudyError::Results`] for a file of other columns or not one row.
pub fn read_case_file(path: &Path, header: &[String]) -> Result<Vec<String>, StudyError> {
    let text = std::fs::read(path).map_err(io(path))?;
    let rows = records(&text, path)?;
    let bad = |message: String| StudyError::Results {
        path: path.to_path_buf(),
        message,
    };
    match rows.as_slice() {
        [h, row] if h == header && row.len() == header.len() => Ok(row.clone()),
        [h, _] if h != header => Err(bad(
            "a per-case file of another study (its columns differ)".into()
        )),
        _ => Err(bad(format!(
            "a per-case file holds a header and one row; this one has {} lines",
            rows.len()
        ))),
    }
}

/// Appends to `store` the rows of the per-case files in `dir/cases/` of
/// cases it does not hold yet, in case order. Returns how many were added.
///
/// # Errors
/// A per-case file that cannot be read or is of another study.
pub fn collect_case_files(
    study: &Study,
    dir: &Path,
    store: &mut ResultStore,
) -> Result<usize, StudyError> {
    let header = study.result_header();
    let mut rows = Vec::new();
    for case in study.cases() {
        let path = case_file(dir, &case.id);
        if store.finished().contains(&case.id) || !path.exists() {
            continue;
        }
        rows.push(read_case_file(&path, &header)?);
    }
    for r in &rows {
        store.append_record(r)?;
    }
    Ok(rows.len())
}
