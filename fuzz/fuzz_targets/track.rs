//! Track files (RON `TrackDescription`), read as a file in `models/tracks/`
//! and built (alignment, grade, irregularities, gauge widening).
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Some(text) = railmbs_fuzz::text(data) else {
        return;
    };
    let file = railmbs_fuzz::bundled_file("tracks");
    if let Ok(track) = railmbs_models::parse_track(text, &file) {
        // A built track answers for every position inside it.
        let l = track.length();
        for k in 0..=4 {
            let _ = track.point(l * k as f64 / 4.0);
        }
    }
});
