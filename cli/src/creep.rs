//! `umsim creep`: creep forces for a table of contact cases.
//!
//! ```text
//! umsim creep --method LAW --cases FILE.csv [-o out.csv]
//! umsim creep --compare [LAW …] --cases FILE.csv [-o out.csv]
//! ```
//!
//! `LAW` is a creep law in the syntax of `umsim bench --creep` and of
//! [`CreepLawSpec`]'s `FromStr`: `kalker`, `mueller[:EXPONENT]` (Pogorelov
//! 2005, Sect. 4.2), `mueller-kalker-saturated[:EXPONENT]`,
//! `fastsim[:N]` (N × N) or `fastsim:nx=NX,ny=NY`, `fastsim-sa[:N]` or
//! `fastsim-sa:nx=NX,ny=NY`, `fastsim-a[:STRIPS]` with
//! `,sliding=continuation|integrated|picard` and `,nodes=K`,
//! `fastsim-a-integrated[:STRIPS]`, `polach[:ka=KA,ks=KS,friction_decrease=A/B]`,
//! `strip[:STRIPS]` (strip theory calibrated to Kalker's linear theory);
//! defaults as in model files. FastSim_A's `integrated` sliding zones are more
//! accurate at large spin, about ten times slower (see
//! `railmbs_wheelrail::creep::SlidingZone`). The older flags `--strips`,
//! `--elements`, `--sliding` and `--nodes` still set those settings of the law.
//!
//! Input columns (any order, by header name): `a,b,G,nu,mu,N,xi,eta,phi` in
//! m, m, Pa, –, –, N, –, –, 1/m. Output columns `Fx,Fy,Mz` in N, N, N·m: forces
//! on the wheel in the contact frame, CONTACT's sign convention (`Fx < 0` for
//! `ξ > 0`), one row per input row. A bad row is an error naming the row (data
//! row number, 1-based, and file line) and the column.
//!
//! `--compare LAW LAW …` evaluates every case with each law (all laws with
//! their defaults, [`CreepLawSpec::every_law`], if none is named) and writes
//! one row per case: `row`, each law's `LAW.Fx,LAW.Fy,LAW.Mz`, then for every
//! law after the first its differences from the first, `LAW.dFx,LAW.dFy,
//! LAW.dMz` and `LAW.dF/muN` (= |(ΔFx, ΔFy)|/(μN)); a summary of the largest
//! and mean `dF/muN` per law goes to standard error.

use railmbs_wheelrail::creep::{
    CreepForces, CreepLaw, CreepLawSpec, INTEGRATED_NODES, SlidingZone,
};
use railmbs_wheelrail::creep_cases::{Case, read_cases};
use std::io::{Read, Write};
use std::path::PathBuf;

/// FastSim_A's treatment of the sliding zones (`--sliding`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Sliding {
    /// Adhesion-continuation direction in closed form (fastest).
    Continuation,
    /// Sliding zone integrated node to node, with re-adhesion.
    Integrated,
    /// One Picard step from the continuation direction.
    Picard,
}

/// The long help of a creep-law argument (`umsim creep --method`, `umsim bench
/// --creep`): the syntax of [`CreepLawSpec`]'s `FromStr` and its defaults.
pub(crate) const LAW_HELP: &str = concat!(
    "Creep-force law and its settings: kalker | mueller[:EXPONENT] (Pogorelov 2005) | ",
    "mueller-kalker-saturated[:EXPONENT] | ",
    "fastsim[:N] (N × N elements) | fastsim:nx=NX,ny=NY | ",
    "fastsim-sa[:N] | fastsim-sa:nx=NX,ny=NY (FastSim_SA: analytic adhesion, FASTSIM sliding) | ",
    "fastsim-a[:STRIPS][,sliding=continuation|integrated|picard][,nodes=K] | ",
    "fastsim-a-integrated[:STRIPS] | polach[:ka=KA,ks=KS,friction_decrease=A/B] | ",
    "strip[:STRIPS] (strip theory with Kalker's coefficients). ",
    "Defaults: Mueller exponents 2, FASTSIM 10 × 10, FastSim_A 20 strips with ",
    "continuation sliding (8 Gauss nodes for integrated/picard), Polach ",
    "ka = ks = 1 without friction decrease, strip theory 10 strips. Example: fastsim-a:10,sliding=integrated"
);

/// Arguments of `umsim creep`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Creep-force law and its settings (`LAW[:key=value,…]`, see `--help`).
    #[arg(
        long,
        visible_alias = "law",
        value_name = "LAW",
        long_help = LAW_HELP,
        required_unless_present = "compare",
        conflicts_with = "compare"
    )]
    pub method: Option<CreepLawSpec>,
    /// Compare laws on the same cases (each `LAW[:key=value,…]`; every law
    /// with its defaults if none is given): their forces and differences
    /// from the first.
    #[arg(long, value_name = "LAW", num_args = 0..)]
    pub compare: Option<Vec<CreepLawSpec>>,
    /// Number of strips (FASTSIM, FastSim_A): overrides the law's.
    #[arg(long)]
    pub strips: Option<usize>,
    /// Number of elements per strip (FASTSIM): overrides the law's nx.
    #[arg(long)]
    pub elements: Option<usize>,
    /// FastSim_A's treatment of the sliding zones: overrides the law's.
    #[arg(long, value_enum)]
    pub sliding: Option<Sliding>,
    /// Gauss nodes per sliding zone (FastSim_A, integrated or picard):
    /// overrides the law's.
    #[arg(long)]
    pub nodes: Option<usize>,
    /// Input CSV with columns a,b (contact semi-axes, m), G (combined shear modulus, Pa), nu (Poisson ratio, -), mu (friction coefficient, -), N (normal force, N), xi,eta (longitudinal and lateral creepage, -), phi (spin creepage, 1/m); see models/creep/cases.csv.
    #[arg(long)]
    pub cases: PathBuf,
    /// Output CSV (Fx,Fy in N, Mz in N·m; forces on the wheel); standard output if omitted.
    #[arg(short = 'o', long)]
    pub output: Option<PathBuf>,
}

impl Args {
    /// The law of `--method` with the settings of `--strips`, `--elements`,
    /// `--sliding` and `--nodes` applied; an error for a flag the law has no
    /// setting for.
    pub fn spec(&self) -> Result<CreepLawSpec, String> {
        let mut spec = self.method.ok_or("--method LAW is needed (or --compare)")?;
        let not_for = |flag: &str, spec: &CreepLawSpec| {
            format!("--{flag} does not apply to the law {}", spec.name())
        };
        if let Some(n) = self.strips {
            match &mut spec {
                CreepLawSpec::Fastsim { ny, .. } => *ny = n,
                CreepLawSpec::FastsimA { strips, .. } => *strips = n,
                other => return Err(not_for("strips", other)),
            }
        }
        if let Some(n) = self.elements {
            match &mut spec {
                CreepLawSpec::Fastsim { nx, .. } => *nx = n,
                other => return Err(not_for("elements", other)),
            }
        }
        if let Some(s) = self.sliding {
            let CreepLawSpec::FastsimA { sliding, .. } = &mut spec else {
                return Err(not_for("sliding", &spec));
            };
            let nodes = match *sliding {
                SlidingZone::Integrated { nodes } | SlidingZone::Picard { nodes } => nodes,
                SlidingZone::Continuation => INTEGRATED_NODES,
            };
            *sliding = match s {
                Sliding::Continuation => SlidingZone::Continuation,
                Sliding::Integrated => SlidingZone::Integrated { nodes },
                Sliding::Picard => SlidingZone::Picard { nodes },
            };
        }
        if let Some(n) = self.nodes {
            match &mut spec {
                CreepLawSpec::FastsimA {
                    sliding: SlidingZone::Integrated { nodes } | SlidingZone::Picard { nodes },
                    ..
                } => *nodes = n,
                other => {
                    return Err(format!(
                        "--nodes applies to FastSim_A with integrated or picard sliding zones, \
                         not to {other}"
                    ));
                }
            }
        }
        Ok(spec)
    }
}

/// The forces of `law` for `case`: an error naming the case's row and line
/// if the law refuses it or its result is not finite.
fn case_forces(law: &dyn CreepLaw, case: &Case, source: &str) -> Result<CreepForces, String> {
    let (row, line) = (case.row, case.line);
    let f = law
        .forces(&case.patch, &case.creepages)
        .map_err(|e| format!("{source}: row {row} (line {line}): {e}"))?;
    if !(f.fx.is_finite() && f.fy.is_finite() && f.mz.is_finite()) {
        return Err(format!(
            "{source}: row {row} (line {line}): {} gives a non-finite result ({}, {}, {}) \
             for this case; nothing is written for it",
            law.name(),
            f.fx,
            f.fy,
            f.mz
        ));
    }
    Ok(f)
}

/// `x` as written to the output CSV (`+ 0.0` turns −0 into 0).
fn cell(x: f64) -> String {
    (x + 0.0).to_string()
}

/// Evaluates every case of the CSV in `input` with `law` and writes `Fx,Fy,Mz`
/// rows to `output`. `source` names the input in error messages.
pub fn evaluate<R: Read, W: Write>(
    law: &dyn CreepLaw,
    input: R,
    source: &str,
    output: W,
) -> Result<usize, String> {
    let cases = read_cases(input, source)?;
    let mut wr = csv::Writer::from_writer(output);
    let werr = |e: csv::Error| format!("cannot write output: {e}");
    wr.write_record(["Fx", "Fy", "Mz"]).map_err(werr)?;
    for case in &cases {
        let f = case_forces(law, case, source)?;
        wr.write_record([cell(f.fx), cell(f.fy), cell(f.mz)])
            .map_err(werr)?;
    }
    wr.flush()
        .map_err(|e| format!("cannot write output: {e}"))?;
    Ok(cases.len())
}

/// Largest and mean |ΔF|/(μN) of one law against the first, over the cases
/// with μN > 0.
#[derive(Debug, Clone, PartialEq)]
pub struct Difference {
    /// The law, as written in the header.
    pub law: String,
    /// Largest |(ΔFx, ΔFy)|/(μN), –.
    pub max: f64,
    /// Mean |(ΔFx, ΔFy)|/(μN), –.
    pub mean: f64,
}

/// `umsim creep --compare`: every case of `input` with each of `laws`
/// (their text as given in `names`), written to `output` as described in the
/// module documentation; returns each later law's difference from the first.
pub fn compare<R: Read, W: Write>(
    laws: &[(String, Box<dyn CreepLaw + Send + Sync>)],
    input: R,
    source: &str,
    output: W,
) -> Result<Vec<Difference>, String> {
    let cases = read_cases(input, source)?;
    let mut wr = csv::Writer::from_writer(output);
    let werr = |e: csv::Error| format!("cannot write output: {e}");
    let mut header = vec!["row".to_string()];
    for (name, _) in laws {
        for q in ["Fx", "Fy", "Mz"] {
            header.push(format!("{name}.{q}"));
        }
    }
    for (name, _) in laws.iter().skip(1) {
        for q in ["dFx", "dFy", "dMz", "dF/muN"] {
            header.push(format!("{name}.{q}"));
        }
    }
    wr.write_record(&header).map_err(werr)?;
    let mut sums = vec![(0.0_f64, 0.0_f64, 0usize); laws.len()];
    for case in &cases {
        let forces = laws
            .iter()
            .map(|(_, law)| case_forces(law.as_ref(), case, source))
            .collect::<Result<Vec<_>, _>>()?;
        let mut rec = vec![case.row.to_string()];
        for f in &forces {
            rec.extend([cell(f.fx), cell(f.fy), cell(f.mz)]);
        }
        let mu_n = case.patch.mu * case.patch.n;
        let r = forces[0];
        for (k, f) in forces.iter().enumerate().skip(1) {
            let (dx, dy, dm) = (f.fx - r.fx, f.fy - r.fy, f.mz - r.mz);
            let rel = if mu_n > 0.0 { dx.hypot(dy) / mu_n } else { 0.0 };
            if mu_n > 0.0 {
                let s = &mut sums[k];
                s.0 = s.0.max(rel);
                s.1 += rel;
                s.2 += 1;
            }
            rec.extend([cell(dx), cell(dy), cell(dm), cell(rel)]);
        }
        wr.write_record(&rec).map_err(werr)?;
    }
    wr.flush()
        .map_err(|e| format!("cannot write output: {e}"))?;
    Ok(laws
        .iter()
        .zip(&sums)
        .skip(1)
        .map(|((name, _), &(max, sum, n))| Difference {
            law: name.clone(),
            max,
            mean: if n > 0 { sum / n as f64 } else { 0.0 },
        })
        .collect())
}

/// Runs `umsim creep`.
pub fn run(args: &Args) -> Result<(), Box<dyn std::error::Error>> {
    let source = args.cases.display().to_string();
    let file = std::fs::File::open(&args.cases).map_err(|e| format!("{source}: {e}"))?;
    let out: Box<dyn Write> = match &args.output {
        Some(path) => Box::new(std::io::BufWriter::new(
            std::fs::File::create(path)
                .map_err(|e| format!("{}: cannot create: {e}", path.display()))?,
        )),
        None => Box::new(std::io::stdout().lock()),
    };
    if let Some(compared) = &args.compare {
        for flag in [
            ("strips", args.strips.is_some()),
            ("elements", args.elements.is_some()),
            ("sliding", args.sliding.is_some()),
            ("nodes", args.nodes.is_some()),
        ] {
            if flag.1 {
                return Err(format!(
                    "--{} does not apply to --compare (give each law its settings)",
                    flag.0
                )
                .into());
            }
        }
        let specs = if compared.is_empty() {
            CreepLawSpec::every_law()
        } else {
            compared.clone()
        };
        let laws = specs
            .iter()
            .map(|s| Ok((s.to_string(), s.build()?)))
            .collect::<Result<Vec<_>, railmbs_wheelrail::creep::CreepError>>()?;
        let diffs = compare(&laws, file, &source, out)?;
        eprintln!("|ΔF|/(μN) against {}:", laws[0].0);
        for d in diffs {
            eprintln!("  {:<55} max {:.4}  mean {:.4}", d.law, d.max, d.mean);
        }
        return Ok(());
    }
    let law = args.spec()?.build()?;
    evaluate(law.as_ref(), file, &source, out)?;
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run_str(law: &str, input: &str) -> Result<String, String> {
        let law = law
            .parse::<CreepLawSpec>()
            .map_err(|e| e.to_string())?
            .build()
            .map_err(|e| e.to_string())?;
        let mut out = Vec::new();
        evaluate(law.as_ref(), input.as_bytes(), "cases.csv", &mut out)?;
        Ok(String::from_utf8(out).unwrap())
    }

    #[test]
    fn evaluates_rows_in_any_column_order() {
        let input = "xi,eta,phi,a,b,G,nu,mu,N\n\
                     0.001,0,0,0.006,0.004,8e10,0.28,0.3,80000\n\
                     0,0,0,0.006,0.004,8e10,0.28,0.3,80000\n";
        for m in [
            "kalker",
            "mueller",
            "mueller-kalker-saturated",
            "fastsim:10",
            "fastsim-a:10",
            "polach",
        ] {
            let out = run_str(m, input).unwrap();
            let lines: Vec<&str> = out.lines().collect();
            assert_eq!(lines[0], "Fx,Fy,Mz");
            assert_eq!(lines.len(), 3);
            let fx: f64 = lines[1].split(',').next().unwrap().parse().unwrap();
            assert!(fx < 0.0, "{m:?}: {fx}");
            assert_eq!(lines[2], "0,0,0");
        }
        // Kalker linear: Fx = −G a b C11 ξ, C11(a/b = 1.5, ν = 0.28) interpolated
        // in Kalker's table between b/a = 0.7 and 0.6 (4.587, 4.813 at ν = 0.28).
        let out = run_str("kalker", input).unwrap();
        let fx: f64 = out
            .lines()
            .nth(1)
            .unwrap()
            .split(',')
            .next()
            .unwrap()
            .parse()
            .unwrap();
        let c07 = 4.54 + 0.12 * (5.58 - 4.54);
        let c06 = 4.78 + 0.12 * (5.80 - 4.78);
        let s = 19.0 - 10.0 / 1.5 - 12.0; // position between rows b/a = 0.7 and 0.6
        let c11 = c07 + s * (c06 - c07);
        assert!((fx / (-8e10 * 0.006 * 0.004 * c11 * 0.001) - 1.0).abs() < 1e-12);
    }

    #[test]
    fn bad_rows_are_named() {
        let e = run_str("kalker", "a,b,G,nu,mu,N,xi,eta\n1,1,1,0.3,0.3,1,0,0\n").unwrap_err();
        assert!(e.contains("missing column 'phi'"), "{e}");
        let e = run_str(
            "fastsim",
            "a,b,G,nu,mu,N,xi,eta,phi\n0.006,0.004,8e10,0.28,0.3,80000,0,0,0\n0.006,x,8e10,0.28,0.3,80000,0,0,0\n",
        )
        .unwrap_err();
        assert!(e.contains("row 2") && e.contains("column 'b'"), "{e}");
        let e = run_str(
            "fastsim-a",
            "a,b,G,nu,mu,N,xi,eta,phi\n0.006,0.004,8e10,0.9,0.3,80000,0,0,0\n",
        )
        .unwrap_err();
        assert!(e.contains("row 1") && e.contains("nu = 0.9"), "{e}");
        assert!(
            run_str("fastsim:0", "")
                .unwrap_err()
                .contains("positive whole number")
        );
    }

    #[derive(clap::Parser)]
    struct Cli {
        #[command(flatten)]
        args: Args,
    }

    fn spec_of(args: &[&str]) -> Result<CreepLawSpec, String> {
        use clap::Parser;
        let cli = Cli::try_parse_from(
            ["creep", "--cases", "c.csv"]
                .iter()
                .chain(args.iter())
                .copied(),
        )
        .map_err(|e| e.to_string())?;
        cli.args.spec()
    }

    #[test]
    fn the_law_and_the_older_flags() {
        let spec = |a: &[&str]| spec_of(a).unwrap();
        // The defaults are the spec's, as for model files and umsim bench.
        assert_eq!(spec(&["--method", "fastsim-a"]), CreepLawSpec::default());
        assert_eq!(spec(&["--method", "mueller"]), CreepLawSpec::mueller());
        assert_eq!(spec(&["--law", "fastsim"]), CreepLawSpec::fastsim());
        assert_eq!(
            spec(&["--method", "fastsim", "--strips", "20", "--elements", "30"]),
            CreepLawSpec::Fastsim { nx: 30, ny: 20 }
        );
        assert_eq!(
            spec(&[
                "--method",
                "fastsim-a",
                "--sliding",
                "picard",
                "--nodes",
                "4"
            ]),
            "fastsim-a:sliding=picard,nodes=4".parse().unwrap()
        );
        assert_eq!(
            spec(&[
                "--method",
                "fastsim-a:strips=5,sliding=integrated,nodes=3",
                "--strips",
                "7"
            ]),
            "fastsim-a:7,sliding=integrated,nodes=3".parse().unwrap()
        );
        assert_eq!(
            spec(&[
                "--method",
                "fastsim-a-integrated:12",
                "--sliding",
                "continuation"
            ]),
            "fastsim-a:12".parse().unwrap()
        );
        for (args, expected) in [
            (
                &["--method", "kalker", "--strips", "3"][..],
                "--strips does not apply to the law kalker",
            ),
            (
                &["--method", "polach", "--sliding", "picard"],
                "--sliding does not apply",
            ),
            (
                &["--method", "fastsim-a", "--elements", "3"],
                "--elements does not apply",
            ),
            (
                &["--method", "fastsim-a", "--nodes", "3"],
                "--nodes applies to FastSim_A with",
            ),
            (
                &["--method", "fastsim:nx=0"],
                "nx: \"0\" is not a positive whole number",
            ),
        ] {
            let e = spec_of(args).unwrap_err();
            assert!(e.contains(expected), "{args:?}: {e}");
        }
    }

    /// `umsim bench --creep` reads the same text to the same law as `umsim
    /// creep --method`, and the default law is the model files' one.
    #[test]
    fn the_three_entry_points_agree() {
        use railmbs_models::{CreepLawSpec, Expr, ForceKind};
        let expr = |s: CreepLawSpec| s.map(|_, &x| Expr::Num(x));
        for text in [
            "kalker",
            "mueller",
            "mueller:3",
            "mueller-kalker-saturated:2.5",
            "fastsim",
            "fastsim:20",
            "fastsim-sa:nx=30,ny=12",
            "fastsim-a",
            "fastsim-a-integrated:12",
            "fastsim-a:sliding=picard",
            "polach",
            "polach:ks=0.5,friction_decrease=0.4/0.6",
        ] {
            let creep = spec_of(&["--method", text]).unwrap();
            assert_eq!(
                crate::bench::parse_creep(text).unwrap(),
                expr(creep),
                "{text}"
            );
        }
        // Every bundled model leaves its wheel–rail law to the default.
        let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../models");
        let scenario =
            railmbs_models::load_scenario(&dir.join("scenarios/free_wheelset_klingel.ron"))
                .unwrap();
        let model = railmbs_models::load_model(&scenario.model).unwrap();
        let law = model
            .forces
            .iter()
            .find_map(|f| match &f.kind {
                ForceKind::WheelRail(w) => Some(w.creep.clone()),
                _ => None,
            })
            .unwrap();
        assert_eq!(law, expr(spec_of(&["--method", "fastsim-a"]).unwrap()));
        assert_eq!(law, crate::bench::parse_creep("fastsim-a").unwrap());
        let e = crate::bench::parse_creep("fastsim:0").unwrap_err();
        assert!(e.starts_with("--creep: creep law \"fastsim:0\""), "{e}");
    }
}
