//! Study files, read as a file in `models/studies/` (their scenarios and
//! tables are the bundled ones), with their cases generated.
#![no_main]
use libfuzzer_sys::fuzz_target;
use std::path::Path;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let file = Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../models/studies/fuzz.ron"
    ));
    if let Ok(study) = railmbs_study::Study::parse(text, file) {
        let _ = study.cases().len();
    }
});
