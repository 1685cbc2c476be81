//! Where compiled plugins are cached, and atomic file writes.

use std::io::Write;
use std::path::{Path, PathBuf};

use crate::BuildError;

/// Environment variable that overrides the default cache directory.
pub const CACHE_DIR_ENV: &str = "RAILMBS_CACHE_DIR";

/// Sub-path appended to the platform cache directory.
const CACHE_SUBDIR: &str = "railmbs/plugins";

/// The plugin cache directory (not created here).
///
/// In order: `explicit`; else `RAILMBS_CACHE_DIR` (used as is); else the platform cache
/// directory + `railmbs/plugins`: `$XDG_CACHE_HOME` (if absolute) or `~/.cache` on Linux and
/// other Unixes, `~/Library/Caches` on macOS, `%LOCALAPPDATA%` on Windows.
pub fn resolve_cache_dir(explicit: Option<&Path>) -> Result<PathBuf, BuildError> {
    if let Some(p) = explicit {
        if p.as_os_str().is_empty() {
            return Err(BuildError::InvalidOption(
                "the explicit cache directory is an empty path".to_owned(),
            ));
        }
        return Ok(p.to_path_buf());
    }
    if let Some(v) = std::env::var_os(CACHE_DIR_ENV).filter(|v| !v.is_empty()) {
        return Ok(PathBuf::from(v));
    }
    platform_cache_dir().map(|d| d.join(CACHE_SUBDIR))
}

fn non_empty_env(name: &str) -> Option<PathBuf> {
    std::env::var_os(name)
        .filter(|v| !v.is_empty())
        .map(PathBuf::from)
}

#[cfg(target_os = "windows")]
fn platform_cache_dir() -> Result<PathBuf, BuildError> {
    non_empty_env("LOCALAPPDATA").ok_or_else(|| BuildError::NoCacheDir {
        detail: "LOCALAPPDATA is not set".to_owned(),
    })
}

#[cfg(target_os = "macos")]
fn platform_cache_dir() -> Result<PathBuf, BuildError> {
    non_empty_env("HOME")
        .map(|h| h.join("Library/Caches"))
        .ok_or_else(|| BuildError::NoCacheDir {
            detail: "HOME is not set".to_owned(),
        })
}

#[cfg(not(any(target_os = "windows", target_os = "macos")))]
fn platform_cache_dir() -> Result<PathBuf, BuildError> {
    // XDG Base Directory spec: a relative XDG_CACHE_HOME is invalid and must be ignored.
    if let Some(x) = non_empty_env("XDG_CACHE_HOME").filter(|p| p.is_absolute()) {
        return Ok(x);
    }
    non_empty_env("HOME")
        .map(|h| h.join(".cache"))
        .ok_or_else(|| BuildError::NoCacheDir {
            detail: "neither XDG_CACHE_HOME (absolute) nor HOME is set".to_owned(),
        })
}

/// The file beside a cached library that records its size and BLAKE3 digest.
pub(crate) fn digest_path(library: &Path) -> PathBuf {
    let mut name = library.as_os_str().to_owned();
    name.push(".blake3");
    PathBuf::from(name)
}

/// `"<size in bytes> <BLAKE3 hex>\n"` of the file at `path`.
fn digest_line(path: &Path) -> Result<String, BuildError> {
    let bytes = std::fs::read(path).map_err(|e| BuildError::io(path, e))?;
    Ok(format!(
        "{} {}\n",
        bytes.len(),
        blake3::hash(&bytes).to_hex()
    ))
}

/// Records the size and digest of the freshly built `built` (not yet in
/// place) for the cache entry `dest`. Written before the library is renamed
/// into place, so that a complete library never lacks its record.
pub(crate) fn record_digest(built: &Path, dest: &Path) -> Result<(), BuildError> {
    let line = digest_line(built)?;
    write_atomic(&digest_path(dest), line.as_bytes())
}

/// Checks the cached library `library` against its recorded size and digest;
/// `Err` says what is wrong (no record, another size, another digest, unreadable).
pub(crate) fn verify_digest(library: &Path) -> Result<(), String> {
    let record_path = digest_path(library);
    let recorded = std::fs::read_to_string(&record_path).map_err(|e| {
        format!(
            "no size and digest recorded ({}: {e})",
            record_path.display()
        )
    })?;
    let actual = digest_line(library).map_err(|e| e.to_string())?;
    if recorded == actual {
        return Ok(());
    }
    let size = |line: &str| line.split(' ').next().unwrap_or("").to_owned();
    Err(if size(&recorded) != size(&actual) {
        format!(
            "its size is {} bytes, {} were recorded when it was built (a truncated file?)",
            size(&actual),
            size(&recorded)
        )
    } else {
        "its content differs from the digest recorded when it was built".to_owned()
    })
}

pub(crate) fn create_dir_all(dir: &Path) -> Result<(), BuildError> {
    std::fs::create_dir_all(dir).map_err(|e| BuildError::io(dir, e))
}

/// Writes `contents` to `dir/file_name` atomically: readers see the old file or the whole new
/// one, never a partial one. Creates `dir` if needed. Returns the written path.
///
/// The data goes to a temporary file in `dir` (same filesystem), is flushed to disk, and is
/// renamed over the destination. `file_name` must be a plain file name (no directory parts),
/// e.g. `"lib.rs"`; this is what `umgen --emit-source DIR` uses.
pub fn write_source(dir: &Path, file_name: &str, contents: &str) -> Result<PathBuf, BuildError> {
    let name_path = Path::new(file_name);
    let plain = matches!(
        name_path.components().collect::<Vec<_>>().as_slice(),
        [std::path::Component::Normal(_)]
    );
    if !plain || file_name.contains(['/', '\\']) {
        return Err(BuildError::InvalidOption(format!(
            "source file name {file_name:?} must be a plain file name without directories"
        )));
    }
    create_dir_all(dir)?;
    let dest = dir.join(file_name);
    write_atomic(&dest, contents.as_bytes())?;
    Ok(dest)
}

/// Atomic write of `bytes` to `dest` (whose parent directory must exist):
/// readers see the old file or the whole new one, never a partial one.
pub fn write_atomic(dest: &Path, bytes: &[u8]) -> Result<(), BuildError> {
    let dir = dest.parent().unwrap_or(Path::new("."));
    let mut builder = tempfile::Builder::new();
    builder.prefix(".tmp-write-");
    // An ordinary file, not a private temporary one: 0o666 minus the umask (usually 0o644),
    // as `std::fs::write` would create it. tempfile's default would be 0o600.
    #[cfg(unix)]
    builder.permissions(std::os::unix::fs::PermissionsExt::from_mode(0o666));
    let mut tmp = builder
        .tempfile_in(dir)
        .map_err(|e| BuildError::io(dir, e))?;
    tmp.write_all(bytes)
        .and_then(|()| tmp.as_file().sync_all())
        .map_err(|e| BuildError::io(tmp.path(), e))?;
    tmp.persist(dest)
        .map_err(|e| BuildError::io(dest, e.error))?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn explicit_cache_dir_wins() {
        let d = Path::new("/some/where");
        assert_eq!(resolve_cache_dir(Some(d)).unwrap(), d);
        assert!(matches!(
            resolve_cache_dir(Some(Path::new(""))),
            Err(BuildError::InvalidOption(_))
        ));
    }

    #[test]
    fn write_source_rejects_paths_and_writes_atomically() {
        let dir = tempfile::tempdir().unwrap();
        let out = dir.path().join("emit");
        for bad in ["", "a/b.rs", "../x.rs", "..", ".", "/abs.rs", "a\\b.rs"] {
            let err = write_source(&out, bad, "x").unwrap_err();
            assert!(
                matches!(err, BuildError::InvalidOption(_)),
                "{bad:?}: {err}"
            );
        }
        let p = write_source(&out, "lib.rs", "fn a() {}").unwrap();
        assert_eq!(p, out.join("lib.rs"));
        assert_eq!(std::fs::read_to_string(&p).unwrap(), "fn a() {}");
        #[cfg(unix)]
        {
            // Same mode as a file created by std::fs::write (0o666 minus the umask).
            use std::os::unix::fs::PermissionsExt;
            let reference = dir.path().join("reference");
            std::fs::write(&reference, "x").unwrap();
            let mode = |p: &Path| std::fs::metadata(p).unwrap().permissions().mode() & 0o777;
            assert_eq!(mode(&p), mode(&reference));
        }
        // Overwrite, and no temporary file left behind.
        write_source(&out, "lib.rs", "fn b() {}").unwrap();
        assert_eq!(std::fs::read_to_string(&p).unwrap(), "fn b() {}");
        let names: Vec<_> = std::fs::read_dir(&out)
            .unwrap()
            .map(|e| e.unwrap().file_name())
            .collect();
        assert_eq!(names, ["lib.rs"]);
    }
}
