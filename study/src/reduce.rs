//! Per-case reductions to scalars, computed while the run streams its rows
//! (the [`CaseReducer`] sink), and the assessment from the run's own table.

use railmbs_runtime::analysis::critical::{DetectionSettings, LimitCycleDetector};
use railmbs_runtime::forces::Assessment;
use railmbs_runtime::run::{LoadSample, OutputSink, RunError};
use serde::Deserialize;

/// Where a column reduction looks.
#[derive(Debug, Clone, Copy, PartialEq, Deserialize)]
pub enum Window {
    /// Output rows with t0 ≤ t ≤ t1, s.
    Time(f64, f64),
    /// Output rows with s0 ≤ s ≤ s1 (the `s[m]` column of a run on a track), m.
    Distance(f64, f64),
}

impl Window {
    pub(crate) fn check(&self) -> Result<(), String> {
        let (a, b) = match self {
            Window::Time(a, b) | Window::Distance(a, b) => (*a, *b),
        };
        if a.is_finite() && b.is_finite() && a <= b {
            Ok(())
        } else {
            Err(format!(
                "a window is (from, to) with from ≤ to, both finite; got ({a}, {b})"
            ))
        }
    }

    fn label(&self) -> String {
        match self {
            Window::Time(a, b) => format!("; t {a}..{b} s"),
            Window::Distance(a, b) => format!("; s {a}..{b} m"),
        }
    }
}

/// The statistic of a column reduction.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Stat {
    /// Largest value.
    Max,
    /// Smallest value.
    Min,
    /// Largest absolute value.
    MaxAbs,
    /// Root mean square over the rows.
    Rms,
}

impl Stat {
    fn name(self) -> &'static str {
        match self {
            Stat::Max => "max",
            Stat::Min => "min",
            Stat::MaxAbs => "maxabs",
            Stat::Rms => "rms",
        }
    }
}

/// What a reduction computes.
#[derive(Debug, Clone, PartialEq)]
pub enum ReductionKind {
    /// The EN 14363 quantities over all wheelsets (see the crate docs).
    Assessment,
    /// A statistic of a column (or of the columns a glob matches).
    Column {
        /// Which statistic.
        stat: Stat,
        /// Column name or glob.
        column: String,
        /// The rows it looks at (all without one).
        window: Option<Window>,
    },
    /// The speed where the limit cycle of `column` dies out (crate docs).
    CriticalSpeed {
        /// The column (a lateral displacement, say).
        column: String,
        /// Amplitude threshold, the column's unit.
        amplitude: f64,
        /// Length of the amplitude window, s.
        window: f64,
    },
}

/// One reduction of a study, with the name of its result column(s).
#[derive(Debug, Clone, PartialEq)]
pub struct Reduction {
    /// What it computes.
    pub kind: ReductionKind,
    /// Name of its (first) result column.
    pub name: String,
}

/// The assessment's result columns.
const ASSESSMENT_COLUMNS: [&str; 15] = [
    "YQ.max",
    "YQ.limit",
    "YQ.element",
    "YQ.t[s]",
    "YQ.s[m]",
    "sumY.max[N]",
    "sumY.limit[N]",
    "sumY.element",
    "sumY.t[s]",
    "sumY.s[m]",
    "Q.max[N]",
    "Q.max.element",
    "Q.min[N]",
    "Q.min.element",
    "assessment.wheelsets",
];

/// Whether a column pattern has wildcards (`*`, `?`); brackets are part of
/// the column names (units) and match literally.
pub(crate) fn is_glob(pattern: &str) -> bool {
    pattern.contains(['*', '?'])
}

/// The matcher of a column pattern: `*` and `?` are wildcards, every other
/// character (the brackets of units included) matches itself.
pub(crate) fn column_matcher(pattern: &str) -> Result<globset::GlobMatcher, globset::Error> {
    let mut escaped = String::new();
    for c in pattern.chars() {
        if matches!(c, '[' | ']' | '{' | '}' | '\\') {
            escaped.push('\\');
        }
        escaped.push(c);
    }
    Ok(globset::GlobBuilder::new(&escaped)
        .backslash_escape(true)
        .build()?
        .compile_matcher())
}

impl Reduction {
    /// A reduction named `name`, or by default after what it computes
    /// (`max(COLUMN)`, `rms(COLUMN; s 0..50 m)`, `critical_speed(COLUMN)[m/s]`).
    pub fn new(kind: ReductionKind, name: Option<String>) -> Self {
        let name = name.unwrap_or_else(|| match &kind {
            ReductionKind::Assessment => "assessment".into(),
            ReductionKind::Column {
                stat,
                column,
                window,
            } => format!(
                "{}({column}{})",
                stat.name(),
                window.as_ref().map(Window::label).unwrap_or_default()
            ),
            ReductionKind::CriticalSpeed { column, .. } => {
                format!("critical_speed({column})[m/s]")
            }
        });
        Reduction { kind, name }
    }

    /// Its result columns.
    pub fn columns(&self) -> Vec<String> {
        match &self.kind {
            ReductionKind::Assessment => ASSESSMENT_COLUMNS.map(String::from).to_vec(),
            ReductionKind::Column { stat, column, .. } => {
                let mut c = vec![self.name.clone()];
                if *stat != Stat::Rms {
                    c.push(format!("{}.t[s]", self.name));
                }
                if is_glob(column) {
                    c.push(format!("{}.column", self.name));
                }
                c
            }
            ReductionKind::CriticalSpeed { .. } => vec![self.name.clone()],
        }
    }
}

/// A cell of the result table.
#[derive(Debug, Clone, PartialEq)]
pub enum Cell {
    /// A finite number.
    Num(f64),
    /// Text (a name, an error).
    Text(String),
    /// Nothing (not computed, or not finite).
    Empty,
}

impl Cell {
    /// A number, empty unless finite.
    pub fn num(x: f64) -> Cell {
        if x.is_finite() {
            Cell::Num(x)
        } else {
            Cell::Empty
        }
    }

    /// As written in the CSV: numbers in shortest round-trip form.
    pub fn text(&self) -> String {
        match self {
            Cell::Num(x) => format!("{x}"),
            Cell::Text(s) => s.clone(),
            Cell::Empty => String::new(),
        }
    }

    /// The number, if one.
    pub fn as_f64(&self) -> Option<f64> {
        match self {
            Cell::Num(x) => Some(*x),
            _ => None,
        }
    }
}

/// The running state of a column statistic over one matched column.
#[derive(Debug, Clone)]
struct Accumulator {
    best: f64,
    best_t: f64,
    sum_sq: f64,
    count: usize,
}

impl Accumulator {
    fn new() -> Self {
        Accumulator {
            best: f64::NAN,
            best_t: f64::NAN,
            sum_sq: 0.0,
            count: 0,
        }
    }

    fn push(&mut self, stat: Stat, t: f64, x: f64) {
        self.count += 1;
        self.sum_sq += x * x;
        let key = match stat {
            Stat::Max | Stat::Rms => x,
            Stat::Min => -x,
            Stat::MaxAbs => x.abs(),
        };
        let best_key = match stat {
            Stat::Min => -self.best,
            Stat::MaxAbs => self.best.abs(),
            _ => self.best,
        };
        if self.count == 1 || key > best_key {
            self.best = if stat == Stat::MaxAbs { x.abs() } else { x };
            self.best_t = t;
        }
    }

    /// The statistic's value.
    fn value(&self, stat: Stat) -> f64 {
        if self.count == 0 {
            return f64::NAN;
        }
        match stat {
            Stat::Rms => (self.sum_sq / self.count as f64).sqrt(),
            _ => self.best,
        }
    }
}

/// A column reduction bound to the columns of a run.
#[derive(Debug)]
struct ColumnState {
    stat: Stat,
    window: Option<Window>,
    /// (column index, its name, accumulator) per matched column.
    columns: Vec<(usize, String, Accumulator)>,
}

/// The critical-speed criterion bound to a column: the runtime's
/// limit-cycle detection (the one `umsim critical-speed` uses).
#[derive(Debug)]
struct CriticalState {
    column: usize,
    speed: usize,
    distance: Option<usize>,
    detector: LimitCycleDetector,
}

impl CriticalState {
    fn push(&mut self, values: &[f64]) {
        let s = self.distance.map(|k| values[k]);
        self.detector
            .push(values[0], values[self.speed], s, &[values[self.column]]);
    }

    fn value(&self) -> f64 {
        self.detector.detection().speed().unwrap_or(f64::NAN)
    }
}

/// The state of one reduction during a run.
#[derive(Debug)]
enum State {
    Assessment,
    Column(ColumnState),
    Critical(CriticalState),
}

/// The sink that reduces a case's rows while the run streams them; the
/// rows are also passed to an optional inner sink (the case's CSV file).
pub(crate) struct CaseReducer<'a> {
    reductions: &'a [Reduction],
    states: Vec<State>,
    /// Index of the `s[m]` column.
    distance: Option<usize>,
    /// (t, s) of every row, for the distance of the assessment's maxima.
    path: Vec<(f64, f64)>,
    inner: Option<&'a mut dyn OutputSink>,
    /// A reduction that does not fit the run's columns.
    pub(crate) setup_error: Option<String>,
}

impl<'a> CaseReducer<'a> {
    pub(crate) fn new(reductions: &'a [Reduction], inner: Option<&'a mut dyn OutputSink>) -> Self {
        CaseReducer {
            reductions,
            states: Vec::new(),
            distance: None,
            path: Vec::new(),
            inner,
            setup_error: None,
        }
    }

    fn bind(&mut self, header: &[String]) -> Result<(), String> {
        let index = |name: &str| header.iter().position(|h| h == name);
        self.distance = index("s[m]");
        for r in self.reductions {
            let state = match &r.kind {
                ReductionKind::Assessment => State::Assessment,
                ReductionKind::Column {
                    stat,
                    column,
                    window,
                } => {
                    let glob = column_matcher(column).map_err(|e| format!("{}: {e}", r.name))?;
                    let columns: Vec<_> = header
                        .iter()
                        .enumerate()
                        .skip(1)
                        .filter(|(_, h)| glob.is_match(h.as_str()))
                        .map(|(k, h)| (k, h.clone(), Accumulator::new()))
                        .collect();
                    if columns.is_empty() {
                        return Err(format!(
                            "reduction \"{}\": no output column matches \"{column}\" \
                             (the scenario's `output` selects the columns; `umsim info` lists them)",
                            r.name
                        ));
                    }
                    if matches!(window, Some(Window::Distance(..))) && self.distance.is_none() {
                        return Err(format!(
                            "reduction \"{}\": a distance window needs a run on a track (column s[m])",
                            r.name
                        ));
                    }
                    State::Column(ColumnState {
                        stat: *stat,
                        window: *window,
                        columns,
                    })
                }
                ReductionKind::CriticalSpeed {
                    column,
                    amplitude,
                    window,
                } => {
                    let Some(c) = index(column) else {
                        return Err(format!(
                            "reduction \"{}\": no output column \"{column}\"",
                            r.name
                        ));
                    };
                    let Some(speed) = index("v[m/s]") else {
                        return Err(format!(
                            "reduction \"{}\": needs a run on a track (column v[m/s])",
                            r.name
                        ));
                    };
                    let detector =
                        LimitCycleDetector::new(DetectionSettings::new(*window, *amplitude))
                            .map_err(|e| format!("reduction \"{}\": {e}", r.name))?;
                    State::Critical(CriticalState {
                        column: c,
                        speed,
                        distance: index("s[m]"),
                        detector,
                    })
                }
            };
            self.states.push(state);
        }
        Ok(())
    }

    /// The result cells of every reduction (in [`Reduction::columns`]
    /// order), with the run's assessment table.
    pub(crate) fn cells(&self, assessment: &[Assessment]) -> Vec<Cell> {
        let mut out = Vec::new();
        for (r, s) in self.reductions.iter().zip(&self.states) {
            match s {
                State::Assessment => out.extend(self.assessment_cells(assessment)),
                State::Column(c) => {
                    let best = c
                        .columns
                        .iter()
                        .filter(|(_, _, a)| a.count > 0)
                        .max_by(|a, b| {
                            let (x, y) = (a.2.value(c.stat), b.2.value(c.stat));
                            let (x, y) = if c.stat == Stat::Min {
                                (-x, -y)
                            } else {
                                (x, y)
                            };
                            x.total_cmp(&y)
                        });
                    out.push(best.map_or(Cell::Empty, |b| Cell::num(b.2.value(c.stat))));
                    if c.stat != Stat::Rms {
                        out.push(best.map_or(Cell::Empty, |b| Cell::num(b.2.best_t)));
                    }
                    if let ReductionKind::Column { column, .. } = &r.kind
                        && is_glob(column)
                    {
                        out.push(best.map_or(Cell::Empty, |b| Cell::Text(b.1.clone())));
                    }
                }
                State::Critical(c) => out.push(Cell::num(c.value())),
            }
        }
        out
    }

    /// Distance (m) at time `t` (s), interpolated between rows.
    fn distance_at(&self, t: f64) -> f64 {
        let k = self.path.partition_point(|&(tk, _)| tk < t);
        match (k.checked_sub(1).map(|j| self.path[j]), self.path.get(k)) {
            (Some((t0, s0)), Some(&(t1, s1))) if t1 > t0 => s0 + (s1 - s0) * (t - t0) / (t1 - t0),
            (_, Some(&(_, s))) | (Some((_, s)), None) => s,
            _ => f64::NAN,
        }
    }

    fn assessment_cells(&self, table: &[Assessment]) -> Vec<Cell> {
        let side = |a: &Assessment| {
            let side = if a.quantity.contains("left") {
                " left"
            } else if a.quantity.contains("right") {
                " right"
            } else {
                ""
            };
            Cell::Text(format!("{}{side}", a.element))
        };
        // The judged rows (those with a limit) of Y/Q and ΣY, as the run's
        // own table judges them.
        let judged = |prefix: &str| {
            table
                .iter()
                .filter(|a| a.quantity.starts_with(prefix) && a.limit.is_some())
                .max_by(|a, b| a.max.total_cmp(&b.max))
        };
        let mut out = Vec::new();
        for prefix in ["Y/Q", "|ΣY|"] {
            match judged(prefix) {
                Some(a) => out.extend([
                    Cell::num(a.max),
                    a.limit.map_or(Cell::Empty, Cell::num),
                    side(a),
                    Cell::num(a.time),
                    Cell::num(self.distance_at(a.time)),
                ]),
                None => out.extend(std::iter::repeat_n(Cell::Empty, 5)),
            }
        }
        let q = |suffix_min: bool| {
            table.iter().filter(move |a| {
                a.quantity.starts_with("Q ") && a.quantity.ends_with(" min") == suffix_min
            })
        };
        match q(false).max_by(|a, b| a.max.total_cmp(&b.max)) {
            Some(a) => out.extend([Cell::num(a.max), side(a)]),
            None => out.extend([Cell::Empty, Cell::Empty]),
        }
        match q(true).min_by(|a, b| a.max.total_cmp(&b.max)) {
            Some(a) => out.extend([Cell::num(a.max), side(a)]),
            None => out.extend([Cell::Empty, Cell::Empty]),
        }
        let mut elements: Vec<&str> = table.iter().map(|a| a.element.as_str()).collect();
        elements.dedup();
        out.push(Cell::Num(elements.len() as f64));
        out
    }
}

impl OutputSink for CaseReducer<'_> {
    fn begin(&mut self, header: &[String]) -> Result<(), RunError> {
        if let Err(message) = self.bind(header) {
            self.setup_error = Some(message.clone());
            return Err(RunError::Setup {
                file: std::path::PathBuf::from("study"),
                message,
            });
        }
        match self.inner.as_mut() {
            Some(s) => s.begin(header),
            None => Ok(()),
        }
    }

    fn row(&mut self, values: &[f64]) -> Result<(), RunError> {
        let t = values[0];
        let s = self.distance.map(|k| values[k]);
        if let Some(s) = s {
            self.path.push((t, s));
        }
        for state in &mut self.states {
            match state {
                State::Assessment => {}
                State::Column(c) => {
                    let inside = match c.window {
                        None => true,
                        Some(Window::Time(a, b)) => (a..=b).contains(&t),
                        Some(Window::Distance(a, b)) => s.is_some_and(|s| (a..=b).contains(&s)),
                    };
                    if inside {
                        for (k, _, acc) in &mut c.columns {
                            acc.push(c.stat, t, values[*k]);
                        }
                    }
                }
                State::Critical(c) => c.push(values),
            }
        }
        match self.inner.as_mut() {
            Some(sink) => sink.row(values),
            None => Ok(()),
        }
    }

    fn accepted_loads(&mut self, samples: &[LoadSample], name: &dyn Fn(usize) -> String) {
        if let Some(s) = self.inner.as_mut() {
            s.accepted_loads(samples, name);
        }
    }

    fn finish(&mut self) -> Result<(), RunError> {
        match self.inner.as_mut() {
            Some(s) => s.finish(),
            None => Ok(()),
        }
    }
}

/// The cells of `reductions` (in [`Reduction::columns`] order) over an
/// output table already in memory (a run kept as a [`Table`](railmbs_runtime::run::Table), or a
/// time series read back), with the run's `assessment` table: the same
/// reducers a study streams its runs through.
///
/// # Errors
/// A reduction that fits none of the table's columns.
pub fn reduce_table(
    reductions: &[Reduction],
    table: &railmbs_runtime::run::Table,
    assessment: &[Assessment],
) -> Result<Vec<Cell>, String> {
    let mut reducer = CaseReducer::new(reductions, None);
    reducer.bind(table.names())?;
    let mut row = vec![0.0; table.names().len()];
    for k in 0..table.rows() {
        for (x, c) in row.iter_mut().zip(table.columns()) {
            *x = c[k];
        }
        reducer.row(&row).map_err(|e| e.to_string())?;
    }
    Ok(reducer.cells(assessment))
}
