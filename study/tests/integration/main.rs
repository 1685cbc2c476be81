//! Integration tests of railmbs-study: case generation, ids, located
//! errors, runs against independent single runs, failures, resume, and one
//! plugin build per study.

mod analyses;
mod cases;
mod critical_speed;
mod errors;
mod ids;
mod runs;

use std::path::{Path, PathBuf};

/// The absolute path of a bundled scenario, as a study file writes it.
pub fn scenario(name: &str) -> String {
    railmbs_testkit::model_path(&format!("scenarios/{name}"))
        .display()
        .to_string()
}

/// Writes `text` as `name` in `dir`, returns its path.
pub fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let path = dir.join(name);
    std::fs::write(&path, text).unwrap();
    path
}

/// Loads the study `text` written as `study.ron` in `dir`.
pub fn load(dir: &Path, text: &str) -> railmbs_study::Study {
    let path = write(dir, "study.ron", text);
    railmbs_study::Study::load(&path).unwrap_or_else(|e| panic!("{e}"))
}
