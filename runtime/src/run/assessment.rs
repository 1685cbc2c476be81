//! The EN 14363 assessment of a run: the maxima of Y/Q, |ΣY| and Q of every
//! wheelset over the accepted steps, with the 2 m sliding means of Y/Q and
//! ΣY over the distance run and their limits (Nadal, Prud'homme). The
//! [`AssessmentReducer`] is the output sink that receives the wheel loads of
//! every accepted step; its table is [`RunSummary::assessment`](super::RunSummary::assessment).

use super::sliding_mean::SlidingMean;
use super::{OutputSink, RunError};
use crate::forces::wheel_rail::prudhomme_limit;
use crate::forces::{Assessment, WheelLoads};

/// The wheel loads of one wheel–rail element at an accepted step.
#[derive(Debug, Clone, PartialEq)]
pub struct LoadSample {
    /// The element's key in the system (its order in the assessment table).
    pub key: usize,
    /// Time of the accepted step, s.
    pub t: f64,
    /// The loads.
    pub loads: WheelLoads,
}

/// Length of the sliding window of Y/Q and ΣY (EN 14363's 2 m), m.
const ASSESSMENT_WINDOW: f64 = 2.0;

/// The sliding means of the assessment over the distance run, and their
/// maxima (value, time): robust against short spikes, whose raw peaks depend
/// on how the step sequence samples them.
#[derive(Debug, Clone)]
struct SlidingMeans {
    last_t: f64,
    y_over_q: [SlidingMean; 2],
    sum_y: SlidingMean,
    max_y_over_q: [(f64, f64); 2],
    max_sum_y: (f64, f64),
}

impl SlidingMeans {
    fn new() -> Self {
        Self {
            last_t: f64::NEG_INFINITY,
            y_over_q: [
                SlidingMean::new(ASSESSMENT_WINDOW),
                SlidingMean::new(ASSESSMENT_WINDOW),
            ],
            sum_y: SlidingMean::new(ASSESSMENT_WINDOW),
            max_y_over_q: [(f64::NEG_INFINITY, f64::NAN); 2],
            max_sum_y: (f64::NEG_INFINITY, f64::NAN),
        }
    }

    /// Adds an accepted step at time `t` (s) and distance `s` (m) with the
    /// wheel loads (Q, Y) per side (N); a time before the last starts over
    /// (a new run).
    fn push(&mut self, t: f64, s: f64, loads: &[(f64, f64); 2]) {
        if t < self.last_t {
            *self = Self::new();
        }
        self.last_t = t;
        for (side, &(q, y)) in loads.iter().enumerate() {
            let ratio = if q > 0.0 { y / q } else { 0.0 };
            if let Some(v) = self.y_over_q[side].push(s, ratio)
                && v > self.max_y_over_q[side].0
            {
                self.max_y_over_q[side] = (v, t);
            }
        }
        if let Some(v) = self.sum_y.push(s, loads[0].1 - loads[1].1)
            && v.abs() > self.max_sum_y.0
        {
            self.max_sum_y = (v.abs(), t);
        }
    }
}

#[derive(Debug, Clone, Copy, Default)]
struct Maxima {
    /// max Y/Q per side and the time.
    y_over_q: [(f64, f64); 2],
    /// max |ΣY| (N) and the time.
    sum_y: (f64, f64),
    /// max Q per side (N) and the time.
    q: [(f64, f64); 2],
    /// min Q per side (N) and the time: wheel unloading, 0 when it lifts.
    q_min: [(f64, f64); 2],
    /// Σ (Q_left + Q_right) over accepted steps and their count: the mean axle
    /// load for Prud'homme's limit.
    axle_load_sum: f64,
    samples: usize,
}

/// The assessment of one wheel–rail element so far.
#[derive(Debug, Clone)]
struct ElementAssessment {
    name: String,
    nadal: Option<f64>,
    /// Running maxima over accepted steps.
    maxima: Maxima,
    /// 2 m sliding means of Y/Q and ΣY over the distance run and their
    /// maxima (from the first step on a track).
    means: Option<SlidingMeans>,
}

impl ElementAssessment {
    /// Adds an accepted step at time `t` (s).
    fn push(&mut self, t: f64, sample: &WheelLoads) {
        self.nadal = sample.nadal;
        let loads = sample.loads;
        let m = &mut self.maxima;
        for (side, &(q, y)) in loads.iter().enumerate() {
            if q > 0.0 && y / q > m.y_over_q[side].0 {
                m.y_over_q[side] = (y / q, t);
            }
            if q > m.q[side].0 {
                m.q[side] = (q, t);
            }
            if m.samples == 0 || q < m.q_min[side].0 {
                m.q_min[side] = (q, t);
            }
        }
        let sum_y = (loads[0].1 - loads[1].1).abs();
        if sum_y > m.sum_y.0 {
            m.sum_y = (sum_y, t);
        }
        m.axle_load_sum += loads[0].0 + loads[1].0;
        m.samples += 1;
        // Sliding means over the distance s of the wheelset.
        if let Some(s) = sample.distance {
            self.means
                .get_or_insert_with(SlidingMeans::new)
                .push(t, s, &loads);
        }
    }

    fn rows(&self) -> Vec<Assessment> {
        let m = &self.maxima;
        if m.samples == 0 {
            return Vec::new();
        }
        let nadal = self.nadal;
        let axle = m.axle_load_sum / m.samples as f64;
        // EN 14363 judges Y/Q and ΣY as 2 m sliding means; the raw peaks are
        // listed too, without a limit (a spike's sampled peak depends on the
        // step sequence) — except when the run was shorter than the window:
        // then the peaks are judged. Where a wheel lifts (Q = 0) its Y/Q
        // counts as 0 in the mean; the minimum Q rows show the lift.
        let row = |quantity: String,
                   (max, time): (f64, f64),
                   limit: Option<(Option<f64>, &'static str)>,
                   unit: &'static str| Assessment {
            element: self.name.clone(),
            quantity,
            max,
            time,
            limit: limit.and_then(|l| l.0),
            limit_name: limit.map_or("", |l| l.1),
            unit,
        };
        let mut rows = Vec::new();
        let means = self.means.as_ref();
        let nadal = Some((nadal, "Nadal"));
        let prudhomme = Some((Some(prudhomme_limit(axle)), "Prud'homme"));
        for (side, label) in [(0, "left"), (1, "right")] {
            let mean = means
                .map(|mm| mm.max_y_over_q[side])
                .filter(|v| v.0.is_finite());
            if let Some(v) = mean {
                rows.push(row(format!("Y/Q {label} (2 m)"), v, nadal, "-"));
            }
            let peak_limit = if mean.is_some() { None } else { nadal };
            rows.push(row(
                format!("Y/Q {label} peak"),
                m.y_over_q[side],
                peak_limit,
                "-",
            ));
        }
        let mean = means.map(|mm| mm.max_sum_y).filter(|v| v.0.is_finite());
        if let Some(v) = mean {
            rows.push(row("|ΣY| (2 m)".into(), v, prudhomme, "N"));
        }
        let peak_limit = if mean.is_some() { None } else { prudhomme };
        rows.push(row("|ΣY| peak".into(), m.sum_y, peak_limit, "N"));
        for (side, label) in [(0, "left"), (1, "right")] {
            rows.push(row(format!("Q {label}"), m.q[side], None, "N"));
            rows.push(row(format!("Q {label} min"), m.q_min[side], None, "N"));
        }
        rows
    }
}

/// The sink that reduces the wheel loads of the accepted steps to the
/// assessment table (rows are ignored).
#[derive(Debug, Clone, Default)]
pub struct AssessmentReducer {
    /// By key, in key order.
    elements: Vec<Option<ElementAssessment>>,
}

impl AssessmentReducer {
    /// An empty reducer.
    pub fn new() -> Self {
        Self::default()
    }

    /// Adds the loads of an accepted step; `name` gives the element's long
    /// name the first time its key is seen.
    pub fn push(&mut self, sample: &LoadSample, name: impl FnOnce() -> String) {
        if self.elements.len() <= sample.key {
            self.elements.resize(sample.key + 1, None);
        }
        self.elements[sample.key]
            .get_or_insert_with(|| ElementAssessment {
                name: name(),
                nadal: None,
                maxima: Maxima::default(),
                means: None,
            })
            .push(sample.t, &sample.loads);
    }

    /// The assessment table: per element (in key order) the sliding-mean
    /// maxima with their limits, the raw peaks, and the Q extremes.
    pub fn table(&self) -> Vec<Assessment> {
        self.elements
            .iter()
            .flatten()
            .flat_map(|e| e.rows())
            .collect()
    }
}

impl OutputSink for AssessmentReducer {
    fn begin(&mut self, _header: &[String]) -> Result<(), RunError> {
        Ok(())
    }

    fn row(&mut self, _values: &[f64]) -> Result<(), RunError> {
        Ok(())
    }

    fn accepted_loads(&mut self, samples: &[LoadSample], name: &dyn Fn(usize) -> String) {
        for s in samples {
            self.push(s, || name(s.key));
        }
    }
}
