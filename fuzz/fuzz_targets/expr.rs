//! Expressions of model files: parsed over three parameter names, evaluated,
//! differentiated in time, and displayed; the displayed text parses again
//! (display is what error messages and `umsim info` show).
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Some(text) = railmbs_fuzz::text(data) else {
        return;
    };
    let names: Vec<String> = ["m", "k", "l_1"].iter().map(|s| s.to_string()).collect();
    if let Ok(e) = railmbs_models::parse_expr(text, &names, true) {
        let _ = e.eval(&[1.0, 2.0, 0.5], 0.25);
        let _ = e.time_derivative().eval(&[1.0, 2.0, 0.5], 0.25);
        let shown = e.display(&names);
        if let Err(err) = railmbs_models::parse_expr(&shown, &names, true) {
            panic!("display of {text:?} is {shown:?}, which does not parse: {err}");
        }
    }
});
