//! The integration tests of `wheelrail`, one module per topic, linked into one
//! test binary.

mod common;
mod conicity_en15302;
mod creep;
mod creepage;
mod elastic_rail;
mod exact_theory;
mod fastsim_sa;
mod geometry_contact;
mod hertz;
mod kik_piotrowski;
mod mueller;
mod polach;
mod profile_reading;
mod strip;
