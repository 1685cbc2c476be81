// sin and cos for generated plugins. This file is compiled into railmbs-codegen (module
// `sin_cos`, whose tests check it against the standard library) and copied verbatim to the
// end of every plugin source, so it must stay self-contained (no imports, no crate paths).

/// |x| (radians) below which [`sin_cos_reduced`] is used. With π/2 split into
/// 32 + 32 + 53 bits, k·P1 and k·P2 are exact for |k| < 2^21, i.e. |x| < 3.29e6.
pub(crate) const SIN_COS_LIMIT: f64 = 1.0e6;

/// sin x and cos x for |x| < [`SIN_COS_LIMIT`], within 1 ulp of glibc's for |x| ≤ 100 and
/// 2 ulp beyond (the reduction's last two roundings); meaningless for other x (NaN, ±∞).
/// Cody–Waite reduction x = k·π/2 + r with π/2 = P1 + P2 + P3 (Cody & Waite 1980), then the
/// Taylor polynomials of sin (to r^17) and cos (to r^18) on |r| ≤ π/4, whose truncation
/// errors (π/4)^19/19! and (π/4)^20/20! are below 1e-19, and the quadrant k mod 4.
/// Branch-free, so that a loop over it vectorizes.
#[inline(always)]
pub(crate) fn sin_cos_reduced(x: f64) -> (f64, f64) {
    const FRAC_2_PI: f64 = core::f64::consts::FRAC_2_PI;
    // Adding 1.5·2^52 rounds to an integer (|x·2/π| < 2^51); its low bits are k.
    const ROUND: f64 = 6_755_399_441_055_744.0;
    const P1: f64 = 1.570_796_326_734_125_6; // π/2 to 32 bits: 0x1.921fb544p+0
    const P2: f64 = 6.077_100_506_303_966e-11; // next 32 bits: 0x1.0b4611a6p-34
    const P3: f64 = 2.022_266_248_795_950_6e-21; // the rest, rounded: 0x1.3198a2e037073p-69
    let biased = x * FRAC_2_PI + ROUND;
    let k = biased - ROUND;
    let quadrant = biased.to_bits();
    let r = ((x - k * P1) - k * P2) - k * P3;
    let z = r * r;
    // Factorials up to 18! are exact in f64, so each coefficient is the rounded 1/n!.
    let sin_r = r + r * z
        * (-1.0 / 6.0
            + z * (1.0 / 120.0
                + z * (-1.0 / 5_040.0
                    + z * (1.0 / 362_880.0
                        + z * (-1.0 / 39_916_800.0
                            + z * (1.0 / 6_227_020_800.0
                                + z * (-1.0 / 1_307_674_368_000.0
                                    + z * (1.0 / 355_687_428_096_000.0))))))));
    let cos_r = 1.0
        + z * (-0.5
            + z * (1.0 / 24.0
                + z * (-1.0 / 720.0
                    + z * (1.0 / 40_320.0
                        + z * (-1.0 / 3_628_800.0
                            + z * (1.0 / 479_001_600.0
                                + z * (-1.0 / 87_178_291_200.0
                                    + z * (1.0 / 20_922_789_888_000.0
                                        + z * (-1.0 / 6_402_373_705_728_000.0)))))))));
    // sin x = (s, c, −s, −c)[k mod 4], cos x = (c, −s, −c, s)[k mod 4]
    let odd = quadrant & 1 != 0;
    let (s, c) = (
        if odd { cos_r } else { sin_r },
        if odd { sin_r } else { cos_r },
    );
    let sin_sign = (quadrant & 2) << 62;
    let cos_sign = (quadrant.wrapping_add(1) & 2) << 62;
    (
        f64::from_bits(s.to_bits() ^ sin_sign),
        f64::from_bits(c.to_bits() ^ cos_sign),
    )
}

/// sin and cos of every element of `x`: one branch-free loop (which LLVM vectorizes; the code
/// generator pads `x` to a multiple of 8 so that no scalar remainder is left) when all
/// |x| < [`SIN_COS_LIMIT`], else the standard library's `sin_cos` for each.
#[inline]
pub(crate) fn sin_cos_batch<const N: usize>(x: &[f64; N]) -> ([f64; N], [f64; N]) {
    let mut sin = [0.0; N];
    let mut cos = [0.0; N];
    if x.iter().all(|a| a.abs() < SIN_COS_LIMIT) {
        for i in 0..N {
            (sin[i], cos[i]) = sin_cos_reduced(x[i]);
        }
    } else {
        for i in 0..N {
            (sin[i], cos[i]) = x[i].sin_cos();
        }
    }
    (sin, cos)
}
