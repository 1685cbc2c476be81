//! The check a plugin file passes before the system loader maps it
//! (`railmbs_runtime::plugin::check_library_bytes`: an object file whose
//! segments lie inside the file).
#![no_main]
use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let _ = railmbs_runtime::plugin::check_library_bytes(data);
});
