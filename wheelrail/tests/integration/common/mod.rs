//! Helpers shared by the creep-law tests: CONTACT's reference results
//! (`../shared/reference/contact`, E.A.H. Vollebregt) and a typical tread
//! contact patch, the bundled S1002/UIC60 pair.
#![allow(dead_code)]

use railmbs_testkit::{model_path, reference_path};
use railmbs_wheelrail::creep::{ContactPatch, Creepages};
use railmbs_wheelrail::geometry::{Track, Wheelset};
use railmbs_wheelrail::profile::{Profile, ProfileKind, ProfileSettings};
use std::collections::HashMap;
use std::path::Path;

/// Rows of a CSV file as (header → value) lookups (numeric columns only).
pub fn csv_rows(path: &Path) -> Vec<HashMap<String, f64>> {
    let mut rd = csv::Reader::from_path(path)
        .unwrap_or_else(|e| panic!("reference CSV {}: {e}", path.display()));
    let hdr = rd.headers().unwrap().clone();
    rd.records()
        .map(|r| {
            let r = r.unwrap();
            hdr.iter()
                .zip(r.iter())
                .filter_map(|(h, v)| Some((h.to_string(), v.parse().ok()?)))
                .collect()
        })
        .collect()
}

/// Rows of a CONTACT result CSV of `../shared/reference/contact` ([`csv_rows`]).
pub fn contact_rows(file: &str) -> Vec<HashMap<String, f64>> {
    csv_rows(&reference_path("contact").join(file))
}

/// The bundled S1002 wheelset (r0 0.46 m, 1360 mm back-to-back) on UIC60
/// 1:40 rails at 1435 mm gauge, default profile settings.
pub fn s1002_uic60() -> (Wheelset, Track) {
    let s = ProfileSettings::default();
    let w = Profile::read(
        &model_path("profiles/MBench_S1002_v3.prw"),
        ProfileKind::Wheel,
        &s,
    )
    .unwrap();
    let r = Profile::read(
        &model_path("profiles/MBench_UIC60_v3.prr"),
        ProfileKind::Rail,
        &s,
    )
    .unwrap();
    (
        Wheelset::new(w.clone(), w, 0.46, 1.360),
        Track::new(r.clone(), r, 1.435),
    )
}

/// A CONTACT case in CONTACT's units (mm, N, N/mm², spin rad/mm) → SI.
pub fn contact_case(row: &HashMap<String, f64>) -> (ContactPatch, Creepages) {
    (
        ContactPatch {
            a: row["AA"] * 1e-3,
            b: row["BB"] * 1e-3,
            g: row["G"] * 1e6,
            nu: row["NU"],
            mu: row["FSTAT"],
            n: row["FN"],
        },
        Creepages {
            xi: row["CKSI"],
            eta: row["CETA"],
            phi: row["CPHI"] * 1e3,
        },
    )
}

/// A typical tread contact: a = 6 mm, b = 4 mm, steel G = 80 GPa, ν = 0.28.
pub fn tread_patch() -> ContactPatch {
    ContactPatch {
        a: 6e-3,
        b: 4e-3,
        g: 80e9,
        nu: 0.28,
        mu: 0.3,
        n: 80e3,
    }
}
