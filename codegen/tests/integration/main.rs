//! The integration tests of `codegen`, one module per topic, linked into one
//! test binary.

mod snapshot;
