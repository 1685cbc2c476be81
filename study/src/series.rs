//! The per-case time series of a study: a case's output rows as a CSV file
//! (the runtime's [`CsvFile`](railmbs_runtime::run::CsvFile), the same file
//! `umsim run` writes) or as a Parquet file ([`ParquetFile`]).

use railmbs_runtime::run::{CsvFile, OutputSink, RunError};
use serde::Deserialize;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// The file format of a study's per-case time series (`series_format` in
/// the study file).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Deserialize)]
pub enum SeriesFormat {
    /// `series/<case id>.csv`: the header line, then one line per output
    /// row, each value in Rust's shortest round-trip form (the default).
    #[default]
    Csv,
    /// `series/<case id>.parquet`: one required `DOUBLE` column per output
    /// column, named as in the CSV header, in the same order, uncompressed,
    /// plain encoding.
    Parquet,
}

impl SeriesFormat {
    /// The file extension: `csv` or `parquet`.
    pub fn extension(self) -> &'static str {
        match self {
            SeriesFormat::Csv => "csv",
            SeriesFormat::Parquet => "parquet",
        }
    }

    /// The time series file of case `id` in folder `dir`.
    pub fn path(self, dir: &Path, id: &str) -> PathBuf {
        dir.join(format!("{id}.{}", self.extension()))
    }

    /// A sink writing the file of case `id` in `dir` in this format.
    pub fn sink(self, dir: &Path, id: &str) -> Box<dyn OutputSink> {
        let path = self.path(dir, id);
        match self {
            SeriesFormat::Csv => Box::new(CsvFile::new(path)),
            SeriesFormat::Parquet => Box::new(ParquetFile::new(path)),
        }
    }
}

/// Output rows kept per Parquet row group: a row group is written (and its
/// memory freed) every this many rows, 8 B per value and column.
const ROW_GROUP_ROWS: usize = 8192;

/// A Parquet file of the output rows: a schema of one required `DOUBLE`
/// column per header name (in order), written as row groups of
/// 8192 rows, uncompressed and plain-encoded (no dictionary),
/// so the values are the computed `f64`s bit for bit. The file is written
/// as `<path>.partial` and renamed to `path` when the run ends
/// ([`OutputSink::finish`], also after a simulation error, with the rows up
/// to it): a file at `path` is always complete.
pub struct ParquetFile {
    path: PathBuf,
    partial: PathBuf,
    writer: Option<parquet::file::writer::SerializedFileWriter<std::fs::File>>,
    /// The rows of the current row group, by column.
    columns: Vec<Vec<f64>>,
}

impl std::fmt::Debug for ParquetFile {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("ParquetFile")
            .field("path", &self.path)
            .field("open", &self.writer.is_some())
            .finish()
    }
}

impl ParquetFile {
    /// A sink that creates `path` (and its folder) at [`OutputSink::begin`].
    pub fn new(path: impl Into<PathBuf>) -> Self {
        let path = path.into();
        let mut partial = path.clone().into_os_string();
        partial.push(".partial");
        Self {
            path,
            partial: partial.into(),
            writer: None,
            columns: Vec::new(),
        }
    }

    /// The file's path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    fn error(&self, e: impl std::fmt::Display) -> RunError {
        RunError::Io {
            path: self.path.clone(),
            source: std::io::Error::other(e.to_string()),
        }
    }

    /// Writes the buffered rows as one row group.
    fn flush_group(&mut self) -> Result<(), RunError> {
        use parquet::data_type::DoubleType;
        if self.columns.first().is_none_or(Vec::is_empty) {
            return Ok(());
        }
        let Some(w) = self.writer.as_mut() else {
            return Ok(());
        };
        let result = (|| {
            let mut group = w.next_row_group()?;
            for values in &self.columns {
                let Some(mut col) = group.next_column()? else {
                    break;
                };
                col.typed::<DoubleType>().write_batch(values, None, None)?;
                col.close()?;
            }
            group.close().map(|_| ())
        })();
        result.map_err(|e| self.error(e))?;
        for c in &mut self.columns {
            c.clear();
        }
        Ok(())
    }
}

impl OutputSink for ParquetFile {
    fn begin(&mut self, header: &[String]) -> Result<(), RunError> {
        use parquet::basic::{Repetition, Type as Physical};
        use parquet::file::properties::{EnabledStatistics, WriterProperties};
        use parquet::schema::types::Type;
        if let Some(dir) = self.path.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).map_err(|source| RunError::Io {
                path: dir.to_path_buf(),
                source,
            })?;
        }
        let fields = header
            .iter()
            .map(|name| {
                Type::primitive_type_builder(name, Physical::DOUBLE)
                    .with_repetition(Repetition::REQUIRED)
                    .build()
                    .map(Arc::new)
            })
            .collect::<Result<Vec<_>, _>>()
            .map_err(|e| self.error(e))?;
        let schema = Type::group_type_builder("railmbs_output")
            .with_fields(fields)
            .build()
            .map_err(|e| self.error(e))?;
        let props = WriterProperties::builder()
            .set_dictionary_enabled(false)
            .set_statistics_enabled(EnabledStatistics::Chunk)
            .set_created_by(format!("railmbs {}", env!("CARGO_PKG_VERSION")))
            .build();
        let file = std::fs::File::create(&self.partial).map_err(|source| RunError::Io {
            path: self.partial.clone(),
            source,
        })?;
        let writer = parquet::file::writer::SerializedFileWriter::new(
            file,
            Arc::new(schema),
            Arc::new(props),
        )
        .map_err(|e| self.error(e))?;
        self.writer = Some(writer);
        self.columns = vec![Vec::with_capacity(ROW_GROUP_ROWS); header.len()];
        Ok(())
    }

    fn row(&mut self, values: &[f64]) -> Result<(), RunError> {
        if self.writer.is_none() {
            return Ok(());
        }
        for (c, &x) in self.columns.iter_mut().zip(values) {
            c.push(x);
        }
        if self
            .columns
            .first()
            .is_some_and(|c| c.len() >= ROW_GROUP_ROWS)
        {
            self.flush_group()?;
        }
        Ok(())
    }

    fn finish(&mut self) -> Result<(), RunError> {
        if self.writer.is_none() {
            return Ok(());
        }
        self.flush_group()?;
        let Some(w) = self.writer.take() else {
            return Ok(());
        };
        w.close().map_err(|e| self.error(e))?;
        std::fs::rename(&self.partial, &self.path).map_err(|source| RunError::Io {
            path: self.path.clone(),
            source,
        })
    }
}
