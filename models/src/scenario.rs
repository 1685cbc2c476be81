//! Scenarios: what to simulate (a model with overrides), for how long, with
//! which integrator, and what to write.

use std::path::PathBuf;

/// Which Jacobian Park's Newton iteration uses.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
pub enum JacobianKind {
    /// Forward finite differences of the generalized forces, one evaluation per
    /// coordinate and velocity (a test oracle; the integrator also has central
    /// differences, which scenarios do not select).
    #[default]
    FiniteDifference,
    /// Assembled from the force elements' local analytic Jacobians (Pogorelov 2005, Sect. 6).
    Analytic,
}

/// How Park's method solves its linear systems (the Newton iteration
/// matrix, and the accelerations of the initial state).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
pub enum LinearSolverKind {
    /// Dense LU of the whole matrix (every model; the reference).
    Dense,
    /// The bordered block-diagonal LU where the model has such structure:
    /// in trains the vehicles are the diagonal blocks and the coordinates
    /// of the coupled bodies the border (work linear in the number of
    /// vehicles); in a vehicle the top-level subsystems (bogies) are blocks
    /// besides the vehicle's own bodies, and the coordinates that couple
    /// across them (car body, bogie frames or bolsters) the border, when
    /// that saves at least half of the dense work. Models without such
    /// structure, with cut joints or with element states (series springs)
    /// use the dense LU. The default.
    #[default]
    Block,
}

/// Integrator settings.
#[derive(Debug, Clone, PartialEq)]
pub enum IntegratorSpec {
    /// Park's implicit method with variable step (Pogorelov 2005, Sect. 6).
    Park {
        /// Relative tolerance of the local error estimate.
        rtol: f64,
        /// Absolute tolerance (m, rad; velocities use it divided by nothing: same number).
        atol: f64,
        /// Largest step, s.
        max_step: f64,
        /// First step, s (default: derived from tolerances and max_step).
        initial_step: Option<f64>,
        /// Jacobian of the Newton iteration (default `FiniteDifference`).
        jacobian: JacobianKind,
        /// Linear solver of the Newton iteration (`solver: Block`, the
        /// default, or `solver: Dense`).
        solver: LinearSolverKind,
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

/// Where a run starts.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, serde::Serialize, serde::Deserialize)]
pub enum InitialStateKind {
    /// At the model's `init` and `vel` with the scenario's `initial`
    /// overrides, as given.
    #[default]
    Given,
    /// At the static (steady) equilibrium found from the given state: the
    /// coordinates with stiffness settle where the forces balance at zero
    /// velocity relative to their frames, rolling coordinates (moving, no
    /// stiffness: wheel spin) keep rolling at the rate that balances them,
    /// and coordinates without stiffness or damping stay as given
    /// (`umsim equilibrium` shows the solution).
    Equilibrium,
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
    /// Points whose accelerations are written (`<name>.ax[m/s2]`, `.ay`,
    /// `.az`): in the frame of their body, kinematic (gravity not included).
    pub accelerometers: Vec<Accelerometer>,
}

/// An acceleration output: a point fixed to a body.
#[derive(Debug, Clone, PartialEq)]
pub struct Accelerometer {
    /// Column prefix.
    pub name: String,
    /// Body name.
    pub body: String,
    /// The point in the body's frame, m.
    pub point: [f64; 3],
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
    /// The track itself, read from `file`, validated and built when the
    /// scenario is loaded (with its measured irregularities, if any).
    pub track: Arc<Track>,
    /// The equivalent conicity override of the quasi-linear analyses (–):
    /// every wheel–rail contact's geometry scaled in the lateral shift so
    /// that its central conicity is this (the runtime's wheel–rail element,
    /// "Conicity override"); `None` (the default, and what scenario files
    /// give) for the profiles' own geometry. Set by `umsim modes
    /// --conicity`.
    pub conicity: Option<f64>,
}

impl ScenarioTrack {
    /// Puts the scenario on the track of `file` instead (read, parsed and built
    /// as when the scenario loads; `file` replaces [`ScenarioTrack::file`]).
    pub fn load_file(&mut self, file: &Path) -> Result<(), ModelErrors> {
        let conicity = self.conicity;
        *self = PendingTrack {
            file: file.to_path_buf(),
            start: self.start,
            speed: self.speed,
            speed_profile: self.speed_profile.clone(),
        }
        .load()?;
        self.conicity = conicity;
        Ok(())
    }
}

/// A scenario's track settings, validated, before the track file is read.
struct PendingTrack {
    file: PathBuf,
    start: f64,
    speed: f64,
    speed_profile: Vec<(f64, f64)>,
}

impl PendingTrack {
    /// Reads, parses and builds the track file: RON errors with line and
    /// column, build errors (geometry, irregularity files) naming the file.
    fn load(self) -> Result<ScenarioTrack, ModelErrors> {
        let text = crate::error::read_text(&self.file, "track")?;
        let track = parse_track(&text, &self.file)?;
        Ok(ScenarioTrack {
            file: self.file,
            start: self.start,
            speed: self.speed,
            speed_profile: self.speed_profile,
            track: Arc::new(track),
            conicity: None,
        })
    }
}

/// Parses and builds the text of the track file `file` (RON,
/// `railmbs_track::TrackDescription`): RON errors with line and column, build
/// errors (geometry, irregularity files, read relative to `file`'s folder)
/// naming the file.
pub fn parse_track(text: &str, file: &Path) -> Result<Track, ModelErrors> {
    let loc = Locator::new(text);
    let description: TrackDescription = ron::Options::default()
        .from_str(text)
        .map_err(|e| ron_error(&loc, file, e))?;
    let base = file.parent().unwrap_or(Path::new(""));
    description
        .build(base)
        .map_err(|e| ModelErrors(vec![ModelError::new(file, "track", e.to_string())]))
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
    /// Initial-condition overrides of coordinates (`initial`), replacing the
    /// model's `init` and `vel`; checked by [`Scenario::initial_state`].
    /// With `initial_state: Equilibrium` they are the starting guess.
    pub initial: Vec<InitialOverride>,
    /// Whether the run starts at the given state or at the equilibrium
    /// found from it (`initial_state: Equilibrium`).
    pub initial_kind: InitialStateKind,
    /// Simulated time from t = 0, s.
    pub end_time: f64,
    /// The integrator and its settings.
    pub integrator: IntegratorSpec,
    /// What is written, and how often.
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
use railmbs_track::{Track, TrackDescription};
use railmbs_wheelrail::readable;
use serde::{Deserialize, Deserializer};
use std::path::Path;
use std::sync::Arc;

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
    #[serde(default)]
    initial_state: InitialStateKind,
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
        #[serde(default)]
        solver: LinearSolverKind,
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
    #[serde(default)]
    accelerometers: OrderedMap<(String, (f64, f64, f64))>,
}

/// Reads a scenario file. The model path and the output file are resolved
/// relative to the scenario file's folder. Names of macros, parameters and
/// coordinates are checked against the model by [`Scenario::parameter_values`]
/// and [`Scenario::initial_state`].
pub fn load_scenario(path: &Path) -> Result<Scenario, ModelErrors> {
    let text = crate::error::read_text(path, "scenario")?;
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
    let Common {
        integrator,
        output,
        track,
        parameters,
    } = common(
        raw.end_time,
        raw.integrator,
        raw.output,
        raw.track,
        raw.parameters,
        path,
        &mut check,
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
    if !errors.is_empty() {
        errors.sort_by_key(|e| e.position.unwrap_or((usize::MAX, usize::MAX)));
        return Err(ModelErrors(errors));
    }
    let track = track.map(PendingTrack::load).transpose()?;
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
        initial_kind: raw.initial_state,
        end_time: raw.end_time,
        integrator,
        output,
        output_file: raw.output_file.map(|f| dir.join(f)),
        track,
    })
}

/// What a single-vehicle scenario and a train share, validated.
struct Common {
    integrator: IntegratorSpec,
    output: OutputSpec,
    track: Option<PendingTrack>,
    parameters: Vec<(String, String)>,
}

/// Most output rows a run may write: end_time / interval. A run past it is
/// refused when the file is read (10⁸ rows of a vehicle's few hundred
/// columns are tens of gigabytes of CSV); a longer study splits its runs.
pub const MAX_OUTPUT_ROWS: f64 = 1e8;

/// Most integration steps a run may need at the least: end_time / step for
/// RK4, end_time / max_step for Park's method. At a microsecond per step
/// (a one-body model) 10⁹ steps are a quarter of an hour; a vehicle takes
/// a hundred times longer.
pub const MAX_STEPS: f64 = 1e9;

/// Why a run of `end_time` (s) with `integrator` and output `interval` (s)
/// could not finish or would fill the disk: (field, message) for more than
/// [`MAX_OUTPUT_ROWS`] rows or [`MAX_STEPS`] steps, or an RK4 step longer
/// than the run. Values that are not positive and finite are left to their
/// own checks.
pub fn run_limit_problems(
    end_time: f64,
    integrator: &IntegratorSpec,
    interval: f64,
) -> Vec<(&'static str, String)> {
    let positive = |x: f64| x.is_finite() && x > 0.0;
    let mut problems = Vec::new();
    if !positive(end_time) {
        return problems;
    }
    match *integrator {
        IntegratorSpec::Rk4 { step } if positive(step) => {
            if step > end_time {
                problems.push((
                    "step",
                    format!(
                        "RK4 step {} s is longer than the run (end_time {} s); a fixed-step \
                         explicit method needs many steps per period of the fastest motion",
                        readable(step),
                        readable(end_time)
                    ),
                ));
            }
            if end_time / step > MAX_STEPS {
                problems.push((
                    "step",
                    format!(
                        "RK4 step {} s over end_time {} s would take {:.3e} steps \
                         (at most {MAX_STEPS:e})",
                        readable(step),
                        readable(end_time),
                        end_time / step
                    ),
                ));
            }
        }
        IntegratorSpec::Park { max_step, .. }
            if positive(max_step) && end_time / max_step > MAX_STEPS =>
        {
            problems.push((
                "max_step",
                format!(
                    "max_step {} s over end_time {} s would take at least {:.3e} steps \
                     (at most {MAX_STEPS:e})",
                    readable(max_step),
                    readable(end_time),
                    end_time / max_step
                ),
            ));
        }
        _ => {}
    }
    let rows = end_time / interval;
    if positive(interval) && rows > MAX_OUTPUT_ROWS {
        problems.push((
            "interval",
            format!(
                "end_time {} s with output interval {} s would write {rows:.3e} rows \
                 (at most {MAX_OUTPUT_ROWS:e}): choose a longer interval",
                readable(end_time),
                readable(interval)
            ),
        ));
    }
    problems
}

/// `end_time` (s) if a run of it with `integrator` and output `interval` (s)
/// is possible (positive, finite, within [`run_limit_problems`]), else why not.
fn checked_end_time(
    end_time: f64,
    integrator: &IntegratorSpec,
    interval: f64,
) -> Result<f64, String> {
    if !(end_time.is_finite() && end_time > 0.0) {
        return Err(format!(
            "end time must be positive and finite, got {end_time} s"
        ));
    }
    match run_limit_problems(end_time, integrator, interval)
        .into_iter()
        .next()
    {
        Some((_, message)) => Err(message),
        None => Ok(end_time),
    }
}

/// Sets `name` to `value` in a list of parameter assignments, replacing an
/// earlier assignment of it.
fn set_assignment(list: &mut Vec<(String, String)>, name: &str, value: &str) {
    match list.iter_mut().find(|(n, _)| n == name) {
        Some((_, v)) => *v = value.to_string(),
        None => list.push((name.to_string(), value.to_string())),
    }
}

/// Validates the parts common to `Scenario` and `Train` files (`check`
/// records an error at the first `key:` of the file when `ok` is false).
fn common(
    end_time: f64,
    raw_integrator: RawIntegrator,
    raw_output: RawOutput,
    raw_track: Option<RawTrack>,
    raw_parameters: OrderedMap<Value>,
    path: &Path,
    check: &mut dyn FnMut(bool, &str, String),
) -> Common {
    let positive = |x: f64| x.is_finite() && x > 0.0;
    check(
        positive(end_time),
        "end_time",
        format!("end_time must be positive and finite, got {} s", end_time),
    );
    let integrator = match raw_integrator {
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
            solver,
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
                solver,
            }
        }
    };
    check(
        positive(raw_output.interval),
        "interval",
        format!(
            "output interval must be positive and finite, got {} s",
            raw_output.interval
        ),
    );
    for (field, message) in run_limit_problems(end_time, &integrator, raw_output.interval) {
        check(false, field, message);
    }
    let track = raw_track.map(|t| {
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
        PendingTrack {
            file: path.parent().unwrap_or(Path::new("")).join(t.file),
            start: t.start,
            speed,
            speed_profile: t.speed_profile,
        }
    });
    let parameters = overrides(raw_parameters, check);
    Common {
        integrator,
        output: OutputSpec {
            interval: raw_output.interval,
            coordinates: raw_output.coordinates,
            velocities: raw_output.velocities,
            bodies: raw_output.bodies,
            forces: raw_output.forces,
            accelerometers: {
                let mut out: Vec<Accelerometer> = Vec::new();
                for (name, (body, (x, y, z))) in raw_output.accelerometers.0 {
                    check(
                        !out.iter().any(|a| a.name == name),
                        "accelerometers",
                        format!("accelerometer \"{name}\" is given twice"),
                    );
                    check(
                        [x, y, z].iter().all(|c| c.is_finite()),
                        "accelerometers",
                        format!("accelerometer \"{name}\": the point must be finite"),
                    );
                    out.push(Accelerometer {
                        name,
                        body,
                        point: [x, y, z],
                    });
                }
                out
            },
        },
        track,
        parameters,
    }
}

/// Parameter overrides as (name, expression text); a RON number is stored as
/// its text.
fn overrides(
    raw_parameters: OrderedMap<Value>,
    check: &mut dyn FnMut(bool, &str, String),
) -> Vec<(String, String)> {
    let mut parameters: Vec<(String, String)> = Vec::new();
    for (name, v) in raw_parameters.0 {
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
    parameters
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

    /// The files a run of this scenario reads, with what each is: the
    /// scenario file, the model file and the track file.
    pub fn input_files(&self) -> Vec<(&'static str, &Path)> {
        let mut files = vec![
            ("scenario file", self.source.as_path()),
            ("model file", self.model.as_path()),
        ];
        files.extend(
            self.track
                .as_ref()
                .map(|t| ("track file", t.file.as_path())),
        );
        files
    }

    /// Replaces the end time (s) by `end_time`, checked like the file's own
    /// (`umsim run --end-time`, studies): positive, finite, and within the
    /// run limits with this scenario's integrator and output interval.
    ///
    /// # Errors
    /// What is wrong, in one message.
    pub fn set_end_time(&mut self, end_time: f64) -> Result<(), String> {
        self.end_time = checked_end_time(end_time, &self.integrator, self.output.interval)?;
        Ok(())
    }

    /// Sets parameter `name` to the expression `value` (over the model's
    /// parameters), replacing the file's own assignment of it if any
    /// (`umsim run --set`); checked with the model when the run is prepared.
    pub fn set_parameter(&mut self, name: &str, value: &str) {
        set_assignment(&mut self.parameters, name, value);
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

/// A coupler between bodies of two vehicles of a train: a linear spring–damper
/// between a point of each body, in the frame of body 1 (like a `Linear6`
/// element): the force on body 2 is −(K δ + C δ̇ + F₀) with δ the position of
/// point 2 relative to point 1 in body 1's axes and the small relative
/// rotation (angular stiffness and damping, default 0).
#[derive(Debug, Clone, PartialEq)]
pub struct TrainCoupler {
    /// Coupler name (unique in the train), prefix of its output columns.
    pub name: String,
    /// Vehicle index of body 1 (in `TrainScenario::vehicles`), from the
    /// vehicle name in `body1: "Coach1.body"`.
    pub vehicle1: usize,
    /// Body long name of body 1 within its vehicle's model (`body` in
    /// `"Coach1.body"`), checked by [`TrainScenario::resolve_coupler`].
    pub body1: String,
    /// Attachment point in body 1's frame (from its centre of mass), m.
    pub point1: [f64; 3],
    /// Vehicle index of body 2 (another vehicle than `vehicle1`).
    pub vehicle2: usize,
    /// Body long name of body 2 within its vehicle's model.
    pub body2: String,
    /// Attachment point in body 2's frame (from its centre of mass), m.
    pub point2: [f64; 3],
    /// Translational stiffness along x, y, z of body 1, N/m.
    pub stiffness: [f64; 3],
    /// Translational damping, N s/m.
    pub damping: [f64; 3],
    /// Rotational stiffness about x, y, z, N m/rad.
    pub angular_stiffness: [f64; 3],
    /// Rotational damping, N m s/rad.
    pub angular_damping: [f64; 3],
    /// Constant force F₀, N (positive x: body 2 pushed backwards, i.e. a
    /// compressed coupler between a leading body 1 and a trailing body 2).
    pub preload: [f64; 3],
    /// Nonlinear longitudinal characteristic replacing `stiffness.x`: rows
    /// (δx m, force N), δx the displacement of point 2 from point 1 along
    /// body 1's x axis, body 2 receiving −f along that axis. With body 1
    /// leading and body 2 trailing, δx > 0 compresses the buffers and δx < 0
    /// pulls the draw gear; slack is a range of zero force. The damping along
    /// x stays linear.
    pub longitudinal: Option<(Vec<(f64, f64)>, crate::Interpolation)>,
}

/// One vehicle of a train: a model file at an arc offset from the train's
/// reference point, with its own macros, parameter overrides and initial
/// conditions.
#[derive(Debug, Clone, PartialEq)]
pub struct TrainVehicle {
    /// Instance name, prefix of all its output columns (`Coach2.body.x[m]`).
    pub name: String,
    /// Model file, resolved relative to the train file.
    pub model: PathBuf,
    /// Arc offset of the vehicle's reference point from the train's, m
    /// (negative behind: 0, −26, −52 for three 26 m coaches).
    pub offset: f64,
    /// Macros of the vehicle's model to apply, in order, before the parameter
    /// overrides.
    pub macros: Vec<String>,
    /// The vehicle's own parameter overrides (name, value expression text);
    /// [`TrainScenario::vehicle_scenario`] puts the train-wide ones its model
    /// knows before them.
    pub parameters: Vec<(String, String)>,
    /// Initial-condition overrides of the vehicle's coordinates (names
    /// without the vehicle prefix).
    pub initial: Vec<InitialOverride>,
}

/// A resolved train scenario (a `Train(...)` file): several vehicles, each
/// from its own model, on one track at one running speed, coupled by couplers.
#[derive(Debug, Clone, PartialEq)]
pub struct TrainScenario {
    /// The train file.
    pub source: PathBuf,
    /// The vehicles, at least one, with unique names.
    pub vehicles: Vec<TrainVehicle>,
    /// Couplers, each between bodies of two different vehicles.
    pub couplers: Vec<TrainCoupler>,
    /// Couplers written as force elements of the model language (any
    /// element, with `"<vehicle>.<body>"` names), after the `Coupler(...)`
    /// ones in the output; resolved against the vehicles' models by
    /// [`TrainScenario::resolve_elements`].
    pub elements: Vec<TrainElement>,
    /// Threads evaluating the vehicles (1: sequentially in the calling
    /// thread); the results do not depend on it.
    pub threads: usize,
    /// Train-wide parameter overrides (applied to every vehicle whose model
    /// has the parameter; each must be known to at least one model).
    pub parameters: Vec<(String, String)>,
    /// Where the run starts: as given (each vehicle's `init`, `vel` and
    /// `initial` overrides), or at the train's static (steady)
    /// equilibrium found from there, all vehicles and couplers solved
    /// together (`initial_state: Equilibrium`, as for one vehicle).
    pub initial_kind: InitialStateKind,
    /// Simulated time from t = 0, s.
    pub end_time: f64,
    /// The integrator and its settings, for the whole train.
    pub integrator: IntegratorSpec,
    /// Names in `bodies` and `forces` are `<vehicle>.<long name>` or `"*"`;
    /// coordinates are written as `<vehicle>.<coordinate>`. Coupler forces
    /// are always written.
    pub output: OutputSpec,
    /// Output CSV, resolved relative to the train file; the command line's
    /// `-o` overrides it.
    pub output_file: Option<PathBuf>,
    /// The train's reference point starts at `start` (the first vehicle at
    /// offset 0 usually) and runs at `speed`.
    pub track: ScenarioTrack,
}

/// A scenario file of either kind.
#[derive(Debug, Clone, PartialEq)]
pub enum AnyScenario {
    /// `Scenario(...)`: one model.
    Single(Scenario),
    /// `Train(...)`: several vehicles coupled.
    Train(TrainScenario),
}

#[derive(Debug, Deserialize)]
#[serde(rename = "Train", deny_unknown_fields)]
struct RawTrain {
    vehicles: Vec<RawVehicle>,
    #[serde(default)]
    couplers: Vec<RawTrainCoupler>,
    #[serde(default, deserialize_with = "some")]
    threads: Option<usize>,
    #[serde(default)]
    parameters: OrderedMap<Value>,
    #[serde(default)]
    initial_state: InitialStateKind,
    end_time: f64,
    integrator: RawIntegrator,
    output: RawOutput,
    #[serde(default, deserialize_with = "some")]
    output_file: Option<String>,
    track: RawTrack,
}

#[derive(Debug, Deserialize)]
#[serde(rename = "Vehicle", deny_unknown_fields)]
struct RawVehicle {
    name: String,
    model: String,
    #[serde(default)]
    offset: f64,
    #[serde(default)]
    macros: Vec<String>,
    #[serde(default)]
    parameters: OrderedMap<Value>,
    #[serde(default)]
    initial: Vec<RawInitial>,
}

#[derive(Debug, Deserialize)]
#[serde(rename = "Coupler", deny_unknown_fields)]
struct RawCoupler {
    name: String,
    body1: String,
    #[serde(default)]
    point1: (f64, f64, f64),
    body2: String,
    #[serde(default)]
    point2: (f64, f64, f64),
    stiffness: (f64, f64, f64),
    #[serde(default)]
    damping: (f64, f64, f64),
    #[serde(default)]
    angular_stiffness: (f64, f64, f64),
    #[serde(default)]
    angular_damping: (f64, f64, f64),
    #[serde(default)]
    preload: (f64, f64, f64),
    #[serde(default, deserialize_with = "some")]
    longitudinal: Option<Vec<(f64, f64)>>,
    #[serde(default)]
    interpolation: crate::Interpolation,
}

/// A coupler of a train file: the linear `Coupler(...)` or any force
/// element of the model language.
// Raw syntax lives only while a file is read; size does not matter.
#[allow(clippy::large_enum_variant)]
#[derive(Debug)]
enum RawTrainCoupler {
    Coupler(RawCoupler),
    Element(crate::forces::RawForce),
}

/// The constructors a train's `couplers` list accepts.
static COUPLER_CONSTRUCTORS: std::sync::LazyLock<Vec<&'static str>> =
    std::sync::LazyLock::new(|| {
        let mut all = vec!["Coupler"];
        all.extend_from_slice(crate::forces::CONSTRUCTORS);
        all
    });

impl<'de> Deserialize<'de> for RawTrainCoupler {
    fn deserialize<D: Deserializer<'de>>(d: D) -> Result<Self, D::Error> {
        use serde::de::{EnumAccess, VariantAccess, Visitor};
        struct V;
        impl<'de> Visitor<'de> for V {
            type Value = RawTrainCoupler;
            fn expecting(&self, f: &mut std::fmt::Formatter) -> std::fmt::Result {
                f.write_str("a coupler or a force element")
            }
            fn visit_enum<A: EnumAccess<'de>>(self, data: A) -> Result<Self::Value, A::Error> {
                let (crate::forces::Constructor(ctor), variant) = data.variant()?;
                let expected: &'static [&'static str] = COUPLER_CONSTRUCTORS.as_slice();
                if ctor == "Coupler" {
                    variant
                        .struct_variant(&[], crate::forces::StructOf::<RawCoupler>::default())
                        .map(RawTrainCoupler::Coupler)
                } else {
                    crate::forces::RawForce::from_variant(&ctor, variant, expected)
                        .map(RawTrainCoupler::Element)
                }
            }
        }
        d.deserialize_enum("Coupler", COUPLER_CONSTRUCTORS.as_slice(), V)
    }
}

/// A coupler of a train written as a force element of the model language
/// (`Linear6`, `Spring`, `Tabulated`, `LoadFriction`, `PointPlane`…) between
/// bodies named `"<vehicle>.<body>"`, as read from the train file; its names
/// are resolved against the vehicles' models by
/// [`TrainScenario::resolve_elements`].
#[derive(Debug, Clone)]
pub struct TrainElement {
    /// Element name (unique among the train's couplers), prefix of its
    /// output columns.
    pub name: String,
    raw: Arc<crate::forces::RawForce>,
}

impl PartialEq for TrainElement {
    /// Same name and same syntax as read (compared through its debug text:
    /// the raw syntax has no other equality).
    fn eq(&self, other: &Self) -> bool {
        self.name == other.name && format!("{:?}", self.raw) == format!("{:?}", other.raw)
    }
}

/// A train coupler element resolved against the vehicles' models: its
/// element with the body indices renumbered to the coupler's own bodies
/// 0, 1, … (in order of first reference), and which body of which vehicle
/// each of them is.
#[derive(Debug, Clone, PartialEq)]
pub struct TrainForce {
    /// Element name.
    pub name: String,
    /// The element; `BodyRef::Body(i)` (or body index `i`) is `bodies[i]`.
    pub kind: crate::forces::ForceKind,
    /// (vehicle index, body index in that vehicle's model) of the element's
    /// body `i`.
    pub bodies: Vec<(usize, usize)>,
}

/// The constructor name of the file's top-level value (`Model`, `Scenario`,
/// `Train`), after whitespace and comments; `None` when there is none.
pub fn top_constructor(text: &str) -> Option<&str> {
    let mut rest = text;
    loop {
        rest = rest.trim_start();
        if let Some(r) = rest.strip_prefix("//") {
            rest = r.split_once('\n').map_or("", |x| x.1);
        } else if let Some(r) = rest.strip_prefix("/*") {
            rest = r.split_once("*/").map_or("", |x| x.1);
        } else {
            break;
        }
    }
    let end = rest
        .find(|c: char| !(c.is_ascii_alphanumeric() || c == '_'))
        .unwrap_or(rest.len());
    (end > 0).then(|| &rest[..end])
}

/// Reads a scenario file of either kind: `Train(...)` files are trains,
/// anything else goes to [`load_scenario`].
pub fn load_any_scenario(path: &Path) -> Result<AnyScenario, ModelErrors> {
    let text = crate::error::read_text(path, "scenario")?;
    if top_constructor(&text) == Some("Train") {
        parse_train(&text, path).map(AnyScenario::Train)
    } else {
        parse_scenario(&text, path).map(AnyScenario::Single)
    }
}

/// Reads a train file (`Train(...)`).
pub fn load_train(path: &Path) -> Result<TrainScenario, ModelErrors> {
    let text = crate::error::read_text(path, "train")?;
    parse_train(&text, path)
}

/// Resolves train text; `path` is the train file (for errors and relative
/// paths). Vehicle and coupler names are checked here; body names of
/// couplers against the models by [`TrainScenario::resolve_coupler`].
pub fn parse_train(text: &str, path: &Path) -> Result<TrainScenario, ModelErrors> {
    let loc = Locator::new(text);
    let raw: RawTrain = ron::Options::default()
        .from_str(text)
        .map_err(|e| ron_error(&loc, path, e))?;
    let mut errors = Vec::new();
    // Errors at a key (first occurrence) or, for an element, at its name.
    let mut report = |key: &str, literal: Option<&str>, element: String, message: String| {
        let position = loc.top().and_then(|top| {
            literal
                .and_then(|l| loc.string_in(top, l))
                .or_else(|| loc.key_anywhere(top, key))
                .map(|k| loc.pos(k))
        });
        errors.push(ModelError {
            file: path.to_path_buf(),
            element,
            message,
            position,
        });
    };
    let mut check = |ok: bool, key: &str, message: String| {
        if !ok {
            report(key, None, String::new(), message);
        }
    };
    let Common {
        integrator,
        output,
        track,
        parameters,
    } = common(
        raw.end_time,
        raw.integrator,
        raw.output,
        Some(raw.track),
        raw.parameters,
        path,
        &mut check,
    );
    let dir = path.parent().unwrap_or(Path::new(""));
    let mut vehicles: Vec<TrainVehicle> = Vec::new();
    let mut problems: Vec<(String, Option<String>, String, String)> = Vec::new();
    for v in raw.vehicles {
        let element = format!("vehicle \"{}\"", v.name);
        if v.name.is_empty() || v.name.contains('.') || v.name == "*" {
            problems.push((
                "name".into(),
                Some(v.name.clone()),
                element.clone(),
                "a vehicle name must be non-empty, without '.', and not \"*\"".into(),
            ));
        }
        if vehicles.iter().any(|w| w.name == v.name) {
            problems.push((
                "name".into(),
                Some(v.name.clone()),
                element.clone(),
                "two vehicles have this name".into(),
            ));
        }
        if !v.offset.is_finite() {
            problems.push((
                "offset".into(),
                Some(v.name.clone()),
                element.clone(),
                format!("offset must be finite, got {} m", v.offset),
            ));
        }
        for init in &v.initial {
            let finite = [init.value, init.velocity]
                .iter()
                .all(|x| x.is_none_or(f64::is_finite));
            if !finite || (init.value.is_none() && init.velocity.is_none()) {
                problems.push((
                    "initial".into(),
                    Some(init.coord.clone()),
                    element.clone(),
                    format!(
                        "initial condition of \"{}\" must set a finite value or velocity",
                        init.coord
                    ),
                ));
            }
        }
        let mut own_check = |ok: bool, key: &str, message: String| {
            if !ok {
                problems.push((key.into(), None, element.clone(), message));
            }
        };
        let own = overrides(v.parameters, &mut own_check);
        vehicles.push(TrainVehicle {
            name: v.name,
            model: dir.join(v.model),
            offset: v.offset,
            macros: v.macros,
            parameters: own,
            initial: v
                .initial
                .into_iter()
                .map(|i| InitialOverride {
                    coordinate: i.coord,
                    value: i.value,
                    velocity: i.velocity,
                })
                .collect(),
        });
    }
    if vehicles.is_empty() {
        problems.push((
            "vehicles".into(),
            None,
            String::new(),
            "a train needs at least one vehicle".into(),
        ));
    }
    let mut couplers: Vec<TrainCoupler> = Vec::new();
    let mut elements: Vec<TrainElement> = Vec::new();
    let mut names: Vec<String> = Vec::new();
    for entry in raw.couplers {
        let c = match entry {
            RawTrainCoupler::Coupler(c) => c,
            RawTrainCoupler::Element(f) => {
                let name = f.name().to_string();
                if names.contains(&name) || name.is_empty() {
                    problems.push((
                        "name".into(),
                        Some(name.clone()),
                        format!("coupler \"{name}\""),
                        "coupler names must be non-empty and unique".into(),
                    ));
                }
                names.push(name.clone());
                elements.push(TrainElement {
                    name,
                    raw: Arc::new(f),
                });
                continue;
            }
        };
        let element = format!("coupler \"{}\"", c.name);
        let duplicate = names.contains(&c.name);
        names.push(c.name.clone());
        if duplicate || c.name.is_empty() {
            problems.push((
                "name".into(),
                Some(c.name.clone()),
                element.clone(),
                "coupler names must be non-empty and unique".into(),
            ));
        }
        let mut side = |body: &str| -> Option<(usize, String)> {
            let found = body.split_once('.').and_then(|(v, b)| {
                vehicles
                    .iter()
                    .position(|w| w.name == v)
                    .map(|k| (k, b.to_string()))
            });
            if found.is_none() {
                let known: Vec<&str> = vehicles.iter().map(|w| w.name.as_str()).collect();
                problems.push((
                    "body1".into(),
                    Some(body.to_string()),
                    element.clone(),
                    format!(
                        "body \"{body}\" must be \"<vehicle>.<body>\" with a vehicle of the \
                         train (vehicles: {})",
                        known.join(", ")
                    ),
                ));
            }
            found
        };
        let s1 = side(&c.body1);
        let s2 = side(&c.body2);
        let v3 = |t: (f64, f64, f64)| [t.0, t.1, t.2];
        let numbers = [
            c.point1,
            c.point2,
            c.stiffness,
            c.damping,
            c.angular_stiffness,
            c.angular_damping,
            c.preload,
        ];
        if numbers
            .iter()
            .any(|t| !(t.0.is_finite() && t.1.is_finite() && t.2.is_finite()))
        {
            problems.push((
                "stiffness".into(),
                Some(c.name.clone()),
                element.clone(),
                "points, stiffness, damping and preload must be finite".into(),
            ));
        }
        for (field, t, what) in [
            ("stiffness", c.stiffness, "stiffness"),
            ("damping", c.damping, "damping"),
            (
                "angular_stiffness",
                c.angular_stiffness,
                "angular stiffness",
            ),
            ("angular_damping", c.angular_damping, "angular damping"),
        ] {
            // A negative stiffness or damping feeds energy into the train.
            if [t.0, t.1, t.2].iter().any(|x| *x < 0.0) {
                problems.push((
                    field.into(),
                    Some(c.name.clone()),
                    element.clone(),
                    format!(
                        "coupler {what} must not be negative, got ({}, {}, {})",
                        t.0, t.1, t.2
                    ),
                ));
            }
        }
        if let Some(rows) = &c.longitudinal
            && (rows.len() < 2
                || rows.windows(2).any(|w| w[1].0 <= w[0].0)
                || rows.iter().any(|(x, f)| !(x.is_finite() && f.is_finite())))
        {
            problems.push((
                "longitudinal".into(),
                Some(c.name.clone()),
                element.clone(),
                "the longitudinal characteristic needs at least 2 finite rows (extension m, \
                 force N) with increasing extensions"
                    .into(),
            ));
        }
        if let (Some((k1, b1)), Some((k2, b2))) = (s1, s2) {
            if k1 == k2 {
                problems.push((
                    "body2".into(),
                    Some(c.body2.clone()),
                    element.clone(),
                    "a coupler joins two different vehicles (use a force element of the \
                     model within one vehicle)"
                        .into(),
                ));
            }
            couplers.push(TrainCoupler {
                name: c.name,
                vehicle1: k1,
                body1: b1,
                point1: v3(c.point1),
                vehicle2: k2,
                body2: b2,
                point2: v3(c.point2),
                stiffness: v3(c.stiffness),
                damping: v3(c.damping),
                angular_stiffness: v3(c.angular_stiffness),
                angular_damping: v3(c.angular_damping),
                preload: v3(c.preload),
                longitudinal: c.longitudinal.map(|rows| (rows, c.interpolation)),
            });
        }
    }
    if raw.threads == Some(0) {
        problems.push((
            "threads".into(),
            None,
            String::new(),
            "threads must be at least 1".into(),
        ));
    }
    for (key, literal, element, message) in problems {
        report(&key, literal.as_deref(), element, message);
    }
    if !errors.is_empty() {
        errors.sort_by_key(|e| e.position.unwrap_or((usize::MAX, usize::MAX)));
        return Err(ModelErrors(errors));
    }
    let track = track.expect("a train always has a track").load()?;
    Ok(TrainScenario {
        source: path.to_path_buf(),
        vehicles,
        couplers,
        elements,
        threads: raw.threads.unwrap_or(1),
        parameters,
        initial_kind: raw.initial_state,
        end_time: raw.end_time,
        integrator,
        output,
        output_file: raw.output_file.map(|f| dir.join(f)),
        track,
    })
}

impl TrainScenario {
    /// The files a run of this train reads, with what each is: the train
    /// file, the track file and each vehicle's model file.
    pub fn input_files(&self) -> Vec<(&'static str, &Path)> {
        let mut files = vec![
            ("train file", self.source.as_path()),
            ("track file", self.track.file.as_path()),
        ];
        files.extend(
            self.vehicles
                .iter()
                .map(|v| ("model file", v.model.as_path())),
        );
        files
    }

    /// Replaces the end time (s), checked like the file's own (see
    /// [`Scenario::set_end_time`]).
    ///
    /// # Errors
    /// What is wrong, in one message.
    pub fn set_end_time(&mut self, end_time: f64) -> Result<(), String> {
        self.end_time = checked_end_time(end_time, &self.integrator, self.output.interval)?;
        Ok(())
    }

    /// Sets the train-wide parameter `name` to the expression `value`
    /// (every vehicle whose model has it), replacing the file's own
    /// assignment; a name no vehicle knows is reported when the train is
    /// built ([`TrainScenario::check_names`]).
    pub fn set_parameter(&mut self, name: &str, value: &str) {
        set_assignment(&mut self.parameters, name, value);
    }

    /// Locates a string literal in the train file, if it can still be read.
    fn locate(&self, literal: &str) -> Option<(usize, usize)> {
        let text = std::fs::read_to_string(&self.source).ok()?;
        let loc = Locator::new(&text);
        let top = loc.top()?;
        loc.string_in(top, literal).map(|k| loc.pos(k))
    }

    /// The single-model scenario of vehicle `k` with its `model`: the train's
    /// integrator and end time, the train-wide parameters its model knows then
    /// its own, the track with the start shifted by the vehicle's offset, and
    /// the output names selecting its bodies and elements (without the
    /// vehicle prefix). [`TrainScenario::check_names`] reports train-wide
    /// parameters and output names no vehicle knows.
    pub fn vehicle_scenario(&self, k: usize, model: &Model) -> Scenario {
        let v = &self.vehicles[k];
        let mut parameters: Vec<(String, String)> = self
            .parameters
            .iter()
            .filter(|(n, _)| model.parameter_index(n).is_some())
            .cloned()
            .collect();
        parameters.extend(v.parameters.iter().cloned());
        let prefix = format!("{}.", v.name);
        let mine = |names: &[String]| -> Vec<String> {
            if names.iter().any(|n| n == "*") {
                return vec!["*".to_string()];
            }
            names
                .iter()
                .filter_map(|n| n.strip_prefix(&prefix).map(str::to_string))
                .collect()
        };
        let mut track = self.track.clone();
        track.start += v.offset;
        Scenario {
            source: self.source.clone(),
            model: v.model.clone(),
            macros: v.macros.clone(),
            parameters,
            initial: v.initial.clone(),
            initial_kind: InitialStateKind::Given,
            end_time: self.end_time,
            integrator: self.integrator.clone(),
            output: OutputSpec {
                interval: self.output.interval,
                coordinates: self.output.coordinates,
                velocities: self.output.velocities,
                bodies: mine(&self.output.bodies),
                forces: mine(&self.output.forces),
                accelerometers: self
                    .output
                    .accelerometers
                    .iter()
                    .filter_map(|a| {
                        a.name.strip_prefix(&prefix).map(|n| Accelerometer {
                            name: n.to_string(),
                            ..a.clone()
                        })
                    })
                    .collect(),
            },
            output_file: None,
            track: Some(track),
        }
    }

    /// Checks that every train-wide parameter is known to some vehicle's
    /// model and every output name starts with a vehicle name (`models` in
    /// vehicle order).
    pub fn check_names(&self, models: &[&Model]) -> Result<(), ModelErrors> {
        let mut errors = Vec::new();
        for (name, _) in &self.parameters {
            if !models.iter().any(|m| m.parameter_index(name).is_some()) {
                errors.push(ModelError {
                    file: self.source.clone(),
                    element: format!("parameter \"{name}\""),
                    message: "no vehicle's model has this parameter".into(),
                    position: self.locate(name),
                });
            }
        }
        let accelerometers = self.output.accelerometers.iter().map(|a| &a.name);
        for name in self
            .output
            .bodies
            .iter()
            .chain(&self.output.forces)
            .chain(accelerometers)
        {
            if name == "*" {
                continue;
            }
            let known = self
                .vehicles
                .iter()
                .any(|v| name.strip_prefix(&format!("{}.", v.name)).is_some());
            if !known {
                errors.push(ModelError {
                    file: self.source.clone(),
                    element: format!("output \"{name}\""),
                    message: "output names are \"<vehicle>.<long name>\" (or \"*\")".into(),
                    position: self.locate(name),
                });
            }
        }
        if errors.is_empty() {
            Ok(())
        } else {
            Err(ModelErrors(errors))
        }
    }

    /// The couplers written as force elements ([`TrainScenario::elements`])
    /// resolved against the vehicles' models (`models` in vehicle order),
    /// with the model files' own resolution and range checks; body names
    /// are `"<vehicle>.<body>"`, expressions numbers (a train has no
    /// parameters of its own). An element needs at least one body of the
    /// train (one body and ground: an external force on the train), must not
    /// join bodies of one vehicle only (that belongs in the vehicle's model)
    /// and cannot be a wheel–rail contact or have first-order states (the
    /// train has no coordinates of its own for them). Errors name the
    /// train file, the element and the position.
    pub fn resolve_elements(&self, models: &[&Model]) -> Result<Vec<TrainForce>, ModelErrors> {
        if self.elements.is_empty() {
            return Ok(Vec::new());
        }
        let text =
            crate::error::read_text(&self.source, "train").map_err(|e| ModelErrors(vec![e]))?;
        let (mut names, mut owner) = (Vec::new(), Vec::new());
        for (k, (v, m)) in self.vehicles.iter().zip(models).enumerate() {
            for (b, body) in m.bodies.iter().enumerate() {
                names.push(format!("{}.{}", v.name, body.name));
                owner.push((k, b));
            }
        }
        let raws: Vec<&crate::forces::RawForce> = self.elements.iter().map(|e| &*e.raw).collect();
        let (kinds, mut errors) =
            crate::load::resolve_foreign_forces(&self.source, &text, &raws, &names);
        if !errors.is_empty() {
            return Err(ModelErrors(errors));
        }
        let mut out = Vec::new();
        for (e, mut kind) in self.elements.iter().zip(kinds) {
            let mut used: Vec<usize> = Vec::new();
            let mut references = 0;
            kind.bodies_mut(&mut |b| {
                references += 1;
                if !used.contains(b) {
                    used.push(*b);
                }
            });
            kind.bodies_mut(&mut |b| *b = used.iter().position(|u| u == b).unwrap_or(0));
            let bodies: Vec<(usize, usize)> = used.iter().map(|&g| owner[g]).collect();
            let mut problem = |message: String| {
                errors.push(ModelError {
                    file: self.source.clone(),
                    element: format!("coupler \"{}\"", e.name),
                    message,
                    position: self.locate(&e.name),
                });
            };
            if matches!(kind, crate::forces::ForceKind::WheelRail(_)) {
                problem(
                    "a wheel–rail contact belongs in a vehicle's model, not among the couplers"
                        .into(),
                );
            } else if matches!(kind, crate::forces::ForceKind::SeriesSpringDamper(_)) {
                problem(
                    "a SeriesSpring has a first-order state, which couplers between vehicles \
                     do not support: put it in a vehicle's model"
                        .into(),
                );
            } else if bodies.is_empty() {
                problem("the element acts on no body of the train".into());
            } else if references > 1 && bodies.iter().all(|b| b.0 == bodies[0].0) {
                problem(format!(
                    "all its bodies belong to vehicle \"{}\": a coupler joins bodies of \
                     different vehicles (put an element within one vehicle in its model)",
                    self.vehicles[bodies[0].0].name
                ));
            }
            out.push(TrainForce {
                name: e.name.clone(),
                kind,
                bodies,
            });
        }
        if errors.is_empty() {
            Ok(out)
        } else {
            Err(ModelErrors(errors))
        }
    }

    /// Body indices of coupler `c`'s two bodies in their vehicles' models
    /// (`models` in vehicle order); unknown bodies are errors at their name.
    pub fn resolve_coupler(
        &self,
        c: &TrainCoupler,
        models: &[&Model],
    ) -> Result<(usize, usize), ModelErrors> {
        let mut errors = Vec::new();
        let mut find = |k: usize, body: &str| {
            let found = models[k].body_index(body);
            if found.is_none() {
                let full = format!("{}.{body}", self.vehicles[k].name);
                errors.push(ModelError {
                    file: self.source.clone(),
                    element: format!("coupler \"{}\"", c.name),
                    message: format!(
                        "model \"{}\" of vehicle \"{}\" has no body \"{body}\"",
                        models[k].name, self.vehicles[k].name
                    ),
                    position: self.locate(&full),
                });
            }
            found
        };
        let b1 = find(c.vehicle1, &c.body1);
        let b2 = find(c.vehicle2, &c.body2);
        match (b1, b2) {
            (Some(b1), Some(b2)) => Ok((b1, b2)),
            _ => Err(ModelErrors(errors)),
        }
    }
}
