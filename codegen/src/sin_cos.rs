//! The sine and cosine of generated plugins.
//!
//! A plugin computes the sin and cos of all arguments that need no other function call in one
//! batch at the start of each evaluation ([`railmbs_cas::Program::batch_sin_cos`]): the
//! coordinates of revolute joints, the angles of track-following frames and sums of them. The
//! batch is one branch-free loop over a polynomial kernel, which LLVM vectorizes; libm's
//! `sin_cos`, one call per argument, cannot be. The kernel source ([`SOURCE`],
//! `sin_cos_kernel.rs`) is compiled here, tested against the standard library below, and
//! copied into every plugin.
//!
//! Accuracy, measured by the tests below against glibc's `sin_cos` (itself within 1 ulp of the
//! exact value): at most 1 ulp apart for |x| ≤ 100 and 2 ulp for |x| < 10⁶ (the batch
//! falls back to the standard library beyond, where a wheelset's rolling angle arrives after
//! about 4·10⁵ m of running). Throughput on the development machine (AMD EPYC, 2 cores), 48
//! arguments: libm 10.5 ns per argument; the batch 4.7 ns (baseline x86-64, SSE2) and 1.1 ns
//! (`-C target-cpu=native`, AVX-512).

mod kernel {
    include!("sin_cos_kernel.rs");
}

/// Source text of the kernel, appended to every generated plugin.
pub const SOURCE: &str = include_str!("sin_cos_kernel.rs");

/// |x| (radians) below which the polynomial kernel is used.
pub const LIMIT: f64 = kernel::SIN_COS_LIMIT;

/// sin and cos of every element of `x`, as a plugin computes them.
pub fn sin_cos_batch<const N: usize>(x: &[f64; N]) -> ([f64; N], [f64; N]) {
    kernel::sin_cos_batch(x)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Distance of `got` from `want` in units of `want`'s ulp (ulp(1) = ε for |want| < 2^-1022).
    fn ulps(got: f64, want: f64) -> f64 {
        if got == want {
            return 0.0;
        }
        let ulp = if want == 0.0 {
            f64::MIN_POSITIVE
        } else {
            let e = want.abs().log2().floor();
            2f64.powf(e - 52.0).max(f64::MIN_POSITIVE * f64::EPSILON)
        };
        (got - want).abs() / ulp
    }

    /// `n` reproducible arguments uniform in [−range, range) (ChaCha8 seeded
    /// with `seed`).
    fn arguments(seed: u64, range: f64, n: usize) -> Vec<f64> {
        use rand::{Rng, SeedableRng};
        let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
        (0..n).map(|_| rng.random_range(-range..range)).collect()
    }

    #[test]
    fn agrees_with_the_standard_library_to_2_ulp() {
        // (range, allowed ulp): 1 ulp near the origin; 2 where the reduction's roundings
        // (r − k·P2, then − k·P3) are of the order of the result's ulp
        for (range, allowed) in [
            (0.1f64, 1.0),
            (1.0, 1.0),
            (10.0, 1.0),
            (100.0, 1.0),
            (1e4, 2.0),
            (9.9e5, 2.0),
        ] {
            let xs = arguments(0x9E37_79B9_7F4A_7C15 ^ range.to_bits(), range, 100_000);
            let mut worst = (0.0f64, 0.0);
            for chunk in xs.chunks_exact(8) {
                let x: [f64; 8] = chunk.try_into().unwrap();
                let (s, c) = sin_cos_batch(&x);
                for i in 0..8 {
                    let (s0, c0) = x[i].sin_cos();
                    let e = ulps(s[i], s0).max(ulps(c[i], c0));
                    if e > worst.0 {
                        worst = (e, x[i]);
                    }
                }
            }
            assert!(
                worst.0 <= allowed,
                "range {range}: {} ulp at x = {:e}",
                worst.0,
                worst.1
            );
        }
    }

    #[test]
    fn exact_values_quadrants_and_the_fallback() {
        use std::f64::consts::{FRAC_PI_2, FRAC_PI_4, PI};
        let x = [
            0.0,
            FRAC_PI_2,
            PI,
            -FRAC_PI_2,
            3.0 * FRAC_PI_4,
            -PI,
            1e-300,
            2.5,
        ];
        let (s, c) = sin_cos_batch(&x);
        for i in 0..x.len() {
            let (s0, c0) = x[i].sin_cos();
            assert!(
                ulps(s[i], s0) <= 1.0 && ulps(c[i], c0) <= 1.0,
                "x = {}: ({}, {}) vs ({s0}, {c0})",
                x[i],
                s[i],
                c[i]
            );
        }
        assert_eq!((s[0], c[0]), (0.0, 1.0));
        assert_eq!((s[1], s[2].abs() < 2e-16, c[2]), (1.0, true, -1.0));
        // beyond the limit, NaN and infinity: the standard library, for the whole batch
        let x = [0.5, 2.0 * LIMIT, f64::NAN, f64::INFINITY];
        let (s, c) = sin_cos_batch(&x);
        assert_eq!((s[0], c[0]), 0.5f64.sin_cos());
        assert_eq!((s[1], c[1]), (2.0 * LIMIT).sin_cos());
        assert!(s[2].is_nan() && c[2].is_nan() && s[3].is_nan() && c[3].is_nan());
    }

    #[test]
    fn the_kernel_source_is_self_contained() {
        // copied into plugins after the generated items: no imports or crate paths
        assert!(
            !SOURCE.contains("use ") && !SOURCE.contains("crate::") && !SOURCE.contains("super::")
        );
        assert!(SOURCE.contains("fn sin_cos_batch<const N: usize>"));
    }
}
