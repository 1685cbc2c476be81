//! Environment-variable lookups (`RAILMBS_CACHE_DIR`, `XDG_CACHE_HOME`, `RUSTC`).
//!
//! One test function in its own test binary: it changes the process environment, which
//! must not race with other threads reading it.

use std::path::Path;

use railmbs_build_support::{BuildError, BuildOptions, build_plugin, resolve_cache_dir};

#[test]
fn environment_variables() {
    let tmp = tempfile::tempdir().unwrap();
    // SAFETY (all set_var/remove_var below): this is the only test in this binary, so no
    // other thread reads or writes the environment meanwhile.
    unsafe { std::env::set_var("RAILMBS_CACHE_DIR", tmp.path()) };
    assert_eq!(resolve_cache_dir(None).unwrap(), tmp.path());
    // The explicit argument beats the variable.
    assert_eq!(
        resolve_cache_dir(Some(Path::new("/explicit"))).unwrap(),
        Path::new("/explicit")
    );

    unsafe { std::env::remove_var("RAILMBS_CACHE_DIR") };
    #[cfg(all(unix, not(target_os = "macos")))]
    {
        unsafe { std::env::set_var("XDG_CACHE_HOME", "/xdg/cache") };
        assert_eq!(
            resolve_cache_dir(None).unwrap(),
            Path::new("/xdg/cache/railmbs/plugins")
        );
        // A relative XDG_CACHE_HOME is ignored (XDG Base Directory spec), HOME is used.
        unsafe {
            std::env::set_var("XDG_CACHE_HOME", "relative");
            std::env::set_var("HOME", "/home/someone");
        }
        assert_eq!(
            resolve_cache_dir(None).unwrap(),
            Path::new("/home/someone/.cache/railmbs/plugins")
        );
        unsafe {
            std::env::remove_var("XDG_CACHE_HOME");
            std::env::remove_var("HOME");
        }
        assert!(matches!(
            resolve_cache_dir(None),
            Err(BuildError::NoCacheDir { .. })
        ));
    }

    // A bogus RUSTC is an error naming the variable, not a silent fallback to PATH.
    unsafe { std::env::set_var("RUSTC", "/nonexistent/bin/rustc-bogus") };
    let err = build_plugin("", &BuildOptions::new(1).with_cache_dir(tmp.path())).unwrap_err();
    assert!(
        matches!(&err, BuildError::RustcNotFound { reason }
            if reason.contains("rustc-bogus") && reason.contains("RUSTC")),
        "{err}"
    );
}
