//! The f64 vectors of generated plugins and the lane count chosen for this machine.
//!
//! Packs of isomorphic instructions ([`railmbs_cas::Program::pack_lanes`]) are emitted as
//! operations on `F64x2` or `F64x4` (`lanes_kernel.rs`, copied into every plugin as
//! [`SOURCE`]): x86-64 vector registers through `core::arch` (SSE2; AVX when the plugin is
//! built with it), lane-wise arrays elsewhere.

// Compiled here for the tests; plugins use their copy.
#[allow(dead_code)]
mod kernel {
    include!("lanes_kernel.rs");
}

/// Source text of the vector types, appended to every generated plugin.
pub const SOURCE: &str = include_str!("lanes_kernel.rs");

/// Lanes of the vector operations in a plugin: 4 (256-bit AVX) when it is built for this
/// machine and the CPU has AVX, else 2 (128-bit vectors: SSE2 is part of x86-64, NEON of
/// AArch64).
pub fn lanes_for(portable: bool) -> usize {
    #[cfg(target_arch = "x86_64")]
    if !portable && std::arch::is_x86_feature_detected!("avx") {
        return 4;
    }
    let _ = portable;
    2
}

#[cfg(test)]
mod tests {
    use super::kernel::{F64x2, F64x4};

    #[test]
    fn lane_operations_are_the_scalar_ones() {
        let a = [1.5, -2.25, 3.0e-7, 4.0e12];
        let b = [0.5, 8.0, -3.0e-7, 1e300];
        let (x, y) = (F64x4::new(a), F64x4::new(b));
        assert_eq!(x.to_array(), a);
        for l in 0..4 {
            assert_eq!(x.add(y).to_array()[l].to_bits(), (a[l] + b[l]).to_bits());
            assert_eq!(x.sub(y).to_array()[l].to_bits(), (a[l] - b[l]).to_bits());
            assert_eq!(x.mul(y).to_array()[l].to_bits(), (a[l] * b[l]).to_bits());
        }
        assert_eq!(F64x4::splat(-0.0).to_array(), [-0.0; 4]);
        let mut out = [0.0; 4];
        x.store(&mut out);
        assert_eq!(out, a);
        let mut two = [9.0; 2];
        F64x2::new([b[2], b[3]]).store(&mut two);
        assert_eq!(two, [b[2], b[3]]);
        assert_eq!(
            F64x2::splat(2.0).sub(F64x2::new([1.0, 3.0])).to_array(),
            [1.0, -1.0]
        );
        assert_eq!(
            F64x2::new([0.1, 1e-300]).mul(F64x2::splat(3.0)).to_array(),
            [0.1 * 3.0, 1e-300 * 3.0]
        );
    }

    #[test]
    fn the_kernel_source_is_self_contained() {
        let src = super::SOURCE;
        assert!(!src.contains("use ") && !src.contains("crate::") && !src.contains("super::"));
    }
}
