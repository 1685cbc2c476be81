//! The workspace's integration tests live in `tests/`: symbolic ≡ numeric on
//! every model, physics oracles (analytic solutions, conservation laws,
//! published references) and end-to-end runs.
