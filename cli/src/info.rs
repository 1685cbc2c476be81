//! `umsim info FILE`: what a model (or the model of a scenario) offers to a
//! run: its parameters with their defaults and descriptions, macros,
//! coordinates, bodies, force elements and every output column they write.

use railmbs_models::{Model, load_model, top_constructor};
use std::fmt::Write as _;
use std::path::PathBuf;

/// Arguments of `umsim info`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// A model file, or a scenario file (its model is described, with the
    /// scenario's parameter values).
    pub file: PathBuf,
}

/// Runs `umsim info`.
pub fn run(args: &Args) -> Result<(), Box<dyn std::error::Error>> {
    let text =
        std::fs::read_to_string(&args.file).map_err(|e| format!("{}: {e}", args.file.display()))?;
    let (model, params, scenario) = match top_constructor(&text) {
        Some("Model") => {
            let model = load_model(&args.file)?;
            let params = model.default_parameter_values();
            (model, params, None)
        }
        Some("Scenario") => {
            let scenario = railmbs_models::load_scenario(&args.file)?;
            let model = load_model(&scenario.model)?;
            let params = scenario.parameter_values(&model)?;
            (model, params, Some(scenario))
        }
        Some("Train") => {
            return Err(format!(
                "{}: a train file; give one of its vehicles' model files",
                args.file.display()
            )
            .into());
        }
        other => {
            return Err(format!(
                "{}: expected a Model(...) or Scenario(...) file, found {}",
                args.file.display(),
                other.map_or("no constructor".to_string(), |c| format!("{c}(...)"))
            )
            .into());
        }
    };
    print!("{}", describe(&model, &params, scenario.as_ref())?);
    Ok(())
}

/// The description `umsim info` prints, at parameter values `params`.
pub fn describe(
    model: &Model,
    params: &[f64],
    scenario: Option<&railmbs_models::Scenario>,
) -> Result<String, Box<dyn std::error::Error>> {
    let mut s = String::new();
    let source = model
        .source
        .as_ref()
        .map_or(String::new(), |p| format!(" ({})", p.display()));
    writeln!(
        s,
        "model \"{}\"{source}: {} bodies, {} coordinates, {} cut joints, {} force elements",
        model.name,
        model.bodies.len(),
        model.coordinates.len(),
        model.cut_joints.len(),
        model.forces.len()
    )?;
    if let Some(sc) = scenario {
        writeln!(
            s,
            "scenario {}: end time {} s, output every {} s",
            sc.source.display(),
            sc.end_time,
            sc.output.interval
        )?;
    }
    let names = model.parameter_names();
    writeln!(
        s,
        "\nparameters ({}): name = value (default expression) [unit, from the description; \
         ? if none] description",
        names.len()
    )?;
    for (k, p) in model.parameters.iter().enumerate() {
        let default = p.default.display(&names);
        let value = params[k];
        let shown =
            if matches!(p.default, railmbs_models::Expr::Num(_)) || default == format!("{value}") {
                format!("{value}")
            } else {
                format!("{value} ({default})")
            };
        let doc = if p.doc.is_empty() {
            String::new()
        } else {
            format!("  {}", p.doc)
        };
        // The unit as the doc gives it (`Parameter::unit`): "-" for a doc
        // without one (dimensionless), "?" without a doc.
        let unit = p.unit().unwrap_or(if p.doc.is_empty() { "?" } else { "-" });
        writeln!(s, "  {} = {shown} [{unit}]{doc}", p.name)?;
    }
    if !model.macros.is_empty() {
        writeln!(s, "\nmacros ({}):", model.macros.len())?;
        for m in &model.macros {
            let sets: Vec<String> = m
                .assignments
                .iter()
                .map(|(k, e)| format!("{} = {}", names[*k], e.display(&names)))
                .collect();
            writeln!(s, "  {}: {}", m.name, sets.join(", "))?;
        }
    }
    writeln!(
        s,
        "\ncoordinates ({}): name (body)",
        model.coordinates.len()
    )?;
    for c in &model.coordinates {
        let body = model.bodies.get(c.body).map_or("?", |b| b.name.as_str());
        writeln!(s, "  {} ({body})", c.name)?;
    }
    writeln!(s, "\nbodies ({}): name, mass (kg)", model.bodies.len())?;
    for b in &model.bodies {
        writeln!(s, "  {}, {}", b.name, b.mass.eval(params, 0.0))?;
    }
    // The output columns each element writes, from the runtime elements
    // that write them (nothing is evaluated).
    let elements = railmbs_runtime::forces::build(model);
    writeln!(
        s,
        "\nforce elements ({}): name (kind): output columns, each `<name>.<column>`",
        model.forces.len()
    )?;
    for (f, element) in model.forces.iter().zip(&elements) {
        let columns = element.output_names();
        let columns = if columns.is_empty() {
            "none".to_string()
        } else {
            columns.join(", ")
        };
        writeln!(s, "  {} ({}): {columns}", f.name, f.kind.constructor())?;
    }
    Ok(s)
}
