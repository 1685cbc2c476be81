//! Contact-geometry benchmarks: building the tables for S1002 on UIC60 1:40 (bundled profiles)
//! and looking contacts up during a simulation.
//!
//! `cargo bench -p railmbs-wheelrail --bench geometry`

use std::hint::black_box;
use std::path::PathBuf;

use criterion::{Criterion, criterion_group, criterion_main};
use railmbs_wheelrail::geometry::{
    ContactGeometry, ContactTable, SearchSettings, TableSettings, Track, Wheelset,
};
use railmbs_wheelrail::profile::{Profile, ProfileKind, ProfileSettings};

fn geometry() -> ContactGeometry {
    let dir = PathBuf::from(concat!(env!("CARGO_MANIFEST_DIR"), "/../models/profiles"));
    let s = ProfileSettings::default();
    let w = Profile::read(&dir.join("MBench_S1002_v3.prw"), ProfileKind::Wheel, &s).unwrap();
    let r = Profile::read(&dir.join("MBench_UIC60_v3.prr"), ProfileKind::Rail, &s).unwrap();
    let ws = Wheelset::new(w.clone(), w, 0.46, 1.360);
    let tr = Track::new(r.clone(), r, 1.435);
    ContactGeometry::new(&ws, &tr, SearchSettings::default()).unwrap()
}

fn bench(c: &mut Criterion) {
    let geo = geometry();
    let mut g = c.benchmark_group("contact_table");
    g.sample_size(10);
    // ±15 mm at 0.1 mm (301 shifts) × roll ±0.02 rad at 2 mrad (21 rolls), plus the rigid
    // contact functions over the 301 shifts
    g.bench_function("s1002_uic60_y15mm_dy0.1mm_roll21", |b| {
        b.iter(|| ContactTable::from_geometry(&geo, TableSettings::default()).unwrap())
    });
    // the rigid contact geometry functions alone (roll from the vertical constraint), ±15 mm
    let ys: Vec<f64> = (-150..=150).map(|k| k as f64 * 1e-4).collect();
    g.bench_function("s1002_uic60_rigid_functions_y15mm_dy0.1mm", |b| {
        b.iter(|| geo.rigid_functions(black_box(&ys)).unwrap())
    });
    g.finish();
    let table = ContactTable::from_geometry(&geo, TableSettings::default()).unwrap();
    c.bench_function("contact_table_lookup", |b| {
        let mut k = 0u32;
        b.iter(|| {
            k = k.wrapping_add(1);
            let y = ((k % 2000) as f64 - 1000.0) * 1.3e-5;
            let roll = ((k % 37) as f64 - 18.0) * 1e-3;
            black_box(table.lookup_regions(black_box(y), black_box(roll)).unwrap())
        })
    });
    c.bench_function("direct_contact_search", |b| {
        b.iter(|| black_box(geo.contacts(black_box(3.3e-3), black_box(1e-4)).unwrap()))
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
