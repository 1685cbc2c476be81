//! Running a scenario: parameters and initial conditions from the scenario, an
//! engine, an integrator, output rows interpolated onto the output grid and
//! written as CSV while the run goes on (a run that stops early keeps what it
//! has written).

use crate::Equations;
use crate::equations::Parts;
use crate::forces::TrackBinding;
use crate::inputs::{DrivenEquations, InputProvider};
use crate::integrate::{self, IntegrationStats, ParkSettings, Rk4Settings};
use crate::model_system::ModelSystem;
use crate::system::SimError;
use crate::track_inputs::{RunningSpeed, TrackInputs};
use nalgebra::{Matrix3, Vector3};
use railmbs_models::{IntegratorSpec, JacobianKind, Model, OutputSpec, Scenario};
use std::io::Write;
use std::ops::ControlFlow;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Errors of a run that are not about the simulation itself.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    #[error("{file}: {message}")]
    Setup { file: PathBuf, message: String },
    #[error("cannot write {path}: {source}")]
    Io {
        path: PathBuf,
        source: std::io::Error,
    },
    #[error(transparent)]
    Sim(#[from] SimError),
}

/// What a finished (or stopped) run did.
#[derive(Debug, Clone)]
pub struct RunSummary {
    pub engine: String,
    /// Simulated time reached, s.
    pub t_end: f64,
    pub steps: usize,
    pub rejected_steps: usize,
    pub newton_iterations: usize,
    pub jacobian_evaluations: usize,
    pub dynamics_evaluations: usize,
    /// CPU (wall-clock, single thread) time of the integration, s.
    pub cpu_time: f64,
    /// Output rows written.
    pub rows: usize,
    /// Set when the simulation stopped with an error; rows up to that point
    /// were written.
    pub error: Option<SimError>,
    /// Maxima of the assessment quantities (Y/Q, ΣY, Q…) over the accepted
    /// steps, with their limits.
    pub assessment: Vec<crate::forces::Assessment>,
}

impl RunSummary {
    /// An empty summary of a run by `engine`, filled segment by segment.
    pub(crate) fn new(engine: String) -> Self {
        Self {
            engine,
            t_end: 0.0,
            steps: 0,
            rejected_steps: 0,
            newton_iterations: 0,
            jacobian_evaluations: 0,
            dynamics_evaluations: 0,
            cpu_time: 0.0,
            rows: 0,
            error: None,
            assessment: Vec::new(),
        }
    }

    /// Adds the counts of one integration segment and records its end time.
    pub(crate) fn add_segment(&mut self, st: &IntegrationStats) {
        self.steps += st.steps;
        self.rejected_steps += st.rejected_steps;
        self.newton_iterations += st.newton_iterations;
        self.jacobian_evaluations += st.jacobian_evaluations;
        self.dynamics_evaluations += st.dynamics_evaluations;
        self.t_end = st.t;
    }

    /// Completes the summary at the end of a run: CPU time, rows written,
    /// assessment, and the time reached (where a failure occurred, or the
    /// last accepted step).
    pub(crate) fn finish(
        &mut self,
        cpu_time: f64,
        rows: usize,
        last_step: Option<f64>,
        assessment: Vec<crate::forces::Assessment>,
    ) {
        match &self.error {
            Some(SimError::NonFinite { t, .. }) | Some(SimError::Diverged { t, .. }) => {
                self.t_end = *t;
            }
            Some(_) => self.t_end = last_step.unwrap_or(self.t_end),
            None => {}
        }
        self.cpu_time = cpu_time;
        self.rows = rows;
        self.assessment = assessment;
    }

    /// Simulated seconds per CPU second.
    pub fn realtime_factor(&self) -> f64 {
        self.t_end / self.cpu_time.max(1e-12)
    }
}

/// Parameter values and initial state of a run.
#[derive(Debug, Clone, PartialEq)]
pub struct InitialState {
    /// In `Model::parameters` order.
    pub params: Vec<f64>,
    /// Generalized coordinates (m, rad).
    pub q: Vec<f64>,
    /// Generalized velocities (m/s, rad/s).
    pub v: Vec<f64>,
}

/// The parameter values and initial state a scenario asks for (errors name the
/// scenario file, with line and column).
pub fn scenario_state(scenario: &Scenario, model: &Model) -> Result<InitialState, RunError> {
    let setup = |message: String| RunError::Setup {
        file: scenario.source.clone(),
        message,
    };
    let params = scenario
        .parameter_values(model)
        .map_err(|e| setup(e.to_string()))?;
    let (q, v) = scenario
        .initial_state(model, &params)
        .map_err(|e| setup(e.to_string()))?;
    if let Some(i) = q.iter().chain(&v).position(|x| !x.is_finite()) {
        return Err(setup(format!(
            "initial state of model \"{}\" is not finite (entry {i}); check the init/vel expressions",
            model.name
        )));
    }
    Ok(InitialState { params, q, v })
}

/// Column layout of the output file.
pub(crate) struct Columns {
    pub(crate) header: Vec<String>,
    /// The running speed law, when the run is on a track: the column `s[m]`
    /// (arc position of the vehicle's reference point) follows `time`.
    arc: Option<RunningSpeed>,
    coordinates: bool,
    velocities: bool,
    bodies: Vec<usize>,
    /// (offset into all force outputs, count) of each selected element.
    forces: Vec<(usize, usize)>,
    /// (body, point in the body's frame) of each accelerometer.
    accelerometers: Vec<(usize, Vector3<f64>)>,
    need_kinematics: bool,
}

fn select(
    names: &[String],
    wanted: &[String],
    what: &str,
    file: &Path,
) -> Result<Vec<usize>, RunError> {
    if wanted.iter().any(|w| w == "*") {
        return Ok((0..names.len()).collect());
    }
    wanted
        .iter()
        .map(|w| {
            names
                .iter()
                .position(|n| n == w)
                .ok_or_else(|| RunError::Setup {
                    file: file.to_path_buf(),
                    message: format!("output: no {what} named \"{w}\""),
                })
        })
        .collect()
}

pub(crate) fn columns(
    model: &Model,
    system: &ModelSystem,
    spec: &OutputSpec,
    file: &Path,
    arc: Option<RunningSpeed>,
) -> Result<Columns, RunError> {
    let mut header = vec!["time".to_string()];
    if arc.is_some() {
        header.push("s[m]".to_string());
    }
    if spec.coordinates {
        header.extend(model.coordinates.iter().map(|c| c.name.clone()));
        header.extend(system.state_names());
    }
    if spec.velocities {
        header.extend(model.coordinates.iter().map(|c| format!("{}.v", c.name)));
        header.extend(system.state_names().iter().map(|c| format!("{c}.v")));
    }
    let body_names: Vec<String> = model.bodies.iter().map(|b| b.name.clone()).collect();
    let bodies = select(&body_names, &spec.bodies, "body", file)?;
    for &b in &bodies {
        let n = &body_names[b];
        for s in [
            "x[m]",
            "y[m]",
            "z[m]",
            "rx[rad]",
            "ry[rad]",
            "rz[rad]",
            "vx[m/s]",
            "vy[m/s]",
            "vz[m/s]",
            "wx[rad/s]",
            "wy[rad/s]",
            "wz[rad/s]",
        ] {
            header.push(format!("{n}.{s}"));
        }
    }
    let force_names: Vec<String> = model.forces.iter().map(|f| f.name.clone()).collect();
    let mut offsets = Vec::with_capacity(force_names.len());
    let mut offset = 0;
    for f in system.forces() {
        offsets.push(offset);
        offset += f.output_names().len();
    }
    let mut accelerometers = Vec::new();
    for a in &spec.accelerometers {
        let b = select(&body_names, std::slice::from_ref(&a.body), "body", file).map_err(|_| {
            RunError::Setup {
                file: file.to_path_buf(),
                message: format!(
                    "output: accelerometer \"{}\" is on \"{}\", which is no body of the model",
                    a.name, a.body
                ),
            }
        })?[0];
        accelerometers.push((b, Vector3::from(a.point)));
    }
    let mut forces = Vec::new();
    for e in select(&force_names, &spec.forces, "force element", file)? {
        let names = system.forces()[e].output_names();
        for s in &names {
            header.push(format!("{}.{s}", force_names[e]));
        }
        forces.push((offsets[e], names.len()));
    }
    for a in &spec.accelerometers {
        for c in ["ax[m/s2]", "ay[m/s2]", "az[m/s2]"] {
            header.push(format!("{}.{c}", a.name));
        }
    }
    Ok(Columns {
        header,
        arc,
        coordinates: spec.coordinates,
        velocities: spec.velocities,
        need_kinematics: !bodies.is_empty() || !forces.is_empty(),
        accelerometers,
        bodies,
        forces,
    })
}

impl Columns {
    /// Appends the values of the columns after `time` and `s[m]` at a state
    /// (`force_values` is scratch for all force elements' outputs).
    pub(crate) fn values(
        &self,
        system: &mut ModelSystem,
        row: RowView,
        values: &mut Vec<f64>,
        force_values: &mut Vec<f64>,
    ) -> Result<(), RunError> {
        let (t, q, v) = (row.t, row.q, row.v);
        if self.coordinates {
            values.extend_from_slice(q);
        }
        if self.velocities {
            values.extend_from_slice(v);
        }
        if self.need_kinematics {
            let eval = system.evaluate(t, q, v, Parts::KINEMATICS)?;
            for &b in &self.bodies {
                let k = &eval.bodies[b];
                values.extend(k.position.iter());
                values.extend(xyz_angles(&k.rotation).iter());
                values.extend(k.velocity.iter());
                values.extend(k.angular_velocity.iter());
            }
            let mut all = std::mem::take(force_values);
            all.clear();
            system.force_outputs(t, &mut all);
            for &(offset, count) in &self.forces {
                values.extend_from_slice(&all[offset..offset + count]);
            }
            *force_values = all;
        }
        if !self.accelerometers.is_empty() {
            accelerations(system, row, &self.accelerometers, values)?;
        }
        Ok(())
    }
}

/// Appends the accelerations (m/s², in the body's frame, gravity not
/// included) of the accelerometer points at an output row. The point's
/// velocity v_P(t, q, q̇) is differentiated along the motion by a central
/// difference over (t ± ε, q ± ε q̇, q̇ ± ε q̈): exact for the rheonomic
/// track-frame inputs as well, O(ε²) truncation, rounding ~1e-16·|v|/ε.
fn accelerations(
    system: &mut ModelSystem,
    row: RowView,
    points: &[(usize, Vector3<f64>)],
    values: &mut Vec<f64>,
) -> Result<(), RunError> {
    let eps = 1e-5;
    let shifted = |sign: f64| -> (Vec<f64>, Vec<f64>) {
        (
            row.q
                .iter()
                .zip(row.v)
                .map(|(q, v)| q + sign * eps * v)
                .collect(),
            row.v
                .iter()
                .zip(row.a)
                .map(|(v, a)| v + sign * eps * a)
                .collect(),
        )
    };
    let mut at = |sign: f64| -> Result<Vec<Vector3<f64>>, RunError> {
        let (q, v) = shifted(sign);
        let e = system.evaluate(row.t + sign * eps, &q, &v, Parts::KINEMATICS)?;
        Ok(points
            .iter()
            .map(|(b, p)| e.bodies[*b].point_velocity(p))
            .collect())
    };
    let (plus, minus) = (at(1.0)?, at(-1.0)?);
    let e = system.evaluate(row.t, row.q, row.v, Parts::KINEMATICS)?;
    for ((b, _), (vp, vm)) in points.iter().zip(plus.iter().zip(&minus)) {
        let a = e.bodies[*b].rotation.transpose() * ((vp - vm) / (2.0 * eps));
        values.extend(a.iter());
    }
    Ok(())
}

/// Cardan angles of a rotation matrix for the sequence x, y, z of the moving
/// frame (A = Rx(a) Ry(b) Rz(c)), rad.
pub fn xyz_angles(a: &Matrix3<f64>) -> Vector3<f64> {
    let b = a[(0, 2)].clamp(-1.0, 1.0).asin();
    let x = (-a[(1, 2)]).atan2(a[(2, 2)]);
    let z = (-a[(0, 1)]).atan2(a[(0, 0)]);
    Vector3::new(x, b, z)
}

/// An engine driven along the track: the wrapped equations, the times at
/// which the frames pass kinks of the track, and the track for the force
/// elements that need it.
pub(crate) type DrivenModel = (Box<dyn Equations>, Vec<f64>, Option<TrackBinding>);

/// Wraps the engine of a model with track-following frames so that the
/// scenario's track drives them; other models pass through.
pub(crate) fn drive_track_frames(
    scenario: &Scenario,
    model: &Model,
    params: &[f64],
    equations: Box<dyn Equations>,
) -> Result<DrivenModel, RunError> {
    if model.track_frames.is_empty() {
        return Ok((equations, Vec::new(), None));
    }
    let setup = |message: String| RunError::Setup {
        file: scenario.source.clone(),
        message,
    };
    let Some(spec) = &scenario.track else {
        return Err(setup(format!(
            "model \"{}\" has {} track-following frame(s): the scenario must say which track \
             and how fast, e.g. `track: (file: \"../tracks/tc1.ron\", start: 11.0, speed: 4.4)`",
            model.name,
            model.track_frames.len()
        )));
    };
    let text = std::fs::read_to_string(&spec.file).map_err(|source| RunError::Io {
        path: spec.file.clone(),
        source,
    })?;
    let description: railmbs_track::TrackDescription =
        ron::from_str(&text).map_err(|e| RunError::Setup {
            file: spec.file.clone(),
            message: format!("not a track description: {e}"),
        })?;
    let base = spec.file.parent().unwrap_or(Path::new(""));
    let track = description.build(base).map_err(|e| RunError::Setup {
        file: spec.file.clone(),
        message: e.to_string(),
    })?;
    let speed = if spec.speed_profile.is_empty() {
        railmbs_track::ConstantSpeed::new(spec.start, spec.speed).map(RunningSpeed::Constant)
    } else {
        railmbs_track::SpeedTable::new(spec.start, &spec.speed_profile).map(RunningSpeed::Profile)
    }
    .map_err(|e| setup(format!("track: {e}")))?;
    let track = std::sync::Arc::new(track);
    let inputs = TrackInputs::for_model(model, params, track.clone(), speed.clone())?;
    let breakpoints = inputs.breakpoints(0.0, scenario.end_time);
    // Each body's track frame: its own or its nearest ancestor's.
    let mut body_offsets: Vec<Option<f64>> = vec![None; model.bodies.len()];
    for (b, body) in model.bodies.iter().enumerate() {
        body_offsets[b] = match body.parent {
            railmbs_models::BodyRef::Body(p) => body_offsets[p],
            railmbs_models::BodyRef::Ground => None,
        };
        if let Some(k) = model.track_frames.iter().position(|f| f.body == b) {
            body_offsets[b] = Some(inputs.offsets()[k]);
        }
    }
    let binding = TrackBinding {
        track,
        speed,
        body_offsets,
        tables: Default::default(),
    };
    Ok((
        Box::new(DrivenEquations::new(equations, Box::new(inputs))?),
        breakpoints,
        Some(binding),
    ))
}

/// One body velocity vector (v, ω) per body, stacked.
fn body_velocities(e: &crate::equations::Evaluation) -> nalgebra::DVector<f64> {
    nalgebra::DVector::from_iterator(
        6 * e.bodies.len(),
        e.bodies
            .iter()
            .flat_map(|b| b.velocity.iter().chain(b.angular_velocity.iter()).copied()),
    )
}

/// Half-width (s) of the gap left around a breakpoint at `t`: segments end
/// this much before a kink of the track and restart this much after it, so
/// that no step ever ends exactly on the kink (where the inputs are one-sided).
/// At 100 m/s it moves a frame by 1e-8 m per second of simulated time.
pub(crate) fn breakpoint_gap(t: f64) -> f64 {
    1e-10 * t.abs().max(1.0)
}

/// Velocities after a kink of the track-following frames (segment ended at
/// `t_before`, restarts at `t_after`): the frames' rates jump there, the
/// bodies' absolute velocities do not. Solves Γ(t⁺) q̇⁺ + γ(t⁺) = V(t⁻) for all
/// bodies in the least-squares sense (exact for bodies with six coordinates
/// relative to their frame), γ being the rheonomic part of the body velocities.
pub(crate) fn continuous_velocities(
    system: &mut ModelSystem,
    t_before: f64,
    t_after: f64,
    q: &[f64],
    v: &[f64],
) -> Result<Vec<f64>, SimError> {
    let t = t_before;
    let parts = Parts {
        jacobians: true,
        ..Parts::KINEMATICS
    };
    let before = body_velocities(system.evaluate(t_before, q, v, parts)?);
    let zero = vec![0.0; q.len()];
    let e = system.evaluate(t_after, q, &zero, parts)?;
    let rhs = before - body_velocities(e);
    let solution = e
        .jacobians
        .clone()
        .svd(true, true)
        .solve(&rhs, 1e-12)
        .map_err(|e| SimError::Other(format!("velocity re-initialization at t = {t} s: {e}")))?;
    // Element states keep their rates (their equations hold at the next step).
    let n = solution.len();
    Ok(solution.iter().chain(&v[n..]).copied().collect())
}

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

/// Refuses an explicit integrator for a system with first-order element
/// states (their rows of the mass matrix are zero).
pub(crate) fn check_integrator(system: &ModelSystem, spec: &IntegratorSpec) -> Result<(), String> {
    if matches!(spec, IntegratorSpec::Rk4 { .. }) && system.state_count() > 0 {
        return Err(format!(
            "the model has first-order element states ({}) which the explicit RK4 integrator \
             cannot solve; use `integrator: Park(..)`",
            system.state_names().join(", ")
        ));
    }
    Ok(())
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

/// Integrator settings of a scenario.
pub(crate) fn run_integrator<S: crate::system::MechanicalSystem>(
    system: &mut S,
    spec: &IntegratorSpec,
    t0: f64,
    q0: &[f64],
    v0: &[f64],
    t_end: f64,
    observer: impl FnMut(f64, &[f64], &[f64], &[f64]) -> ControlFlow<()>,
) -> Result<IntegrationStats, SimError> {
    match spec {
        IntegratorSpec::Rk4 { step } => integrate::integrate_rk4(
            system,
            &Rk4Settings::new(*step),
            t0,
            q0,
            v0,
            t_end,
            observer,
        ),
        IntegratorSpec::Park {
            rtol,
            atol,
            max_step,
            initial_step,
            jacobian,
        } => {
            let mut settings = ParkSettings::with_tolerances(*rtol, *atol);
            settings.max_step = *max_step;
            settings.initial_step = *initial_step;
            settings.jacobian = match jacobian {
                JacobianKind::FiniteDifference => integrate::JacobianKind::ForwardDifference,
                JacobianKind::Analytic => integrate::JacobianKind::Analytic,
            };
            integrate::integrate_park(system, &settings, t0, q0, v0, t_end, observer)
        }
    }
}

/// Output rows waiting to be written, and where they go. Rows are produced by
/// the integrator's observer (interpolated states) and written from
/// [`ModelSystem`]'s accept-step hook, which can evaluate kinematics and force
/// outputs, so the file grows while the run goes on.
pub(crate) struct Recorder {
    columns: Columns,
    sink: CsvSink,
}

impl Recorder {
    /// Writes all pending rows. Needs the system for kinematics-based columns.
    pub(crate) fn flush(&mut self, system: &mut ModelSystem) {
        let cols = &self.columns;
        self.sink.drain(|values, force_values, row| {
            if let Some(arc) = &cols.arc {
                values.push(arc_position(arc, row.t)?);
            }
            cols.values(system, row.slice(0..row.q.len()), values, force_values)
        });
    }
}

/// Arc position s(t) of a speed law, m.
pub(crate) fn arc_position(arc: &RunningSpeed, t: f64) -> Result<f64, RunError> {
    use railmbs_track::SpeedLaw;
    arc.motion(t)
        .map(|m| m.s)
        .map_err(|e| RunError::Sim(SimError::Other(e.to_string())))
}

/// The CSV side of a run's output, shared by the scenario and train
/// recorders: rows waiting to be written, the open file, reusable buffers,
/// and the first write failure (after which rows are dropped).
pub(crate) struct CsvSink {
    pub(crate) pending: PendingRows,
    writer: CsvWriter,
    rows: usize,
    values: Vec<f64>,
    /// All force elements' outputs of the row being written.
    force_values: Vec<f64>,
    line: String,
    pub(crate) failure: Option<RunError>,
}

impl CsvSink {
    /// Creates `output` (and its folder) with the header line; no file for
    /// `None` (rows are still counted).
    pub(crate) fn open(output: Option<&Path>, header: &[String]) -> Result<Self, RunError> {
        let writer = match output {
            Some(p) => {
                if let Some(dir) = p.parent().filter(|d| !d.as_os_str().is_empty()) {
                    std::fs::create_dir_all(dir).map_err(|source| RunError::Io {
                        path: dir.to_path_buf(),
                        source,
                    })?;
                }
                let io = |source| RunError::Io {
                    path: p.to_path_buf(),
                    source,
                };
                let mut w = std::io::BufWriter::new(std::fs::File::create(p).map_err(io)?);
                writeln!(w, "{}", header.join(",")).map_err(io)?;
                Some((p.to_path_buf(), w))
            }
            None => None,
        };
        Ok(Self {
            pending: Default::default(),
            writer,
            rows: 0,
            values: Vec::new(),
            force_values: Vec::new(),
            line: String::new(),
            failure: None,
        })
    }

    /// Writes the pending rows: each starts with its time, `fill` appends the
    /// rest (given the row and a buffer for force outputs). The first failure
    /// is kept and stops the writing.
    pub(crate) fn drain(
        &mut self,
        mut fill: impl FnMut(&mut Vec<f64>, &mut Vec<f64>, &Row) -> Result<(), RunError>,
    ) {
        while let Some(row) = self.pending.pop_front() {
            if self.failure.is_some() {
                continue;
            }
            self.values.clear();
            self.values.push(row.t);
            let written = fill(&mut self.values, &mut self.force_values, &row)
                .and_then(|()| write_row_text(&mut self.writer, &mut self.line, &self.values));
            match written {
                Ok(()) => self.rows += 1,
                Err(e) => self.failure = Some(e),
            }
        }
    }

    /// Flushes the file; returns the rows written, or the first failure.
    pub(crate) fn close(&mut self) -> Result<usize, RunError> {
        if let Some((path, mut w)) = self.writer.take() {
            w.flush().map_err(|source| RunError::Io { path, source })?;
        }
        match self.failure.take() {
            Some(e) => Err(e),
            None => Ok(self.rows),
        }
    }
}

/// An open CSV output: its path (for errors) and the buffered file.
pub(crate) type CsvWriter = Option<(PathBuf, std::io::BufWriter<std::fs::File>)>;

/// Writes one CSV row of `values` (through the reusable `line` buffer).
pub(crate) fn write_row_text(
    writer: &mut CsvWriter,
    line: &mut String,
    values: &[f64],
) -> Result<(), RunError> {
    let Some((path, w)) = writer.as_mut() else {
        return Ok(());
    };
    use std::fmt::Write as _;
    line.clear();
    for (k, x) in values.iter().enumerate() {
        if k > 0 {
            line.push(',');
        }
        let _ = write!(line, "{x}");
    }
    writeln!(w, "{line}").map_err(|source| RunError::Io {
        path: path.clone(),
        source,
    })
}

/// Integrates from breakpoint to breakpoint (kinks of the track) up to
/// `t_end`, restarting after each with the velocities `restart` gives
/// (continuous absolute velocities); adds each segment's counts to `summary`
/// and stores the first error there.
#[allow(clippy::too_many_arguments)]
pub(crate) fn integrate_segments<S: crate::system::MechanicalSystem>(
    system: &mut S,
    integrator: &IntegratorSpec,
    (q0, v0): (&[f64], &[f64]),
    breakpoints: &[f64],
    t_end: f64,
    observer: &mut impl FnMut(f64, &[f64], &[f64], &[f64]) -> ControlFlow<()>,
    summary: &mut RunSummary,
    mut restart: impl FnMut(&mut S, f64, f64, &[f64], &[f64]) -> Result<Vec<f64>, SimError>,
) {
    let (mut t0, mut q, mut v) = (0.0, q0.to_vec(), v0.to_vec());
    for (k, &breakpoint) in breakpoints.iter().chain([&t_end]).enumerate() {
        let last = k == breakpoints.len();
        let segment_end = if last {
            t_end
        } else {
            breakpoint - breakpoint_gap(breakpoint)
        };
        let st = match run_integrator(system, integrator, t0, &q, &v, segment_end, &mut *observer) {
            Ok(st) => st,
            Err(e) => {
                summary.error = Some(e);
                return;
            }
        };
        summary.add_segment(&st);
        if st.stopped_by_observer || last {
            return;
        }
        q.copy_from_slice(st.q.as_slice());
        t0 = breakpoint + breakpoint_gap(breakpoint);
        match restart(system, st.t, t0, &q, st.v.as_slice()) {
            Ok(vn) => v = vn,
            Err(e) => {
                summary.error = Some(e);
                return;
            }
        }
    }
}

/// The output grid of a run: rows at k·interval (and always at the end
/// time), interpolated from the accepted steps by cubic Hermite
/// interpolation, plus the progress callback now and then. Called once per
/// accepted step by the integrator's observer.
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
            let reached = to <= t + 1e-12 * t_end.max(1.0);
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

    /// [`OutputSchedule::observe`] into a CSV sink; asks the integrator to
    /// stop once the sink has failed (its first error is kept).
    pub(crate) fn observe_into(
        &mut self,
        t: f64,
        q: &[f64],
        v: &[f64],
        a: &[f64],
        sink: &mut CsvSink,
        progress: &mut impl FnMut(f64),
    ) -> ControlFlow<()> {
        if sink.failure.is_some() {
            return ControlFlow::Break(());
        }
        self.observe(t, q, v, a, &mut sink.pending, progress);
        ControlFlow::Continue(())
    }

    /// The previous accepted step's end time, if any.
    pub(crate) fn last_time(&self) -> Option<f64> {
        self.prev.as_ref().map(|p| p.0)
    }
}

/// Runs `scenario` on `model` with the engine `equations` and writes the output
/// CSV to `output` (if given). `progress` is called with the simulated time
/// now and then. A simulation error stops the run: rows up to that point are
/// written, and the summary carries the error.
pub fn run_scenario(
    scenario: &Scenario,
    model: &Model,
    equations: Box<dyn Equations>,
    output: Option<&Path>,
    mut progress: impl FnMut(f64),
) -> Result<RunSummary, RunError> {
    let InitialState {
        params,
        q: q0,
        v: v0,
    } = scenario_state(scenario, model)?;
    let engine = equations.engine_name().to_string();
    let (equations, breakpoints, binding) =
        drive_track_frames(scenario, model, &params, equations)?;
    let mut system = ModelSystem::new(model, equations, params)?;
    check_integrator(&system, &scenario.integrator).map_err(|message| RunError::Setup {
        file: scenario.source.clone(),
        message,
    })?;
    let (q0, v0) = system.initial_state(0.0, &q0, &v0)?;
    match &binding {
        Some(b) => system.bind_track(b)?,
        None => {
            if let Some(f) = system.forces().iter().find(|f| f.needs_track()) {
                return Err(RunError::Setup {
                    file: scenario.source.clone(),
                    message: format!(
                        "force element \"{}\" needs a track: put its wheelset on a \
                         track-following frame and give the scenario a `track`",
                        f.name()
                    ),
                });
            }
        }
    }
    let arc = binding.as_ref().map(|b| b.speed.clone());
    let columns = columns(model, &system, &scenario.output, &scenario.source, arc)?;
    let recorder = std::rc::Rc::new(std::cell::RefCell::new(Recorder {
        sink: CsvSink::open(output, &columns.header)?,
        columns,
    }));
    system.set_recorder(Some(recorder.clone()));

    let t_end = scenario.end_time;
    let mut schedule = OutputSchedule::new(t_end, scenario.output.interval, q0.len());
    let start = Instant::now();
    let mut observer = |t: f64, q: &[f64], v: &[f64], a: &[f64]| {
        schedule.observe_into(t, q, v, a, &mut recorder.borrow_mut().sink, &mut progress)
    };
    // Integrate from breakpoint to breakpoint (kinks of the track), restarting
    // with continuous absolute velocities at each.
    let mut summary = RunSummary::new(engine);
    integrate_segments(
        &mut system,
        &scenario.integrator,
        (&q0, &v0),
        &breakpoints,
        t_end,
        &mut observer,
        &mut summary,
        continuous_velocities,
    );

    let cpu_time = start.elapsed().as_secs_f64();
    system.set_recorder(None);
    let mut rec = recorder.borrow_mut();
    rec.flush(&mut system);
    let rows = rec.sink.close()?;
    summary.finish(cpu_time, rows, schedule.last_time(), system.assessment());
    Ok(summary)
}
