//! # railmbs-wheelrail
//!
//! Wheel–rail contact as pure functions, validated against published references
//! (Pogorelov 2005, Sect. 4; reference data in `../shared/reference`):
//!
//! - [`profile`]: wheel and rail profiles (SIMPACK `.prw`/`.prr`, MiniProf
//!   `.whl`/`.ban`, two-column y–z), orientation, smoothing, evaluation;
//! - [`geometry`]: contact geometry of a wheelset on a track, one- and two-point
//!   contact, tables over lateral shift and roll;
//! - [`conicity`]: equivalent conicity by EN 15302;
//! - [`hertz`]: Hertzian contact ellipse, approach, pressure;
//! - [`kik_piotrowski`]: non-elliptic multi-patch contact by the modified
//!   Kik–Piotrowski method (virtual penetration, strips);
//! - [`creepage`]: creepages and spin from body velocities;
//! - [`creep`]: creep-force laws (Kalker linear, Mueller (Pogorelov 2005), Kalker-saturated
//!   Mueller, FASTSIM, FastSim_SA, FastSim_A, Polach);
//! - [`kalker`]: Kalker's creepage coefficients;
//! - [`elastic_rail`]: massless elastic rail with inner/outer iterations.

/// Digest of this crate's source files and of the compiler that built it
/// (see `build.rs`): anything cached from this crate's results, such as a
/// contact table on disk, is valid only under the same digest, so a change
/// to the code invalidates such caches by itself.
pub const SOURCE_DIGEST: &str = env!("RAILMBS_WHEELRAIL_SOURCE_DIGEST");

pub mod conicity;
pub mod creep;
pub mod creep_cases;
pub mod creepage;
pub mod elastic_rail;
pub mod geometry;
pub mod hertz;
pub mod kalker;
pub mod kik_piotrowski;
pub mod profile;

/// `x` as written for a reader in a message: plain between 10⁻⁴ and 10⁶ (and
/// 0, ±inf, NaN), else with an exponent (Rust's `{}` writes 1e100 with 100
/// digits and 1e-308 with 308).
pub fn readable(x: f64) -> String {
    if x == 0.0 || !x.is_finite() || (1e-4..1e6).contains(&x.abs()) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}
