//! Study files, read as a file in `models/studies/` (their scenarios and
//! tables are the bundled ones), with their cases generated.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Some(text) = railmbs_fuzz::text(data) else {
        return;
    };
    let file = railmbs_fuzz::bundled_file("studies");
    if let Ok(study) = railmbs_study::Study::parse(text, &file) {
        let _ = study.cases().len();
    }
});
