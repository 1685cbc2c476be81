//! Model files: the text is read as a model file in `models/mechanisms/`, so
//! its `Subsystem` references reach the bundled subsystem files
//! (`subsystems/…`), which are then read, resolved and flattened too.
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Some(text) = railmbs_fuzz::text(data) else {
        return;
    };
    let file = railmbs_fuzz::bundled_file("mechanisms");
    if let Ok(model) = railmbs_models::parse_model(text, &file) {
        // The loaded model is usable: its parameter values resolve or say why.
        let _ = model.parameter_values(&[], &[]);
    }
});
