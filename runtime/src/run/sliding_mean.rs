//! Sliding means over the accepted steps of a run, for the assessment
//! quantities of EN 14363 (Y/Q and ΣY as 2 m sliding means over the distance
//! run): the maximum of a window mean does not depend on how a short spike
//! happens to be sampled by the step sequence, the maximum of the raw signal
//! does.
//!
//! Samples (x, y) arrive with non-decreasing x (distance, m, or time, s); the
//! signal between samples is taken as linear, and the mean over the window
//! [x − L, x] is its exact integral over the window divided by L. Until the
//! samples span a whole window there is no mean. A sample at or before the
//! last one's x replaces the samples it does not follow (a repeated step end;
//! a new run starting over).

use std::collections::VecDeque;

/// Mean of a piecewise-linear signal over the last `length` of its argument.
#[derive(Debug, Clone)]
pub struct SlidingMean {
    length: f64,
    samples: VecDeque<(f64, f64)>,
    /// Integral of the signal from the first kept sample to the last, by the
    /// trapezoidal rule over the kept segments.
    integral: f64,
}

impl SlidingMean {
    /// A window of `length` in the unit of the samples' argument; a length
    /// that is not positive and finite gives no means.
    pub fn new(length: f64) -> Self {
        Self {
            length,
            samples: VecDeque::new(),
            integral: 0.0,
        }
    }

    /// Window length.
    pub fn length(&self) -> f64 {
        self.length
    }

    /// Adds the sample (x, y); returns the window mean ending at x once the
    /// samples span the window. A sample with x not after the last one
    /// replaces it (a repeated step end).
    pub fn push(&mut self, x: f64, y: f64) -> Option<f64> {
        // Samples at or after x are superseded (a repeated step end).
        while let Some(&(x_last, y_last)) = self.samples.back() {
            if x > x_last {
                self.integral += 0.5 * (y_last + y) * (x - x_last);
                break;
            }
            self.samples.pop_back();
            if let Some(&(x0, y0)) = self.samples.back() {
                self.integral -= 0.5 * (y0 + y_last) * (x_last - x0);
            }
        }
        self.samples.push_back((x, y));
        // Drop samples wholly before the window, keeping one at or before its
        // start so the window's first segment is known.
        let start = x - self.length;
        while self.samples.len() > 2 && self.samples[1].0 <= start {
            let (x0, y0) = self.samples[0];
            let (x1, y1) = self.samples[1];
            self.integral -= 0.5 * (y0 + y1) * (x1 - x0);
            self.samples.pop_front();
        }
        let (x0, y0) = self.samples[0];
        if x0 > start || !(self.length > 0.0 && self.length.is_finite()) {
            return None;
        }
        // Remove the part of the first segment before the window start.
        let (x1, y1) = self.samples.get(1).copied().unwrap_or((x, y));
        let cut = if x1 > x0 {
            let y_start = y0 + (y1 - y0) * (start - x0) / (x1 - x0);
            0.5 * (y0 + y_start) * (start - x0)
        } else {
            0.0
        };
        Some((self.integral - cut) / self.length)
    }

    /// Forgets all samples (a new run).
    pub fn clear(&mut self) {
        self.samples.clear();
        self.integral = 0.0;
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The mean of a linear signal over [x − L, x] is its value at x − L/2,
    /// whatever the sampling.
    #[test]
    fn linear_signal_mean_is_the_midpoint_value() {
        let mut m = SlidingMean::new(2.0);
        let mut x = 0.0;
        let mut k = 0;
        while x < 10.0 {
            let mean = m.push(x, 3.0 * x + 1.0);
            if x >= 2.0 {
                let exact = 3.0 * (x - 1.0) + 1.0;
                let got = mean.expect("window spanned");
                assert!((got - exact).abs() < 1e-12, "x = {x}: {got} vs {exact}");
            } else {
                assert!(mean.is_none());
            }
            // Irregular steps.
            k += 1;
            x += 0.05 + 0.37 * ((k * 7919) % 13) as f64 / 13.0;
        }
    }

    /// A spike narrower than the window contributes its area / L however it
    /// is sampled: a triangle of height 100 and base 0.02 in a 2 m window
    /// gives 0.5 on top of the baseline.
    #[test]
    fn spike_contributes_its_area_regardless_of_sampling() {
        for offset in [0.0, 0.003, 0.0071] {
            let mut m = SlidingMean::new(2.0);
            let mut best: f64 = 0.0;
            let mut x = 0.0;
            let spike = |x: f64| (100.0 * (1.0 - (x - 5.0 - offset).abs() / 0.01)).max(0.0);
            // Samples every 1 mm: the triangle's corners fall between them.
            while x < 8.0 {
                if let Some(v) = m.push(x, 1.0 + spike(x)) {
                    best = best.max(v);
                }
                x += 0.001;
            }
            assert!((best - 1.5).abs() < 1e-3, "offset {offset}: {best}");
        }
    }

    #[test]
    fn a_repeated_sample_replaces_the_last() {
        let mut m = SlidingMean::new(1.0);
        m.push(0.0, 0.0);
        m.push(0.5, 100.0);
        m.push(0.5, 1.0);
        let v = m.push(1.0, 2.0).unwrap();
        // Piecewise linear through (0, 0), (0.5, 1), (1, 2): mean 1.
        assert!((v - 1.0).abs() < 1e-12, "{v}");
    }
}
