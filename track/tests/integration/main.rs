//! The integration tests of `track`, one module per topic, linked into one
//! test binary.

mod alignment;
mod cases;
mod frame;
mod irregularity;
mod spec;
