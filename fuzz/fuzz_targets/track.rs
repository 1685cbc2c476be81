//! Track files (RON `TrackDescription`), read as a file in `models/tracks/`
//! and built (alignment, grade, irregularities, gauge widening).
#![no_main]
use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let file = Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../models/tracks/fuzz.ron"
    ));
    if let Ok(track) = railmbs_models::parse_track(text, file) {
        // A built track answers for every position inside it.
        let l = track.length();
        for k in 0..=4 {
            let _ = track.point(l * k as f64 / 4.0);
        }
    }
});
