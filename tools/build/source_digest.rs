// Shared by the build scripts of crates whose results are cached on disk
// (wheelrail: contact tables; codegen: the plugin index), with `include!`:
// a digest of source folders and of the compiler, so that a cache entry made
// by other code is never mistaken for one made by this code, without a
// version number someone must remember to bump.

/// Digest (16 hex digits) of every file under `dirs` (relative to the crate's
/// manifest directory; a folder that does not exist counts as empty), their
/// paths, the compiler's `rustc -vV` and the target; also tells cargo to
/// rerun the build script when any of them changes.
fn source_digest(dirs: &[&str]) -> String {
    use std::hash::{DefaultHasher, Hash, Hasher};
    use std::path::{Path, PathBuf};

    fn walk(dir: &Path, out: &mut Vec<PathBuf>) {
        let Ok(entries) = std::fs::read_dir(dir) else {
            return;
        };
        for entry in entries.flatten() {
            let path = entry.path();
            if path.is_dir() {
                walk(&path, out);
            } else {
                out.push(path);
            }
        }
    }

    let root = PathBuf::from(std::env::var_os("CARGO_MANIFEST_DIR").expect("set by cargo"));
    // SipHash with fixed keys: deterministic for one compiler, which is all a
    // cache key needs (another compiler gives another digest anyway).
    let mut hasher = DefaultHasher::new();
    for dir in dirs {
        println!("cargo:rerun-if-changed={dir}");
        let mut files = Vec::new();
        walk(&root.join(dir), &mut files);
        files.sort();
        for file in &files {
            file.strip_prefix(&root)
                .expect("under the root")
                .hash(&mut hasher);
            std::fs::read(file)
                .unwrap_or_else(|e| panic!("{}: {e}", file.display()))
                .hash(&mut hasher);
        }
    }
    let rustc = std::env::var_os("RUSTC").unwrap_or_else(|| "rustc".into());
    if let Ok(out) = std::process::Command::new(rustc).arg("-vV").output() {
        out.stdout.hash(&mut hasher);
    }
    std::env::var("TARGET").unwrap_or_default().hash(&mut hasher);
    format!("{:016x}", hasher.finish())
}
