//! Choosing the equations-of-motion engine for a model.

use railmbs_codegen::{GenerateOptions, PluginFile};
use railmbs_models::{IntegratorSpec, Model};
use railmbs_runtime::{Equations, Formalism, NumericEquations, Plugin, PluginEquations};
use std::io::IsTerminal;
use std::path::{Path, PathBuf};

/// Which engine computes the equations of motion.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Engine {
    /// Recursive numeric-iterative evaluation, no code generation (composite
    /// bodies; for RK4 runs of open trees of 40 coordinates or more the
    /// articulated-body formalism, [`build_run_engine`]).
    Numeric,
    /// A compiled symbolic plugin (built through the cache when none is given).
    Symbolic,
    /// The numeric engine with the articulated-body formalism: q̈ in O(n)
    /// without the mass matrix, for open trees (no cut joints) integrated
    /// with RK4. Park's method and the analyses need M and its Jacobians:
    /// they refuse this engine (use `numeric`, the composite-body M).
    NumericAba,
}

impl Engine {
    /// Refuses [`Engine::NumericAba`] for `what` (a command or integrator
    /// that needs the mass matrix), saying why and what to use instead.
    pub fn require_mass_matrix(self, what: &str) -> Result<(), String> {
        if self == Engine::NumericAba {
            Err(format!(
                "--engine numeric-aba: {what} needs the mass matrix M (and its Jacobians), \
                 which the articulated-body method does not form; it serves explicit \
                 integration (RK4) only. Use --engine numeric (composite-body M)"
            ))
        } else {
            Ok(())
        }
    }
}

/// Generates and compiles (through the plugin cache) the plugin of `model`, for this
/// machine's CPU unless `portable` (see `GenerateOptions::portable`).
pub fn build_symbolic(
    model: &Model,
    portable: bool,
) -> Result<PluginFile, Box<dyn std::error::Error>> {
    let mut opts = GenerateOptions::new();
    opts.portable = portable;
    // On a terminal, say why the first run of a model waits (derivation and
    // rustc take seconds to minutes; later runs find the plugin cached).
    let terminal = std::io::stderr().is_terminal();
    if terminal {
        eprint!(
            "umsim: symbolic equations of model \"{}\": deriving, then compiling unless cached…",
            model.name
        );
    }
    let built = railmbs_codegen::find_or_build_plugin(model, &opts, None);
    if terminal {
        match &built {
            Ok(b) if b.cache_hit => eprintln!(" cached"),
            Ok(b) => eprintln!(
                " compiled in {:.1} s",
                b.compile_time.map_or(0.0, |d| d.as_secs_f64())
            ),
            Err(_) => eprintln!(),
        }
    }
    let built = built?;
    if let Some(damage) = &built.rebuilt_damaged {
        eprintln!("umsim: warning: rebuilt a damaged plugin cache entry: {damage}");
    }
    Ok(built)
}

/// Builds the engine for `model`. The symbolic engine loads `plugin` (checked
/// against the model) or builds the model's plugin through the cache.
pub fn build_engine(
    model: &Model,
    engine: Engine,
    plugin: Option<&Path>,
) -> Result<Box<dyn Equations>, Box<dyn std::error::Error>> {
    build_engine_with(model, engine, plugin, false)
}

/// [`build_engine`] for a run integrated by `integrator`: with
/// [`Engine::Numeric`] and RK4 the formalism is the faster one for the
/// model's size ([`Formalism::for_explicit_integration`]: articulated-body
/// q̈ for open trees of 40 coordinates or more); Park's method keeps the
/// composite-body M it needs. The run summary's engine line names the one
/// used (`numeric` or `numeric-aba`).
pub fn build_run_engine(
    model: &Model,
    engine: Engine,
    plugin: Option<&Path>,
    integrator: &IntegratorSpec,
) -> Result<Box<dyn Equations>, Box<dyn std::error::Error>> {
    match (engine, integrator) {
        (Engine::Numeric, IntegratorSpec::Rk4 { .. }) => Ok(Box::new(
            NumericEquations::with_formalism(model, Formalism::for_explicit_integration(model))?,
        )),
        _ => build_engine(model, engine, plugin),
    }
}

/// [`build_engine`], building a portable plugin if `portable` (and no `plugin` is given).
pub fn build_engine_with(
    model: &Model,
    engine: Engine,
    plugin: Option<&Path>,
    portable: bool,
) -> Result<Box<dyn Equations>, Box<dyn std::error::Error>> {
    match engine {
        Engine::Numeric => Ok(Box::new(NumericEquations::new(model))),
        Engine::NumericAba => Ok(Box::new(NumericEquations::with_formalism(
            model,
            Formalism::ArticulatedBody,
        )?)),
        Engine::Symbolic => {
            let path = match plugin {
                Some(p) => p.to_path_buf(),
                None => build_symbolic(model, portable)?.path,
            };
            let plugin = Plugin::load_for(&path, model)?;
            Ok(Box::new(PluginEquations::new(plugin)))
        }
    }
}

/// The engine and parameter options shared by the analysis commands
/// (`umsim equilibrium`, `modes`, `curving`), flattened into their clap
/// arguments.
#[derive(Debug, clap::Args)]
pub struct EngineOptions {
    /// Which equations of motion to use.
    #[arg(long, value_enum, default_value_t = Engine::Numeric)]
    pub engine: Engine,
    /// A compiled plugin of the scenario's model (implies `--engine symbolic`).
    #[arg(long)]
    pub plugin: Option<PathBuf>,
    /// Sets a model parameter, `NAME=VALUE` (as for `umsim run`); repeatable.
    #[arg(long = "set", value_name = "NAME=VALUE", value_parser = crate::run::parse_assignment)]
    pub set: Vec<(String, String)>,
}

impl EngineOptions {
    /// The scenario file `path` with the `--set` assignments applied, and
    /// its model.
    pub fn load(
        &self,
        path: &Path,
    ) -> Result<(railmbs_models::Scenario, Model), Box<dyn std::error::Error>> {
        let mut scenario = railmbs_models::load_scenario(path)?;
        for (name, value) in &self.set {
            scenario.set_parameter(name, value);
        }
        let model = railmbs_models::load_model(&scenario.model)?;
        Ok((scenario, model))
    }

    /// The engine of `model` as chosen (`--plugin` implies symbolic).
    pub fn build(&self, model: &Model) -> Result<Box<dyn Equations>, Box<dyn std::error::Error>> {
        let engine = if self.plugin.is_some() {
            Engine::Symbolic
        } else {
            self.engine
        };
        engine.require_mass_matrix("this analysis")?;
        build_engine(model, engine, self.plugin.as_deref())
    }
}
