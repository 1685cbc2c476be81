//! Rust errors as the Python exceptions of `railmbs.errors` (defined in
//! Python, so that their docs and attributes are plain Python): a model or
//! scenario problem becomes `ModelError` with the file, element, line and
//! column that `umsim` prints; a failed simulation `SimulationError`; a
//! plugin that cannot be built or loaded `PluginError`; bad contact inputs
//! `ContactError`. All derive from `RailmbsError`.

use pyo3::prelude::*;
use pyo3::types::PyDict;
use railmbs_models::{ModelError, ModelErrors};

/// The exception class `name` of `railmbs.errors`.
fn class<'py>(py: Python<'py>, name: &str) -> PyResult<Bound<'py, PyAny>> {
    py.import("railmbs.errors")?.getattr(name)
}

/// A `railmbs.errors.<name>(message, **attributes)` exception.
fn new_error(
    py: Python<'_>,
    name: &str,
    message: &str,
    attributes: &[(&str, Bound<'_, PyAny>)],
) -> PyErr {
    let made = (|| -> PyResult<PyErr> {
        let kwargs = PyDict::new(py);
        for (k, v) in attributes {
            kwargs.set_item(k, v)?;
        }
        let exc = class(py, name)?.call((message,), Some(&kwargs))?;
        Ok(PyErr::from_value(exc))
    })();
    made.unwrap_or_else(|e| e)
}

/// `(file, element, message, line, column)` of one problem; `None` for an
/// empty element and an unknown position.
fn problem<'py>(py: Python<'py>, e: &ModelError) -> PyResult<Bound<'py, PyAny>> {
    let element = (!e.element.is_empty()).then_some(e.element.as_str());
    Ok((
        e.file.display().to_string(),
        element,
        e.message.as_str(),
        e.line(),
        e.column(),
    )
        .into_pyobject(py)?
        .into_any())
}

/// `ModelError` of all the problems of a file: the message lists them as
/// `umsim` does (`file:line:column: element: message`, one a line), the
/// attributes are the first one's, `problems` all of them.
pub fn model_errors(py: Python<'_>, errors: &ModelErrors) -> PyErr {
    let first = errors.iter().next();
    let attrs = (|| -> PyResult<Vec<(&str, Bound<'_, PyAny>)>> {
        let mut attrs = Vec::new();
        if let Some(e) = first {
            attrs.push((
                "file",
                e.file.display().to_string().into_pyobject(py)?.into_any(),
            ));
            if !e.element.is_empty() {
                attrs.push(("element", e.element.as_str().into_pyobject(py)?.into_any()));
            }
            if let Some((line, column)) = e.position {
                attrs.push(("line", line.into_pyobject(py)?.into_any()));
                attrs.push(("column", column.into_pyobject(py)?.into_any()));
            }
        }
        let all = errors
            .iter()
            .map(|e| problem(py, e))
            .collect::<PyResult<Vec<_>>>()?;
        attrs.push(("problems", all.into_pyobject(py)?.into_any()));
        Ok(attrs)
    })();
    match attrs {
        Ok(attrs) => new_error(py, "ModelError", &errors.to_string(), &attrs),
        Err(e) => e,
    }
}

/// `ModelError` of one problem of `file` without a position.
pub fn file_error(py: Python<'_>, file: &std::path::Path, element: &str, message: &str) -> PyErr {
    model_errors(
        py,
        &ModelErrors(vec![ModelError::new(file, element, message)]),
    )
}

/// An exception of class `name` with just a message.
pub fn plain(py: Python<'_>, name: &str, message: impl std::fmt::Display) -> PyErr {
    new_error(py, name, &message.to_string(), &[])
}

/// `SimulationError(message, time=…, result=…)`: the run stopped at `time`
/// (s); `result` holds the rows written until then.
pub fn simulation_error(
    py: Python<'_>,
    message: &str,
    time: f64,
    result: Option<Bound<'_, PyAny>>,
) -> PyErr {
    let mut attrs = vec![("time", pyo3::types::PyFloat::new(py, time).into_any())];
    if let Some(r) = result {
        attrs.push(("result", r));
    }
    new_error(py, "SimulationError", message, &attrs)
}

/// `AnalysisError(message, file=…)`: an analysis found no result (no
/// equilibrium, a failed eigendecomposition, no steady curving state, a
/// scenario it cannot use); `file` is the scenario file it names.
pub fn analysis_error(py: Python<'_>, message: &str, file: Option<String>) -> PyErr {
    let mut attrs = Vec::new();
    if let Some(f) = file
        && let Ok(f) = f.into_pyobject(py)
    {
        attrs.push(("file", f.into_any()));
    }
    new_error(py, "AnalysisError", message, &attrs)
}
