//! Compiled symbolic plugins for tests, through the plugin cache.

use railmbs_models::Model;
use railmbs_runtime::{Equations, Plugin, PluginEquations};
use std::collections::HashMap;
use std::path::PathBuf;
use std::sync::{Mutex, OnceLock};

/// The plugin cache of the tests: `RAILMBS_CACHE_DIR` if set (CI sets it, so
/// every test binary and every `umsim` the tests start share one cache and
/// no model is compiled twice), else `railmbs-plugins` in the target
/// directory's `tmp/` folder (found from the test executable,
/// `<target>/<profile>/deps/<test>`), away from the user's cache.
pub fn plugin_cache_dir() -> PathBuf {
    if let Some(dir) = std::env::var_os(railmbs_build_support::CACHE_DIR_ENV) {
        return PathBuf::from(dir);
    }
    let exe = std::env::current_exe().expect("the test executable's path");
    let target = exe
        .ancestors()
        .nth(3)
        .expect("a test executable under <target>/<profile>/deps");
    target.join("tmp").join("railmbs-plugins")
}

/// Builds (through [`plugin_cache_dir`]) and loads the symbolic plugin of
/// `model` with default generation options and default parameters; built
/// once per test process and model.
pub fn symbolic_engine(model: &Model) -> PluginEquations {
    static BUILT: OnceLock<Mutex<HashMap<String, PathBuf>>> = OnceLock::new();
    let path = {
        let mut map = BUILT
            .get_or_init(|| Mutex::new(HashMap::new()))
            .lock()
            .unwrap();
        map.entry(model.structural_hash())
            .or_insert_with(|| {
                let opts = railmbs_codegen::GenerateOptions::new();
                railmbs_codegen::build_plugin(model, &opts, Some(plugin_cache_dir()))
                    .unwrap_or_else(|e| panic!("{}: {e}", model.name))
                    .path
            })
            .clone()
    };
    let plugin = Plugin::load_for(&path, model).unwrap_or_else(|e| panic!("{e}"));
    let mut eq = PluginEquations::new(plugin);
    eq.set_parameters(&model.default_parameter_values())
        .unwrap_or_else(|e| panic!("{e}"));
    eq
}
