//! Scenario and train files: the text is read as a file in
//! `models/scenarios/`, so model, track and profile paths reach the bundled
//! files (`../vehicles/…`, `../tracks/…`), which are then loaded too.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Some(text) = railmbs_fuzz::text(data) else {
        return;
    };
    let file = railmbs_fuzz::bundled_file("scenarios");
    let _ = railmbs_models::parse_scenario(text, &file);
    let _ = railmbs_models::parse_train(text, &file);
});
