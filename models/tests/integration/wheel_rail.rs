//! Wheel–rail elements: their profile files are read and validated when the
//! model loads, and a missing or malformed file is a load error that names
//! the model file, the element and the profile, at the profile's field.

use crate::common;

use common::*;
use railmbs_models::{ForceKind, ModelErrors, WheelRail};
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::sync::atomic::{AtomicUsize, Ordering};

/// A bundled profile file (models/profiles), absolute.
fn bundled(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("profiles")
        .join(name)
}

/// A wheel–rail element "wr" on body "a" with these profile paths.
fn element(wheel: &Path, rail: &Path) -> String {
    format!(
        "WheelRail(name: \"wr\", wheelset: \"a\", wheel_profile: \"{}\",\n                  \
         rail_profile: \"{}\", radius: 0.46)",
        wheel.display(),
        rail.display()
    )
}

/// BASE with `element` added to its forces.
fn with(element: &str) -> String {
    BASE.replacen("c: \"k\"),", &format!("c: \"k\"),\n        {element},"), 1)
}

/// The errors of BASE with `element` added.
fn errors_of(text: &str) -> ModelErrors {
    match load(text) {
        Ok(_) => panic!("should not load:\n{text}"),
        Err(e) => e,
    }
}

/// The error of element "wr" containing `needle`, checked to sit at the
/// (1-based) line and column of the quoted `literal` in `text`.
fn at_literal<'a>(
    errors: &'a ModelErrors,
    text: &str,
    literal: &str,
    needle: &str,
) -> &'a railmbs_models::ModelError {
    let e = find(errors, "force \"wr\"", needle);
    let quoted = format!("\"{literal}\"");
    let off = text.find(&quoted).expect("literal in the text");
    let line = text[..off].matches('\n').count() + 1;
    let col = off - text[..off].rfind('\n').map_or(0, |p| p + 1) + 1;
    assert_eq!(e.position, Some((line, col)), "{e}");
    e
}

/// A file with `text` in a fresh temporary folder, removed when dropped.
struct TempFile(PathBuf);

impl TempFile {
    fn new(name: &str, text: &str) -> TempFile {
        static N: AtomicUsize = AtomicUsize::new(0);
        let dir = std::env::temp_dir().join(format!(
            "railmbs-wheel-rail-{}-{}",
            std::process::id(),
            N.fetch_add(1, Ordering::Relaxed)
        ));
        std::fs::create_dir_all(&dir).unwrap();
        let path = dir.join(name);
        std::fs::write(&path, text).unwrap();
        TempFile(std::fs::canonicalize(path).unwrap())
    }
}

impl Drop for TempFile {
    fn drop(&mut self) {
        if let Some(dir) = self.0.parent() {
            std::fs::remove_dir_all(dir).ok();
        }
    }
}

fn wheel_rail(m: &railmbs_models::Model) -> &WheelRail {
    m.forces
        .iter()
        .find_map(|f| match &f.kind {
            ForceKind::WheelRail(w) => Some(&**w),
            _ => None,
        })
        .expect("a wheel–rail element")
}

#[test]
fn profiles_are_read_when_the_model_loads() {
    let (wheel, rail) = (
        bundled("MBench_S1002_v3.prw"),
        bundled("MBench_UIC60_v3.ban"),
    );
    let m = load(&with(&element(&wheel, &rail))).unwrap_or_else(|e| panic!("{e}"));
    let w = wheel_rail(&m);
    assert_eq!(
        w.wheel_profiles[0].path,
        std::fs::canonicalize(&wheel).unwrap()
    );
    assert_eq!(
        w.rail_profiles[0].path,
        std::fs::canonicalize(&rail).unwrap()
    );
    // The file's own header says how many points it holds.
    let text = std::fs::read_to_string(&rail).unwrap();
    let declared: usize = text
        .lines()
        .find_map(|l| l.strip_prefix("XYPoints="))
        .expect("XYPoints header")
        .trim()
        .parse()
        .unwrap();
    assert_eq!(w.rail_profiles[0].points.points.len(), declared);
    // The right-hand profiles default to the left ones: the same points.
    assert!(Arc::ptr_eq(
        &w.wheel_profiles[0].points,
        &w.wheel_profiles[1].points
    ));
    assert!(Arc::ptr_eq(
        &w.rail_profiles[0].points,
        &w.rail_profiles[1].points
    ));
}

#[test]
fn a_missing_profile_file_is_a_load_error_at_its_field() {
    let missing = std::env::temp_dir().join("railmbs-no-such-profile.prw");
    let text = with(&element(&missing, &bundled("MBench_UIC60_v3.ban")));
    let errors = errors_of(&text);
    let e = at_literal(
        &errors,
        &text,
        &missing.display().to_string(),
        &format!("profile file not found: {}", missing.display()),
    );
    assert_eq!(e.file, Path::new(FILE));
    assert_eq!(errors.len(), 1, "{errors}");
}

#[test]
fn a_malformed_profile_file_is_a_load_error_naming_its_line() {
    // Two columns (y z, mm): the third point's height is not a number.
    let bad = TempFile::new("rail.txt", "-30 -5\n-20 -1\n-10 zero\n0 0\n10 -1\n20 -5\n");
    let text = with(&element(&bundled("MBench_S1002_v3.prw"), &bad.0));
    let errors = errors_of(&text);
    let e = at_literal(
        &errors,
        &text,
        &bad.0.display().to_string(),
        &format!("rail profile {}:3:", bad.0.display()),
    );
    assert_eq!(e.file, Path::new(FILE));
    assert_eq!(errors.len(), 1, "{errors}");

    // Points that go back: not a profile.
    let bad = TempFile::new("rail.txt", "-30 -5\n-20 -1\n-25 -1\n0 0\n10 -1\n20 -5\n");
    let text = with(&element(&bundled("MBench_S1002_v3.prw"), &bad.0));
    at_literal(
        &errors_of(&text),
        &text,
        &bad.0.display().to_string(),
        &format!(
            "rail profile {}:3: lateral coordinate not strictly monotonic",
            bad.0.display()
        ),
    );
}

#[test]
fn a_rail_profile_given_for_the_wheel_is_a_load_error() {
    let rail = bundled("MBench_UIC60_v3.ban");
    let text = with(&element(&rail, &rail));
    let errors = errors_of(&text);
    find(
        &errors,
        "force \"wr\"",
        "is a rail profile, a wheel profile was expected",
    );
    assert_eq!(errors.len(), 1, "{errors}");
}

/// A wheel–rail element on a body that cannot move (no coordinate on it or
/// on a body it hangs from) is refused at its wheelset field: the contact
/// would press on a fixed body and report wheel loads of 10¹⁰ N.
#[test]
fn a_wheelset_that_cannot_move_is_refused() {
    let (wheel, rail) = (
        bundled("MBench_S1002_v3.prw"),
        bundled("MBench_UIC60_v3.prr"),
    );
    // Body "a" turns about Z (coordinate qa): accepted.
    load(&with(&element(&wheel, &rail))).unwrap();
    // A body "fixed" welded to the ground.
    let fixed = with(&element(&wheel, &rail).replace("wheelset: \"a\"", "wheelset: \"fixed\""))
        .replacen(
            "    ],\n    cut_joints",
            "        Body(name: \"fixed\", mass: 1, inertia: (ixx: 1, iyy: 1, izz: 1),\n             \
             joint: Joint(parent: \"ground\", transforms: [Tz(0.5)])),\n    ],\n    cut_joints",
            1,
        );
    let errors = errors_of(&fixed);
    let e = find(
        &errors,
        "force \"wr\"",
        "the wheelset body \"fixed\" cannot move",
    );
    // At the element's `wheelset` field.
    let off = fixed.find("wheelset: \"fixed\"").unwrap();
    let line = fixed[..off].matches('\n').count() + 1;
    let col = off - fixed[..off].rfind('\n').map_or(0, |p| p + 1) + 1;
    assert_eq!(e.position, Some((line, col)), "{e}");
}
