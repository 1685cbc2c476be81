//! Compiled symbolic plugins: the loader that wraps a plugin as an [`Equations`] engine.
//!
//! The interface itself (the `#[repr(C)]` structs, the exported functions' signatures, the
//! ABI version and the CPU features a plugin reports) is defined once, in the crate
//! `railmbs-plugin-abi` (re-exported here as [`abi`]); the code generator pastes the same
//! definition into every plugin. The loader checks the ABI version, the model's
//! structural hash and the counts, and refuses a plugin built from another model. A loaded
//! library is never unloaded (unloading Rust cdylibs is unsound): it lives for the rest of
//! the process.

use crate::equations::{BodyKinematics, Equations, Evaluation, Parts};
use crate::system::SimError;
use nalgebra::{Matrix3, Vector3};
use railmbs_models::Model;
pub use railmbs_plugin_abi as abi;
pub use railmbs_plugin_abi::{ABI_VERSION, Inputs, Outputs, PluginInfo};
use railmbs_plugin_abi::{
    EVALUATE_SYMBOL, EvaluateFn, INFO_SYMBOL, InfoFn, PART_CONSTRAINTS, PART_DYNAMICS,
    PART_KINEMATICS, TARGET_FEATURES_SYMBOL, TargetFeaturesFn,
};
use std::ffi::CStr;
use std::os::raw::c_char;
use std::path::{Path, PathBuf};

/// Why a plugin cannot be used.
#[derive(Debug, thiserror::Error)]
pub enum PluginError {
    /// The file is not a shared library the system can load.
    #[error("{path}: not a loadable library: {reason}")]
    NotALibrary {
        /// The file.
        path: PathBuf,
        /// The system loader's message.
        reason: String,
    },
    /// A library without one of the interface's functions.
    #[error("{path}: not a railmbs plugin (missing symbol `{symbol}`)")]
    MissingSymbol {
        /// The library.
        path: PathBuf,
        /// The function it lacks.
        symbol: String,
    },
    #[error(
        "{path}: plugin ABI version {found}, this umsim needs {expected}; regenerate it with `umgen`"
    )]
    /// A plugin of another version of the interface.
    AbiVersion {
        /// The plugin.
        path: PathBuf,
        /// Its ABI version.
        found: u32,
        /// This loader's ([`ABI_VERSION`]).
        expected: u32,
    },
    #[error(
        "{path}: plugin was built from another model (plugin: \"{plugin_model}\", hash {plugin_hash}; \
         model file: \"{model}\", hash {model_hash}); regenerate it with `umgen`"
    )]
    /// A plugin built from another model (structural hash or counts differ).
    ModelMismatch {
        /// The plugin.
        path: PathBuf,
        /// Name of the model it was built from.
        plugin_model: String,
        /// Structural hash of that model.
        plugin_hash: String,
        /// Name of the model it was loaded for.
        model: String,
        /// Structural hash of that model.
        model_hash: String,
    },
    #[error(
        "{path}: plugin was compiled for CPU features this machine lacks ({}); rebuild it on \
         this machine with `umgen`, or build plugins for several machines with `umgen --portable`",
        missing.join(", ")
    )]
    /// A plugin compiled for CPU features this machine lacks (or the loader cannot confirm).
    CpuFeatures {
        /// The plugin.
        path: PathBuf,
        /// The features.
        missing: Vec<String>,
    },
}

/// Whether this CPU has the target feature `name` (rustc's name, e.g. `avx2`): `None` if
/// the loader cannot tell (a name outside the interface's list [`abi::TARGET_FEATURES`],
/// or not an x86-64 machine). Every feature a plugin may report is in that list, the one
/// from which plugins build their report, so a plugin of this ABI never names one the
/// loader cannot check.
pub fn host_has_target_feature(name: &str) -> Option<bool> {
    #[cfg(target_arch = "x86_64")]
    {
        macro_rules! detect {
            ($($f:tt),*) => {
                match name {
                    $($f => Some(std::arch::is_x86_feature_detected!($f)),)*
                    _ => None,
                }
            };
        }
        railmbs_plugin_abi::with_target_features!(detect)
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        let _ = name;
        None
    }
}

/// A symbol's name without its NUL.
fn symbol_name(symbol: &[u8]) -> String {
    String::from_utf8_lossy(symbol.strip_suffix(b"\0").unwrap_or(symbol)).into_owned()
}

fn c_str(p: *const c_char) -> String {
    if p.is_null() {
        return String::new();
    }
    // SAFETY: plugins export NUL-terminated static strings.
    unsafe { CStr::from_ptr(p) }.to_string_lossy().into_owned()
}

/// A NUL-separated list ending with an empty entry.
fn c_str_list(p: *const c_char, count: usize) -> Vec<String> {
    let mut out = Vec::with_capacity(count);
    let mut cur = p;
    for _ in 0..count {
        if cur.is_null() {
            break;
        }
        // SAFETY: the plugin's list holds `count` NUL-terminated names.
        let s = unsafe { CStr::from_ptr(cur) };
        let len = s.to_bytes().len();
        out.push(s.to_string_lossy().into_owned());
        // SAFETY: stays within the list (each name is followed by its NUL).
        cur = unsafe { cur.add(len + 1) };
    }
    out
}

/// A loaded plugin (the library stays loaded for the life of the process).
#[derive(Debug, Clone)]
pub struct Plugin {
    path: PathBuf,
    evaluate: EvaluateFn,
    /// The CPU features the library was compiled with (`railmbs_target_features`).
    pub target_features: Vec<String>,
    /// Generalized coordinates n.
    pub dof: usize,
    /// Bodies (ground excluded).
    pub bodies: usize,
    /// Scalar constraint equations.
    pub constraints: usize,
    /// Parameters (fixed ones included).
    pub parameters: usize,
    /// Runtime inputs (3 numbers each: value, rate, acceleration).
    pub inputs: usize,
    /// Name of the model the plugin was built from.
    pub model_name: String,
    /// Structural hash of that model.
    pub model_hash: String,
    /// Its coordinate names, in order.
    pub coordinate_names: Vec<String>,
    /// Its parameter names, in order.
    pub parameter_names: Vec<String>,
    /// (parameter index, value) fixed at generation time.
    pub fixed: Vec<(usize, f64)>,
}

/// `e` and its sources, joined by `: ` (libloading's own message is only
/// "dlopen failed"; the system loader's reason is its source).
fn error_chain(e: &dyn std::error::Error) -> String {
    let mut text = e.to_string();
    let mut source = e.source();
    while let Some(s) = source {
        text.push_str(": ");
        text.push_str(&s.to_string());
        source = s.source();
    }
    text
}

/// Checks that `path` is a readable, complete object file before the system
/// loader maps it: mapping a truncated library crashes the process with
/// SIGBUS when a page past the end of the file is touched.
fn check_library_file(path: &Path) -> Result<(), PluginError> {
    let not_a_library = |reason: String| PluginError::NotALibrary {
        path: path.to_path_buf(),
        reason,
    };
    // Only the headers are read (ReadCache reads the ranges parsing asks
    // for), not the whole library.
    let file = std::fs::File::open(path).map_err(|e| not_a_library(e.to_string()))?;
    let len = file
        .metadata()
        .map_err(|e| not_a_library(e.to_string()))?
        .len();
    check_object_headers(&object::ReadCache::new(file), len).map_err(not_a_library)
}

/// The check of [`Plugin::open`] before the system loader maps a file, on
/// the file's bytes in memory: `Err` with the reason unless `bytes` is an
/// object file whose every segment lies inside it.
pub fn check_library_bytes(bytes: &[u8]) -> Result<(), String> {
    check_object_headers(bytes, bytes.len() as u64)
}

/// The object file in `data` (`len` bytes) parses and its segments end
/// within it.
fn check_object_headers<'a, R: object::ReadRef<'a>>(data: R, len: u64) -> Result<(), String> {
    use object::{Object, ObjectSegment};
    let parsed = object::File::parse(data)
        .map_err(|e| format!("not an object file the loader can map ({e})"))?;
    for segment in parsed.segments() {
        let (offset, size) = segment.file_range();
        let end = offset.saturating_add(size);
        if end > len {
            return Err(format!(
                "truncated: a segment ends at byte {end}, the file has {len} bytes"
            ));
        }
    }
    Ok(())
}

impl Plugin {
    /// Loads the library at `path` and reads its description (no model check).
    /// A bare file name (`chain10.so`) is a file in the working directory, as
    /// for any other file argument (the system loader would search its
    /// library path instead).
    pub fn open(path: &Path) -> Result<Self, PluginError> {
        let relative_name = path.parent().is_some_and(|p| p.as_os_str().is_empty());
        let path = &if relative_name {
            Path::new(".").join(path)
        } else {
            path.to_path_buf()
        };
        check_library_file(path)?;
        // SAFETY: loading runs the library's initializers; railmbs plugins have
        // none beyond the Rust runtime's. Any library can be named here, which is
        // why the file was checked to be a whole object file and the symbols and
        // versions are checked before use.
        let lib =
            unsafe { libloading::Library::new(path) }.map_err(|e| PluginError::NotALibrary {
                path: path.to_path_buf(),
                reason: error_chain(&e),
            })?;
        let lib: &'static libloading::Library = Box::leak(Box::new(lib));
        let missing = |symbol: &[u8]| PluginError::MissingSymbol {
            path: path.to_path_buf(),
            symbol: symbol_name(symbol),
        };
        // The CPU check comes first: `railmbs_target_features` only returns a
        // pointer, every other function may use the features it lists. A library
        // without it is from ABI 1 (built without native features): its version
        // check below says so.
        let mut target_features: Option<Vec<String>> = None;
        // SAFETY: the signature is that of the ABI; the function reads nothing.
        if let Ok(features) = unsafe { lib.get::<TargetFeaturesFn>(TARGET_FEATURES_SYMBOL) } {
            // SAFETY: a NUL-terminated static string of the plugin.
            let list: Vec<String> = c_str(unsafe { features() })
                .split(',')
                .map(str::trim)
                .filter(|f| !f.is_empty())
                .map(str::to_owned)
                .collect();
            // The ones this CPU lacks or the loader cannot confirm.
            let missing: Vec<String> = list
                .iter()
                .filter(|f| host_has_target_feature(f) != Some(true))
                .cloned()
                .collect();
            target_features = Some(list);
            if !missing.is_empty() {
                return Err(PluginError::CpuFeatures {
                    path: path.to_path_buf(),
                    missing,
                });
            }
        }
        // SAFETY: the signatures are those of the ABI; checked by version below
        // before `evaluate` is ever called.
        let info_fn: InfoFn = unsafe { lib.get::<InfoFn>(INFO_SYMBOL) }
            .map(|s| *s)
            .map_err(|_| missing(INFO_SYMBOL))?;
        let evaluate: EvaluateFn = unsafe { lib.get::<EvaluateFn>(EVALUATE_SYMBOL) }
            .map(|s| *s)
            .map_err(|_| missing(EVALUATE_SYMBOL))?;
        // Read the version first through a struct prefix every ABI version shares.
        let mut info = std::mem::MaybeUninit::<PluginInfo>::zeroed();
        // SAFETY: `info` is a writable PluginInfo-sized buffer.
        unsafe { info_fn(info.as_mut_ptr()) };
        // SAFETY: zero-initialized and filled by the plugin.
        let info = unsafe { info.assume_init() };
        if info.abi_version != ABI_VERSION {
            return Err(PluginError::AbiVersion {
                path: path.to_path_buf(),
                found: info.abi_version,
                expected: ABI_VERSION,
            });
        }
        let Some(target_features) = target_features else {
            return Err(missing(TARGET_FEATURES_SYMBOL));
        };
        let fixed = (0..info.fixed_count as usize)
            .map(|k| {
                // SAFETY: arrays of `fixed_count` entries exported by the plugin.
                unsafe {
                    (
                        *info.fixed_indices.add(k) as usize,
                        *info.fixed_values.add(k),
                    )
                }
            })
            .collect();
        Ok(Self {
            path: path.to_path_buf(),
            evaluate,
            target_features,
            dof: info.dof as usize,
            bodies: info.bodies as usize,
            constraints: info.constraints as usize,
            parameters: info.parameters as usize,
            inputs: info.inputs as usize,
            model_name: c_str(info.model_name),
            model_hash: c_str(info.model_hash),
            coordinate_names: c_str_list(info.coordinate_names, info.dof as usize),
            parameter_names: c_str_list(info.parameter_names, info.parameters as usize),
            fixed,
        })
    }

    /// Loads the plugin and checks that it was built from `model`.
    pub fn load_for(path: &Path, model: &Model) -> Result<Self, PluginError> {
        let p = Self::open(path)?;
        let hash = model.structural_hash();
        if p.model_hash != hash
            || p.dof != model.coordinates.len()
            || p.bodies != model.bodies.len()
            || p.parameters != model.parameters.len()
            || p.inputs != 6 * model.track_frames.len()
        {
            return Err(PluginError::ModelMismatch {
                path: path.to_path_buf(),
                plugin_model: p.model_name,
                plugin_hash: p.model_hash,
                model: model.name.clone(),
                model_hash: hash,
            });
        }
        Ok(p)
    }

    /// The library file.
    pub fn path(&self) -> &Path {
        &self.path
    }
}

/// A plugin as an [`Equations`] engine.
#[derive(Debug, Clone)]
pub struct PluginEquations {
    plugin: Plugin,
    params: Vec<f64>,
    parameters_set: bool,
    kinematics: Vec<f64>,
    inputs: Vec<f64>,
}

impl PluginEquations {
    /// Wraps a loaded plugin.
    pub fn new(plugin: Plugin) -> Self {
        let nb = plugin.bodies;
        let ni = plugin.inputs;
        Self {
            params: vec![0.0; plugin.parameters],
            plugin,
            parameters_set: false,
            kinematics: vec![0.0; 18 * nb],
            inputs: vec![0.0; 3 * ni],
        }
    }

    /// The plugin.
    pub fn plugin(&self) -> &Plugin {
        &self.plugin
    }
}

impl Equations for PluginEquations {
    fn engine_name(&self) -> &str {
        "symbolic"
    }
    fn dof(&self) -> usize {
        self.plugin.dof
    }
    fn body_count(&self) -> usize {
        self.plugin.bodies
    }
    fn constraint_count(&self) -> usize {
        self.plugin.constraints
    }
    fn parameter_count(&self) -> usize {
        self.plugin.parameters
    }
    fn input_count(&self) -> usize {
        self.plugin.inputs
    }

    fn set_inputs(&mut self, u: &[f64]) -> Result<(), SimError> {
        if u.len() != self.inputs.len() {
            return Err(SimError::Other(format!(
                "plugin {} takes {} input values (3 per input), got {}",
                self.plugin.path.display(),
                self.inputs.len(),
                u.len()
            )));
        }
        self.inputs.copy_from_slice(u);
        Ok(())
    }

    fn set_parameters(&mut self, params: &[f64]) -> Result<(), SimError> {
        if params.len() != self.plugin.parameters {
            return Err(SimError::Other(format!(
                "plugin {} takes {} parameters, got {}",
                self.plugin.path.display(),
                self.plugin.parameters,
                params.len()
            )));
        }
        for &(i, value) in &self.plugin.fixed {
            if params[i] != value {
                let name = self
                    .plugin
                    .parameter_names
                    .get(i)
                    .cloned()
                    .unwrap_or_default();
                return Err(SimError::Other(format!(
                    "parameter \"{name}\" was fixed at {value} when the plugin {} was generated, \
                     but the run asks for {}; regenerate without `--fixed {name}`",
                    self.plugin.path.display(),
                    params[i]
                )));
            }
        }
        self.params.copy_from_slice(params);
        self.parameters_set = true;
        Ok(())
    }

    fn evaluate(
        &mut self,
        t: f64,
        q: &[f64],
        v: &[f64],
        parts: Parts,
        out: &mut Evaluation,
    ) -> Result<(), SimError> {
        let n = self.plugin.dof;
        if !self.parameters_set {
            return Err(SimError::Other(
                "plugin evaluated before its parameters were set".into(),
            ));
        }
        if q.len() != n || v.len() != n {
            return Err(SimError::Other(format!(
                "state has {} coordinates and {} velocities, the plugin has {n}",
                q.len(),
                v.len()
            )));
        }
        let mut bits = 0;
        if parts.mass || parts.bias || parts.gravity {
            bits |= PART_DYNAMICS;
        }
        if parts.kinematics || parts.jacobians {
            bits |= PART_KINEMATICS;
        }
        if parts.constraints && self.plugin.constraints > 0 {
            bits |= PART_CONSTRAINTS;
        }
        let inputs = Inputs {
            t,
            q: q.as_ptr(),
            v: v.as_ptr(),
            p: self.params.as_ptr(),
            u: if self.inputs.is_empty() {
                std::ptr::null()
            } else {
                self.inputs.as_ptr()
            },
        };
        let outputs = Outputs {
            mass: out.mass.as_mut_slice().as_mut_ptr(),
            bias: out.bias.as_mut_slice().as_mut_ptr(),
            gravity: out.gravity.as_mut_slice().as_mut_ptr(),
            kinematics: self.kinematics.as_mut_ptr(),
            jacobians: out.jacobians.as_mut_slice().as_mut_ptr(),
            constraints: out.constraints.as_mut_slice().as_mut_ptr(),
            constraint_jacobian: out.constraint_jacobian.as_mut_slice().as_mut_ptr(),
        };
        // SAFETY: buffers are sized by `Evaluation::for_equations` from this
        // plugin's counts (checked against the model when loaded), as the ABI
        // requires; the plugin only writes within them.
        let status = unsafe { (self.plugin.evaluate)(&inputs, bits, &outputs) };
        if status != 0 {
            return Err(SimError::Other(format!(
                "plugin {} refused the evaluation (status {status})",
                self.plugin.path.display()
            )));
        }
        if bits & PART_KINEMATICS != 0 {
            for (j, b) in out.bodies.iter_mut().enumerate() {
                let k = &self.kinematics[18 * j..18 * j + 18];
                *b = BodyKinematics {
                    position: Vector3::new(k[0], k[1], k[2]),
                    rotation: Matrix3::from_column_slice(&k[3..12]),
                    velocity: Vector3::new(k[12], k[13], k[14]),
                    angular_velocity: Vector3::new(k[15], k[16], k[17]),
                };
            }
        }
        Ok(())
    }
}
