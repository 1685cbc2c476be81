//! # railmbs-python
//!
//! The extension module `railmbs._railmbs` of the Python package `railmbs`
//! (PyO3, stable ABI for CPython ≥ 3.9). It exposes, in process, what the
//! command line offers: scenarios and models loaded from files or strings,
//! their parameters, macros, initial conditions, end time and creep law
//! changed, run by either engine into an in-memory table ([`sim`]), and the
//! wheel–rail contact library over numpy arrays ([`contact`]), and
//! parameter studies: study files, the engine that runs their cases on one
//! compiled plugin and the resumable result table ([`study`]). The
//! pure-Python part of the package (`python/railmbs`) defines the exception
//! classes, the result object and the numpy broadcasting, and carries the
//! type stubs.

use pyo3::prelude::*;

pub mod analysis;
pub mod contact;
pub mod errors;
pub mod sim;
pub mod study;

/// The module `railmbs._railmbs`.
#[pymodule]
fn _railmbs(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add_class::<sim::Model>()?;
    m.add_class::<sim::Scenario>()?;
    m.add_class::<study::Study>()?;
    m.add_class::<study::StudyEngine>()?;
    m.add_class::<study::ResultStore>()?;
    m.add_class::<contact::Profile>()?;
    m.add_class::<contact::WheelsetGeometry>()?;
    m.add_function(wrap_pyfunction!(contact::hertz_contact, m)?)?;
    m.add_function(wrap_pyfunction!(contact::creep_forces_flat, m)?)?;
    m.add_function(wrap_pyfunction!(contact::creep_law_name, m)?)?;
    m.add(
        "CREEP_LAW_SYNTAX",
        railmbs_wheelrail::creep::CREEP_LAW_SYNTAX,
    )?;
    Ok(())
}
