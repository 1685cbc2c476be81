//! Load a scenario, run it in process, read a column.
//!
//! `models/scenarios/pendulum.ron` swings a pendulum from 0.1 rad for 10 s.
//! The run writes its rows into an in-memory table (the columns `umsim run`
//! writes as CSV); the period is read off the angle's zero crossings and
//! compared with the pendulum's: T = 2π √(L/g) (1 + φ₀²/16 + …), L the
//! equivalent length (I + m l²)/(m l) of the sphere on its rod.
//!
//! ```sh
//! cargo run --release -p railmbs-examples --example run_scenario
//! ```

use railmbs_runtime::NumericEquations;
use railmbs_runtime::run::{Table, run_scenario_into};
use std::error::Error;
use std::path::Path;

fn main() -> Result<(), Box<dyn Error>> {
    let file = Path::new(env!("CARGO_MANIFEST_DIR")).join("../models/scenarios/pendulum.ron");
    // Loading reads and validates everything: errors name file, element, line and column.
    let scenario = railmbs_models::load_scenario(&file)?;
    let model = railmbs_models::load_model(&scenario.model)?;
    let engine = Box::new(NumericEquations::new(&model));

    let mut table = Table::new();
    let summary = run_scenario_into(&scenario, &model, engine, &mut table, |_t| {})?;
    if let Some(e) = summary.error {
        return Err(e.into());
    }
    let time = table.column("time").ok_or("no time column")?;
    let phi = table.column("phi").ok_or("no column phi")?;

    // Upward zero crossings of φ, linearly interpolated between rows.
    let crossings: Vec<f64> = (1..phi.len())
        .filter(|&k| phi[k - 1] < 0.0 && phi[k] >= 0.0)
        .map(|k| time[k - 1] + (time[k] - time[k - 1]) * phi[k - 1] / (phi[k - 1] - phi[k]))
        .collect();
    let periods = crossings.len() - 1;
    let period = (crossings[periods] - crossings[0]) / periods as f64;

    let (l, r, g, phi0) = (1.0_f64, 0.01_f64, 9.81_f64, 0.1_f64); // the model's defaults
    let length = l * (1.0 + 0.4 * (r / l).powi(2));
    let expected = 2.0 * std::f64::consts::PI * (length / g).sqrt() * (1.0 + phi0 * phi0 / 16.0);
    println!(
        "{}: {} rows, {} steps; period {period:.6} s over {periods} swings, pendulum theory {expected:.6} s",
        model.name,
        table.rows(),
        summary.steps
    );
    // The series' next term is (11/3072) φ₀⁴ ≈ 4e-7, interpolating the crossings
    // between rows 0.01 s apart errs by ~1e-6 s per crossing: 1e-5 is ample.
    let error = (period - expected).abs() / expected;
    if error > 1e-5 {
        return Err(format!("period off by {error:e} (relative)").into());
    }
    Ok(())
}

#[test]
fn runs() {
    main().unwrap();
}
