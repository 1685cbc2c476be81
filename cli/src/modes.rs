//! `umsim modes SCENARIO [--speed FROM:TO:STEP] [-o CSV] [--engine …]
//! [--plugin FILE] [--set NAME=VALUE]…`: the linear modes of a scenario's
//! model at its steady state (eigenvalues, frequency, damping ratio, named
//! by their dominant coordinates; the CSV holds the normalized mode
//! shapes), or with `--speed` the root locus over speed (CSV: one row per
//! speed and mode) and the linear critical speed, where the least damped
//! lateral (hunting) mode's damping ratio crosses zero; `--plot FILE` draws
//! that mode's damping ratio and frequency against speed. `--sweep
//! NAME=FROM:TO:STEP` is the same over a model parameter at the scenario's
//! speed (a suspension stiffness); `--conicity FROM:TO:STEP` over the
//! equivalent conicity of the wheel–rail contacts (the classical
//! quasi-linear analysis), and with `--speed` the linear critical speed at
//! each conicity.

use crate::engine::EngineOptions;
use railmbs_runtime::analysis::modes::Mode;
use railmbs_runtime::analysis::speed::{
    CriticalAtConicity, SpeedModes, conicity_locus, critical_speed, critical_speed_over_conicity,
    parameter_locus, root_locus, scenario_modes,
};
use railmbs_runtime::forces::ContactTableCache;
use railmbs_runtime::run::RunError;
use std::fmt::Write as _;
use std::path::PathBuf;

/// Arguments of `umsim modes`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Scenario file (RON): model, track and speed; the steady state is
    /// found from its initial state (as `umsim equilibrium`).
    pub scenario: PathBuf,
    /// A root locus over running speeds `FROM:TO:STEP` (m/s) instead of the
    /// scenario's own speed.
    #[arg(long, value_name = "FROM:TO:STEP", value_parser = parse_speeds)]
    pub speed: Option<Speeds>,
    /// A locus over a model parameter, `NAME=FROM:TO:STEP` (the parameter's
    /// unit), at the scenario's own speed; the critical value where the
    /// least damped lateral mode's damping ratio crosses zero.
    #[arg(long, value_name = "NAME=FROM:TO:STEP", value_parser = parse_sweep, conflicts_with = "speed")]
    pub sweep: Option<(String, Speeds)>,
    /// The classical quasi-linear analysis: a locus over the equivalent
    /// conicity `FROM:TO:STEP` (–) of every wheel–rail contact (the
    /// profiles' geometry scaled in the lateral shift so that ½ dΔr/dy at
    /// the centre is λ; the contact angles' and the roll's slopes scaled
    /// alike), at the scenario's speed; with `--speed`, the linear critical
    /// speed at each conicity (a root locus per conicity).
    #[arg(long, value_name = "FROM:TO:STEP", value_parser = parse_conicities, conflicts_with = "sweep")]
    pub conicity: Option<Speeds>,
    /// CSV: the modes with their shapes, or with `--speed` the root locus.
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// With `--speed`, a plot (`.svg` or `.png`) of the least damped lateral
    /// mode's damping ratio and frequency against speed, the linear critical
    /// speed in the title (its data in a CSV beside it, `FILE.csv`).
    #[arg(long, value_name = "FILE")]
    pub plot: Option<PathBuf>,
    /// Engine and parameters.
    #[command(flatten)]
    pub engine: EngineOptions,
}

/// The running speeds of `--speed`, m/s.
#[derive(Debug, Clone, PartialEq)]
pub struct Speeds(pub Vec<f64>);

/// The speeds of `FROM:TO:STEP`, m/s: FROM, FROM + STEP, … up to TO
/// (included when it falls on the grid, to a millionth of a step).
pub(crate) fn parse_speeds(text: &str) -> Result<Speeds, String> {
    let parts: Vec<&str> = text.split(':').collect();
    let [from, to, step] = parts[..] else {
        return Err(format!("expected FROM:TO:STEP in m/s, got {text:?}"));
    };
    let number = |s: &str| {
        s.trim()
            .parse::<f64>()
            .ok()
            .filter(|x| x.is_finite())
            .ok_or_else(|| format!("{s:?} in {text:?} is not a finite number"))
    };
    let (from, to, step) = (number(from)?, number(to)?, number(step)?);
    railmbs_runtime::analysis::speed::speed_grid(from, to, step)
        .map(Speeds)
        .map_err(|e| format!("{text:?}: {e}"))
}

/// The conicities of `--conicity FROM:TO:STEP` (–, FROM > 0).
fn parse_conicities(text: &str) -> Result<Speeds, String> {
    let values =
        parse_speeds(text).map_err(|e| e.replace("(m/s)", "(–)").replace(" in m/s", ""))?;
    if values.0.first().is_some_and(|&x| x <= 0.0) {
        return Err(format!(
            "{text:?}: an equivalent conicity must be positive (FROM > 0)"
        ));
    }
    Ok(values)
}

/// `NAME=FROM:TO:STEP` of `--sweep` (FROM ≥ 0 as for speeds).
fn parse_sweep(text: &str) -> Result<(String, Speeds), String> {
    match text.split_once('=') {
        Some((name, range)) if !name.trim().is_empty() => {
            Ok((name.trim().to_string(), parse_speeds(range)?))
        }
        _ => Err(format!("expected NAME=FROM:TO:STEP, got {text:?}")),
    }
}

/// Runs `umsim modes`.
pub fn run(args: &Args) -> Result<(), Box<dyn std::error::Error>> {
    let (scenario, model) = args.engine.load(&args.scenario)?;
    // Built once (a plugin is compiled or loaded once), then one engine per speed.
    let mut make = {
        let model = model.clone();
        let mut first = Some(args.engine.build(&model)?);
        move || -> Result<Box<dyn railmbs_runtime::Equations>, RunError> {
            match first.take() {
                Some(e) => Ok(e),
                None => args
                    .engine
                    .build(&model)
                    .map_err(|e| RunError::Sim(railmbs_runtime::SimError::Other(e.to_string()))),
            }
        }
    };
    if let Some(p) = &args.plot {
        crate::plot::Format::of(p)?;
        if args.speed.is_none() && args.sweep.is_none() && args.conicity.is_none() {
            return Err("--plot needs --speed, --sweep or --conicity (a locus to plot)".into());
        }
    }
    if let Some(Speeds(conicities)) = &args.conicity {
        let start = std::time::Instant::now();
        let axis = Axis {
            label: "conicity[-]",
            values: conicities,
        };
        if let Some(Speeds(speeds)) = &args.speed {
            let table =
                critical_speed_over_conicity(&scenario, &model, conicities, speeds, &mut make)?;
            let total = start.elapsed().as_secs_f64();
            print!("{}", describe_critical_over(&table, speeds, total)?);
            if let Some(path) = &args.output {
                write_critical_over(path, &table)?;
                println!("critical speeds written to {}", path.display());
            }
            if let Some(plot) = &args.plot {
                plot_critical_over(plot, args.output.as_deref(), &table)?;
            }
            return Ok(());
        }
        let locus = conicity_locus(&scenario, &model, conicities, &mut make)?;
        let total = start.elapsed().as_secs_f64();
        print!("{}", describe_locus_over(&locus, &axis, total)?);
        if let Some(path) = &args.output {
            write_locus_over(path, &locus, &axis)?;
            println!("locus written to {}", path.display());
        }
        if let Some(plot) = &args.plot {
            plot_locus_over(plot, args.output.as_deref(), &locus, &axis)?;
        }
        return Ok(());
    }
    if let Some((name, Speeds(values))) = &args.sweep {
        let start = std::time::Instant::now();
        let locus = parameter_locus(&scenario, &model, name, values, &mut make)?;
        let total = start.elapsed().as_secs_f64();
        let axis = Axis {
            label: name,
            values,
        };
        print!("{}", describe_locus_over(&locus, &axis, total)?);
        if let Some(path) = &args.output {
            write_locus_over(path, &locus, &axis)?;
            println!("locus written to {}", path.display());
        }
        if let Some(plot) = &args.plot {
            plot_locus_over(plot, args.output.as_deref(), &locus, &axis)?;
        }
        return Ok(());
    }
    match &args.speed {
        None => {
            let start = std::time::Instant::now();
            let one = scenario_modes(&scenario, &model, make()?, &ContactTableCache::new())?;
            let total = start.elapsed().as_secs_f64();
            print!("{}", describe(&one, total)?);
            if let Some(path) = &args.output {
                write_shapes(path, &one)?;
                println!("modes and shapes written to {}", path.display());
            }
        }
        Some(Speeds(speeds)) => {
            let start = std::time::Instant::now();
            let locus = root_locus(&scenario, &model, speeds, &mut make)?;
            let total = start.elapsed().as_secs_f64();
            print!("{}", describe_locus(&locus, total)?);
            if let Some(path) = &args.output {
                write_locus(path, &locus)?;
                println!("root locus written to {}", path.display());
            }
            if let Some(plot) = &args.plot {
                plot_locus(plot, args.output.as_deref(), &locus)?;
            }
        }
    }
    Ok(())
}

/// One line of the modes table.
fn mode_line(s: &mut String, k: usize, m: &Mode) -> std::fmt::Result {
    writeln!(
        s,
        "{k:>4}  {:>9.4}  {:>9.4}  {:>9.4}  {:>11.4e}  {:>10.4}  {}",
        m.frequency, m.natural_frequency, m.damping_ratio, m.re, m.im, m.name
    )
}

/// The table of the modes at one speed.
pub fn describe(one: &SpeedModes, seconds: f64) -> Result<String, std::fmt::Error> {
    let mut s = String::new();
    let [eq, lin, eig] = one.seconds;
    writeln!(
        s,
        "modes at {} m/s: {} states ({} positions left out: nothing depends on them), {} modes \
         and {} zero eigenvalues ({}); \
         equilibrium {:.1} ms (with the set-up {:.1} ms), linearization {:.1} ms, \
         eigendecomposition {:.1} ms, total {:.1} ms",
        one.speed,
        one.linearization.a.nrows(),
        one.linearization.left_out.len(),
        one.modes.modes.len(),
        one.modes.zero_modes.len(),
        if one.modes.zero_modes.is_empty() {
            "none".to_string()
        } else {
            one.modes.zero_modes.join("; ")
        },
        1e3 * one.equilibrium.seconds,
        1e3 * eq,
        1e3 * lin,
        1e3 * eig,
        1e3 * seconds
    )?;
    writeln!(
        s,
        "\nmode  f [Hz]     fn [Hz]    zeta [-]   Re [1/s]     Im [rad/s]  dominant coordinates"
    )?;
    for (k, m) in one.modes.modes.iter().enumerate() {
        mode_line(&mut s, k + 1, m)?;
    }
    if let Some(m) = one.modes.least_damped_lateral() {
        writeln!(
            s,
            "\nleast damped lateral mode: {} at {:.4} Hz, damping ratio {:.4}",
            m.name, m.frequency, m.damping_ratio
        )?;
    }
    Ok(s)
}

/// The variable of a locus: its name (with unit) and its value per point.
pub struct Axis<'a> {
    /// `speed[m/s]`, or a parameter's name.
    pub label: &'a str,
    /// Its value at each point of the locus.
    pub values: &'a [f64],
}

/// The values where the least damped lateral mode's damping ratio crosses
/// zero first, interpolated linearly (the linear critical speed on a speed
/// axis).
fn critical_value(locus: &[SpeedModes], axis: &Axis) -> Option<f64> {
    let samples: Vec<(f64, f64)> = locus
        .iter()
        .zip(axis.values)
        .filter_map(|(one, &x)| {
            one.modes
                .least_damped_lateral()
                .map(|m| (x, m.damping_ratio))
        })
        .collect();
    railmbs_runtime::analysis::modes::zero_crossing(&samples)
}

/// The summary of a locus over a parameter: the least damped lateral mode
/// per value and the critical value.
pub fn describe_locus_over(
    locus: &[SpeedModes],
    axis: &Axis,
    seconds: f64,
) -> Result<String, std::fmt::Error> {
    let mut s = String::new();
    writeln!(
        s,
        "locus over {} at {} values in {:.2} s\n\n{:>11}  f [Hz]     zeta [-]   least damped lateral mode",
        axis.label,
        locus.len(),
        seconds,
        axis.label
    )?;
    lines(&mut s, locus, axis.values)?;
    match critical_value(locus, axis) {
        Some(x) => writeln!(
            s,
            "\nthe least damped lateral mode's damping ratio crosses zero at {} = {x:.6}",
            axis.label
        )?,
        None => writeln!(
            s,
            "\nthe least damped lateral mode's damping ratio does not cross zero in this range"
        )?,
    }
    Ok(s)
}

/// A line per point: the value and the least damped lateral mode.
fn lines(s: &mut String, locus: &[SpeedModes], values: &[f64]) -> std::fmt::Result {
    for (one, x) in locus.iter().zip(values) {
        match one.modes.least_damped_lateral() {
            Some(m) => writeln!(
                s,
                "{:>11.5}  {:>9.4}  {:>9.4}  {}",
                x, m.frequency, m.damping_ratio, m.name
            )?,
            None => writeln!(s, "{x:>11.5}  (no lateral mode)")?,
        }
    }
    Ok(())
}

/// The summary of a root locus: the least damped lateral mode per speed and
/// the critical speed.
pub fn describe_locus(locus: &[SpeedModes], seconds: f64) -> Result<String, std::fmt::Error> {
    let mut s = String::new();
    writeln!(
        s,
        "root locus at {} speeds in {:.2} s\n\nspeed [m/s]  f [Hz]     zeta [-]   least damped lateral mode",
        locus.len(),
        seconds
    )?;
    let speeds: Vec<f64> = locus.iter().map(|one| one.speed).collect();
    lines(&mut s, locus, &speeds)?;
    match critical_speed(locus) {
        Some(v) => writeln!(
            s,
            "\nlinear critical speed: {v:.3} m/s ({:.1} km/h)",
            3.6 * v
        )?,
        None => writeln!(
            s,
            "\nno linear critical speed in this range (the least damped lateral mode's damping \
             ratio does not cross zero)"
        )?,
    }
    Ok(s)
}

/// The linear critical speeds over the equivalent conicity: one line per
/// conicity.
pub fn describe_critical_over(
    table: &[CriticalAtConicity],
    speeds: &[f64],
    seconds: f64,
) -> Result<String, std::fmt::Error> {
    let mut s = String::new();
    let (from, to) = (
        speeds.first().unwrap_or(&0.0),
        speeds.last().unwrap_or(&0.0),
    );
    writeln!(
        s,
        "linear critical speed over the equivalent conicity: {} conicities × {} speeds \
         ({from} to {to} m/s) in {seconds:.2} s\n\nconicity[-]  critical speed [m/s]  [km/h]",
        table.len(),
        speeds.len(),
    )?;
    for (x, v, _) in table {
        match v {
            Some(v) => writeln!(s, "{x:>11.5}  {v:>20.3}  {:>6.1}", 3.6 * v)?,
            None => writeln!(s, "{x:>11.5}  {:>20}", "not in the range")?,
        }
    }
    Ok(s)
}

/// The critical speeds over the conicity as CSV: `conicity[-]`,
/// `critical_speed[m/s]` (empty where none is in the speed range).
fn write_critical_over(
    path: &std::path::Path,
    table: &[CriticalAtConicity],
) -> Result<(), Box<dyn std::error::Error>> {
    let mut w = csv::Writer::from_path(path).map_err(|e| csv_error(path, e))?;
    w.write_record(["conicity[-]", "critical_speed[m/s]"])
        .map_err(|e| csv_error(path, e))?;
    for (x, v, _) in table {
        w.write_record([
            format!("{x:?}"),
            v.map_or(String::new(), |v| format!("{v:?}")),
        ])
        .map_err(|e| csv_error(path, e))?;
    }
    w.flush().map_err(|e| csv_error(path, e))?;
    Ok(())
}

/// The plot of the critical speed against the conicity (`umsim plot` of a
/// CSV beside it, the conicities with a critical speed in the range).
fn plot_critical_over(
    plot: &std::path::Path,
    output: Option<&std::path::Path>,
    table: &[CriticalAtConicity],
) -> Result<(), Box<dyn std::error::Error>> {
    let csv = plot_data_path(plot, output)?;
    let found: Vec<CriticalAtConicity> = table
        .iter()
        .filter(|(_, v, _)| v.is_some())
        .map(|(x, v, _)| (*x, *v, Vec::new()))
        .collect();
    if found.is_empty() {
        return Err("--plot: no conicity has a linear critical speed in the speed range".into());
    }
    write_critical_over(&csv, &found)?;
    crate::plot::run(&crate::plot::Args {
        input: csv.clone(),
        y: vec!["critical_speed[m/s]".into()],
        x: "conicity[-]".into(),
        from: None,
        to: None,
        title: Some("linear critical speed against the equivalent conicity".into()),
        width: 1000,
        height: None,
        output: plot.to_path_buf(),
    })?;
    println!(
        "critical-speed plot written to {} (data {})",
        plot.display(),
        csv.display()
    );
    Ok(())
}

/// The CSV a plot's data is written to, beside the plot (its name with
/// `.csv`); an error if that is the `-o` file.
fn plot_data_path(
    plot: &std::path::Path,
    output: Option<&std::path::Path>,
) -> Result<std::path::PathBuf, String> {
    let csv = plot.with_extension("csv");
    if output == Some(csv.as_path()) {
        return Err(format!(
            "--plot {} would write its data over the -o file {}",
            plot.display(),
            csv.display()
        ));
    }
    Ok(csv)
}

fn csv_error(path: &std::path::Path, e: impl std::fmt::Display) -> String {
    format!("{}: {e}", path.display())
}

/// The modes at one speed with their normalized shapes: a row per mode,
/// `<coordinate>.re`/`.im` columns.
fn write_shapes(
    path: &std::path::Path,
    one: &SpeedModes,
) -> Result<(), Box<dyn std::error::Error>> {
    let mut w = csv::Writer::from_path(path).map_err(|e| csv_error(path, e))?;
    let mut header: Vec<String> = [
        "mode",
        "f[Hz]",
        "fn[Hz]",
        "zeta[-]",
        "Re[1/s]",
        "Im[rad/s]",
        "name",
    ]
    .iter()
    .map(|s| s.to_string())
    .collect();
    for c in &one.coordinates {
        header.push(format!("{}.re", c.name));
        header.push(format!("{}.im", c.name));
    }
    w.write_record(&header).map_err(|e| csv_error(path, e))?;
    for (k, m) in one.modes.modes.iter().enumerate() {
        let mut row = vec![
            (k + 1).to_string(),
            format!("{:?}", m.frequency),
            format!("{:?}", m.natural_frequency),
            format!("{:?}", m.damping_ratio),
            format!("{:?}", m.re),
            format!("{:?}", m.im),
            m.name.clone(),
        ];
        for (re, im) in &m.shape {
            row.push(format!("{re:?}"));
            row.push(format!("{im:?}"));
        }
        w.write_record(&row).map_err(|e| csv_error(path, e))?;
    }
    w.flush().map_err(|e| csv_error(path, e))?;
    Ok(())
}

/// The root locus: a row per speed and mode.
fn write_locus(
    path: &std::path::Path,
    locus: &[SpeedModes],
) -> Result<(), Box<dyn std::error::Error>> {
    let speeds: Vec<f64> = locus.iter().map(|one| one.speed).collect();
    write_locus_over(
        path,
        locus,
        &Axis {
            label: "speed[m/s]",
            values: &speeds,
        },
    )
}

/// A locus: a row per point and mode, the first column the axis.
fn write_locus_over(
    path: &std::path::Path,
    locus: &[SpeedModes],
    axis: &Axis,
) -> Result<(), Box<dyn std::error::Error>> {
    let mut w = csv::Writer::from_path(path).map_err(|e| csv_error(path, e))?;
    w.write_record([
        axis.label,
        "mode",
        "f[Hz]",
        "fn[Hz]",
        "zeta[-]",
        "Re[1/s]",
        "Im[rad/s]",
        "lateral",
        "name",
    ])
    .map_err(|e| csv_error(path, e))?;
    for (one, x) in locus.iter().zip(axis.values) {
        for (k, m) in one.modes.modes.iter().enumerate() {
            w.write_record([
                format!("{x:?}"),
                (k + 1).to_string(),
                format!("{:?}", m.frequency),
                format!("{:?}", m.natural_frequency),
                format!("{:?}", m.damping_ratio),
                format!("{:?}", m.re),
                format!("{:?}", m.im),
                u8::from(m.is_lateral()).to_string(),
                m.name.clone(),
            ])
            .map_err(|e| csv_error(path, e))?;
        }
    }
    w.flush().map_err(|e| csv_error(path, e))?;
    Ok(())
}

/// The root-locus plot: the least damped lateral mode's damping ratio and
/// frequency against speed (`umsim plot` of a CSV beside the plot, one row
/// per speed), the linear critical speed in the title.
fn plot_locus(
    plot: &std::path::Path,
    output: Option<&std::path::Path>,
    locus: &[SpeedModes],
) -> Result<(), Box<dyn std::error::Error>> {
    let speeds: Vec<f64> = locus.iter().map(|one| one.speed).collect();
    let axis = Axis {
        label: "speed[m/s]",
        values: &speeds,
    };
    plot_locus_over(plot, output, locus, &axis)
}

/// [`plot_locus`] over any axis.
fn plot_locus_over(
    plot: &std::path::Path,
    output: Option<&std::path::Path>,
    locus: &[SpeedModes],
    axis: &Axis,
) -> Result<(), Box<dyn std::error::Error>> {
    let csv = plot_data_path(plot, output)?;
    let mut w = csv::Writer::from_path(&csv).map_err(|e| csv_error(&csv, e))?;
    w.write_record([axis.label, "zeta[-]", "f[Hz]"])
        .map_err(|e| csv_error(&csv, e))?;
    for (one, x) in locus.iter().zip(axis.values) {
        if let Some(m) = one.modes.least_damped_lateral() {
            w.write_record([
                format!("{x:?}"),
                format!("{:?}", m.damping_ratio),
                format!("{:?}", m.frequency),
            ])
            .map_err(|e| csv_error(&csv, e))?;
        }
    }
    w.flush().map_err(|e| csv_error(&csv, e))?;
    let title = match critical_value(locus, axis) {
        Some(v) if axis.label == "speed[m/s]" => format!(
            "least damped lateral mode; linear critical speed {v:.2} m/s ({:.1} km/h): zeta = 0",
            3.6 * v
        ),
        Some(v) => format!(
            "least damped lateral mode; zeta = 0 at {} = {v:.5}",
            axis.label
        ),
        None => "least damped lateral mode; its damping ratio does not cross zero here".into(),
    };
    crate::plot::run(&crate::plot::Args {
        input: csv.clone(),
        y: vec!["zeta[-]".into(), "f[Hz]".into()],
        x: axis.label.into(),
        from: None,
        to: None,
        title: Some(title),
        width: 1000,
        height: None,
        output: plot.to_path_buf(),
    })?;
    println!(
        "root-locus plot written to {} (data {})",
        plot.display(),
        csv.display()
    );
    Ok(())
}
