//! The CSV output of a run (`umsim run`, `run_scenario`, `run_train`) read
//! back as columns by name.

use std::path::Path;

/// Columns of a run's CSV output.
pub struct Table {
    /// Column names, `time` first.
    pub header: Vec<String>,
    /// One row of values per output time.
    pub rows: Vec<Vec<f64>>,
}

impl Table {
    /// Reads a CSV file written by a run (numbers only after the header).
    pub fn read(path: &Path) -> Table {
        let text =
            std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        Table::parse(&text)
    }

    /// Parses CSV text: a header line, then rows of numbers.
    pub fn parse(text: &str) -> Table {
        let mut lines = text.lines();
        let header = lines
            .next()
            .expect("a header line")
            .split(',')
            .map(str::to_string)
            .collect();
        let rows = lines
            .map(|l| {
                l.split(',')
                    .map(|x| x.parse().unwrap_or_else(|e| panic!("{x:?}: {e}")))
                    .collect()
            })
            .collect();
        Table { header, rows }
    }

    /// Index of the column `name`; panics naming it and the header if absent.
    pub fn index(&self, name: &str) -> usize {
        self.header
            .iter()
            .position(|h| h == name)
            .unwrap_or_else(|| panic!("no column {name} in {:?}", self.header))
    }

    /// The column `name`.
    pub fn col(&self, name: &str) -> Vec<f64> {
        let k = self.index(name);
        self.rows.iter().map(|r| r[k]).collect()
    }
}
