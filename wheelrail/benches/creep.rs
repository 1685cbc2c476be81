//! Creep-force evaluations per second for each law (one core).
//!
//! `cargo bench -p railmbs-wheelrail --bench creep`; criterion reports the
//! throughput in elements/s = evaluations/s over a fixed set of 64 tread-contact
//! cases (creepages from adhesion-dominated to near saturation, spin up to
//! 0.3 1/m). `-- "creep/fastsim-a"` (a criterion filter) runs one group of laws.
//!
//! Group `fig24` (Pogorelov 2005, Fig. 24: FASTSIM against FastSim_SA versus
//! the number of elements per strip `n` "for a typical contact on the running
//! surface"): both laws with 10 strips and `n` elements on 64 running-surface
//! cases with creepages up to 40 % of saturation ([`running_surface_cases`]),
//! `-- fig24`.

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use railmbs_wheelrail::creep::{
    ContactPatch, CreepLaw, Creepages, Fastsim, FastsimA, FastsimSa, KalkerLinear, Mueller,
    MuellerKalkerSaturated, Polach, SlidingZone, StripTheory,
};
use std::hint::black_box;

fn cases() -> Vec<Creepages> {
    let mut v = Vec::new();
    for xi in [0.0, 5e-4, 2e-3, 6e-3] {
        for eta in [-1e-3, 0.0, 1e-3, 4e-3] {
            for phi in [-0.3, -0.05, 0.1, 0.3] {
                v.push(Creepages { xi, eta, phi });
            }
        }
    }
    v
}

/// Running-surface contacts: |ξ|, |η| ≤ 1.2e-3 (saturation, μN over Kalker's
/// f₁₁, is at about 2.7e-3 for this patch), |φ| ≤ 0.15 1/m.
fn running_surface_cases() -> Vec<Creepages> {
    let mut v = Vec::new();
    for xi in [-5e-4, 2e-4, 6e-4, 1e-3] {
        for eta in [-8e-4, 0.0, 4e-4, 1.2e-3] {
            for phi in [-0.1, 0.0, 0.05, 0.15] {
                v.push(Creepages { xi, eta, phi });
            }
        }
    }
    v
}

fn bench(c: &mut Criterion) {
    let p = ContactPatch {
        a: 6e-3,
        b: 4e-3,
        g: 80e9,
        nu: 0.28,
        mu: 0.3,
        n: 80e3,
    };
    let cs = cases();
    let laws: Vec<(String, Box<dyn CreepLaw>)> = vec![
        ("kalker".into(), Box::new(KalkerLinear)),
        ("mueller".into(), Box::new(Mueller::default())),
        (
            "fastsim-sa 10x10".into(),
            Box::new(FastsimSa::new(10, 10).unwrap()),
        ),
        (
            "fastsim-sa 20x20".into(),
            Box::new(FastsimSa::new(20, 20).unwrap()),
        ),
        (
            "mueller-kalker-saturated".into(),
            Box::new(MuellerKalkerSaturated::default()),
        ),
        (
            "fastsim 10x10".into(),
            Box::new(Fastsim::new(10, 10).unwrap()),
        ),
        (
            "fastsim 10x20".into(),
            Box::new(Fastsim::new(10, 20).unwrap()),
        ),
        (
            "fastsim 20x20".into(),
            Box::new(Fastsim::new(20, 20).unwrap()),
        ),
        ("fastsim-a 10".into(), Box::new(FastsimA::new(10).unwrap())),
        ("fastsim-a 20".into(), Box::new(FastsimA::new(20).unwrap())),
        (
            "fastsim-a 10 integrated".into(),
            Box::new(FastsimA::integrated(10).unwrap()),
        ),
        (
            "fastsim-a 20 integrated".into(),
            Box::new(FastsimA::integrated(20).unwrap()),
        ),
        (
            "fastsim-a 10 picard 8".into(),
            Box::new(
                FastsimA::new(10)
                    .unwrap()
                    .with_sliding(SlidingZone::Picard { nodes: 8 })
                    .unwrap(),
            ),
        ),
        ("strip 10".into(), Box::new(StripTheory::new(10).unwrap())),
        ("strip 20".into(), Box::new(StripTheory::new(20).unwrap())),
        ("polach".into(), Box::new(Polach::new())),
        (
            "polach 2005 options".into(),
            Box::new(
                Polach::new()
                    .with_reduction(0.3, 0.1)
                    .unwrap()
                    .with_falling_friction(0.4, 0.6, 30.0)
                    .unwrap(),
            ),
        ),
    ];
    let mut g = c.benchmark_group("creep");
    g.throughput(Throughput::Elements(cs.len() as u64));
    for (name, law) in &laws {
        g.bench_function(name.as_str(), |b| {
            b.iter(|| {
                let mut s = 0.0;
                for c in &cs {
                    let f = law.forces(black_box(&p), black_box(c)).unwrap();
                    s += f.fx + f.fy + f.mz;
                }
                s
            })
        });
    }
    g.finish();

    let cs = running_surface_cases();
    let mut g = c.benchmark_group("fig24");
    g.throughput(Throughput::Elements(cs.len() as u64));
    for n in [5, 10, 20, 40, 60, 80, 100] {
        let pair: [(&str, Box<dyn CreepLaw>); 2] = [
            ("fastsim", Box::new(Fastsim::new(10, n).unwrap())),
            ("fastsim-sa", Box::new(FastsimSa::new(10, n).unwrap())),
        ];
        for (name, law) in &pair {
            g.bench_function(format!("{name} n={n}"), |b| {
                b.iter(|| {
                    let mut s = 0.0;
                    for c in &cs {
                        let f = law.forces(black_box(&p), black_box(c)).unwrap();
                        s += f.fx + f.fy + f.mz;
                    }
                    s
                })
            });
        }
    }
    g.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
