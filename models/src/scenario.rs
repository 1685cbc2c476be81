//! Scenarios: what to simulate (a model with overrides), for how long, with
//! which integrator, and what to write.

use std::path::PathBuf;

/// Which Jacobian Park's Newton iteration uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
pub enum JacobianKind {
    /// Central finite differences of the generalized forces (test oracle).
    #[default]
    FiniteDifference,
    /// Assembled from the force elements' local analytic Jacobians (paper Sect. 6).
    Analytic,
}

/// Integrator settings.
#[derive(Debug, Clone, PartialEq)]
pub enum IntegratorSpec {
    /// Park's implicit method with variable step (paper Sect. 6).
    Park {
        /// Relative tolerance of the local error estimate.
        rtol: f64,
        /// Absolute tolerance (m, rad; velocities use it divided by nothing: same number).
        atol: f64,
        /// Largest step, s.
        max_step: f64,
        /// First step, s (default: derived from tolerances and max_step).
        initial_step: Option<f64>,
        jacobian: JacobianKind,
    },
    /// Classical explicit fourth-order Runge–Kutta with fixed step (models
    /// without cut joints).
    Rk4 {
        /// s.
        step: f64,
    },
}

/// An initial-condition override of one coordinate.
#[derive(Debug, Clone, PartialEq)]
pub struct InitialOverride {
    /// Long coordinate name.
    pub coordinate: String,
    /// m or rad, if overridden.
    pub value: Option<f64>,
    /// m/s or rad/s, if overridden.
    pub velocity: Option<f64>,
}

/// Which variables go to the output file besides `time`.
#[derive(Debug, Clone, PartialEq)]
pub struct OutputSpec {
    /// Output interval, s. The end time is always the last row.
    pub interval: f64,
    /// All generalized coordinates, columns named exactly as the coordinates.
    pub coordinates: bool,
    /// Generalized velocities, columns `<coordinate>.v`.
    pub velocities: bool,
    /// Bodies whose position, orientation and velocities are written
    /// (`<body>.x`, `.y`, `.z`, `.vx` …); `["*"]` for all.
    pub bodies: Vec<String>,
    /// Force elements whose forces are written (`<element>.F` …); `["*"]` for all.
    pub forces: Vec<String>,
}

/// A resolved scenario.
#[derive(Debug, Clone, PartialEq)]
pub struct Scenario {
    /// The scenario file.
    pub source: PathBuf,
    /// Model file, resolved relative to the scenario file.
    pub model: PathBuf,
    /// Macros of the model to apply, in order, before `parameters`.
    pub macros: Vec<String>,
    /// Parameter overrides: (identifier name, value expression text over the
    /// model's parameters; a RON number is stored as its text). Resolved by
    /// `Model::parameter_values`, which names this scenario file in its errors.
    pub parameters: Vec<(String, String)>,
    pub initial: Vec<InitialOverride>,
    /// s.
    pub end_time: f64,
    pub integrator: IntegratorSpec,
    pub output: OutputSpec,
    /// Output CSV, resolved relative to the scenario file; the command line's
    /// `-o` overrides it.
    pub output_file: Option<PathBuf>,
}
