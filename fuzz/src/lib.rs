//! What the fuzz targets share: every reader takes text, and the file
//! readers are given a path inside a bundled folder so that the relative
//! references an input makes (subsystems, tracks, profiles) reach the
//! bundled files.

use std::path::PathBuf;

/// The fuzz input as text, or `None` when it is not UTF-8 (the readers take
/// `&str`; byte-level decoding is the standard library's).
pub fn text(data: &[u8]) -> Option<&str> {
    std::str::from_utf8(data).ok()
}

/// The path `models/<folder>/fuzz.ron` of the repository (the file does not
/// exist; only its folder matters, for relative references).
pub fn bundled_file(folder: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../models")
        .join(folder)
        .join("fuzz.ron")
}
