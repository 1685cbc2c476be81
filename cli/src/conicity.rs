//! `umsim conicity`: equivalent conicity of a wheelset on a track by EN 15302 (Annex B).
//!
//! Reads wheel and rail profiles (format from the extension: `.prw`/`.whl` wheels,
//! `.prr`/`.ban` rails, anything else two columns `y z` in mm), computes the rolling radius
//! difference function and writes `amplitude_mm,tan_gamma_e` for the amplitudes
//! 0.5, 1.0, …, 10 mm as CSV (stdout unless `-o`).

use std::io::Write;
use std::path::PathBuf;

use railmbs_wheelrail::conicity::{RollTreatment, conicity_curve};
use railmbs_wheelrail::geometry::{ContactGeometry, SearchSettings, Track, Wheelset};
use railmbs_wheelrail::profile::{Profile, ProfileKind, ProfileSettings};

/// Arguments of `umsim conicity`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Wheel profile (left wheel, and right wheel unless --wheel-right is given).
    #[arg(long, value_name = "FILE")]
    pub wheel: PathBuf,
    /// Right wheel profile (same convention as the left one; mirrored when placed).
    #[arg(long, value_name = "FILE")]
    pub wheel_right: Option<PathBuf>,
    /// Rail profile (left rail, and right rail unless --rail-right is given).
    #[arg(long, value_name = "FILE")]
    pub rail: PathBuf,
    /// Right rail profile.
    #[arg(long, value_name = "FILE")]
    pub rail_right: Option<PathBuf>,
    /// Track gauge in mm, measured 14 mm below the rail tops.
    #[arg(long, value_name = "MM", default_value_t = 1435.0)]
    pub gauge: f64,
    /// Distance between the wheels' flange backs (back-to-back) in mm.
    #[arg(long, value_name = "MM", default_value_t = 1360.0)]
    pub flange_back: f64,
    /// Rail inclination applied to the rail profiles as read, as `1:40` or a tangent such as
    /// 0.025; 0 for profiles already inclined in their files (MBench_UIC60, SUIC519A).
    #[arg(long, value_name = "RATIO", default_value = "0")]
    pub rail_inclination: String,
    /// Nominal wheel diameters left,right at the taping lines in mm.
    #[arg(long, value_name = "MM,MM", default_value = "920,920")]
    pub diameters: String,
    /// Smoothing length of the profile smoothing spline in mm (0 interpolates).
    #[arg(long, value_name = "MM", default_value_t = 0.1)]
    pub smoothing: f64,
    /// Use the rigid wheelset's roll in Δr (both wheels touching) instead of neglecting the
    /// roll as the EN 15302 reference calculation does.
    #[arg(long)]
    pub with_roll: bool,
    /// Output CSV file (stdout when absent).
    #[arg(short = 'o', long, value_name = "FILE")]
    pub output: Option<PathBuf>,
}

/// Parses a rail inclination `1:40`, `1/40` or a tangent `0.025` into an angle (rad).
pub fn parse_inclination(text: &str) -> Result<f64, String> {
    let t = text.trim();
    let bad =
        || format!("--rail-inclination: `{text}` is not a ratio like 1:40 or a tangent like 0.025");
    let tangent = if let Some((a, b)) = t.split_once([':', '/']) {
        let a: f64 = a.trim().parse().map_err(|_| bad())?;
        let b: f64 = b.trim().parse().map_err(|_| bad())?;
        if b == 0.0 {
            return Err(bad());
        }
        a / b
    } else {
        t.parse::<f64>().map_err(|_| bad())?
    };
    if !tangent.is_finite() || tangent.abs() > 0.5 {
        return Err(format!(
            "--rail-inclination: tangent {tangent} out of range (|tan| ≤ 0.5)"
        ));
    }
    Ok(tangent.atan())
}

fn parse_diameters(text: &str) -> Result<(f64, f64), String> {
    let bad = || format!("--diameters: `{text}` is not two positive diameters in mm like 920,920");
    let (a, b) = text.split_once(',').ok_or_else(bad)?;
    let a: f64 = a.trim().parse().map_err(|_| bad())?;
    let b: f64 = b.trim().parse().map_err(|_| bad())?;
    if !(a.is_finite() && b.is_finite() && a > 0.0 && b > 0.0) {
        return Err(bad());
    }
    Ok((a, b))
}

/// Amplitudes of the output: 0.5 to 10 mm in steps of 0.5 mm (m).
pub fn amplitudes() -> Vec<f64> {
    (1..=20).map(|k| k as f64 * 0.5e-3).collect()
}

/// Runs `umsim conicity`.
pub fn run(args: &Args) -> Result<(), Box<dyn std::error::Error>> {
    for (name, v) in [("--gauge", args.gauge), ("--flange-back", args.flange_back)] {
        if !(v.is_finite() && v > 0.0) {
            return Err(format!("{name}: must be a positive number of mm, got {v}").into());
        }
    }
    if !(args.smoothing.is_finite() && args.smoothing >= 0.0) {
        return Err(format!("--smoothing: must be ≥ 0 mm, got {}", args.smoothing).into());
    }
    let inclination = parse_inclination(&args.rail_inclination)?;
    let (dl, dr) = parse_diameters(&args.diameters)?;
    let wheel_settings = ProfileSettings {
        smoothing_length: args.smoothing * 1e-3,
        ..Default::default()
    };
    let rail_settings = ProfileSettings {
        rail_inclination: inclination,
        ..wheel_settings
    };
    let wl = Profile::read(&args.wheel, ProfileKind::Wheel, &wheel_settings)?;
    let wr = match &args.wheel_right {
        Some(p) => Profile::read(p, ProfileKind::Wheel, &wheel_settings)?,
        None => wl.clone(),
    };
    let rl = Profile::read(&args.rail, ProfileKind::Rail, &rail_settings)?;
    let rr = match &args.rail_right {
        Some(p) => Profile::read(p, ProfileKind::Rail, &rail_settings)?,
        None => rl.clone(),
    };
    let mut wheelset = Wheelset::new(wl, wr, 0.5e-3 * dl, args.flange_back * 1e-3);
    wheelset.radius_right = 0.5e-3 * dr;
    let track = Track::new(rl, rr, args.gauge * 1e-3);
    let geo = ContactGeometry::new(&wheelset, &track, SearchSettings::default())?;
    let roll = if args.with_roll {
        RollTreatment::Rigid
    } else {
        RollTreatment::Neglected
    };
    let curve = conicity_curve(&geo, &amplitudes(), roll)?;
    let sink: Box<dyn Write> = match &args.output {
        Some(p) => Box::new(
            std::fs::File::create(p).map_err(|e| format!("{}: cannot create: {e}", p.display()))?,
        ),
        None => Box::new(std::io::stdout().lock()),
    };
    let mut w = csv::Writer::from_writer(sink);
    w.write_record(["amplitude_mm", "tan_gamma_e"])?;
    for (a, t) in curve {
        w.write_record([format!("{:.1}", a * 1e3), format!("{t:.5}")])?;
    }
    w.flush()?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inclination_forms() {
        let a = (1.0_f64 / 40.0).atan();
        assert!((parse_inclination("1:40").unwrap() - a).abs() < 1e-15);
        assert!((parse_inclination("1/40").unwrap() - a).abs() < 1e-15);
        assert!((parse_inclination("0.025").unwrap() - a).abs() < 1e-15);
        assert_eq!(parse_inclination("0").unwrap(), 0.0);
        assert!(parse_inclination("1:0").is_err());
        assert!(parse_inclination("steep").is_err());
        assert!(parse_inclination("3").is_err());
    }

    #[test]
    fn diameters_form() {
        assert_eq!(parse_diameters("920, 918").unwrap(), (920.0, 918.0));
        assert!(parse_diameters("920").is_err());
        assert!(parse_diameters("920,-1").is_err());
    }
}
