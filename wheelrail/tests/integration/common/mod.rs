//! Helpers shared by the creep-law tests: CONTACT's reference results
//! (`../shared/reference/contact`, E.A.H. Vollebregt) and a typical tread
//! contact patch.
#![allow(dead_code)]

use railmbs_testkit::reference_path;
use railmbs_wheelrail::creep::{ContactPatch, Creepages};
use std::collections::HashMap;

/// Rows of a CONTACT result CSV as (header → value) lookups (numeric
/// columns only).
pub fn contact_rows(file: &str) -> Vec<HashMap<String, f64>> {
    let mut rd =
        csv::Reader::from_path(reference_path("contact").join(file)).expect("reference CSV");
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
