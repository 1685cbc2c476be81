//! Where output rows go: an [`OutputSink`] receives the header once, then
//! every row in time order, then the end of the run. [`CsvFile`] writes what
//! `umsim run` writes; [`Table`] keeps the columns in memory by name;
//! [`Discard`] only counts; [`AssessmentReducer`](super::AssessmentReducer)
//! reduces the accepted steps' wheel loads to the EN 14363 table.

use super::{LoadSample, RunError};
use std::io::Write;
use std::path::{Path, PathBuf};

/// A receiver of a run's output rows.
pub trait OutputSink {
    /// The column names (units in brackets), once, before the first row.
    ///
    /// # Errors
    /// The sink's own (a file that cannot be written).
    fn begin(&mut self, header: &[String]) -> Result<(), RunError>;

    /// One row: a value per column of the header, the first the time (s).
    ///
    /// # Errors
    /// The sink's own; the run then stops and returns the error.
    fn row(&mut self, values: &[f64]) -> Result<(), RunError>;

    /// The wheel loads of an accepted step, one sample per wheel–rail
    /// element (`name` gives an element's long name by key). Ignored by
    /// default; [`AssessmentReducer`](super::AssessmentReducer) reduces them.
    fn accepted_loads(&mut self, _samples: &[LoadSample], _name: &dyn Fn(usize) -> String) {}

    /// The end of the run (also after a simulation error): flush.
    ///
    /// # Errors
    /// The sink's own.
    fn finish(&mut self) -> Result<(), RunError> {
        Ok(())
    }
}

impl<T: OutputSink + ?Sized> OutputSink for &mut T {
    fn begin(&mut self, header: &[String]) -> Result<(), RunError> {
        (**self).begin(header)
    }

    fn row(&mut self, values: &[f64]) -> Result<(), RunError> {
        (**self).row(values)
    }

    fn accepted_loads(&mut self, samples: &[LoadSample], name: &dyn Fn(usize) -> String) {
        (**self).accepted_loads(samples, name);
    }

    fn finish(&mut self) -> Result<(), RunError> {
        (**self).finish()
    }
}

/// Capacity of a [`CsvFile`]'s write buffer, bytes.
const CSV_BUFFER_BYTES: usize = 1 << 18;

/// A CSV file: the header line, then one line per row with each value in
/// Rust's shortest round-trip form (`{}`), comma-separated.
#[derive(Debug)]
pub struct CsvFile {
    path: PathBuf,
    writer: Option<std::io::BufWriter<std::fs::File>>,
    /// Reusable text of one row.
    line: String,
}

impl CsvFile {
    /// A sink that creates `path` (and its folder) at [`OutputSink::begin`].
    pub fn new(path: impl Into<PathBuf>) -> Self {
        Self {
            path: path.into(),
            writer: None,
            line: String::new(),
        }
    }

    /// The file's path.
    pub fn path(&self) -> &Path {
        &self.path
    }

    /// Fails when the output file is one of `inputs` (the scenario, model
    /// or track file a run reads): `-o scenario.ron` must not replace the
    /// scenario by its results.
    ///
    /// # Errors
    /// [`RunError::Setup`] naming the file and what it is.
    pub fn refuse_inputs<'p>(
        &self,
        inputs: impl IntoIterator<Item = (&'p str, &'p Path)>,
    ) -> Result<(), RunError> {
        for (what, input) in inputs {
            // Both must exist to be the same file; a new output is none.
            if same_file::is_same_file(&self.path, input).unwrap_or(false) {
                return Err(RunError::Setup {
                    file: self.path.clone(),
                    message: format!(
                        "the output file is the run's {what} ({}); choose another output file",
                        input.display()
                    ),
                });
            }
        }
        Ok(())
    }

    fn io(&self, source: std::io::Error) -> RunError {
        RunError::Io {
            path: self.path.clone(),
            source,
        }
    }
}

impl OutputSink for CsvFile {
    fn begin(&mut self, header: &[String]) -> Result<(), RunError> {
        let p = &self.path;
        if let Some(dir) = p.parent().filter(|d| !d.as_os_str().is_empty()) {
            std::fs::create_dir_all(dir).map_err(|source| RunError::Io {
                path: dir.to_path_buf(),
                source,
            })?;
        }
        let file = std::fs::File::create(p).map_err(|e| self.io(e))?;
        // A row of a vehicle run is a few kB: a larger buffer than the
        // default 8 kB writes it to the file in fewer system calls.
        let mut w = std::io::BufWriter::with_capacity(CSV_BUFFER_BYTES, file);
        writeln!(w, "{}", header.join(",")).map_err(|e| self.io(e))?;
        self.writer = Some(w);
        Ok(())
    }

    fn row(&mut self, values: &[f64]) -> Result<(), RunError> {
        let Some(w) = self.writer.as_mut() else {
            return Ok(());
        };
        self.line.clear();
        let mut digits = ryu::Buffer::new();
        for (k, &x) in values.iter().enumerate() {
            if k > 0 {
                self.line.push(',');
            }
            push_display(&mut self.line, x, &mut digits);
        }
        self.line.push('\n');
        w.write_all(self.line.as_bytes()).map_err(|e| self.io(e))
    }

    fn finish(&mut self) -> Result<(), RunError> {
        if let Some(mut w) = self.writer.take() {
            w.flush().map_err(|e| self.io(e))?;
        }
        Ok(())
    }
}

/// Appends `x` to `out` exactly as `write!(out, "{x}")` (Rust's `Display`
/// of `f64`: the shortest digits that read back as `x`, the closest to `x`
/// among those, laid out without an exponent), faster: where it is safe the
/// digits come from Ryū (`digits`, a reusable buffer), else from `{}`.
///
/// Both algorithms return the shortest digit string in `x`'s rounding
/// interval (the same interval: its ends included for an even mantissa) and,
/// of those, the closest to `x`; they can differ only in a tie, two shortest
/// candidates equally far from `x`, which Ryū breaks to even and Rust's
/// Dragon4 upwards. A tie at n ≤ 17 digits means x = (2c + 1)·10^E/2 for
/// an integer c < 10^17. Writing x = m·2^e with m odd, this needs e = E − 1
/// and, for E < 0, m·5^(−E) = 2c + 1 < 2·10^17 < 5^25, so −E ≤ 24 and
/// e ≥ −25; for E ≥ 0, e ≥ −1. So x with e ≤ −26 (all non-round values
/// below 2^26 ≈ 6.7e7 in magnitude, the bulk of a run's output) has no tie
/// and takes Ryū; zero, non-finite and other values take `{}`. The layout
/// is Rust's: Ryū's exponent form d.ddde−N (|x| < 1e−5) is written out as
/// 0.000…ddd. Tested against `{}` bit pattern by bit pattern.
pub(crate) fn push_display(out: &mut String, x: f64, digits: &mut ryu::Buffer) {
    use std::fmt::Write as _;
    if !ryu_is_exact_display(x) {
        let _ = write!(out, "{x}");
        return;
    }
    let s = digits.format_finite(x);
    let Some((mantissa, exponent)) = s.split_once('e') else {
        // "123.456" or "0.00123": Rust's layout. (An integer, "123.0",
        // cannot come from x = m·2^e with m odd, e < 0 and |x| < 2^27,
        // where every integer is a double of its own.)
        if s.ends_with(".0") {
            let _ = write!(out, "{x}");
        } else {
            out.push_str(s);
        }
        return;
    };
    // d.ddde-N or de-N: x = 0.dddd × 10^(1 − N).
    let (sign, mantissa) = match mantissa.strip_prefix('-') {
        Some(m) => ("-", m),
        None => ("", mantissa),
    };
    let zeros = match exponent.parse::<i32>() {
        Ok(k) if k < 0 => (-k - 1) as usize,
        // (|x| < 2^27 has no positive exponent.)
        _ => {
            let _ = write!(out, "{x}");
            return;
        }
    };
    out.push_str(sign);
    out.push_str("0.");
    out.extend(std::iter::repeat_n('0', zeros));
    out.extend(mantissa.chars().filter(|&c| c != '.'));
}

/// Whether `x` = m·2^e (m odd) has e ≤ −26, where Ryū's shortest digits
/// are those of `{}` (see [`push_display`]).
fn ryu_is_exact_display(x: f64) -> bool {
    let bits = x.to_bits();
    let biased = ((bits >> 52) & 0x7ff) as i32;
    let fraction = bits & ((1 << 52) - 1);
    if biased == 0x7ff {
        return false;
    }
    let (m, e) = if biased == 0 {
        (fraction, -1074)
    } else {
        (fraction | 1 << 52, biased - 1075)
    };
    m != 0 && e + m.trailing_zeros() as i32 <= -26
}

/// Output columns in memory, by name (for studies and bindings).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Table {
    names: Vec<String>,
    columns: Vec<Vec<f64>>,
}

impl Table {
    /// An empty table; [`OutputSink::begin`] sets its columns.
    pub fn new() -> Self {
        Self::default()
    }

    /// Column names in order (the CSV header).
    pub fn names(&self) -> &[String] {
        &self.names
    }

    /// The column `name` (values in its unit, one per row), if there is one.
    pub fn column(&self, name: &str) -> Option<&[f64]> {
        let k = self.names.iter().position(|n| n == name)?;
        Some(&self.columns[k])
    }

    /// All columns, in header order.
    pub fn columns(&self) -> &[Vec<f64>] {
        &self.columns
    }

    /// The columns, in header order, without copying them (for bindings
    /// that hand them on, e.g. as numpy arrays).
    pub fn into_columns(self) -> Vec<Vec<f64>> {
        self.columns
    }

    /// Number of rows.
    pub fn rows(&self) -> usize {
        self.columns.first().map_or(0, Vec::len)
    }
}

impl OutputSink for Table {
    fn begin(&mut self, header: &[String]) -> Result<(), RunError> {
        self.names = header.to_vec();
        self.columns = vec![Vec::new(); header.len()];
        Ok(())
    }

    fn row(&mut self, values: &[f64]) -> Result<(), RunError> {
        for (c, &x) in self.columns.iter_mut().zip(values) {
            c.push(x);
        }
        Ok(())
    }
}

/// A sink that drops every row (the runner still counts them).
#[derive(Debug, Clone, Copy, Default)]
pub struct Discard;

impl OutputSink for Discard {
    fn begin(&mut self, _header: &[String]) -> Result<(), RunError> {
        Ok(())
    }

    fn row(&mut self, _values: &[f64]) -> Result<(), RunError> {
        Ok(())
    }
}

/// A sink that stops the run at the next row once `flag` is set (by a
/// Ctrl-C handler, say), with [`RunError::Interrupted`] naming the time of
/// the last row written; everything before is kept (the inner sink is
/// finished as after any stop).
#[derive(Debug)]
pub struct Interruptible<S> {
    inner: S,
    flag: std::sync::Arc<std::sync::atomic::AtomicBool>,
    rows: usize,
    last_time: Option<f64>,
}

impl<S: OutputSink> Interruptible<S> {
    /// `inner`, stopped when `flag` becomes true.
    pub fn new(inner: S, flag: std::sync::Arc<std::sync::atomic::AtomicBool>) -> Self {
        Self {
            inner,
            flag,
            rows: 0,
            last_time: None,
        }
    }
}

impl<S: OutputSink> OutputSink for Interruptible<S> {
    fn begin(&mut self, header: &[String]) -> Result<(), RunError> {
        self.inner.begin(header)
    }

    fn row(&mut self, values: &[f64]) -> Result<(), RunError> {
        if self.flag.load(std::sync::atomic::Ordering::Relaxed) {
            return Err(RunError::Interrupted {
                rows: self.rows,
                last_time: self.last_time,
            });
        }
        self.inner.row(values)?;
        self.rows += 1;
        self.last_time = values.first().copied();
        Ok(())
    }

    fn accepted_loads(&mut self, samples: &[LoadSample], name: &dyn Fn(usize) -> String) {
        self.inner.accepted_loads(samples, name);
    }

    fn finish(&mut self) -> Result<(), RunError> {
        self.inner.finish()
    }
}

#[cfg(test)]
mod tests {
    use super::push_display;

    /// `push_display` of `x` against `write!("{x}")`, byte for byte.
    fn check(x: f64, digits: &mut ryu::Buffer, line: &mut String) {
        line.clear();
        push_display(line, x, digits);
        assert_eq!(*line, format!("{x}"), "bits {:#018x}", x.to_bits());
    }

    /// SplitMix64 (Steele, Lea & Flood 2014): a fixed, seeded sequence.
    fn splitmix(state: &mut u64) -> u64 {
        *state = state.wrapping_add(0x9e37_79b9_7f4a_7c15);
        let mut z = *state;
        z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
        z ^ (z >> 31)
    }

    #[test]
    fn display_digits_equal_rusts_display() {
        let (mut digits, mut line) = (ryu::Buffer::new(), String::new());
        let mut c = |x: f64| check(x, &mut digits, &mut line);
        // Specials, extremes, subnormals.
        for x in [
            0.0,
            -0.0,
            f64::NAN,
            f64::INFINITY,
            f64::NEG_INFINITY,
            f64::MAX,
            f64::MIN,
            f64::MIN_POSITIVE,
            f64::EPSILON,
            5e-324,
            -5e-324,
            2.225e-308,
        ] {
            c(x);
        }
        // Powers of ten and their neighbours (the layout's switch at 1e-5,
        // digit counts), both signs.
        for k in -40..=40 {
            let p = 10f64.powi(k);
            for x in [
                p,
                p.next_up(),
                p.next_down(),
                1.5 * p,
                9.999_999_999_999_999 * p,
            ] {
                c(x);
                c(-x);
            }
        }
        // The time column and other decimal grids.
        for k in 0..200_000 {
            c(k as f64 * 0.01);
            c(k as f64 * 1e-7);
            c(-(k as f64) / 3.0);
        }
        // Both sides of the Ryū/`{}` boundary m·2^e, e = −26 (odd m): the
        // values nearest to a tie that take Ryū.
        let mut s = 20_261_202_u64;
        for _ in 0..200_000 {
            let m = (splitmix(&mut s) >> (11 + splitmix(&mut s) % 50)) | 1;
            for e in [-27, -26, -25, -24] {
                c(m as f64 * 2f64.powi(e));
            }
        }
        // Random mantissas at the exponents of a run's output (|x| from
        // 1e-18 to 1.3e8), then any bit pattern.
        for _ in 0..2_000_000 {
            let r = splitmix(&mut s);
            let biased = 1023 - 60 + (r >> 52) % 87;
            c(f64::from_bits(
                (r & ((1 << 52) - 1)) | biased << 52 | (r >> 63) << 63,
            ));
            c(f64::from_bits(splitmix(&mut s)));
        }
    }
}
