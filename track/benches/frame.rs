//! Cost of one track-frame evaluation and one irregularity evaluation.
//!
//! `cargo bench -p railmbs-track --bench frame`

use std::hint::black_box;

use criterion::{Criterion, criterion_group, criterion_main};
use railmbs_track::cases::manchester_tc1;
use railmbs_track::{
    Component, ConstantSpeed, Irregularities, Irregularity, PsdModel, SpeedTable,
    StochasticIrregularity, StochasticSpec,
};

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
    let spec = StochasticSpec {
        model: PsdModel::ErriLow,
        component: Component::Lateral,
        wavelength_min: 3.0,
        wavelength_max: 100.0,
        harmonics: 1000,
        seed: 1,
        start: 0.0,
        end: 3000.0,
        fade: 20.0,
    };
    let irr = StochasticIrregularity::generate(&spec).unwrap();
    let direct = Irregularities::new().with(Irregularity::Stochastic(irr.clone()));
    c.bench_function("deviation stochastic 1000 harmonics", |b| {
        b.iter(|| direct.deviation(black_box(1000.0)).unwrap())
    });
    // The table a run builds at start-up: 100 m of the 3000 m extent (2 000
    // samples) at 0.05 m, 1 000 harmonics (a bundled freight track samples
    // 2 920 m at 600 harmonics per component).
    let short = StochasticIrregularity::generate(&StochasticSpec { end: 100.0, ..spec }).unwrap();
    c.bench_function("sampled 0.05 m, 100 m, 1000 harmonics", |b| {
        b.iter(|| short.sampled(black_box(0.05)).unwrap())
    });
    let irr = irr.sampled(0.05).unwrap();
    let tab = Irregularities::new().with(Irregularity::Measured(irr));
    c.bench_function("deviation stochastic sampled 0.05 m", |b| {
        b.iter(|| tab.deviation(black_box(1000.0)).unwrap())
    });
}

criterion_group!(benches, bench);
criterion_main!(benches);
