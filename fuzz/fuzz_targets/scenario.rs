//! Scenario and train files: the text is read as a file in
//! `models/scenarios/`, so model, track and profile paths reach the bundled
//! files (`../vehicles/…`, `../tracks/…`), which are then loaded too.
#![no_main]
use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let file = Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../models/scenarios/fuzz.ron"
    ));
    let _ = railmbs_models::parse_scenario(text, file);
    let _ = railmbs_models::parse_train(text, file);
});
