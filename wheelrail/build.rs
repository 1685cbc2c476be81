//! Records a digest of this crate's source and of the compiler as
//! `RAILMBS_WHEELRAIL_SOURCE_DIGEST` ([`railmbs_wheelrail::SOURCE_DIGEST`]):
//! contact tables cached on disk are keyed by it.

include!("../tools/build/source_digest.rs");

fn main() {
    println!(
        "cargo:rustc-env=RAILMBS_WHEELRAIL_SOURCE_DIGEST={}",
        source_digest(&["src"])
    );
}
