//! Records a digest of this crate's source and of the compiler as
//! `RAILMBS_WHEELRAIL_SOURCE_DIGEST`, so that caches of what the crate
//! computes (contact tables) are invalidated by any change to the code that
//! computes them, without a version number someone must remember to bump.

use std::hash::{DefaultHasher, Hash, Hasher};
use std::path::{Path, PathBuf};

fn sources(dir: &Path, out: &mut Vec<PathBuf>) {
    let entries = std::fs::read_dir(dir).unwrap_or_else(|e| panic!("{}: {e}", dir.display()));
    for entry in entries {
        let path = entry.expect("directory entry").path();
        if path.is_dir() {
            sources(&path, out);
        } else {
            out.push(path);
        }
    }
}

fn main() {
    let root = PathBuf::from(std::env::var_os("CARGO_MANIFEST_DIR").expect("set by cargo"));
    let mut files = Vec::new();
    sources(&root.join("src"), &mut files);
    files.sort();
    // SipHash with fixed keys: deterministic for one compiler, which is all a
    // cache key needs (another compiler gives another digest anyway).
    let mut hasher = DefaultHasher::new();
    for file in &files {
        file.strip_prefix(&root)
            .expect("under the root")
            .hash(&mut hasher);
        std::fs::read(file)
            .unwrap_or_else(|e| panic!("{}: {e}", file.display()))
            .hash(&mut hasher);
    }
    let rustc = std::env::var_os("RUSTC").unwrap_or_else(|| "rustc".into());
    if let Ok(out) = std::process::Command::new(rustc).arg("-vV").output() {
        out.stdout.hash(&mut hasher);
    }
    std::env::var("TARGET")
        .unwrap_or_default()
        .hash(&mut hasher);
    println!(
        "cargo:rustc-env=RAILMBS_WHEELRAIL_SOURCE_DIGEST={:016x}",
        hasher.finish()
    );
    println!("cargo:rerun-if-changed=src");
}
