//! End-to-end: compile generated sources with the real rustc, load them, call them.

use std::path::Path;

use libloading::Library;
use railmbs_build_support::{BuildError, BuildOptions, build_plugin};

const ADD_SRC: &str = r#"
#[no_mangle]
pub extern "C" fn add(a: f64, b: f64) -> f64 {
    a + b
}
"#;

fn options(cache: &Path) -> BuildOptions {
    BuildOptions::new(1).with_cache_dir(cache)
}

/// Loads `path` and calls its `add(a, b)`.
fn call_add(path: &Path, a: f64, b: f64) -> f64 {
    // SAFETY: the library is one we just compiled from ADD_SRC; `add` has exactly this
    // signature, and its initialisers are Rust's std ones.
    unsafe {
        let lib = Library::new(path).expect("load plugin");
        let add = lib
            .get::<unsafe extern "C" fn(f64, f64) -> f64>(b"add")
            .expect("symbol add");
        let r = add(a, b);
        // Rust cdylibs must not be unloaded (docs/design.md, plugin boundary): keep it mapped.
        std::mem::forget(lib);
        r
    }
}

/// Names in `dir` that look like leftovers of builds (temporary files or directories).
fn leftovers(dir: &Path) -> Vec<String> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with(".tmp"))
        .collect()
}

#[test]
fn compile_load_call_and_cache() {
    let cache = tempfile::tempdir().unwrap();
    let first = build_plugin(ADD_SRC, &options(cache.path())).unwrap();
    assert!(!first.cache_hit);
    assert!(first.compile_time.is_some());
    assert!(first.path.starts_with(cache.path()));
    assert!(first.path.is_file());
    // 1.5 + 2.25 = 3.75 is exact in binary floating point, so equality is the right test.
    assert_eq!(call_add(&first.path, 1.5, 2.25), 3.75);

    let second = build_plugin(ADD_SRC, &options(cache.path())).unwrap();
    assert!(second.cache_hit, "same source, flags, rustc and ABI: hit");
    assert_eq!(second.compile_time, None);
    assert_eq!(second.path, first.path);
    assert_eq!(second.hash, first.hash);

    let mut other_flag = options(cache.path());
    other_flag.codegen_units = 1;
    let third = build_plugin(ADD_SRC, &other_flag).unwrap();
    assert!(!third.cache_hit, "different flag: miss");
    assert_ne!(third.path, first.path);
    assert_eq!(call_add(&third.path, -1.0, 0.5), -0.5);

    let mut other_abi = options(cache.path());
    other_abi.abi_version = 2;
    let fourth = build_plugin(ADD_SRC, &other_abi).unwrap();
    assert!(!fourth.cache_hit, "different ABI version: miss");
    assert_ne!(fourth.path, first.path);
    assert_ne!(fourth.path, third.path);

    assert!(
        leftovers(cache.path()).is_empty(),
        "{:?}",
        leftovers(cache.path())
    );
}

/// A damaged cache entry (truncated, as by a full disk or a killed copy; changed; or
/// without its recorded digest) is rebuilt and reported, never handed out: loading a
/// truncated shared library crashes the process with SIGBUS.
#[test]
fn damaged_cache_entries_are_rebuilt() {
    let cache = tempfile::tempdir().unwrap();
    let first = build_plugin(ADD_SRC, &options(cache.path())).unwrap();
    let intact = std::fs::read(&first.path).unwrap();
    let record = {
        let mut p = first.path.clone().into_os_string();
        p.push(".blake3");
        std::path::PathBuf::from(p)
    };
    assert!(record.is_file());
    let damages: [(&str, &dyn Fn()); 3] = [
        ("truncated", &|| {
            std::fs::write(&first.path, &intact[..1000]).unwrap()
        }),
        ("its content differs", &|| {
            let mut changed = intact.clone();
            let k = changed.len() / 2;
            changed[k] ^= 0xff;
            std::fs::write(&first.path, changed).unwrap();
        }),
        ("no size and digest recorded", &|| {
            std::fs::remove_file(&record).unwrap()
        }),
    ];
    for (what, damage) in damages {
        damage();
        let again = build_plugin(ADD_SRC, &options(cache.path())).unwrap();
        assert!(!again.cache_hit, "{what}: a damaged entry is no hit");
        let reason = again.rebuilt_damaged.expect("the damage is reported");
        assert!(reason.contains(what), "{what}: {reason}");
        assert_eq!(
            std::fs::read(&again.path).unwrap(),
            intact,
            "{what}: rebuilt as built"
        );
        let hit = build_plugin(ADD_SRC, &options(cache.path())).unwrap();
        assert!(hit.cache_hit && hit.rebuilt_damaged.is_none(), "{what}");
    }
    assert_eq!(call_add(&first.path, 1.5, 2.25), 3.75);
}

#[test]
fn syntax_error_keeps_the_source() {
    let cache = tempfile::tempdir().unwrap();
    let bad = "#[no_mangle]\npub extern \"C\" fn broken(a: f64) -> f64 { a + }\n";
    let err = build_plugin(bad, &options(cache.path())).unwrap_err();
    let msg = err.to_string();
    let BuildError::CompileFailed {
        source_path,
        stderr_path,
        stderr,
        ..
    } = err
    else {
        panic!("expected CompileFailed, got {msg}");
    };
    assert_eq!(source_path.parent().unwrap(), cache.path().join("failed"));
    assert_eq!(std::fs::read_to_string(&source_path).unwrap(), bad);
    assert_eq!(std::fs::read_to_string(&stderr_path).unwrap(), stderr);
    assert!(msg.contains(&source_path.display().to_string()), "{msg}");
    assert!(stderr.contains("error"), "{stderr}");
    // The diagnostics point at the kept file (temporary directory remapped to failed/).
    assert!(
        stderr.contains(&source_path.display().to_string()),
        "{stderr}"
    );
    // Nothing half-built in the cache.
    assert!(leftovers(cache.path()).is_empty());
    let libs = std::fs::read_dir(cache.path())
        .unwrap()
        .filter(|e| e.as_ref().unwrap().path().is_file())
        .count();
    assert_eq!(libs, 0);
}

#[test]
fn bogus_rustc_is_reported() {
    let cache = tempfile::tempdir().unwrap();
    let mut o = options(cache.path());
    o.rustc = Some(cache.path().join("no-such-rustc"));
    let err = build_plugin(ADD_SRC, &o).unwrap_err();
    assert!(
        matches!(&err, BuildError::RustcNotFound { reason } if reason.contains("no-such-rustc")),
        "{err}"
    );
    assert!(err.to_string().starts_with("rustc not found"), "{err}");
}

#[test]
fn concurrent_builds_of_the_same_source() {
    let cache = tempfile::tempdir().unwrap();
    // A source no other test compiles, so both threads start on an empty cache.
    let src = format!("{ADD_SRC}\n#[no_mangle] pub extern \"C\" fn three() -> f64 {{ 3.0 }}\n");
    let results: Vec<_> = std::thread::scope(|s| {
        let handles: Vec<_> = (0..2)
            .map(|_| s.spawn(|| build_plugin(&src, &options(cache.path()))))
            .collect();
        handles.into_iter().map(|h| h.join().unwrap()).collect()
    });
    let outs: Vec<_> = results.into_iter().map(Result::unwrap).collect();
    assert_eq!(outs[0].path, outs[1].path);
    assert_eq!(call_add(&outs[0].path, 2.0, 0.25), 2.25);
    assert!(leftovers(cache.path()).is_empty());
}

#[test]
fn io_error_names_the_path() {
    let dir = tempfile::tempdir().unwrap();
    // A regular file where the cache directory should be.
    let not_a_dir = dir.path().join("cache-is-a-file");
    std::fs::write(&not_a_dir, b"").unwrap();
    let err = build_plugin(ADD_SRC, &options(&not_a_dir)).unwrap_err();
    assert!(
        matches!(&err, BuildError::Io { path, .. } if path == &not_a_dir),
        "{err}"
    );
    assert!(err.to_string().contains("cache-is-a-file"), "{err}");
}
