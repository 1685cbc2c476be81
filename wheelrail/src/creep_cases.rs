//! Tables of contact cases for creep laws (`umsim creep --cases`): a CSV with
//! the columns [`COLUMNS`] in any order, by header name, in m, m, Pa, –, –, N,
//! –, –, 1/m; `#` starts a comment line. A bad row is an error naming the row
//! (data row number, 1-based, and file line) and the column.

use crate::creep::{ContactPatch, Creepages};
use std::io::Read;

/// The columns of a cases file: semi-axes `a`, `b` (m), combined shear
/// modulus `G` (Pa), Poisson ratio `nu` (–), friction coefficient `mu` (–),
/// normal force `N` (N), creepages `xi`, `eta` (–) and spin `phi` (1/m).
pub const COLUMNS: [&str; 9] = ["a", "b", "G", "nu", "mu", "N", "xi", "eta", "phi"];

/// One case of a cases file: the patch, the creepages, and where it is (data
/// row, 1-based, and file line) for messages.
pub struct Case {
    /// The contact patch (semi-axes m, modulus Pa, friction, normal force N).
    pub patch: ContactPatch,
    /// The creepages (ξ, η –; φ 1/m).
    pub creepages: Creepages,
    /// Data row, 1-based.
    pub row: usize,
    /// Line in the file.
    pub line: u64,
}

/// Reads every case of the CSV in `input`; `source` names it in messages.
pub fn read_cases<R: Read>(input: R, source: &str) -> Result<Vec<Case>, String> {
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
    let mut cases = Vec::new();
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
        cases.push(Case {
            patch: ContactPatch {
                a: v[0],
                b: v[1],
                g: v[2],
                nu: v[3],
                mu: v[4],
                n: v[5],
            },
            creepages: Creepages {
                xi: v[6],
                eta: v[7],
                phi: v[8],
            },
            row,
            line,
        });
    }
    Ok(cases)
}
