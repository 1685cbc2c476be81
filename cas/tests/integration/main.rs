//! The integration tests of `cas`, one module per topic, linked into one
//! test binary.

mod identities;
mod pendulum;
mod props;
