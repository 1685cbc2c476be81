//! Cost of one track-frame evaluation and one irregularity evaluation.
//!
//! `cargo bench -p railmbs-track --bench frame`

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use railmbs_track::cases::{manchester_tc1, straight_lateral_irregularity};
use railmbs_track::{ConstantSpeed, SpeedTable};

fn bench(c: &mut Criterion) {
    let t = manchester_tc1().unwrap();
    let law = ConstantSpeed::new(11.0, 4.4).unwrap();
    // t = 12 s: s = 63.8 m, inside the entry clothoid (the quadrature path).
    c.bench_function("frame_at_time tc1 clothoid", |b| {
        b.iter(|| t.frame_at_time(&law, black_box(12.0)).unwrap())
    });
    c.bench_function("frame_at_time tc1 curve", |b| {
        b.iter(|| t.frame_at_time(&law, black_box(20.0)).unwrap())
    });
    let table = SpeedTable::new(11.0, &[(0.0, 0.0), (10.0, 4.4), (42.0, 4.4)]).unwrap();
    c.bench_function("frame_at_time tc1 clothoid, speed table", |b| {
        b.iter(|| t.frame_at_time(&table, black_box(14.0)).unwrap())
    });
    c.bench_function("deviation tc1 (dip)", |b| {
        b.iter(|| t.deviation(black_box(173.0)).unwrap())
    });
    let s = straight_lateral_irregularity(2000.0, 1).unwrap();
    c.bench_function("deviation stochastic 4000 harmonics", |b| {
        b.iter(|| s.deviation(black_box(1000.0)).unwrap())
    });
    let irr = match &s.irregularities().items()[0] {
        railmbs_track::Irregularity::Stochastic(x) => x.sampled(0.05).unwrap(),
        _ => unreachable!("the case holds one stochastic irregularity"),
    };
    let tab = railmbs_track::Irregularities::new().with(railmbs_track::Irregularity::Measured(irr));
    c.bench_function("deviation stochastic sampled 0.05 m", |b| {
        b.iter(|| tab.deviation(black_box(1000.0)).unwrap())
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
