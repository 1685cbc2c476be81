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

    /// How far `other`'s coordinate columns are from this table's, in
    /// integration tolerances: the largest |x − y| / (`atol` + `rtol` |x|)
    /// over every row and every column but `time` and those with a unit in
    /// brackets (forces, speeds: the coordinates are m and rad, the
    /// quantities the integrator's tolerances hold), with its column; and
    /// whether any value of any column differs at all. Panics if the two
    /// have different headers or numbers of rows.
    pub fn coordinate_difference(&self, other: &Table, rtol: f64, atol: f64) -> Difference {
        assert_eq!(
            self.header, other.header,
            "the runs write different columns"
        );
        assert_eq!(
            self.rows.len(),
            other.rows.len(),
            "the runs write different rows"
        );
        let mut d = Difference {
            tolerances: 0.0,
            column: String::new(),
            differs: false,
        };
        for (ra, rb) in self.rows.iter().zip(&other.rows) {
            for (k, (x, y)) in ra.iter().zip(rb).enumerate() {
                d.differs |= x != y;
                if self.header[k].ends_with(']') || self.header[k] == "time" {
                    continue;
                }
                let e = (x - y).abs() / (atol + rtol * x.abs());
                if e > d.tolerances {
                    (d.tolerances, d.column) = (e, self.header[k].clone());
                }
            }
        }
        eprintln!(
            "largest difference {} tolerances ({})",
            d.tolerances, d.column
        );
        d
    }
}

/// [`Table::coordinate_difference`]'s result.
#[derive(Debug, Clone)]
pub struct Difference {
    /// The largest difference of a coordinate, in tolerances.
    pub tolerances: f64,
    /// The column where it is.
    pub column: String,
    /// Whether any value of any column differs (bit for bit).
    pub differs: bool,
}
