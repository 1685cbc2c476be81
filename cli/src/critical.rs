//! `umsim critical-speed SCENARIO [--bifurcation FROM:TO:STEP] [--signal
//! COORD]… [--window S] [--threshold M] [--track FILE] [-o CSV] [--plot
//! FILE.svg|png] [--end-time S] [--engine …] [--set NAME=VALUE]…`: the nonlinear critical
//! speed (`railmbs_runtime::analysis::critical`).
//!
//! Without `--bifurcation`, the scenario is a decelerating run (its
//! `speed_profile`) from a large disturbance; the command reports the
//! speed and position where the lateral limit cycle died out (`-o`: the
//! run's rows). With `--bifurcation`, one run at constant-speed plateaus
//! from FROM down to TO (the plateaus' speeds descending), each started
//! from the state the previous one ended in, and the limit-cycle amplitude
//! per plateau (`-o`: the diagram, a row per speed). `--plot` draws the
//! signals against the speed, or the diagram.

use crate::engine::EngineOptions;
use crate::modes::{Speeds, parse_speeds};
use railmbs_runtime::analysis::critical::{
    BranchPoint, Detection, DetectionSettings, Staircase, bifurcation, decelerating_run,
    wheelset_lateral_coordinates,
};
use railmbs_runtime::run::{Discard, OutputSink, output_sink, scenario::scenario_system};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Arguments of `umsim critical-speed`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Scenario file (RON) on a track: a decelerating run (`speed_profile`)
    /// from a large lateral disturbance, or with `--bifurcation` the
    /// starting state of the continuation.
    pub scenario: PathBuf,
    /// A bifurcation diagram at plateau speeds `FROM:TO:STEP` (m/s), run
    /// from TO down to FROM.
    #[arg(long, value_name = "FROM:TO:STEP", value_parser = parse_speeds)]
    pub bifurcation: Option<Speeds>,
    /// Coordinate whose limit cycle is detected; repeatable [default: the
    /// lateral coordinates of the wheelsets on wheel–rail elements].
    #[arg(long = "signal", value_name = "COORDINATE")]
    pub signals: Vec<String>,
    /// Length of the amplitude's sliding window, s (longer than a hunting period).
    #[arg(long, default_value_t = 1.0)]
    pub window: f64,
    /// Amplitude below which the limit cycle has died out, in the signal's
    /// unit (m).
    #[arg(long, default_value_t = 1e-3)]
    pub threshold: f64,
    /// Amplitude from which a limit cycle is established, m: flange hunting
    /// reaches the flangeway clearance (about 6.5 mm for S1002 wheels on
    /// UIC60 rails), residual oscillations on the tread stay below.
    #[arg(long, default_value_t = 4e-3)]
    pub on: f64,
    /// The limit cycle has also died out when its amplitude falls below
    /// this fraction of the largest it had (0 for none).
    #[arg(long, default_value_t = 0.5)]
    pub relative: f64,
    /// Length of each plateau of `--bifurcation`, s (the first is twice as long).
    #[arg(long, default_value_t = 6.0)]
    pub hold: f64,
    /// Length of the ramp between plateaus, s.
    #[arg(long, default_value_t = 0.5)]
    pub ramp: f64,
    /// The end of each plateau over which the amplitude is measured, s
    /// [default: half a plateau].
    #[arg(long)]
    pub measure: Option<f64>,
    /// Runs the decelerating run to this end time instead of the
    /// scenario's, s (for a scenario bundled short, as the freight car's
    /// hunting run; ignored with `--bifurcation`, whose plan sets the end).
    #[arg(long, value_name = "SECONDS")]
    pub end_time: Option<f64>,
    /// Runs on this track file instead of the scenario's (a longer straight
    /// track for a long continuation).
    #[arg(long, value_name = "FILE")]
    pub track: Option<PathBuf>,
    /// CSV: the run's rows, or with `--bifurcation` the diagram.
    #[arg(short, long)]
    pub output: Option<PathBuf>,
    /// Plot (`.svg` or `.png`): the signals against the speed, or the
    /// diagram (written from the CSV of `-o`, or one beside the plot).
    #[arg(long, value_name = "FILE")]
    pub plot: Option<PathBuf>,
    /// Engine and parameters.
    #[command(flatten)]
    pub engine: EngineOptions,
}

/// Runs `umsim critical-speed`.
pub fn run(args: &Args) -> Result<(), Box<dyn std::error::Error>> {
    let (mut scenario, model) = args.engine.load(&args.scenario)?;
    if let Some(t) = args.end_time {
        scenario
            .set_end_time(t)
            .map_err(|e| format!("{}: --end-time: {e}", args.scenario.display()))?;
    }
    if let Some(file) = &args.track {
        let Some(track) = &mut scenario.track else {
            return Err(format!(
                "{}: --track: the scenario has no track",
                args.scenario.display()
            )
            .into());
        };
        track.load_file(file)?;
    }
    let signals = if args.signals.is_empty() {
        let system = scenario_system(&scenario, &model, args.engine.build(&model)?)?;
        wheelset_lateral_coordinates(&model, &system.coordinates)
    } else {
        args.signals.clone()
    };
    // The CSV: -o, or one beside the plot.
    let csv = args
        .output
        .clone()
        .or_else(|| args.plot.as_ref().map(|p| p.with_extension("csv")));
    if let Some(p) = &args.plot {
        crate::plot::Format::of(p)?;
    }
    let start = std::time::Instant::now();
    match &args.bifurcation {
        None => {
            let settings = DetectionSettings {
                relative: args.relative,
                on: args.on,
                ..DetectionSettings::new(args.window, args.threshold)
            };
            let mut sink = output_sink(csv.as_deref(), &scenario.input_files())?;
            let (summary, detection) = decelerating_run(
                &scenario,
                &model,
                args.engine.build(&model)?,
                &signals,
                settings,
                &mut *sink,
                |_| {},
            )?;
            print!("{}", describe_detection(&signals, &settings, &detection));
            if let Some(e) = &summary.error {
                println!("the run stopped at t = {} s: {e}", summary.t_end);
            }
            println!(
                "{} steps, {:.2} s CPU (total {:.2} s)",
                summary.steps,
                summary.cpu_time,
                start.elapsed().as_secs_f64()
            );
            if let Some(path) = &csv {
                println!("run written to {}", path.display());
                if let Some(plot) = &args.plot {
                    let y: Vec<String> = signals.clone();
                    draw(
                        path,
                        "v[m/s]",
                        &[y.join(",")],
                        plot,
                        "lateral limit cycle against speed",
                    )?;
                }
            }
        }
        Some(Speeds(speeds)) => {
            let plan = Staircase {
                speeds: speeds.iter().rev().copied().collect(),
                first_hold: 2.0 * args.hold,
                hold: args.hold,
                ramp: args.ramp,
                measure: args.measure.unwrap_or(0.5 * args.hold),
            };
            let (summary, points) = bifurcation(
                &scenario,
                &model,
                args.engine.build(&model)?,
                &signals,
                &plan,
                &mut Discard as &mut dyn OutputSink,
                |_| {},
            )?;
            print!("{}", describe_branch(&signals, &points, args.on));
            if let Some(e) = &summary.error {
                println!("the run stopped at t = {} s: {e}", summary.t_end);
            }
            println!(
                "{} plateaus, {} steps, {:.2} s CPU (total {:.2} s)",
                points.len(),
                summary.steps,
                summary.cpu_time,
                start.elapsed().as_secs_f64()
            );
            if let Some(path) = &csv {
                write_branch(path, &points, args.threshold)?;
                println!("bifurcation diagram written to {}", path.display());
                if let Some(plot) = &args.plot {
                    draw(
                        path,
                        "speed[m/s]",
                        &["amplitude[m]".to_string()],
                        plot,
                        "bifurcation diagram: limit-cycle amplitude against speed",
                    )?;
                }
            }
        }
    }
    Ok(())
}

/// Plots `y` against `x` of the CSV `input` into `output` with `umsim plot`.
fn draw(
    input: &Path,
    x: &str,
    y: &[String],
    output: &Path,
    title: &str,
) -> Result<(), Box<dyn std::error::Error>> {
    crate::plot::run(&crate::plot::Args {
        input: input.to_path_buf(),
        y: y.to_vec(),
        x: x.to_string(),
        from: None,
        to: None,
        title: Some(title.to_string()),
        width: 1000,
        height: None,
        output: output.to_path_buf(),
    })?;
    println!("plot written to {}", output.display());
    Ok(())
}

/// The report of a decelerating run.
pub fn describe_detection(
    signals: &[String],
    settings: &DetectionSettings,
    detection: &Detection,
) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "limit cycle of {} (amplitude: half the range over {} s; established from {} m, died out \
         below {} m or {} of its largest amplitude)",
        signals.join(", "),
        settings.window,
        settings.on,
        settings.off,
        settings.relative
    );
    let _ = match detection {
        Detection::Collapsed(c) => writeln!(
            s,
            "nonlinear critical speed: {:.3} m/s ({:.1} km/h) at t = {:.2} s{}; the limit cycle's \
             amplitude was up to {:.3} mm",
            c.speed,
            3.6 * c.speed,
            c.t,
            c.position
                .map_or(String::new(), |p| format!(", s = {p:.1} m")),
            1e3 * c.amplitude
        ),
        Detection::StillHunting { speed, amplitude } => writeln!(
            s,
            "no critical speed found: the limit cycle (amplitude {:.3} mm) still goes on at the \
             end of the run, at {speed:.3} m/s; decelerate further",
            1e3 * amplitude
        ),
        Detection::NoLimitCycle { max_amplitude } => writeln!(
            s,
            "no critical speed found: no limit cycle (largest amplitude {:.4} mm, below the {} m \
             needed); start faster or with a larger disturbance",
            1e3 * max_amplitude,
            settings.on
        ),
    };
    s
}

/// The lowest speed of the diagram where the limit cycle still goes on
/// (amplitude at least `threshold`, the on threshold) with every faster plateau hunting too:
/// the stable branch's fold lies between it and the next plateau.
pub fn lowest_hunting(points: &[BranchPoint], threshold: f64) -> Option<(f64, Option<f64>)> {
    let n = points
        .iter()
        .take_while(|p| p.amplitude >= threshold)
        .count();
    (n > 0).then(|| (points[n - 1].speed, points.get(n).map(|p| p.speed)))
}

/// The report of a bifurcation diagram.
pub fn describe_branch(signals: &[String], points: &[BranchPoint], threshold: f64) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "bifurcation diagram of {} (amplitude: half the range at the end of each plateau)\n\n\
         speed [m/s]  amplitude [mm]  first half [mm]  second half [mm]  settled",
        signals.join(", ")
    );
    for p in points {
        let _ = writeln!(
            s,
            "{:>11.3}  {:>14.4}  {:>15.4}  {:>16.4}  {}",
            p.speed,
            1e3 * p.amplitude,
            1e3 * p.early,
            1e3 * p.late,
            if p.settled(0.1 * threshold) {
                "yes"
            } else {
                "no"
            }
        );
    }
    let _ = match lowest_hunting(points, threshold) {
        Some((v, Some(below))) => writeln!(
            s,
            "\nthe limit cycle (amplitude ≥ {threshold} m) goes on down to {v:.3} m/s and has \
             died out at {below:.3} m/s: the nonlinear critical speed lies between"
        ),
        Some((v, None)) => writeln!(
            s,
            "\nthe limit cycle goes on down to the lowest speed, {v:.3} m/s"
        ),
        None => writeln!(
            s,
            "\nno limit cycle at the first (highest) speed: start faster or with a larger disturbance"
        ),
    };
    s
}

/// The diagram as CSV: a row per plateau.
fn write_branch(
    path: &Path,
    points: &[BranchPoint],
    threshold: f64,
) -> Result<(), Box<dyn std::error::Error>> {
    let err = |e: csv::Error| format!("{}: {e}", path.display());
    let mut w = csv::Writer::from_path(path).map_err(err)?;
    w.write_record([
        "speed[m/s]",
        "amplitude[m]",
        "first_half[m]",
        "second_half[m]",
        "settled",
    ])
    .map_err(err)?;
    for p in points {
        w.write_record([
            format!("{:?}", p.speed),
            format!("{:?}", p.amplitude),
            format!("{:?}", p.early),
            format!("{:?}", p.late),
            u8::from(p.settled(0.1 * threshold)).to_string(),
        ])
        .map_err(err)?;
    }
    w.flush().map_err(|e| format!("{}: {e}", path.display()))?;
    Ok(())
}
