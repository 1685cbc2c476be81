//! The cli crate's own helpers: starting the `umsim` binary under test.

use std::process::{Command, Output};

/// Runs the `umsim` built for these tests with `args` in the repository's
/// root (so bundled files are named as in the README, `models/...`).
pub fn umsim(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_umsim"))
        .args(args)
        .current_dir(railmbs_testkit::repo_path(""))
        .output()
        .expect("umsim starts")
}

/// Output bytes as text (lossy).
pub fn text(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}
