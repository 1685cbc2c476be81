//! Paths of the repository's files: the bundled model library (`models/`)
//! and the reference data beside the checkout (`../shared/reference`).

use std::path::{Path, PathBuf};

/// The repository's root (the workspace folder, the kit's parent).
fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .parent()
        .expect("the kit lives in the workspace folder")
}

/// `rel` under the repository's root.
pub fn repo_path(rel: &str) -> PathBuf {
    root().join(rel)
}

/// `rel` under the repository's `models/` folder (mechanisms, vehicles,
/// scenarios, tracks, profiles).
pub fn model_path(rel: &str) -> PathBuf {
    repo_path("models").join(rel)
}

/// `rel` under the reference data, `../shared/reference` beside the checkout
/// (see `../shared/reference/README.md`; CI checks `shared/` out beside the
/// repository).
pub fn reference_path(rel: &str) -> PathBuf {
    let beside = root().parent().expect("the checkout lives in a folder");
    beside.join("shared/reference").join(rel)
}

/// The `.ron` files directly in `models/<folder>` (not in its subfolders),
/// sorted by name.
pub fn model_files(folder: &str) -> Vec<PathBuf> {
    let dir = model_path(folder);
    let mut paths: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .filter_map(|e| {
            let p = e.ok()?.path();
            (p.extension()? == "ron").then_some(p)
        })
        .collect();
    paths.sort();
    paths
}
