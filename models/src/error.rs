//! Errors of model and scenario files: file, element, message and position.

use std::fmt;
use std::path::{Path, PathBuf};

/// One problem in a model or scenario file.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ModelError {
    /// The file the problem is in.
    pub file: PathBuf,
    /// The element, by kind and long name, e.g. `body "link2"` or `force "k1"`;
    /// empty for problems of the file as a whole.
    pub element: String,
    /// What is wrong.
    pub message: String,
    /// 1-based (line, column) in the file, where known.
    pub position: Option<(usize, usize)>,
}

/// The text of `path`, or an error saying which `kind` of file (model,
/// scenario, train) could not be read and why.
pub(crate) fn read_text(path: &Path, kind: &str) -> Result<String, ModelError> {
    std::fs::read_to_string(path)
        .map_err(|e| ModelError::new(path, "", format!("cannot read the {kind} file: {e}")))
}

impl ModelError {
    /// An error without a position.
    pub fn new(file: &Path, element: impl Into<String>, message: impl Into<String>) -> Self {
        ModelError {
            file: file.to_path_buf(),
            element: element.into(),
            message: message.into(),
            position: None,
        }
    }

    /// 1-based line, if known.
    pub fn line(&self) -> Option<usize> {
        self.position.map(|p| p.0)
    }

    /// 1-based column, if known.
    pub fn column(&self) -> Option<usize> {
        self.position.map(|p| p.1)
    }
}

impl fmt::Display for ModelError {
    /// `file:line:column: element: message`.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        write!(f, "{}", self.file.display())?;
        if let Some((line, col)) = self.position {
            write!(f, ":{line}:{col}")?;
        }
        write!(f, ": ")?;
        if !self.element.is_empty() {
            write!(f, "{}: ", self.element)?;
        }
        write!(f, "{}", self.message)
    }
}

impl std::error::Error for ModelError {}

/// All the problems found in a file (never empty when returned as an error).
#[derive(Debug, Clone, PartialEq, Eq, Default)]
pub struct ModelErrors(pub Vec<ModelError>);

impl ModelErrors {
    /// True if no problem was recorded.
    pub fn is_empty(&self) -> bool {
        self.0.is_empty()
    }

    /// Number of problems.
    pub fn len(&self) -> usize {
        self.0.len()
    }

    /// The problems, in the order they are reported.
    pub fn iter(&self) -> std::slice::Iter<'_, ModelError> {
        self.0.iter()
    }
}

impl From<ModelError> for ModelErrors {
    fn from(e: ModelError) -> Self {
        ModelErrors(vec![e])
    }
}

impl fmt::Display for ModelErrors {
    /// One error per line.
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        for (i, e) in self.0.iter().enumerate() {
            if i > 0 {
                writeln!(f)?;
            }
            write!(f, "{e}")?;
        }
        Ok(())
    }
}

impl std::error::Error for ModelErrors {}

impl<'a> IntoIterator for &'a ModelErrors {
    type Item = &'a ModelError;
    type IntoIter = std::slice::Iter<'a, ModelError>;
    fn into_iter(self) -> Self::IntoIter {
        self.0.iter()
    }
}
