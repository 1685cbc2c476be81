//! Creep case tables (`umsim creep --cases`), every case evaluated with every
//! law at its defaults (`CreepLawSpec::every_law`).
#![no_main]
use libfuzzer_sys::fuzz_target;
use railmbs_wheelrail::creep::{CreepLaw, CreepLawSpec};
use railmbs_wheelrail::creep_cases::read_cases;
use std::sync::OnceLock;

type Laws = Vec<Box<dyn CreepLaw + Send + Sync>>;

fn laws() -> &'static Laws {
    static L: OnceLock<Laws> = OnceLock::new();
    L.get_or_init(|| {
        CreepLawSpec::every_law()
            .iter()
            .map(|s| s.build().expect("default law"))
            .collect()
    })
}

fuzz_target!(|data: &[u8]| {
    let Ok(cases) = read_cases(data, "fuzz.csv") else {
        return;
    };
    for case in cases.iter().take(64) {
        for law in laws() {
            let _ = law.forces(&case.patch, &case.creepages);
        }
    }
});
