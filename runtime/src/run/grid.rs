//! The output grid of a run: rows at k·interval (and at the end time),
//! interpolated between accepted steps by cubic Hermite interpolation.

use std::time::Instant;

/// Time, coordinates, velocities and accelerations at the end of a step.
pub(crate) type StepEnd = (f64, Vec<f64>, Vec<f64>, Vec<f64>);

/// Cubic Hermite interpolation on [t0, t1] from values and derivatives.
pub(crate) fn hermite(t0: f64, t1: f64, t: f64, y0: f64, d0: f64, y1: f64, d1: f64) -> f64 {
    let h = t1 - t0;
    if h <= 0.0 {
        return y1;
    }
    let s = (t - t0) / h;
    let s2 = s * s;
    let s3 = s2 * s;
    (2.0 * s3 - 3.0 * s2 + 1.0) * y0
        + (s3 - 2.0 * s2 + s) * h * d0
        + (-2.0 * s3 + 3.0 * s2) * y1
        + (s3 - s2) * h * d1
}

/// Time derivative of [`hermite`] at t.
pub(crate) fn hermite_derivative(
    t0: f64,
    t1: f64,
    t: f64,
    y0: f64,
    d0: f64,
    y1: f64,
    d1: f64,
) -> f64 {
    let h = t1 - t0;
    if h <= 0.0 {
        return d1;
    }
    let s = (t - t0) / h;
    let s2 = s * s;
    ((6.0 * s2 - 6.0 * s) * y0 + (-6.0 * s2 + 6.0 * s) * y1) / h
        + (3.0 * s2 - 4.0 * s + 1.0) * d0
        + (3.0 * s2 - 2.0 * s) * d1
}

/// The output grid of a run: rows at k·interval (and always at the end
/// time), interpolated from the accepted steps by cubic Hermite
/// interpolation, plus the progress callback now and then. The runner calls
/// [`OutputSchedule::observe`] with the initial state of every segment and
/// after every accepted step.
pub(crate) struct OutputSchedule {
    t_end: f64,
    interval: f64,
    n: usize,
    /// The previous accepted step's end (t, q, q̇, q̈).
    prev: Option<StepEnd>,
    next_row: usize,
    last_progress: Instant,
    calls: u64,
}

/// An output row's state: time (s), q, q̇ and q̈ (interpolated).
pub(crate) struct Row {
    pub t: f64,
    pub q: Vec<f64>,
    pub v: Vec<f64>,
    pub a: Vec<f64>,
}

impl Row {
    /// The coordinates `r` of the row (one vehicle's part of a train's row),
    /// borrowed.
    pub(crate) fn slice(&self, r: std::ops::Range<usize>) -> RowView<'_> {
        RowView {
            t: self.t,
            q: &self.q[r.clone()],
            v: &self.v[r.clone()],
            a: &self.a[r],
        }
    }
}

/// A borrowed [`Row`] or part of one: time (s), q, q̇ and q̈.
#[derive(Clone, Copy)]
pub(crate) struct RowView<'a> {
    pub t: f64,
    pub q: &'a [f64],
    pub v: &'a [f64],
    pub a: &'a [f64],
}

/// Rows waiting to be written.
pub(crate) type PendingRows = std::collections::VecDeque<Row>;

impl OutputSchedule {
    /// A grid of rows every `interval` (s) up to `t_end` (s) for states of
    /// `n` coordinates.
    pub(crate) fn new(t_end: f64, interval: f64, n: usize) -> Self {
        Self {
            t_end,
            interval,
            n,
            prev: None,
            next_row: 0,
            last_progress: Instant::now(),
            calls: 0,
        }
    }

    /// Time of the next row to be written, s.
    pub(crate) fn next_row_time(&self) -> f64 {
        (self.next_row as f64 * self.interval).min(self.t_end)
    }

    /// Queues the output rows in (t_prev, t] after an accepted step ending at
    /// (t, q, q̇, q̈); the end time is always the last row.
    pub(crate) fn observe(
        &mut self,
        t: f64,
        q: &[f64],
        v: &[f64],
        a: &[f64],
        pending: &mut PendingRows,
        progress: &mut impl FnMut(f64),
    ) {
        let (t_end, n) = (self.t_end, self.n);
        loop {
            let mut to = self.next_row as f64 * self.interval;
            let is_last = to >= t_end * (1.0 - 1e-12);
            if is_last {
                to = t_end;
            }
            // A row within rounding of the step's end is written there; the
            // tolerance never reaches a row interval (a huge end time would
            // otherwise let every row count as reached).
            let reached = to <= t + (1e-12 * t_end.max(1.0)).min(1e-6 * self.interval);
            if !reached || (is_last && t < t_end * (1.0 - 1e-12)) {
                break;
            }
            let row = match &self.prev {
                Some((t0, q0, v0, a0)) if to < t => Row {
                    t: to,
                    q: (0..n)
                        .map(|i| hermite(*t0, t, to, q0[i], v0[i], q[i], v[i]))
                        .collect(),
                    v: (0..n)
                        .map(|i| hermite(*t0, t, to, v0[i], a0[i], v[i], a[i]))
                        .collect(),
                    // The derivative of the velocity interpolant, so that
                    // q̈ is consistent with the q̇ written.
                    a: (0..n)
                        .map(|i| hermite_derivative(*t0, t, to, v0[i], a0[i], v[i], a[i]))
                        .collect(),
                },
                _ => Row {
                    t: to,
                    q: q.to_vec(),
                    v: v.to_vec(),
                    a: a.to_vec(),
                },
            };
            pending.push_back(row);
            self.next_row += 1;
            if is_last {
                break;
            }
        }
        match &mut self.prev {
            Some(p) => {
                p.0 = t;
                p.1.copy_from_slice(q);
                p.2.copy_from_slice(v);
                p.3.copy_from_slice(a);
            }
            None => self.prev = Some((t, q.to_vec(), v.to_vec(), a.to_vec())),
        }
        // The clock is read every 64 steps only: this runs once per step.
        self.calls += 1;
        if self.calls.is_multiple_of(64) && self.last_progress.elapsed().as_millis() > 100 {
            progress(t);
            self.last_progress = Instant::now();
        }
    }

    /// The previous accepted step's end time, if any.
    pub(crate) fn last_time(&self) -> Option<f64> {
        self.prev.as_ref().map(|p| p.0)
    }
}
