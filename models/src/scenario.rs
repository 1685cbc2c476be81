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

/// The track a vehicle runs on (for models with track-following frames).
#[derive(Debug, Clone, PartialEq)]
pub struct ScenarioTrack {
    /// Track description file (RON, `railmbs_track::TrackDescription`),
    /// resolved relative to the scenario file.
    pub file: PathBuf,
    /// Arc position of the vehicle's reference point at t = 0, m.
    pub start: f64,
    /// Running speed along the track at t = 0, m/s (constant unless
    /// `speed_profile` is given).
    pub speed: f64,
    /// Speed profile: knots (t s, v m/s), the speed linear between them and
    /// held before the first and after the last (e.g. a slow deceleration to
    /// find a critical speed). Empty for constant speed.
    pub speed_profile: Vec<(f64, f64)>,
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
    /// Track and running speed, for models with track-following frames:
    /// `track: (file: "../tracks/tc1.ron", start: 11.0, speed: 4.4)`.
    pub track: Option<ScenarioTrack>,
}

use crate::error::{ModelError, ModelErrors};
use crate::load::ron_error;
use crate::locate::Locator;
use crate::model::Model;
use crate::raw::{OrderedMap, Value};
use serde::{Deserialize, Deserializer};
use std::path::Path;

fn some<'de, D: Deserializer<'de>, T: Deserialize<'de>>(d: D) -> Result<Option<T>, D::Error> {
    T::deserialize(d).map(Some)
}

fn yes() -> bool {
    true
}

#[derive(Debug, Deserialize)]
#[serde(rename = "Scenario", deny_unknown_fields)]
struct RawScenario {
    model: String,
    #[serde(default)]
    macros: Vec<String>,
    #[serde(default)]
    parameters: OrderedMap<Value>,
    #[serde(default)]
    initial: Vec<RawInitial>,
    end_time: f64,
    integrator: RawIntegrator,
    output: RawOutput,
    #[serde(default, deserialize_with = "some")]
    output_file: Option<String>,
    #[serde(default, deserialize_with = "some")]
    track: Option<RawTrack>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawTrack {
    file: String,
    #[serde(default)]
    start: f64,
    #[serde(default, deserialize_with = "some")]
    speed: Option<f64>,
    #[serde(default)]
    speed_profile: Vec<(f64, f64)>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawInitial {
    coord: String,
    #[serde(default, deserialize_with = "some")]
    value: Option<f64>,
    #[serde(default, deserialize_with = "some")]
    velocity: Option<f64>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
enum RawIntegrator {
    Rk4 {
        step: f64,
    },
    Park {
        rtol: f64,
        atol: f64,
        max_step: f64,
        #[serde(default, deserialize_with = "some")]
        initial_step: Option<f64>,
        #[serde(default)]
        jacobian: JacobianKind,
    },
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct RawOutput {
    interval: f64,
    #[serde(default = "yes")]
    coordinates: bool,
    #[serde(default)]
    velocities: bool,
    #[serde(default)]
    bodies: Vec<String>,
    #[serde(default)]
    forces: Vec<String>,
}

/// Reads a scenario file. The model path and the output file are resolved
/// relative to the scenario file's folder. Names of macros, parameters and
/// coordinates are checked against the model by [`Scenario::parameter_values`]
/// and [`Scenario::initial_state`].
pub fn load_scenario(path: &Path) -> Result<Scenario, ModelErrors> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| ModelError::new(path, "", format!("cannot read the scenario file: {e}")))?;
    parse_scenario(&text, path)
}

/// Resolves scenario text; `path` is the scenario file (for errors and relative paths).
pub fn parse_scenario(text: &str, path: &Path) -> Result<Scenario, ModelErrors> {
    let loc = Locator::new(text);
    let raw: RawScenario = ron::Options::default()
        .from_str(text)
        .map_err(|e| ron_error(&loc, path, e))?;
    let mut errors = Vec::new();
    let mut check = |ok: bool, key: &str, message: String| {
        if !ok {
            let position = loc
                .top()
                .and_then(|top| loc.key_anywhere(top, key))
                .map(|k| loc.pos(k));
            errors.push(ModelError {
                file: path.to_path_buf(),
                element: String::new(),
                message,
                position,
            });
        }
    };
    let positive = |x: f64| x.is_finite() && x > 0.0;
    check(
        positive(raw.end_time),
        "end_time",
        format!(
            "end_time must be positive and finite, got {} s",
            raw.end_time
        ),
    );
    let integrator = match raw.integrator {
        RawIntegrator::Rk4 { step } => {
            check(
                positive(step),
                "step",
                format!("integrator step must be positive and finite, got {step} s"),
            );
            IntegratorSpec::Rk4 { step }
        }
        RawIntegrator::Park {
            rtol,
            atol,
            max_step,
            initial_step,
            jacobian,
        } => {
            check(
                positive(rtol),
                "rtol",
                format!("integrator rtol must be positive and finite, got {rtol}"),
            );
            check(
                positive(atol),
                "atol",
                format!("integrator atol must be positive and finite, got {atol}"),
            );
            check(
                positive(max_step),
                "max_step",
                format!("integrator max_step must be positive and finite, got {max_step} s"),
            );
            if let Some(h) = initial_step {
                check(
                    positive(h),
                    "initial_step",
                    format!("integrator initial_step must be positive and finite, got {h} s"),
                );
            }
            IntegratorSpec::Park {
                rtol,
                atol,
                max_step,
                initial_step,
                jacobian,
            }
        }
    };
    check(
        positive(raw.output.interval),
        "interval",
        format!(
            "output interval must be positive and finite, got {} s",
            raw.output.interval
        ),
    );
    for init in &raw.initial {
        for (what, x) in [("value", init.value), ("velocity", init.velocity)] {
            if let Some(x) = x {
                check(
                    x.is_finite(),
                    what,
                    format!("initial {what} of \"{}\" is not finite: {x}", init.coord),
                );
            }
        }
        check(
            init.value.is_some() || init.velocity.is_some(),
            "initial",
            format!(
                "initial condition of \"{}\" sets neither value nor velocity",
                init.coord
            ),
        );
    }
    let track = raw.track.map(|t| {
        let profile_speed = t.speed_profile.first().map(|k| k.1);
        check(
            t.speed.is_some() != profile_speed.is_some(),
            "track",
            "the track needs either `speed` (constant) or `speed_profile` (knots (t, v)), not both"
                .into(),
        );
        for (i, &(kt, kv)) in t.speed_profile.iter().enumerate() {
            check(
                kt.is_finite() && kv.is_finite() && kv >= 0.0,
                "speed_profile",
                format!("speed_profile knot {i} ({kt} s, {kv} m/s) must be finite with v ≥ 0"),
            );
            if i > 0 {
                check(
                    kt > t.speed_profile[i - 1].0,
                    "speed_profile",
                    format!("speed_profile knot {i}: times must increase"),
                );
            }
        }
        if let Some(&(t0, _)) = t.speed_profile.first() {
            check(
                t0 == 0.0,
                "speed_profile",
                format!("the first speed_profile knot must be at t = 0, got {t0} s"),
            );
        }
        check(
            t.start.is_finite(),
            "start",
            format!("track start must be finite, got {}", t.start),
        );
        let speed = t.speed.or(profile_speed).unwrap_or(0.0);
        check(
            speed.is_finite(),
            "speed",
            format!("track speed must be finite, got {speed} m/s"),
        );
        ScenarioTrack {
            file: path.parent().unwrap_or(Path::new("")).join(t.file),
            start: t.start,
            speed,
            speed_profile: t.speed_profile,
        }
    });
    let mut parameters: Vec<(String, String)> = Vec::new();
    for (name, v) in raw.parameters.0 {
        check(
            !parameters.iter().any(|(n, _)| n == &name),
            "parameters",
            format!("parameter \"{name}\" is overridden twice"),
        );
        let text = match v {
            Value::Num(x) => {
                check(
                    x.is_finite(),
                    "parameters",
                    format!("parameter \"{name}\" is not finite: {x}"),
                );
                format!("{x:?}")
            }
            Value::Text(s) => s,
        };
        parameters.push((name, text));
    }
    if !errors.is_empty() {
        errors.sort_by_key(|e| e.position.unwrap_or((usize::MAX, usize::MAX)));
        return Err(ModelErrors(errors));
    }
    let dir = path.parent().unwrap_or(Path::new(""));
    Ok(Scenario {
        source: path.to_path_buf(),
        model: dir.join(&raw.model),
        macros: raw.macros,
        parameters,
        initial: raw
            .initial
            .into_iter()
            .map(|i| InitialOverride {
                coordinate: i.coord,
                value: i.value,
                velocity: i.velocity,
            })
            .collect(),
        end_time: raw.end_time,
        integrator,
        output: OutputSpec {
            interval: raw.output.interval,
            coordinates: raw.output.coordinates,
            velocities: raw.output.velocities,
            bodies: raw.output.bodies,
            forces: raw.output.forces,
        },
        output_file: raw.output_file.map(|f| dir.join(f)),
        track,
    })
}

impl Scenario {
    /// Locates a string literal (a macro, parameter or coordinate name) in the
    /// scenario file, if the file can still be read.
    fn locate(&self, literal: &str) -> Option<(usize, usize)> {
        let text = std::fs::read_to_string(&self.source).ok()?;
        let loc = Locator::new(&text);
        let top = loc.top()?;
        loc.string_in(top, literal).map(|k| loc.pos(k))
    }

    fn scenario_error(&self, mut e: ModelError, literal: &str) -> ModelError {
        e.file = self.source.clone();
        e.position = self.locate(literal);
        e
    }

    /// Parameter values of `model` with this scenario's macros and overrides;
    /// errors (unknown macro or parameter, bad value) name the scenario file.
    pub fn parameter_values(&self, model: &Model) -> Result<Vec<f64>, ModelErrors> {
        model
            .parameter_values(&self.macros, &self.parameters)
            .map_err(|e| {
                let literal = e.element.split('"').nth(1).unwrap_or_default().to_string();
                ModelErrors(vec![self.scenario_error(e, &literal)])
            })
    }

    /// Initial coordinates and velocities of `model` for parameter values
    /// `params`, with this scenario's initial overrides applied. Every unknown
    /// coordinate name is reported.
    pub fn initial_state(
        &self,
        model: &Model,
        params: &[f64],
    ) -> Result<(Vec<f64>, Vec<f64>), ModelErrors> {
        let (mut q, mut v) = model.initial_state(params);
        let mut errors = Vec::new();
        for init in &self.initial {
            match model.coordinate_index(&init.coordinate) {
                Some(i) => {
                    if let Some(x) = init.value {
                        q[i] = x;
                    }
                    if let Some(x) = init.velocity {
                        v[i] = x;
                    }
                }
                None => {
                    let e = ModelError::new(
                        &self.source,
                        format!("initial \"{}\"", init.coordinate),
                        format!("unknown coordinate of model \"{}\"", model.name),
                    );
                    errors.push(self.scenario_error(e, &init.coordinate));
                }
            }
        }
        if errors.is_empty() {
            Ok((q, v))
        } else {
            Err(ModelErrors(errors))
        }
    }
}
