//! Reading sampled signals.

/// Times (s) where `y` crosses zero upwards, interpolated linearly between
/// the samples `(t[i-1], y[i-1])` and `(t[i], y[i])`.
pub fn up_crossings(t: &[f64], y: &[f64]) -> Vec<f64> {
    (1..y.len())
        .filter(|&i| y[i - 1] < 0.0 && y[i] >= 0.0)
        .map(|i| t[i - 1] + (t[i] - t[i - 1]) * (-y[i - 1]) / (y[i] - y[i - 1]))
        .collect()
}
