//! CPU cost of the Kik–Piotrowski contact per wheel, S1002 on UIC60 1:40
//! (bundled profiles), against Hertz with the strip law on the same contact.
//!
//! `cargo bench -p railmbs-wheelrail --bench kik_piotrowski`

use std::hint::black_box;
use std::path::PathBuf;

use criterion::{Criterion, criterion_group, criterion_main};
use railmbs_wheelrail::creep::{ContactPatch, CreepLaw, Creepages, StripTheory};
use railmbs_wheelrail::geometry::{ContactGeometry, SearchSettings, Track, Wheelset};
use railmbs_wheelrail::hertz::{HertzShape, wheel_rail_curvatures};
use railmbs_wheelrail::kik_piotrowski::KikPiotrowski;
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
    let kp = KikPiotrowski::default();
    let creep = Creepages {
        xi: 1e-3,
        eta: -5e-4,
        phi: 0.5,
    };
    let g = kp.young / (2.0 * (1.0 + kp.poisson));
    // tread (0 mm), two-point tread/flange root (5.08 mm), flange flank (7 mm)
    for (name, y) in [
        ("tread_y0", 0.0),
        ("two_point_y5.08mm", 5.08e-3),
        ("flange_y7mm", 7e-3),
    ] {
        let samples = geo.gap_samples(0, y, 0.0, 0.1e-3).unwrap();
        let (approach, patches) = kp.patches_for_vertical_force(&samples, 1e4).unwrap();
        c.bench_function(&format!("kp_gap_samples_0.1mm_{name}"), |b| {
            b.iter(|| black_box(geo.gap_samples(0, black_box(y), 0.0, 0.1e-3).unwrap()))
        });
        c.bench_function(&format!("kp_patches_{name}"), |b| {
            b.iter(|| {
                black_box(
                    kp.patches(black_box(&samples), black_box(approach))
                        .unwrap(),
                )
            })
        });
        c.bench_function(&format!("kp_patches_for_vertical_force_{name}"), |b| {
            b.iter(|| {
                black_box(
                    kp.patches_for_vertical_force(black_box(&samples), 1e4)
                        .unwrap(),
                )
            })
        });
        // What the wheel–rail element does per wheel and evaluation: the gap
        // near the patches at the approach, the patches, their creep forces.
        c.bench_function(&format!("kp_wheel_in_element_{name}"), |b| {
            b.iter(|| {
                let s = geo
                    .gap_samples_below(0, black_box(y), 0.0, 0.1e-3, approach)
                    .unwrap();
                for p in kp.patches(&s, approach).unwrap() {
                    black_box(p.creep_forces(g, kp.poisson, 0.3, &creep).unwrap());
                }
            })
        });
        c.bench_function(&format!("kp_gap_samples_below_0.1mm_{name}"), |b| {
            b.iter(|| {
                black_box(
                    geo.gap_samples_below(0, black_box(y), 0.0, 0.1e-3, approach)
                        .unwrap(),
                )
            })
        });
        c.bench_function(&format!("kp_creep_forces_{name}"), |b| {
            b.iter(|| {
                for p in &patches {
                    black_box(
                        p.creep_forces(g, kp.poisson, 0.3, black_box(&creep))
                            .unwrap(),
                    );
                }
            })
        });
        // the elliptic alternative on the same contact: Hertz from the
        // contact point's curvatures and the strip law with 10 strips
        let cs = geo.contacts(y, 0.0).unwrap()[0];
        let ct = *cs.deepest();
        let law = StripTheory::new(10).unwrap();
        c.bench_function(&format!("hertz_strip10_{name}"), |b| {
            b.iter(|| {
                let (ca, cb) = wheel_rail_curvatures(
                    ct.rolling_radius / ct.contact_angle.cos(),
                    ct.wheel_transverse_curvature,
                    ct.rail_transverse_curvature,
                );
                let h = HertzShape::new(ca, cb.max(1e-3), kp.young, kp.poisson)
                    .unwrap()
                    .contact(black_box(1e4))
                    .unwrap();
                let cp = ContactPatch {
                    a: h.a,
                    b: h.b,
                    g,
                    nu: kp.poisson,
                    mu: 0.3,
                    n: 1e4,
                };
                black_box(law.forces(&cp, black_box(&creep)).unwrap())
            })
        });
    }
}

criterion_group!(benches, bench);
criterion_main!(benches);
