//! The integration tests of `runtime`, one module per topic, linked into one
//! test binary.

mod aba;
mod force_elements;
mod force_elements_contact;
mod force_elements_decay;
mod force_elements_series;
mod force_elements_surface;
mod force_elements_tabulated;
mod force_elements_torsion;
mod output_rows;
mod outputs_accelerometer;
mod scenario_checks;
