//! Finding rustc and reading its version.

use std::collections::HashMap;
use std::ffi::OsString;
use std::io;
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::{Mutex, OnceLock};

use crate::BuildError;

/// A rustc that runs, with its `rustc -vV` output (part of every cache key).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Rustc {
    /// The program to run: an absolute path, or a bare name that the OS looks up on `PATH`.
    pub path: PathBuf,
    /// The complete output of `rustc -vV` (version, commit, host triple, LLVM version).
    pub version: String,
}

impl Rustc {
    /// The host target triple (the `host:` line of `rustc -vV`).
    pub fn host(&self) -> Option<&str> {
        self.version
            .lines()
            .find_map(|l| l.strip_prefix("host:"))
            .map(str::trim)
    }
}

impl Rustc {
    /// What `rustc --print cfg` says about the target for the target-selecting flags among
    /// `flags` (`-C target-cpu=…`, `-C target-feature=…`, `--target …`), memoized per rustc and
    /// flags. With `-C target-cpu=native` the answer names this machine's CPU features, so a
    /// cache key including it never hands one machine a library built for another's CPU (a
    /// cache directory shared over the network, say).
    pub fn target_cfg(&self, flags: &[String]) -> Result<String, BuildError> {
        type TargetCfgCache = Mutex<HashMap<(PathBuf, Vec<String>), String>>;
        static CACHE: OnceLock<TargetCfgCache> = OnceLock::new();
        let mut args = Vec::new();
        let mut it = flags.iter().peekable();
        while let Some(f) = it.next() {
            let value = match f.as_str() {
                "-C" | "--target" => it.peek().map(|v| v.as_str()),
                _ => None,
            };
            let selects =
                |v: &str| v.starts_with("target-cpu=") || v.starts_with("target-feature=");
            match (f.as_str(), value) {
                ("-C", Some(v)) if selects(v) => args.extend([f.clone(), v.to_owned()]),
                ("--target", Some(v)) => args.extend([f.clone(), v.to_owned()]),
                (g, _) if g.starts_with("-C") && selects(&g[2..]) => args.push(f.clone()),
                (g, _) if g.starts_with("--target=") => args.push(f.clone()),
                _ => {}
            }
        }
        let key = (self.path.clone(), args.clone());
        let cache = CACHE.get_or_init(Default::default);
        if let Some(v) = cache.lock().unwrap_or_else(|e| e.into_inner()).get(&key) {
            return Ok(v.clone());
        }
        let out = Command::new(&self.path)
            .args(["--print", "cfg"])
            .args(&args)
            .output()
            .map_err(|e| BuildError::RustcNotFound {
                reason: format!("`{}` could not be started: {e}", self.path.display()),
            })?;
        if !out.status.success() {
            return Err(BuildError::InvalidOption(format!(
                "`rustc --print cfg {}` failed: {}",
                args.join(" "),
                String::from_utf8_lossy(&out.stderr).trim()
            )));
        }
        let cfg = String::from_utf8_lossy(&out.stdout).into_owned();
        cache
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .insert(key, cfg.clone());
        Ok(cfg)
    }
}

/// Finds rustc: `explicit` if given, else the `RUSTC` environment variable, else `rustc` on `PATH`.
///
/// An explicit path or a set `RUSTC` that does not work is an error; there is no silent
/// fallback to another compiler. The candidate must answer `-vV` with a line starting with
/// `rustc `. The version text is memoized per program path for the life of the process.
pub fn find_rustc(explicit: Option<&Path>) -> Result<Rustc, BuildError> {
    let (path, origin) = if let Some(p) = explicit {
        (p.to_path_buf(), "the explicit rustc path")
    } else if let Some(v) = std::env::var_os("RUSTC").filter(|v| !v.is_empty()) {
        (PathBuf::from(v), "the RUSTC environment variable")
    } else {
        let found =
            search_path(std::env::var_os("PATH")).ok_or_else(|| BuildError::RustcNotFound {
                reason: "RUSTC is not set and there is no `rustc` in any PATH directory; install \
                     Rust (https://rustup.rs) or set RUSTC to the compiler's path"
                    .to_owned(),
            })?;
        (found, "PATH")
    };
    let version = version_of(&path).map_err(|why| BuildError::RustcNotFound {
        reason: format!("`{}` (from {origin}) {why}", path.display()),
    })?;
    Ok(Rustc { path, version })
}

/// The first `rustc` (with the platform's executable suffix) in the directories of `path_var`.
pub(crate) fn search_path(path_var: Option<OsString>) -> Option<PathBuf> {
    let name = format!("rustc{}", std::env::consts::EXE_SUFFIX);
    std::env::split_paths(&path_var?)
        .filter(|d| !d.as_os_str().is_empty())
        .map(|d| d.join(&name))
        .find(|p| p.is_file())
}

/// `rustc -vV` of `path`, memoized; `Err` says in words why it is not a usable rustc.
fn version_of(path: &Path) -> Result<String, String> {
    static CACHE: OnceLock<Mutex<HashMap<PathBuf, String>>> = OnceLock::new();
    let cache = CACHE.get_or_init(Default::default);
    if let Some(v) = cache.lock().unwrap_or_else(|e| e.into_inner()).get(path) {
        return Ok(v.clone());
    }
    let out = Command::new(path).arg("-vV").output().map_err(|e| {
        if e.kind() == io::ErrorKind::NotFound {
            "does not exist or is not on PATH".to_owned()
        } else {
            format!("cannot be run: {e}")
        }
    })?;
    if !out.status.success() {
        return Err(format!(
            "failed to answer `-vV` ({}): {}",
            out.status,
            String::from_utf8_lossy(&out.stderr).trim()
        ));
    }
    let version = String::from_utf8_lossy(&out.stdout).into_owned();
    if !version.starts_with("rustc ") {
        return Err(format!(
            "is not rustc: `-vV` printed {:?}",
            version.lines().next().unwrap_or("")
        ));
    }
    cache
        .lock()
        .unwrap_or_else(|e| e.into_inner())
        .insert(path.to_path_buf(), version.clone());
    Ok(version)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn path_search_skips_missing_dirs() {
        let dir = tempfile::tempdir().unwrap();
        let exe = dir
            .path()
            .join(format!("rustc{}", std::env::consts::EXE_SUFFIX));
        std::fs::write(&exe, b"").unwrap();
        let var = std::env::join_paths([Path::new("/nonexistent-railmbs"), dir.path()]).unwrap();
        assert_eq!(search_path(Some(var)), Some(exe));
        assert_eq!(search_path(None), None);
    }

    #[test]
    fn target_cfg_depends_only_on_target_selecting_flags() {
        let rustc = find_rustc(None).unwrap();
        let flags = |f: &[&str]| f.iter().map(|s| s.to_string()).collect::<Vec<_>>();
        let base = rustc.target_cfg(&[]).unwrap();
        assert!(base.contains("target_arch="), "{base}");
        assert_eq!(
            rustc
                .target_cfg(&flags(&["-C", "opt-level=2", "--cap-lints", "allow"]))
                .unwrap(),
            base
        );
        // Naming the CPU changes the description exactly as rustc says it does.
        let native = rustc
            .target_cfg(&flags(&["-C", "target-cpu=native"]))
            .unwrap();
        let glued = rustc.target_cfg(&flags(&["-Ctarget-cpu=native"])).unwrap();
        assert_eq!(native, glued);
        if cfg!(target_arch = "x86_64") {
            assert!(!base.contains("target_feature=\"avx\""), "{base}");
            let v3 = rustc
                .target_cfg(&flags(&["-C", "target-cpu=x86-64-v3"]))
                .unwrap();
            assert!(v3.contains("target_feature=\"avx2\""), "{v3}");
        }
    }

    #[test]
    fn non_rustc_program_is_rejected() {
        // A program that exists but is not rustc must not be accepted as one.
        #[cfg(unix)]
        {
            let err = find_rustc(Some(Path::new("/bin/echo"))).unwrap_err();
            assert!(
                matches!(&err, BuildError::RustcNotFound { reason } if reason.contains("is not rustc")),
                "{err}"
            );
        }
    }
}
