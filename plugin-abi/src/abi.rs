// The plugin interface of railmbs (crate `railmbs-plugin-abi`, file `abi.rs`): compiled by
// the loader, pasted verbatim into every plugin by the code generator. Change it only here,
// and bump `ABI_VERSION` with any change of a struct, a signature or a meaning.

/// Version of the plugin interface. The loader refuses a plugin of any other version.
pub const ABI_VERSION: u32 = 2;

/// `parts` bit of `railmbs_evaluate`: the mass matrix M, the bias forces k and the
/// generalized gravity forces Q_g.
pub const PART_DYNAMICS: u32 = 1;
/// `parts` bit of `railmbs_evaluate`: the body kinematics and the Jacobians Γ.
pub const PART_KINEMATICS: u32 = 2;
/// `parts` bit of `railmbs_evaluate`: the constraints g and their Jacobian G.
pub const PART_CONSTRAINTS: u32 = 4;

/// Plugin description, filled by `railmbs_plugin_info`.
#[repr(C)]
#[derive(Debug)]
pub struct PluginInfo {
    /// [`ABI_VERSION`] of the plugin.
    pub abi_version: u32,
    /// Generalized coordinates n.
    pub dof: u32,
    /// Bodies nb (ground excluded).
    pub bodies: u32,
    /// Scalar constraint equations nc.
    pub constraints: u32,
    /// Parameters np (fixed ones included).
    pub parameters: u32,
    /// Runtime inputs (3 numbers each: value, rate, acceleration).
    pub inputs: u32,
    /// Structural hash of the model the plugin was built from (NUL-terminated).
    pub model_hash: *const core::ffi::c_char,
    /// Name of the model (NUL-terminated).
    pub model_name: *const core::ffi::c_char,
    /// The n coordinate names, each NUL-terminated, then an empty name.
    pub coordinate_names: *const core::ffi::c_char,
    /// The np parameter names, each NUL-terminated, then an empty name.
    pub parameter_names: *const core::ffi::c_char,
    /// Parameters fixed at generation time.
    pub fixed_count: u32,
    /// Their indices in the parameter vector (`fixed_count` entries).
    pub fixed_indices: *const u32,
    /// Their values (`fixed_count` entries); the host refuses others.
    pub fixed_values: *const f64,
}

/// Host-owned inputs of `railmbs_evaluate`.
#[repr(C)]
#[derive(Debug)]
pub struct Inputs {
    /// Time.
    pub t: f64,
    /// Coordinates q (n).
    pub q: *const f64,
    /// Velocities q̇ (n).
    pub v: *const f64,
    /// Parameters (np).
    pub p: *const f64,
    /// Runtime inputs (3 per input); null when there are none.
    pub u: *const f64,
}

/// Host-owned output buffers of `railmbs_evaluate` (column-major matrices; buffers of
/// parts not requested may be null).
#[repr(C)]
#[derive(Debug)]
pub struct Outputs {
    /// M, n×n, both triangles.
    pub mass: *mut f64,
    /// k, n.
    pub bias: *mut f64,
    /// Q_g, n.
    pub gravity: *mut f64,
    /// 18 per body: position (3), rotation matrix (9, column-major), velocity (3),
    /// angular velocity (3).
    pub kinematics: *mut f64,
    /// Stacked Γ, 6·nb × n.
    pub jacobians: *mut f64,
    /// g, nc.
    pub constraints: *mut f64,
    /// G = ∂g/∂q, nc × n.
    pub constraint_jacobian: *mut f64,
}

/// `railmbs_plugin_info`: fills the `PluginInfo` it is given (nothing for a null pointer).
pub type InfoFn = unsafe extern "C" fn(info: *mut PluginInfo);
/// `railmbs_target_features`: the NUL-terminated, comma-separated target features the
/// library was compiled with (its `COMPILED_TARGET_FEATURES`). Runs no vector instruction.
pub type TargetFeaturesFn = unsafe extern "C" fn() -> *const core::ffi::c_char;
/// `railmbs_evaluate`: writes the requested `parts` (`PART_*` bits); 0, or 1 for a null
/// pointer.
pub type EvaluateFn =
    unsafe extern "C" fn(inputs: *const Inputs, parts: u32, outputs: *const Outputs) -> i32;

/// Symbol of the [`InfoFn`] (NUL-terminated).
pub const INFO_SYMBOL: &[u8] = b"railmbs_plugin_info\0";
/// Symbol of the [`TargetFeaturesFn`] (NUL-terminated).
pub const TARGET_FEATURES_SYMBOL: &[u8] = b"railmbs_target_features\0";
/// Symbol of the [`EvaluateFn`] (NUL-terminated).
pub const EVALUATE_SYMBOL: &[u8] = b"railmbs_evaluate\0";

/// Calls `$callback!` with the x86 target features a plugin reports, as string literals
/// (macros such as `cfg!(target_feature = …)` and `is_x86_feature_detected!` need literals).
/// These are the features LLVM may use by itself in straight-line f64 code (vector widths,
/// FMA, bit manipulation).
#[macro_export]
macro_rules! with_target_features {
    ($callback:ident) => {
        $callback!(
            "sse3",
            "ssse3",
            "sse4.1",
            "sse4.2",
            "sse4a",
            "popcnt",
            "lzcnt",
            "bmi1",
            "bmi2",
            "movbe",
            "f16c",
            "fma",
            "avx",
            "avx2",
            "avx512f",
            "avx512dq",
            "avx512cd",
            "avx512bw",
            "avx512vl",
            "avx512ifma",
            "avx512vbmi",
            "avx512vbmi2",
            "avx512vnni",
            "avx512bitalg",
            "avx512vpopcntdq",
            "avx512bf16"
        )
    };
}

macro_rules! target_feature_names {
    ($($f:tt),*) => {
        [$($f),*]
    };
}

macro_rules! target_features_compiled {
    ($($f:tt),*) => {
        [$(cfg!(target_feature = $f)),*]
    };
}

/// The target features a plugin reports when compiled with them (`with_target_features!`).
pub const TARGET_FEATURES: [&str; 26] = with_target_features!(target_feature_names);

/// The features of [`TARGET_FEATURES`] this code was compiled with, as a NUL-terminated,
/// comma-separated list (possibly empty): what a plugin's `railmbs_target_features`
/// returns, built at compile time from `cfg!(target_feature)`.
pub static COMPILED_TARGET_FEATURES: [u8; TARGET_FEATURES_CAPACITY] = {
    const ENABLED: [bool; 26] = with_target_features!(target_features_compiled);
    let mut out = [0u8; TARGET_FEATURES_CAPACITY];
    let mut len = 0;
    let mut i = 0;
    while i < TARGET_FEATURES.len() {
        if ENABLED[i] {
            if len > 0 {
                out[len] = b',';
                len += 1;
            }
            let name = TARGET_FEATURES[i].as_bytes();
            let mut j = 0;
            while j < name.len() {
                out[len] = name[j];
                len += 1;
                j += 1;
            }
        }
        i += 1;
    }
    out
};

/// Bytes of every name of [`TARGET_FEATURES`] with its separator, and the NUL.
const TARGET_FEATURES_CAPACITY: usize = {
    let mut n = 1;
    let mut i = 0;
    while i < TARGET_FEATURES.len() {
        n += TARGET_FEATURES[i].len() + 1;
        i += 1;
    }
    n
};
