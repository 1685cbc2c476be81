//! `umsim curving SCENARIO --radius R --cant H --speed V|FROM:TO:STEP
//! [-o CSV] [--engine …] [--plugin FILE] [--set NAME=VALUE]…`: the
//! quasi-static curving solution of the scenario's vehicle on a circular
//! curve (radius R m, positive left, negative right; cant H m) at constant
//! speed, solved directly as the steady state in the track-following frames
//! (`railmbs_runtime::analysis::curving`): every wheelset's lateral position
//! and angle of attack, wheel loads Q, lateral forces Y, ΣY, creep forces
//! and wear numbers. A speed range gives one table per speed; the CSV holds
//! one row per speed and wheelset with all the contact element's outputs.

use crate::engine::EngineOptions;
use crate::modes::{Speeds, parse_speeds};
use railmbs_runtime::analysis::curving::{Curve, Curving, curving_from};
use railmbs_runtime::forces::ContactTableCache;
use railmbs_runtime::run::RunError;
use std::fmt::Write as _;
use std::path::PathBuf;

/// Arguments of `umsim curving`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Scenario file (RON): the vehicle (its track is replaced by the curve;
    /// its initial state is the starting guess).
    pub scenario: PathBuf,
    /// Curve radius, m: positive for a left curve, negative for a right one.
    #[arg(long, value_name = "M", allow_hyphen_values = true)]
    pub radius: f64,
    /// Cant (outer rail above the inner), m.
    #[arg(long, value_name = "M", default_value_t = 0.0)]
    pub cant: f64,
    /// Running speed, m/s, or a sweep `FROM:TO:STEP`.
    #[arg(long, value_name = "M/S|FROM:TO:STEP", value_parser = parse_speed_or_sweep)]
    pub speed: Speeds,
    /// CSV: one row per speed and wheelset.
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Engine and parameters.
    #[command(flatten)]
    pub engine: EngineOptions,
}

/// One speed (m/s) or `FROM:TO:STEP`.
fn parse_speed_or_sweep(text: &str) -> Result<Speeds, String> {
    if text.contains(':') {
        return parse_speeds(text);
    }
    match text.trim().parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(Speeds(vec![v])),
        _ => Err(format!(
            "{text:?}: expected a speed > 0 in m/s or FROM:TO:STEP"
        )),
    }
}

/// Runs `umsim curving`.
pub fn run(args: &Args) -> Result<(), Box<dyn std::error::Error>> {
    let (scenario, model) = args.engine.load(&args.scenario)?;
    let tables = ContactTableCache::new();
    let mut make = || -> Result<Box<dyn railmbs_runtime::Equations>, RunError> {
        args.engine
            .build(&model)
            .map_err(|e| RunError::Sim(railmbs_runtime::SimError::Other(e.to_string())))
    };
    let mut results = Vec::new();
    for &speed in &args.speed.0 {
        let curve = Curve {
            radius: args.radius,
            cant: args.cant,
            speed,
        };
        // A sweep starts each speed from the one before.
        let one = curving_from(
            &scenario,
            &model,
            &mut make,
            &tables,
            &curve,
            results.last(),
        )?;
        print!("{}", describe(&one)?);
        results.push(one);
    }
    if let Some(path) = &args.output {
        write_csv(path, &results)?;
        println!("curving solution written to {}", path.display());
    }
    Ok(())
}

/// The tables `umsim curving` prints for one speed.
pub fn describe(c: &Curving) -> Result<String, std::fmt::Error> {
    let mut s = String::new();
    let eq = &c.equilibrium;
    writeln!(
        s,
        "curving: R = {} m ({}), cant {} m, {} m/s, uncompensated lateral acceleration \
         {:.3} m/s²; {} Newton iterations, residual {:.2e} (tolerance {:.1e}); solve {:.1} ms \
         (before it: set-up and any continuation {:.1} ms)",
        c.curve.radius.abs(),
        if c.curve.radius > 0.0 {
            "left"
        } else {
            "right"
        },
        c.curve.cant,
        c.curve.speed,
        c.curve.cant_deficiency_acceleration(),
        eq.iterations,
        eq.residual,
        eq.tolerance,
        1e3 * c.seconds[1],
        1e3 * c.seconds[0]
    )?;
    let width = c
        .wheelsets
        .iter()
        .map(|w| w.element.len())
        .max()
        .unwrap_or(8)
        .max(8);
    writeln!(
        s,
        "\n{:<width$}  {:>8}  {:>8}  {:>8}  {:>8}  {:>8}  {:>8}  {:>8}  {:>8}  {:>8}  {:>8}  \
         {:>8}  {:>8}  {:>8}",
        "wheelset",
        "y [mm]",
        "aoa[mrad]",
        "QL [kN]",
        "QR [kN]",
        "YL [kN]",
        "YR [kN]",
        "SumY[kN]",
        "FxL [kN]",
        "FxR [kN]",
        "FyL [kN]",
        "FyR [kN]",
        "TgL [N]",
        "TgR [N]"
    )?;
    for w in &c.wheelsets {
        let o = |name: &str, scale: f64| w.output(name).map_or(f64::NAN, |x| x * scale);
        writeln!(
            s,
            "{:<width$}  {:>8.3}  {:>8.3}  {:>8.3}  {:>8.3}  {:>8.3}  {:>8.3}  {:>8.3}  {:>8.3}  \
             {:>8.3}  {:>8.3}  {:>8.3}  {:>8.1}  {:>8.1}",
            w.element,
            w.lateral.map_or(f64::NAN, |y| 1e3 * y),
            w.yaw.map_or(f64::NAN, |y| 1e3 * y),
            o("L.Q [N]", 1e-3),
            o("R.Q [N]", 1e-3),
            o("L.Y [N]", 1e-3),
            o("R.Y [N]", 1e-3),
            o("SumY [N]", 1e-3),
            o("L.Fx [N]", 1e-3),
            o("R.Fx [N]", 1e-3),
            o("L.Fy [N]", 1e-3),
            o("R.Fy [N]", 1e-3),
            o("L.Tgamma [N]", 1.0),
            o("R.Tgamma [N]", 1.0),
        )?;
    }
    Ok(s)
}

/// The CSV: speed, wheelset, lateral position, angle of attack, then the
/// wheel–rail element's outputs (as a run's columns, without the element's
/// name).
fn write_csv(
    path: &std::path::Path,
    results: &[Curving],
) -> Result<(), Box<dyn std::error::Error>> {
    let mut w = csv::Writer::from_path(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let Some(first) = results.first().and_then(|c| c.wheelsets.first()) else {
        return Ok(());
    };
    let mut header = vec![
        "speed[m/s]".to_string(),
        "radius[m]".into(),
        "cant[m]".into(),
        "wheelset".into(),
        "y[m]".into(),
        "aoa[rad]".into(),
    ];
    header.extend(first.outputs.iter().map(|(n, _)| n.clone()));
    w.write_record(&header)?;
    for c in results {
        for ws in &c.wheelsets {
            let mut row = vec![
                format!("{:?}", c.curve.speed),
                format!("{:?}", c.curve.radius),
                format!("{:?}", c.curve.cant),
                ws.element.clone(),
                format!("{:?}", ws.lateral.unwrap_or(f64::NAN)),
                format!("{:?}", ws.yaw.unwrap_or(f64::NAN)),
            ];
            row.extend(ws.outputs.iter().map(|(_, x)| format!("{x:?}")));
            w.write_record(&row)?;
        }
    }
    w.flush()?;
    Ok(())
}
