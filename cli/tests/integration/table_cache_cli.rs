//! The contact-table cache as a user meets it: a vehicle run writes the same
//! numbers whether its contact table is built, read from the cache, or
//! rebuilt because the cache entry was damaged.

use railmbs_testkit::repo_path;
use std::path::Path;
use std::process::Command;

/// `umsim run` of the wheelset-on-springs scenario (0.5 s) with the cache in
/// `cache`; returns the CSV text.
fn run_with_cache(cache: &Path, out: &Path) -> String {
    let status = Command::new(env!("CARGO_BIN_EXE_umsim"))
        .args(["run", "models/scenarios/wheelset_on_springs_30.ron", "-q"])
        .args(["--end-time", "0.5", "-o"])
        .arg(out)
        .env("RAILMBS_CACHE_DIR", cache)
        .current_dir(repo_path(""))
        .status()
        .expect("umsim starts");
    assert!(status.success());
    std::fs::read_to_string(out).expect("output written")
}

/// The entries of the cache's contact-table folder.
fn entries(cache: &Path) -> Vec<std::path::PathBuf> {
    let dir = cache.join("contact-tables");
    let mut v: Vec<_> = std::fs::read_dir(&dir)
        .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|x| x == "table"))
        .collect();
    v.sort();
    v
}

#[test]
fn cached_damaged_and_fresh_contact_tables_give_the_same_run() {
    let dir = tempfile::tempdir().unwrap();
    let cache = dir.path().join("cache");
    let out = dir.path().join("run.csv");

    let built = run_with_cache(&cache, &out);
    let stored = entries(&cache);
    assert_eq!(stored.len(), 1, "one wheelset, one table: {stored:?}");
    let entry = &stored[0];
    let size = std::fs::metadata(entry).unwrap().len();

    // The table read back from the cache gives the same numbers.
    assert_eq!(run_with_cache(&cache, &out), built);

    // A truncated entry and one with a flipped byte are rebuilt, whole.
    let bytes = std::fs::read(entry).unwrap();
    std::fs::write(entry, &bytes[..bytes.len() / 2]).unwrap();
    assert_eq!(run_with_cache(&cache, &out), built);
    assert_eq!(std::fs::metadata(entry).unwrap().len(), size);
    let mut flipped = bytes.clone();
    let last = flipped.len() - 1;
    flipped[last] ^= 0x40;
    std::fs::write(entry, &flipped).unwrap();
    assert_eq!(run_with_cache(&cache, &out), built);
    assert_eq!(std::fs::read(entry).unwrap(), bytes);
    assert_eq!(entries(&cache).len(), 1);

    // A cache that cannot be written (a file where its folder should be)
    // only costs the rebuild.
    let blocked = dir.path().join("blocked");
    std::fs::create_dir_all(&blocked).unwrap();
    std::fs::write(blocked.join("contact-tables"), "not a folder").unwrap();
    assert_eq!(run_with_cache(&blocked, &out), built);
}
