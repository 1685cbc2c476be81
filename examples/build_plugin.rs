//! Build the symbolic plugin of a model and compare it with the numeric engine.
//!
//! `umgen` in process: the equations of motion of the three-link chain
//! (`models/mechanisms/chain3.ron`) are derived symbolically, emitted as Rust,
//! compiled into a `cdylib` through the content-hash cache (a second run is a
//! cache hit) and loaded; its mass matrix M and bias forces k at a random-ish
//! state must agree with the numeric-iterative engine's to rounding.
//!
//! ```sh
//! cargo run --release -p railmbs-examples --example build_plugin
//! ```

use railmbs_codegen::GenerateOptions;
use railmbs_runtime::{Equations, Evaluation, NumericEquations, Parts, Plugin, PluginEquations};
use std::error::Error;
use std::path::Path;

fn main() -> Result<(), Box<dyn Error>> {
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("../models/mechanisms/chain3.ron");
    let model = railmbs_models::load_model(&file)?;

    let built = railmbs_codegen::build_plugin(&model, &GenerateOptions::new(), None)?;
    println!(
        "plugin of \"{}\": {} ({})",
        model.name,
        built.path.display(),
        if built.cache_hit {
            "cache hit"
        } else {
            "compiled"
        }
    );
    let mut symbolic = PluginEquations::new(Plugin::load_for(&built.path, &model)?);
    let mut numeric = NumericEquations::new(&model);

    let params = model.parameter_values(&[], &[])?;
    let n = numeric.dof();
    let q: Vec<f64> = (0..n).map(|i| 0.3 + 0.7 * i as f64).collect();
    let v: Vec<f64> = (0..n).map(|i| 1.1 - 0.4 * i as f64).collect();
    let mut results = Vec::new();
    for engine in [&mut symbolic as &mut dyn Equations, &mut numeric] {
        engine.set_parameters(&params)?;
        let mut out = Evaluation::for_equations(engine);
        engine.evaluate(0.0, &q, &v, Parts::MASS_AND_BIAS, &mut out)?;
        results.push(out);
    }
    let (s, m) = (&results[0], &results[1]);
    let scale = m.mass.amax().max(m.bias.amax());
    let difference = (&s.mass - &m.mass).amax().max((&s.bias - &m.bias).amax());
    println!("M and k of the two engines differ by {difference:e} (scale {scale:e})");
    // Both evaluate the same recursions in a different order: rounding only.
    if difference > 1e-12 * scale {
        return Err(format!("engines disagree by {difference:e}").into());
    }
    Ok(())
}

#[test]
fn runs() {
    main().unwrap();
}
