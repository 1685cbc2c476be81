// Vectors of f64 lanes for generated plugins. This file is compiled into railmbs-codegen
// (module `lanes`, whose tests check it) and copied verbatim to the end of every plugin
// source, so it must stay self-contained (no imports, no crate paths).
//
// `F64x2` and `F64x4` wrap the x86-64 vector registers (SSE2, part of every x86-64 CPU, and
// AVX when the plugin is compiled with it) through `core::arch` intrinsics: LLVM does not
// re-vectorize lane-wise array code whose lanes are also read as scalars, so the types must
// be real vectors. Elsewhere they are arrays with lane-wise loops.

macro_rules! f64_lanes_array {
    ($name:ident, $w:literal) => {
        /// `$w` f64 lanes operated on together (plain array).
        #[derive(Clone, Copy, Debug, PartialEq)]
        pub(crate) struct $name([f64; $w]);

        impl $name {
            #[inline(always)]
            pub(crate) fn new(x: [f64; $w]) -> Self {
                Self(x)
            }
            #[inline(always)]
            pub(crate) fn splat(x: f64) -> Self {
                Self([x; $w])
            }
            #[inline(always)]
            pub(crate) fn to_array(self) -> [f64; $w] {
                self.0
            }
            #[inline(always)]
            pub(crate) fn store(self, out: &mut [f64; $w]) {
                *out = self.0;
            }
            #[inline(always)]
            pub(crate) fn add(self, o: Self) -> Self {
                let mut r = self.0;
                for l in 0..$w {
                    r[l] += o.0[l];
                }
                Self(r)
            }
            #[inline(always)]
            pub(crate) fn sub(self, o: Self) -> Self {
                let mut r = self.0;
                for l in 0..$w {
                    r[l] -= o.0[l];
                }
                Self(r)
            }
            #[inline(always)]
            pub(crate) fn mul(self, o: Self) -> Self {
                let mut r = self.0;
                for l in 0..$w {
                    r[l] *= o.0[l];
                }
                Self(r)
            }
        }
    };
}

macro_rules! f64_lanes_x86 {
    ($name:ident, $w:literal, $reg:ident, $store:ident, $set1:ident, $add:ident, $sub:ident, $mul:ident) => {
        /// `$w` f64 lanes in one x86-64 vector register.
        #[derive(Clone, Copy, Debug)]
        pub(crate) struct $name(core::arch::x86_64::$reg);

        impl $name {
            #[inline(always)]
            pub(crate) fn new(x: [f64; $w]) -> Self {
                // SAFETY: the register type holds exactly `$w` f64 lanes, in order.
                Self(unsafe { core::mem::transmute::<[f64; $w], core::arch::x86_64::$reg>(x) })
            }
            #[inline(always)]
            pub(crate) fn splat(x: f64) -> Self {
                // SAFETY: the instruction set is enabled (see the `cfg`).
                Self(unsafe { core::arch::x86_64::$set1(x) })
            }
            #[inline(always)]
            pub(crate) fn to_array(self) -> [f64; $w] {
                // SAFETY: as in `new`.
                unsafe { core::mem::transmute::<core::arch::x86_64::$reg, [f64; $w]>(self.0) }
            }
            #[inline(always)]
            pub(crate) fn store(self, out: &mut [f64; $w]) {
                // SAFETY: `out` holds `$w` f64 (unaligned store).
                unsafe { core::arch::x86_64::$store(out.as_mut_ptr(), self.0) }
            }
            #[inline(always)]
            pub(crate) fn add(self, o: Self) -> Self {
                // SAFETY: the instruction set is enabled (see the `cfg`).
                Self(unsafe { core::arch::x86_64::$add(self.0, o.0) })
            }
            #[inline(always)]
            pub(crate) fn sub(self, o: Self) -> Self {
                // SAFETY: as in `add`.
                Self(unsafe { core::arch::x86_64::$sub(self.0, o.0) })
            }
            #[inline(always)]
            pub(crate) fn mul(self, o: Self) -> Self {
                // SAFETY: as in `add`.
                Self(unsafe { core::arch::x86_64::$mul(self.0, o.0) })
            }
        }

        impl PartialEq for $name {
            fn eq(&self, o: &Self) -> bool {
                self.to_array() == o.to_array()
            }
        }
    };
}

#[cfg(target_arch = "x86_64")]
f64_lanes_x86!(F64x2, 2, __m128d, _mm_storeu_pd, _mm_set1_pd, _mm_add_pd, _mm_sub_pd, _mm_mul_pd);
#[cfg(not(target_arch = "x86_64"))]
f64_lanes_array!(F64x2, 2);
#[cfg(all(target_arch = "x86_64", target_feature = "avx"))]
f64_lanes_x86!(F64x4, 4, __m256d, _mm256_storeu_pd, _mm256_set1_pd, _mm256_add_pd, _mm256_sub_pd, _mm256_mul_pd);
#[cfg(not(all(target_arch = "x86_64", target_feature = "avx")))]
f64_lanes_array!(F64x4, 4);
