//! Reproducible random test inputs: ChaCha8 (`rand_chacha`) seeded from a
//! `u64`, so a test draws the same states on every machine and run.

use rand_chacha::ChaCha8Rng;

pub use rand::{Rng, SeedableRng};

/// The generator for `seed`.
pub fn seeded_rng(seed: u64) -> ChaCha8Rng {
    ChaCha8Rng::seed_from_u64(seed)
}

/// `n` values drawn uniformly from [lo, hi).
pub fn uniform_vec(rng: &mut impl Rng, n: usize, lo: f64, hi: f64) -> Vec<f64> {
    (0..n).map(|_| rng.random_range(lo..hi)).collect()
}
