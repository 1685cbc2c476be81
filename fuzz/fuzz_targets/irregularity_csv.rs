//! Measured-irregularity CSV files (`MeasuredIrregularity::from_csv`), then
//! sampled as a track's irregularity at both ends and in the middle.
#![no_main]
use libfuzzer_sys::fuzz_target;
use railmbs_track::{Irregularities, Irregularity, MeasuredIrregularity};
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let Some(text) = railmbs_fuzz::text(data) else {
        return;
    };
    if let Ok(m) = MeasuredIrregularity::from_csv_text(text, Path::new("fuzz.csv")) {
        let (a, b) = m.range();
        let mut irr = Irregularities::new();
        irr.push(Irregularity::Measured(m));
        for s in [a, 0.5 * (a + b), b] {
            let _ = irr.deviation_and_rate(s);
        }
    }
});
