//! Errors of the track crate.

use std::path::PathBuf;

/// Everything that can go wrong when building or evaluating a track.
///
/// Variants returned on the hot path ([`TrackError::OutOfRange`],
/// [`TrackError::NotFinite`]) carry no heap data, so evaluation never allocates.
#[derive(Debug, thiserror::Error, Clone, PartialEq)]
pub enum TrackError {
    /// An input to an evaluation is NaN or infinite.
    #[error("{what} is not finite: {value}")]
    NotFinite {
        /// Which input.
        what: &'static str,
        /// The offending value.
        value: f64,
    },
    /// The arc position lies outside the track.
    #[error("arc position s = {s} m lies outside the track [{start}, {end}] m")]
    OutOfRange {
        /// Requested arc position, m.
        s: f64,
        /// First valid arc position, m.
        start: f64,
        /// Last valid arc position, m.
        end: f64,
    },
    /// An output buffer has the wrong length.
    #[error("input buffer has length {got}, expected {expected}")]
    InputLength {
        /// Required length.
        expected: usize,
        /// Given length.
        got: usize,
    },
    /// A parameter of a track description is invalid.
    #[error("invalid {what}: {reason}")]
    Invalid {
        /// What is invalid (e.g. "section 3 length").
        what: String,
        /// Why.
        reason: String,
    },
    /// Two consecutive sections do not join smoothly.
    #[error(
        "{quantity} jumps at the joint between section {before} and section {after} \
         (s = {s} m): {value_before} -> {value_after}"
    )]
    Discontinuity {
        /// "curvature" (1/m) or "cant" (m).
        quantity: &'static str,
        /// Index of the section before the joint.
        before: usize,
        /// Index of the section after the joint.
        after: usize,
        /// Arc position of the joint, m.
        s: f64,
        /// Value at the end of the first section.
        value_before: f64,
        /// Value at the start of the second section.
        value_after: f64,
    },
    /// A file could not be read.
    #[error("cannot read {}: {message}", file.display())]
    Io {
        /// The file.
        file: PathBuf,
        /// The operating system's message.
        message: String,
    },
    /// A CSV file has a bad header or row.
    #[error("{}: row {row}: {message}", file.display())]
    Csv {
        /// The file.
        file: PathBuf,
        /// 1-based line number in the file (the header is line 1).
        row: usize,
        /// What is wrong.
        message: String,
    },
}

pub(crate) fn invalid(what: impl Into<String>, reason: impl Into<String>) -> TrackError {
    TrackError::Invalid {
        what: what.into(),
        reason: reason.into(),
    }
}

/// Checks that `value` is finite, naming it in the error otherwise.
pub(crate) fn finite(what: &'static str, value: f64) -> Result<f64, TrackError> {
    if value.is_finite() {
        Ok(value)
    } else {
        Err(TrackError::NotFinite { what, value })
    }
}

/// Checks a description parameter: finite and, if `positive`, > 0.
pub(crate) fn check_param(what: &str, value: f64, positive: bool) -> Result<f64, TrackError> {
    if !value.is_finite() {
        return Err(invalid(what, format!("{value} is not finite")));
    }
    if positive && value <= 0.0 {
        return Err(invalid(what, format!("{value} must be > 0")));
    }
    Ok(value)
}
