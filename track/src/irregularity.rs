//! Track irregularities: deviations of each rail from its design position, as
//! functions of the arc position s.
//!
//! Deviations are resolved in the track-following frame: lateral positive to the
//! left (frame y), vertical positive up (frame z), m. Derived quantities:
//! gauge change = left lateral − right lateral; cross-level = left vertical −
//! right vertical; alignment = mean lateral; level = mean vertical.

use std::f64::consts::PI;
use std::path::Path;

use crate::error::{TrackError, check_param, finite, invalid};
use crate::psd::{SampledIrregularity, StochasticIrregularity};

/// Per-rail deviations from the design geometry, m (or m/m for rates).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct RailDeviation {
    /// Left rail, lateral (positive to the left).
    pub left_lateral: f64,
    /// Left rail, vertical (positive up).
    pub left_vertical: f64,
    /// Right rail, lateral (positive to the left).
    pub right_lateral: f64,
    /// Right rail, vertical (positive up).
    pub right_vertical: f64,
}

impl RailDeviation {
    /// Gauge change (positive: wider), m.
    pub fn gauge(&self) -> f64 {
        self.left_lateral - self.right_lateral
    }
    /// Cross-level (left rail above right rail), m.
    pub fn cross_level(&self) -> f64 {
        self.left_vertical - self.right_vertical
    }
    /// Alignment: mean lateral deviation, m.
    pub fn alignment(&self) -> f64 {
        0.5 * (self.left_lateral + self.right_lateral)
    }
    /// Level: mean vertical deviation, m.
    pub fn level(&self) -> f64 {
        0.5 * (self.left_vertical + self.right_vertical)
    }
    fn add(&mut self, o: &RailDeviation) {
        self.left_lateral += o.left_lateral;
        self.left_vertical += o.left_vertical;
        self.right_lateral += o.right_lateral;
        self.right_vertical += o.right_vertical;
    }
    /// The deviation produced by a value `v` of one component.
    pub fn from_component(component: Component, v: f64) -> Self {
        match component {
            Component::Lateral => RailDeviation {
                left_lateral: v,
                right_lateral: v,
                ..Default::default()
            },
            Component::Vertical => RailDeviation {
                left_vertical: v,
                right_vertical: v,
                ..Default::default()
            },
            Component::Gauge => RailDeviation {
                left_lateral: 0.5 * v,
                right_lateral: -0.5 * v,
                ..Default::default()
            },
            Component::CrossLevel => RailDeviation {
                left_vertical: 0.5 * v,
                right_vertical: -0.5 * v,
                ..Default::default()
            },
        }
    }
}

/// Which irregularity component a signal drives. Gauge and cross-level are
/// split equally between the rails (±v/2), keeping the centre line in place.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Component {
    /// Both rails move laterally (alignment).
    Lateral,
    /// Both rails move vertically (level).
    Vertical,
    /// Gauge change: left rail +v/2, right rail −v/2 laterally.
    Gauge,
    /// Cross-level: left rail +v/2, right rail −v/2 vertically.
    CrossLevel,
}

/// Which rail(s) a dip affects.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum Rail {
    /// The left rail.
    Left,
    /// The right rail.
    Right,
    /// Both rails.
    Both,
}

/// Shape of a vertical dip over its length L, depth d, u = s − start ∈ [0, L].
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum DipShape {
    /// Linear ("V"): z = −d (1 − |2u/L − 1|), straight ramps down to the depth
    /// at mid-length and back up (the Manchester benchmark's "linear dip").
    Linear,
    /// Cosine: z = −(d/2)(1 − cos(2πu/L)), with zero slope at both ends.
    Cosine,
}

/// A single vertical dip in one or both rails.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Dip {
    /// Affected rail(s).
    pub rail: Rail,
    /// Arc position where the dip starts, m.
    pub start: f64,
    /// Length, m (> 0).
    pub length: f64,
    /// Depth, m (positive: the rail goes down).
    pub depth: f64,
    /// Shape.
    pub shape: DipShape,
}

impl Dip {
    /// Validated dip.
    pub fn new(
        rail: Rail,
        start: f64,
        length: f64,
        depth: f64,
        shape: DipShape,
    ) -> Result<Self, TrackError> {
        check_param("dip start", start, false)?;
        check_param("dip length", length, true)?;
        check_param("dip depth", depth, false)?;
        Ok(Dip {
            rail,
            start,
            length,
            depth,
            shape,
        })
    }

    /// Vertical deviation and its s-derivative at `s`.
    pub fn vertical(&self, s: f64) -> (f64, f64) {
        let u = s - self.start;
        if !(0.0..=self.length).contains(&u) {
            return (0.0, 0.0);
        }
        let (d, l) = (self.depth, self.length);
        match self.shape {
            DipShape::Linear => {
                let r = 2.0 * u / l - 1.0;
                let slope = if r < 0.0 { -2.0 * d / l } else { 2.0 * d / l };
                (-d * (1.0 - r.abs()), slope)
            }
            DipShape::Cosine => {
                let w = 2.0 * PI / l;
                (
                    -0.5 * d * (1.0 - (w * u).cos()),
                    -0.5 * d * w * (w * u).sin(),
                )
            }
        }
    }

    fn eval(&self, s: f64) -> (RailDeviation, RailDeviation) {
        let (v, dv) = self.vertical(s);
        let make = |x: f64| {
            let (l, r) = match self.rail {
                Rail::Left => (x, 0.0),
                Rail::Right => (0.0, x),
                Rail::Both => (x, x),
            };
            RailDeviation {
                left_vertical: l,
                right_vertical: r,
                ..Default::default()
            }
        };
        (make(v), make(dv))
    }
}

/// A sinusoidal irregularity a·sin(2π(s − start)/λ + phase) on [start, end],
/// zero outside. It starts from 0 when phase = 0, and ends at 0 when
/// (end − start) is a multiple of λ/2.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sinusoid {
    /// Driven component.
    pub component: Component,
    /// Wavelength λ, m.
    pub wavelength: f64,
    /// Amplitude a (half of peak-to-peak), m.
    pub amplitude: f64,
    /// Start of the extent, m.
    pub start: f64,
    /// End of the extent, m.
    pub end: f64,
    /// Phase at `start`, rad.
    pub phase: f64,
}

impl Sinusoid {
    /// Validated sinusoid with zero phase.
    pub fn new(
        component: Component,
        wavelength: f64,
        amplitude: f64,
        start: f64,
        end: f64,
    ) -> Result<Self, TrackError> {
        check_param("sinusoid wavelength", wavelength, true)?;
        check_param("sinusoid amplitude", amplitude, false)?;
        check_param("sinusoid start", start, false)?;
        check_param("sinusoid end", end, false)?;
        if end <= start {
            return Err(invalid(
                "sinusoid extent",
                format!("end {end} m must be after start {start} m"),
            ));
        }
        Ok(Sinusoid {
            component,
            wavelength,
            amplitude,
            start,
            end,
            phase: 0.0,
        })
    }

    fn eval(&self, s: f64) -> (RailDeviation, RailDeviation) {
        if s < self.start || s > self.end {
            return Default::default();
        }
        let w = 2.0 * PI / self.wavelength;
        let (sn, cs) = (w * (s - self.start) + self.phase).sin_cos();
        (
            RailDeviation::from_component(self.component, self.amplitude * sn),
            RailDeviation::from_component(self.component, self.amplitude * w * cs),
        )
    }
}

/// Gauge widening by `widening` (m), zero before `start`, ramped linearly over
/// `ramp` m (0: a step), constant afterwards; split ±widening/2 between rails.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GaugeWidening {
    /// Start of the ramp, m.
    pub start: f64,
    /// Ramp length, m (≥ 0).
    pub ramp: f64,
    /// Widening, m.
    pub widening: f64,
}

impl GaugeWidening {
    /// Validated widening.
    pub fn new(start: f64, ramp: f64, widening: f64) -> Result<Self, TrackError> {
        check_param("gauge widening start", start, false)?;
        check_param("gauge widening ramp", ramp, false)?;
        check_param("gauge widening", widening, false)?;
        if ramp < 0.0 {
            return Err(invalid(
                "gauge widening ramp",
                format!("{ramp} m must be ≥ 0"),
            ));
        }
        Ok(GaugeWidening {
            start,
            ramp,
            widening,
        })
    }

    /// A constant widening over the whole track.
    pub fn constant(widening: f64) -> Result<Self, TrackError> {
        check_param("gauge widening", widening, false)?;
        Ok(GaugeWidening {
            start: f64::NEG_INFINITY,
            ramp: 0.0,
            widening,
        })
    }

    fn eval(&self, s: f64) -> (RailDeviation, RailDeviation) {
        let u = s - self.start;
        let (w, dw) = if u < 0.0 {
            (0.0, 0.0)
        } else if u < self.ramp {
            (self.widening * u / self.ramp, self.widening / self.ramp)
        } else {
            (self.widening, 0.0)
        };
        (
            RailDeviation::from_component(Component::Gauge, w),
            RailDeviation::from_component(Component::Gauge, dw),
        )
    }
}

/// Measured irregularities: samples at strictly increasing s, linearly
/// interpolated; zero outside the sampled range.
#[derive(Debug, Clone, PartialEq)]
pub struct MeasuredIrregularity {
    s: Vec<f64>,
    values: Vec<RailDeviation>,
}

/// The CSV header of [`MeasuredIrregularity::from_csv`].
pub const MEASURED_CSV_HEADER: [&str; 5] = [
    "s",
    "left_lateral",
    "left_vertical",
    "right_lateral",
    "right_vertical",
];

impl MeasuredIrregularity {
    /// From samples (s in m strictly increasing, at least two).
    pub fn from_samples(s: Vec<f64>, values: Vec<RailDeviation>) -> Result<Self, TrackError> {
        if s.len() != values.len() {
            return Err(invalid(
                "measured irregularity",
                format!("{} positions but {} samples", s.len(), values.len()),
            ));
        }
        if s.len() < 2 {
            return Err(invalid(
                "measured irregularity",
                "needs at least two samples",
            ));
        }
        for i in 0..s.len() {
            // The element's name is formatted only for an error (a sampled
            // stochastic irregularity has tens of thousands of samples).
            if !s[i].is_finite() {
                check_param(
                    &format!("measured irregularity sample {i} position"),
                    s[i],
                    false,
                )?;
            }
            let v = &values[i];
            for x in [
                v.left_lateral,
                v.left_vertical,
                v.right_lateral,
                v.right_vertical,
            ] {
                if !x.is_finite() {
                    check_param(&format!("measured irregularity sample {i} value"), x, false)?;
                }
            }
            if i > 0 && s[i] <= s[i - 1] {
                return Err(invalid(
                    format!("measured irregularity sample {i}"),
                    format!("position {} m is not greater than {} m", s[i], s[i - 1]),
                ));
            }
        }
        Ok(MeasuredIrregularity { s, values })
    }

    /// Reads a CSV file with the header `s,left_lateral,left_vertical,
    /// right_lateral,right_vertical` (columns in any order, all in m; `#` starts
    /// a comment line). Errors name the file and the line.
    pub fn from_csv(path: impl AsRef<Path>) -> Result<Self, TrackError> {
        let path = path.as_ref();
        let text = std::fs::read_to_string(path).map_err(|e| TrackError::Io {
            file: path.to_path_buf(),
            message: e.to_string(),
        })?;
        Self::from_csv_text(&text, path)
    }

    /// Parses the text of a CSV file as [`MeasuredIrregularity::from_csv`]
    /// reads it; `path` names the file in errors.
    pub fn from_csv_text(text: &str, path: &Path) -> Result<Self, TrackError> {
        let file = path.to_path_buf();
        let mut reader = csv::ReaderBuilder::new()
            .has_headers(true)
            .trim(csv::Trim::All)
            .comment(Some(b'#'))
            .from_reader(text.as_bytes());
        let csv_err = |row: usize, message: String| TrackError::Csv {
            file: file.clone(),
            row,
            message,
        };
        let headers = reader
            .headers()
            .map_err(|e| csv_err(1, e.to_string()))?
            .clone();
        let mut col = [usize::MAX; 5];
        for (k, name) in MEASURED_CSV_HEADER.iter().enumerate() {
            match headers.iter().position(|h| h.eq_ignore_ascii_case(name)) {
                Some(j) => col[k] = j,
                None => {
                    return Err(csv_err(
                        1,
                        format!(
                            "missing column `{name}` (expected columns {})",
                            MEASURED_CSV_HEADER.join(",")
                        ),
                    ));
                }
            }
        }
        let mut s = Vec::new();
        let mut values = Vec::new();
        for rec in reader.records() {
            let rec = rec.map_err(|e| {
                let line = e.position().map(|p| p.line() as usize).unwrap_or(0);
                csv_err(line, e.to_string())
            })?;
            let line = rec.position().map(|p| p.line() as usize).unwrap_or(0);
            let mut x = [0.0; 5];
            for k in 0..5 {
                let field = rec.get(col[k]).unwrap_or("");
                let v: f64 = field.parse().map_err(|_| {
                    csv_err(
                        line,
                        format!(
                            "column `{}`: `{field}` is not a number",
                            MEASURED_CSV_HEADER[k]
                        ),
                    )
                })?;
                if !v.is_finite() {
                    return Err(csv_err(
                        line,
                        format!("column `{}`: {v} is not finite", MEASURED_CSV_HEADER[k]),
                    ));
                }
                x[k] = v;
            }
            if let Some(&prev) = s.last()
                && x[0] <= prev
            {
                return Err(csv_err(
                    line,
                    format!(
                        "s = {} m is not greater than the previous s = {prev} m",
                        x[0]
                    ),
                ));
            }
            s.push(x[0]);
            values.push(RailDeviation {
                left_lateral: x[1],
                left_vertical: x[2],
                right_lateral: x[3],
                right_vertical: x[4],
            });
        }
        if s.len() < 2 {
            return Err(csv_err(
                1,
                format!("needs at least two data rows, found {}", s.len()),
            ));
        }
        Ok(MeasuredIrregularity { s, values })
    }

    /// First and last sampled position, m.
    pub fn range(&self) -> (f64, f64) {
        (self.s[0], self.s[self.s.len() - 1])
    }

    fn eval(&self, s: f64) -> (RailDeviation, RailDeviation) {
        let n = self.s.len();
        if s < self.s[0] || s > self.s[n - 1] {
            return Default::default();
        }
        let i = interval(&self.s, s);
        interpolate(
            s,
            (self.s[i], self.s[i + 1]),
            (&self.values[i], &self.values[i + 1]),
        )
    }
}

/// The sample interval [s_i, s_i+1] of the strictly increasing positions
/// `positions` (at least two) that holds `s`: the last i with s_i ≤ s, at
/// most the last but one.
pub(crate) fn interval(positions: &[f64], s: f64) -> usize {
    let n = positions.len();
    (positions.partition_point(|&k| k <= s).max(1) - 1).min(n - 2)
}

/// Deviation and its s-derivative at `s` between the samples `a` at `s0`
/// and `b` at `s1`, by linear interpolation.
pub(crate) fn interpolate(
    s: f64,
    (s0, s1): (f64, f64),
    (a, b): (&RailDeviation, &RailDeviation),
) -> (RailDeviation, RailDeviation) {
    let h = s1 - s0;
    let t = (s - s0) / h;
    let lerp = |x: f64, y: f64| x + (y - x) * t;
    let rate = |x: f64, y: f64| (y - x) / h;
    (
        RailDeviation {
            left_lateral: lerp(a.left_lateral, b.left_lateral),
            left_vertical: lerp(a.left_vertical, b.left_vertical),
            right_lateral: lerp(a.right_lateral, b.right_lateral),
            right_vertical: lerp(a.right_vertical, b.right_vertical),
        },
        RailDeviation {
            left_lateral: rate(a.left_lateral, b.left_lateral),
            left_vertical: rate(a.left_vertical, b.left_vertical),
            right_lateral: rate(a.right_lateral, b.right_lateral),
            right_vertical: rate(a.right_vertical, b.right_vertical),
        },
    )
}

/// One irregularity of any kind.
#[derive(Debug, Clone, PartialEq)]
pub enum Irregularity {
    /// A single dip.
    Dip(Dip),
    /// A sinusoid.
    Sinusoid(Sinusoid),
    /// A gauge widening.
    GaugeWidening(GaugeWidening),
    /// A stochastic irregularity from a PSD.
    Stochastic(StochasticIrregularity),
    /// Measured samples.
    Measured(MeasuredIrregularity),
    /// A stochastic irregularity tabulated on first use.
    Sampled(SampledIrregularity),
}

impl Irregularity {
    /// Deviation and its s-derivative (m/m) at `s`.
    pub fn eval(&self, s: f64) -> (RailDeviation, RailDeviation) {
        match self {
            Irregularity::Dip(d) => d.eval(s),
            Irregularity::Sinusoid(x) => x.eval(s),
            Irregularity::GaugeWidening(x) => x.eval(s),
            Irregularity::Stochastic(x) => x.eval(s),
            Irregularity::Measured(x) => x.eval(s),
            Irregularity::Sampled(x) => x.eval(s),
        }
    }
}

/// The sum of any number of irregularities.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Irregularities {
    items: Vec<Irregularity>,
}

impl Irregularities {
    /// No irregularities.
    pub fn new() -> Self {
        Self::default()
    }
    /// Adds one.
    pub fn with(mut self, item: Irregularity) -> Self {
        self.items.push(item);
        self
    }
    /// Adds one.
    pub fn push(&mut self, item: Irregularity) {
        self.items.push(item);
    }
    /// The items.
    pub fn items(&self) -> &[Irregularity] {
        &self.items
    }

    /// Total per-rail deviation at `s` (m). No allocation.
    pub fn deviation(&self, s: f64) -> Result<RailDeviation, TrackError> {
        Ok(self.deviation_and_rate(s)?.0)
    }

    /// Total per-rail deviation at `s` (m) and its derivative d/ds (m/m); the
    /// time rate at running speed ṡ is ṡ times the latter. No allocation.
    pub fn deviation_and_rate(&self, s: f64) -> Result<(RailDeviation, RailDeviation), TrackError> {
        finite("arc position s", s)?;
        let mut v = RailDeviation::default();
        let mut d = RailDeviation::default();
        for it in &self.items {
            let (a, b) = it.eval(s);
            v.add(&a);
            d.add(&b);
        }
        Ok((v, d))
    }
}
