//! `umsim creep`: creep forces for a table of contact cases.
//!
//! ```text
//! umsim creep --method kalker|mueller|fastsim|fastsim-a|polach [--strips M] [--elements N] \
//!             [--sliding continuation|integrated|picard] [--nodes K] --cases FILE.csv [-o out.csv]
//! ```
//!
//! `--sliding` selects FastSim_A's treatment of the sliding zones (default
//! `continuation`; `integrated` is more accurate at large spin, about ten times
//! slower; see `railmbs_wheelrail::creep::SlidingZone`), with `--nodes` Gauss
//! nodes per zone (default 8). `polach` is Polach's 1999 law (constant
//! friction, no reduction factors).
//!
//! Input columns (any order, by header name): `a,b,G,nu,mu,N,xi,eta,phi` in
//! m, m, Pa, –, –, N, –, –, 1/m. Output columns `Fx,Fy,Mz` in N, N, N·m: forces
//! on the wheel in the contact frame, CONTACT's sign convention (`Fx < 0` for
//! `ξ > 0`), one row per input row. A bad row is an error naming the row (data
//! row number, 1-based, and file line) and the column.

use railmbs_wheelrail::creep::{
    ContactPatch, CreepLaw, Creepages, Fastsim, FastsimA, KalkerLinear, Mueller, Polach,
    SlidingZone,
};
use std::io::{Read, Write};
use std::path::PathBuf;

/// Creep-force law to use.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Method {
    /// Kalker's linear theory.
    Kalker,
    /// Kalker's linear force saturated towards μN (exponent 2).
    Mueller,
    /// Kalker's FASTSIM, strips × elements, parabolic traction bound.
    Fastsim,
    /// Semi-analytic FastSim_A, strips only.
    FastsimA,
    /// Polach's method (1999; spin included).
    Polach,
}

/// FastSim_A's treatment of the sliding zones.
#[derive(Debug, Clone, Copy, PartialEq, Eq, clap::ValueEnum)]
pub enum Sliding {
    /// Adhesion-continuation direction in closed form (fastest).
    Continuation,
    /// Sliding zone integrated node to node, with re-adhesion.
    Integrated,
    /// One Picard step from the continuation direction.
    Picard,
}

/// Arguments of `umsim creep`.
#[derive(Debug, clap::Args)]
pub struct Args {
    /// Creep-force law.
    #[arg(long, value_enum)]
    pub method: Method,
    /// Number of strips (FASTSIM: default 10, FastSim_A: default 20, as in
    /// model files and `umsim bench --creep`).
    #[arg(long)]
    pub strips: Option<usize>,
    /// Number of elements per strip (FASTSIM).
    #[arg(long, default_value_t = 10)]
    pub elements: usize,
    /// FastSim_A's treatment of the sliding zones.
    #[arg(long, value_enum, default_value_t = Sliding::Continuation)]
    pub sliding: Sliding,
    /// Gauss nodes per sliding zone (FastSim_A with `--sliding integrated|picard`).
    #[arg(long, default_value_t = railmbs_wheelrail::creep::INTEGRATED_NODES)]
    pub nodes: usize,
    /// Input CSV with columns a,b,G,nu,mu,N,xi,eta,phi.
    #[arg(long)]
    pub cases: PathBuf,
    /// Output CSV (Fx,Fy,Mz); standard output if omitted.
    #[arg(short = 'o', long)]
    pub output: Option<PathBuf>,
}

const COLUMNS: [&str; 9] = ["a", "b", "G", "nu", "mu", "N", "xi", "eta", "phi"];

/// Builds the law for the arguments (FastSim_A with the continuation
/// direction).
pub fn law(method: Method, strips: usize, elements: usize) -> Result<Box<dyn CreepLaw>, String> {
    law_with_sliding(method, strips, elements, Sliding::Continuation, 0)
}

/// Builds the law for the arguments, FastSim_A with the given sliding-zone
/// treatment and Gauss nodes per zone.
pub fn law_with_sliding(
    method: Method,
    strips: usize,
    elements: usize,
    sliding: Sliding,
    nodes: usize,
) -> Result<Box<dyn CreepLaw>, String> {
    let err = |e: railmbs_wheelrail::creep::CreepError| e.to_string();
    Ok(match method {
        Method::Kalker => Box::new(KalkerLinear),
        Method::Mueller => Box::new(Mueller::default()),
        Method::Fastsim => Box::new(Fastsim::new(strips, elements).map_err(err)?),
        Method::FastsimA => {
            let zone = match sliding {
                Sliding::Continuation => SlidingZone::Continuation,
                Sliding::Integrated => SlidingZone::Integrated { nodes },
                Sliding::Picard => SlidingZone::Picard { nodes },
            };
            Box::new(
                FastsimA::new(strips)
                    .and_then(|l| l.with_sliding(zone))
                    .map_err(err)?,
            )
        }
        Method::Polach => Box::new(Polach::new()),
    })
}

/// Evaluates every case of the CSV in `input` with `law` and writes `Fx,Fy,Mz`
/// rows to `output`. `source` names the input in error messages.
pub fn evaluate<R: Read, W: Write>(
    law: &dyn CreepLaw,
    input: R,
    source: &str,
    output: W,
) -> Result<usize, String> {
    let mut rd = csv::ReaderBuilder::new()
        .trim(csv::Trim::All)
        .comment(Some(b'#'))
        .from_reader(input);
    let header = rd
        .headers()
        .map_err(|e| format!("{source}: cannot read the header: {e}"))?
        .clone();
    let mut idx = [0usize; 9];
    for (k, name) in COLUMNS.iter().enumerate() {
        idx[k] = header.iter().position(|h| h == *name).ok_or_else(|| {
            format!(
                "{source}: missing column '{name}' (need {}; found {})",
                COLUMNS.join(","),
                header.iter().collect::<Vec<_>>().join(",")
            )
        })?;
    }
    let mut wr = csv::Writer::from_writer(output);
    wr.write_record(["Fx", "Fy", "Mz"])
        .map_err(|e| format!("cannot write output: {e}"))?;
    let mut n = 0;
    for (row, rec) in rd.records().enumerate() {
        let row = row + 1;
        let rec = rec.map_err(|e| format!("{source}: row {row}: {e}"))?;
        let line = rec.position().map_or(0, |p| p.line());
        let mut v = [0.0; 9];
        for k in 0..9 {
            let s = rec.get(idx[k]).unwrap_or("");
            v[k] = s.parse::<f64>().map_err(|_| {
                format!(
                    "{source}: row {row} (line {line}), column '{}': '{s}' is not a number",
                    COLUMNS[k]
                )
            })?;
        }
        let patch = ContactPatch {
            a: v[0],
            b: v[1],
            g: v[2],
            nu: v[3],
            mu: v[4],
            n: v[5],
        };
        let c = Creepages {
            xi: v[6],
            eta: v[7],
            phi: v[8],
        };
        let f = law
            .forces(&patch, &c)
            .map_err(|e| format!("{source}: row {row} (line {line}): {e}"))?;
        // `+ 0.0` turns −0 into 0 in the output.
        wr.write_record([
            (f.fx + 0.0).to_string(),
            (f.fy + 0.0).to_string(),
            (f.mz + 0.0).to_string(),
        ])
        .map_err(|e| format!("cannot write output: {e}"))?;
        n += 1;
    }
    wr.flush()
        .map_err(|e| format!("cannot write output: {e}"))?;
    Ok(n)
}

/// Runs `umsim creep`.
pub fn run(args: &Args) -> Result<(), Box<dyn std::error::Error>> {
    let strips = args.strips.unwrap_or(match args.method {
        Method::FastsimA => railmbs_wheelrail::creep::FASTSIM_A_STRIPS,
        _ => railmbs_wheelrail::creep::FASTSIM_DIVISIONS,
    });
    let law = law_with_sliding(
        args.method,
        strips,
        args.elements,
        args.sliding,
        args.nodes,
    )?;
    let source = args.cases.display().to_string();
    let file = std::fs::File::open(&args.cases).map_err(|e| format!("{source}: {e}"))?;
    match &args.output {
        Some(path) => {
            let out = std::fs::File::create(path)
                .map_err(|e| format!("{}: cannot create: {e}", path.display()))?;
            evaluate(law.as_ref(), file, &source, std::io::BufWriter::new(out))?;
        }
        None => {
            evaluate(law.as_ref(), file, &source, std::io::stdout().lock())?;
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn run_str(method: Method, input: &str) -> Result<String, String> {
        let law = law(method, 10, 10)?;
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
            Method::Kalker,
            Method::Mueller,
            Method::Fastsim,
            Method::FastsimA,
            Method::Polach,
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
        let out = run_str(Method::Kalker, input).unwrap();
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
        let e = run_str(
            Method::Kalker,
            "a,b,G,nu,mu,N,xi,eta\n1,1,1,0.3,0.3,1,0,0\n",
        )
        .unwrap_err();
        assert!(e.contains("missing column 'phi'"), "{e}");
        let e = run_str(
            Method::Fastsim,
            "a,b,G,nu,mu,N,xi,eta,phi\n0.006,0.004,8e10,0.28,0.3,80000,0,0,0\n0.006,x,8e10,0.28,0.3,80000,0,0,0\n",
        )
        .unwrap_err();
        assert!(e.contains("row 2") && e.contains("column 'b'"), "{e}");
        let e = run_str(
            Method::FastsimA,
            "a,b,G,nu,mu,N,xi,eta,phi\n0.006,0.004,8e10,0.9,0.3,80000,0,0,0\n",
        )
        .unwrap_err();
        assert!(e.contains("row 1") && e.contains("nu = 0.9"), "{e}");
        assert!(law(Method::Fastsim, 0, 10).is_err());
    }
}
