//! Profiles in every format (SIMPACK, MiniProf, two columns), read as a wheel
//! and as a rail; a profile that reads is smoothed, and paired with the
//! bundled S1002 wheel or UIC60 rail for the contact geometry and the
//! equivalent conicity at 3 mm, as `umsim conicity` does.
#![no_main]
use libfuzzer_sys::fuzz_target;
use railmbs_wheelrail::conicity::{RollTreatment, conicity_curve};
use railmbs_wheelrail::geometry::{ContactGeometry, SearchSettings, Track, Wheelset};
use railmbs_wheelrail::profile::{
    Profile, ProfileFormat, ProfileKind, ProfileSettings, parse_points,
};
use std::sync::OnceLock;

const DIR: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../models/profiles/");

fn bundled(file: &str, kind: ProfileKind) -> Profile {
    Profile::read(
        format!("{DIR}{file}").as_ref(),
        kind,
        &ProfileSettings::default(),
    )
    .expect("bundled profile")
}

fn wheel() -> &'static Profile {
    static W: OnceLock<Profile> = OnceLock::new();
    W.get_or_init(|| bundled("MBench_S1002_v3.prw", ProfileKind::Wheel))
}

fn rail() -> &'static Profile {
    static R: OnceLock<Profile> = OnceLock::new();
    R.get_or_init(|| bundled("MBench_UIC60_v3.prr", ProfileKind::Rail))
}

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    for format in [
        ProfileFormat::Simpack,
        ProfileFormat::MiniProf,
        ProfileFormat::TwoColumn,
    ] {
        for kind in [ProfileKind::Wheel, ProfileKind::Rail] {
            let Ok(points) = parse_points(text, "fuzz", format, kind) else {
                continue;
            };
            let Ok(profile) = Profile::from_points(&points, &ProfileSettings::default()) else {
                continue;
            };
            let (ws, track) = match kind {
                ProfileKind::Wheel => (
                    Wheelset::new(profile.clone(), profile, 0.46, 1.360),
                    Track::new(rail().clone(), rail().clone(), 1.435),
                ),
                ProfileKind::Rail => (
                    Wheelset::new(wheel().clone(), wheel().clone(), 0.46, 1.360),
                    Track::new(profile.clone(), profile, 1.435),
                ),
            };
            let Ok(geo) = ContactGeometry::new(&ws, &track, SearchSettings::default()) else {
                continue;
            };
            let _ = conicity_curve(&geo, &[3e-3], RollTreatment::Neglected);
        }
    }
});
