//! Running a scenario or a train: the runner owns the time loop. It steps a
//! solver of [`railmbs_integrate`] from breakpoint to breakpoint (kinks of
//! the track), interpolates output rows onto the output grid ([`grid`]),
//! evaluates the output columns ([`columns`]) and hands the rows to an
//! [`OutputSink`] ([`sink`]: a CSV file, an in-memory [`Table`]) while the
//! run goes on (a run that stops early keeps what it has written); the wheel
//! loads of every accepted step go to the sinks too, and the
//! [`AssessmentReducer`] ([`assessment`]) makes the run's EN 14363 table of
//! them.
//! [`scenario`] turns a scenario into an initial state and a driven engine.

pub mod assessment;
pub mod columns;
pub mod grid;
pub mod scenario;
pub mod sink;
pub mod sliding_mean;

pub use assessment::{AssessmentReducer, LoadSample};
pub use columns::xyz_angles;
pub use scenario::{InitialState, scenario_state};
pub use sink::{CsvFile, Discard, Interruptible, OutputSink, Table};

use crate::Equations;
use crate::forces::ContactTableCache;
use crate::integrate::{self, IntegrationStats, Park, ParkSettings, Rk4, Rk4Settings, Stepper};
use crate::model_system::ModelSystem;
use crate::system::{MechanicalSystem, SimError};
use grid::{OutputSchedule, PendingRows, Row};
use railmbs_models::{IntegratorSpec, JacobianKind, LinearSolverKind, Model, Scenario};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Errors of a run that are not about the simulation itself.
#[derive(Debug, thiserror::Error)]
pub enum RunError {
    /// The scenario (or a file it names) is not usable.
    #[error("{file}: {message}")]
    Setup {
        /// The file at fault.
        file: PathBuf,
        /// What is wrong, with line and column where known.
        message: String,
    },
    /// A file could not be read or written.
    #[error("cannot write {path}: {source}")]
    Io {
        /// The file.
        path: PathBuf,
        /// The operating system's error.
        source: std::io::Error,
    },
    /// The simulation itself failed before it started (a bad initial state).
    #[error(transparent)]
    Sim(#[from] SimError),
    /// The scenario does not fit its model (an unknown parameter, macro or
    /// coordinate), located in the scenario file.
    #[error(transparent)]
    Model(#[from] railmbs_models::ModelErrors),
    /// The run was interrupted (Ctrl-C): it stopped at the next output row,
    /// and the rows before were written.
    #[error("interrupted after {rows} output rows{}", last_time.map_or(String::new(), |t| format!(", the last at t = {t} s")))]
    Interrupted {
        /// Rows written.
        rows: usize,
        /// Time of the last row written, s.
        last_time: Option<f64>,
    },
}

/// The CPU time of the calling thread since [`CpuClock::start`] (a run
/// happens in one thread, so a study's cases on a pool each get their own),
/// or the wall-clock time where the platform has no per-thread CPU clock.
pub struct CpuClock {
    thread: Option<cpu_time::ThreadTime>,
    wall: Instant,
}

impl CpuClock {
    /// Starts the clock.
    pub fn start() -> CpuClock {
        CpuClock {
            thread: cpu_time::ThreadTime::try_now().ok(),
            wall: Instant::now(),
        }
    }

    /// Seconds since the start.
    pub fn seconds(&self) -> f64 {
        match &self.thread {
            Some(t) => t.elapsed().as_secs_f64(),
            None => self.wall.elapsed().as_secs_f64(),
        }
    }
}

/// What a finished (or stopped) run did.
#[derive(Debug, Clone)]
pub struct RunSummary {
    /// The engine(s) that ran (`numeric`, `symbolic`; a train's joined by `+`).
    pub engine: String,
    /// Simulated time reached, s.
    pub t_end: f64,
    /// Accepted steps.
    pub steps: usize,
    /// Rejected step attempts.
    pub rejected_steps: usize,
    /// Newton iterations of Park's method.
    pub newton_iterations: usize,
    /// Evaluations of the Jacobians ∂f/∂q, ∂f/∂q̇.
    pub jacobian_evaluations: usize,
    /// Evaluations of M and f.
    pub dynamics_evaluations: usize,
    /// CPU time of the integration (and output) in the thread that ran it,
    /// s ([`CpuClock`]; wall-clock time where the platform has no thread clock).
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

/// The output columns of a system `S`: their names and their values at an
/// output row.
pub(crate) trait RowColumns<S> {
    /// Column names, the first `time`.
    fn header(&self) -> &[String];

    /// Appends the values after `time` of the row. May evaluate `system`
    /// at the row's state.
    fn values(&self, system: &mut S, row: &Row, values: &mut Vec<f64>) -> Result<(), RunError>;
}

/// What the runner needs of a system besides integrating it: the wheel
/// loads of its accepted steps for the assessment.
pub(crate) trait RunSystem: MechanicalSystem {
    /// Moves the wheel loads of the last accepted step to `out` (nothing
    /// when they were taken already).
    fn take_assessment_loads(&mut self, out: &mut Vec<LoadSample>);

    /// Long name of the element with assessment key `key`.
    fn assessment_name(&self, key: usize) -> String;
}

impl RunSystem for ModelSystem {
    fn take_assessment_loads(&mut self, out: &mut Vec<LoadSample>) {
        ModelSystem::take_assessment_loads(self, out);
    }

    fn assessment_name(&self, key: usize) -> String {
        self.forces()[key].name().to_string()
    }
}

/// The wheel loads the system's last accepted step left, to both the
/// reducer and the sink.
fn pass_loads<S: RunSystem>(
    system: &mut S,
    buffer: &mut Vec<LoadSample>,
    reducer: &mut AssessmentReducer,
    sink: &mut dyn OutputSink,
) {
    buffer.clear();
    system.take_assessment_loads(buffer);
    if buffer.is_empty() {
        return;
    }
    let name = |k: usize| system.assessment_name(k);
    reducer.accepted_loads(buffer, &name);
    sink.accepted_loads(buffer, &name);
}

/// The error of a run that took [`MAX_STEPS_PER_ROW`] steps without
/// reaching the output row at `next_row` (s); `t` (s) and `h` (s) are the
/// last step's end and length.
fn no_progress(t: f64, h: f64, next_row: f64) -> SimError {
    SimError::Diverged {
        t,
        reason: format!(
            "no progress: {MAX_STEPS_PER_ROW} steps without reaching the next output row \
             at t = {next_row} s (the last step was {h:e} s); either the tolerances ask for \
             more than double precision allows (rtol ≥ 1e-9 and atol ≥ 1e-9 are safe \
             floors) or the model is much stiffer here than elsewhere (a contact or \
             a friction element chattering)"
        ),
    }
}

/// A solver of the scenario's integrator for `system` at (t0, q0, v0).
fn solver<'s, S: MechanicalSystem>(
    system: &'s mut S,
    spec: &IntegratorSpec,
    t0: f64,
    q0: &[f64],
    v0: &[f64],
) -> Result<Box<dyn Stepper<System = &'s mut S> + 's>, SimError> {
    Ok(match spec {
        IntegratorSpec::Rk4 { step } => {
            Box::new(Rk4::new(system, &Rk4Settings::new(*step), t0, q0, v0)?)
        }
        IntegratorSpec::Park {
            rtol,
            atol,
            max_step,
            initial_step,
            jacobian,
            solver,
        } => {
            let mut settings = ParkSettings::with_tolerances(*rtol, *atol);
            settings.solver = match solver {
                LinearSolverKind::Dense => integrate::LinearSolver::Dense,
                LinearSolverKind::Block => integrate::LinearSolver::Block,
            };
            settings.max_step = *max_step;
            settings.initial_step = *initial_step;
            settings.jacobian = match jacobian {
                JacobianKind::FiniteDifference => integrate::JacobianKind::ForwardDifference,
                JacobianKind::Analytic => integrate::JacobianKind::Analytic,
            };
            Box::new(Park::new(system, settings, t0, q0, v0)?)
        }
    })
}

/// Accepted steps without reaching an output row after which a run stops as
/// making no progress (as CVODE's `mxstep`): the step size has collapsed far
/// below the output interval, usually because the tolerances ask for more
/// than double precision allows or the model is far stiffer than expected.
/// A million steps is seconds to minutes of CPU with nothing written.
pub const MAX_STEPS_PER_ROW: usize = 1_000_000;

/// Rows interpolated but not yet written, and what was written.
struct Rows {
    /// Accepted steps since the last output row.
    steps_since_row: usize,
    pending: PendingRows,
    values: Vec<f64>,
    written: usize,
    /// The first failure (evaluating or writing a row); the run stops.
    failure: Option<RunError>,
    /// The assessment of the accepted steps' wheel loads.
    reducer: AssessmentReducer,
    /// Reusable buffer of wheel loads.
    loads: Vec<LoadSample>,
}

impl Rows {
    /// Evaluates and writes the pending rows (each starts with its time).
    fn flush<S>(
        &mut self,
        system: &mut S,
        columns: &impl RowColumns<S>,
        sink: &mut dyn OutputSink,
    ) {
        while let Some(row) = self.pending.pop_front() {
            if self.failure.is_some() {
                continue;
            }
            self.values.clear();
            self.values.push(row.t);
            let written = columns
                .values(system, &row, &mut self.values)
                .and_then(|()| sink.row(&self.values));
            match written {
                Ok(()) => self.written += 1,
                Err(e) => self.failure = Some(e),
            }
        }
    }
}

/// One run of a system: its integrator, the kinks of its inputs, the end
/// time and the output grid.
pub(crate) struct Runner<'a> {
    /// The scenario's integrator.
    pub integrator: &'a IntegratorSpec,
    /// Times of the kinks of the track-following frames, s (sorted).
    pub breakpoints: &'a [f64],
    /// End time, s.
    pub t_end: f64,
    /// Output interval, s.
    pub interval: f64,
}

impl Runner<'_> {
    /// Integrates `system` from `(q0, v0)` at t = 0 to the end time,
    /// segment by segment between breakpoints (restarting after each with
    /// the velocities `restart` gives: continuous absolute velocities), and
    /// writes the rows of `columns` to `sink`. Adds the segments' counts to
    /// `summary` and stores a simulation error there (the rows up to it are
    /// written); returns the rows written, the time of the last accepted
    /// step and the assessment table, or the sink's error.
    ///
    /// A row is evaluated after the step following the one that reached it
    /// has been accepted (and at the end): the force elements' accepted
    /// states, which some outputs show, are those of that step, as they
    /// always were.
    #[allow(clippy::too_many_arguments)]
    pub(crate) fn run<S: RunSystem>(
        &self,
        system: &mut S,
        (q0, v0): (&[f64], &[f64]),
        columns: &impl RowColumns<S>,
        sink: &mut dyn OutputSink,
        summary: &mut RunSummary,
        progress: &mut impl FnMut(f64),
        mut restart: impl FnMut(&mut S, f64, f64, &[f64], &[f64]) -> Result<Vec<f64>, SimError>,
    ) -> Result<(usize, Option<f64>, Vec<crate::forces::Assessment>), RunError> {
        sink.begin(columns.header())?;
        let mut schedule = OutputSchedule::new(self.t_end, self.interval, q0.len());
        let mut rows = Rows {
            steps_since_row: 0,
            pending: PendingRows::new(),
            values: Vec::new(),
            written: 0,
            failure: None,
            reducer: AssessmentReducer::new(),
            loads: Vec::new(),
        };
        let (mut t0, mut q, mut v) = (0.0, q0.to_vec(), v0.to_vec());
        for (k, &breakpoint) in self.breakpoints.iter().chain([&self.t_end]).enumerate() {
            let last = k == self.breakpoints.len();
            let segment_end = if last {
                self.t_end
            } else {
                breakpoint - scenario::breakpoint_gap(breakpoint)
            };
            let segment = self.segment(
                &mut *system,
                (t0, &q, &v, segment_end),
                columns,
                sink,
                &mut schedule,
                &mut rows,
                progress,
                summary,
            );
            let st = match segment {
                Ok(Some(st)) => st,
                // The sink failed: the run stops.
                Ok(None) => break,
                Err(e) => {
                    summary.error = Some(e);
                    break;
                }
            };
            summary.add_segment(&st);
            if last {
                break;
            }
            q.copy_from_slice(st.q.as_slice());
            t0 = breakpoint + scenario::breakpoint_gap(breakpoint);
            match restart(system, st.t, t0, &q, st.v.as_slice()) {
                Ok(vn) => v = vn,
                Err(e) => {
                    summary.error = Some(e);
                    break;
                }
            }
        }
        rows.flush(system, columns, sink);
        sink.finish()?;
        match rows.failure {
            Some(e) => Err(e),
            None => Ok((rows.written, schedule.last_time(), rows.reducer.table())),
        }
    }

    /// One segment from `t0` (state `q`, `v`) to `t1`; `None` when the sink
    /// failed. After an error of a step the counts of the segment up to it
    /// are added to `summary`.
    #[allow(clippy::too_many_arguments)]
    fn segment<S: RunSystem>(
        &self,
        system: &mut S,
        (t0, q, v, t1): (f64, &[f64], &[f64], f64),
        columns: &impl RowColumns<S>,
        sink: &mut dyn OutputSink,
        schedule: &mut OutputSchedule,
        rows: &mut Rows,
        progress: &mut impl FnMut(f64),
        summary: &mut RunSummary,
    ) -> Result<Option<IntegrationStats>, SimError> {
        if rows.failure.is_some() {
            return Ok(None);
        }
        let mut solver = solver(system, self.integrator, t0, q, v)?;
        solver.set_stop_time(t1)?;
        // The first evaluation of a run accepts the initial state.
        pass_loads(
            &mut **solver.system_mut(),
            &mut rows.loads,
            &mut rows.reducer,
            sink,
        );
        let s = solver.state();
        schedule.observe(s.t, s.q, s.v, s.accel, &mut rows.pending, progress);
        rows.flush(&mut **solver.system_mut(), columns, sink);
        while solver.t() < t1 && rows.failure.is_none() {
            // The rows within the step are evaluated before the step is
            // accepted: with the element states (friction modes, elastic
            // rails) that the step was integrated with.
            let step = solver.step_observed(&mut |system, s| {
                schedule.observe(s.t, s.q, s.v, s.accel, &mut rows.pending, progress);
                if rows.pending.is_empty() {
                    rows.steps_since_row += 1;
                    if rows.steps_since_row >= MAX_STEPS_PER_ROW {
                        return Err(no_progress(s.t, s.h, schedule.next_row_time()));
                    }
                } else {
                    rows.steps_since_row = 0;
                }
                rows.flush(&mut **system, columns, sink);
                Ok(())
            });
            if let Err(e) = step {
                summary.add_segment(solver.stats());
                return Err(e);
            }
            let system = &mut **solver.system_mut();
            pass_loads(system, &mut rows.loads, &mut rows.reducer, sink);
        }
        if rows.failure.is_some() {
            return Ok(None);
        }
        Ok(Some(solver.stats().clone()))
    }
}

/// A scenario's system ready to run, with its columns and breakpoints.
struct ScenarioRun {
    system: ModelSystem,
    q0: Vec<f64>,
    v0: Vec<f64>,
    breakpoints: Vec<f64>,
    columns: columns::Columns,
}

/// Builds the system of `scenario` on `model` with the engine `equations`
/// ([`scenario::scenario_system`]) and its output columns.
fn prepare(
    scenario: &Scenario,
    model: &Model,
    equations: Box<dyn Equations>,
    tables: &ContactTableCache,
) -> Result<ScenarioRun, RunError> {
    let scenario::ScenarioSystem {
        system,
        q0,
        v0,
        breakpoints,
        arc,
        ..
    } = scenario::scenario_system_sharing(scenario, model, equations, tables)?;
    let columns = columns::columns(model, &system, &scenario.output, &scenario.source, arc)?;
    Ok(ScenarioRun {
        system,
        q0,
        v0,
        breakpoints,
        columns,
    })
}

/// The sink of a run writing to `output` (a [`CsvFile`], refused when it is
/// one of the run's `inputs`), or a [`Discard`] without one.
///
/// # Errors
/// [`RunError::Setup`] when `output` is one of `inputs`.
pub fn output_sink(
    output: Option<&Path>,
    inputs: &[(&str, &Path)],
) -> Result<Box<dyn OutputSink>, RunError> {
    Ok(match output {
        Some(path) => {
            let csv = CsvFile::new(path);
            csv.refuse_inputs(inputs.iter().copied())?;
            Box::new(csv)
        }
        None => Box::new(Discard),
    })
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
    progress: impl FnMut(f64),
) -> Result<RunSummary, RunError> {
    let mut sink = output_sink(output, &scenario.input_files())?;
    run_scenario_into(scenario, model, equations, &mut *sink, progress)
}

/// [`run_scenario`] writing the rows to `sink` (a [`CsvFile`], a [`Table`]…).
pub fn run_scenario_into(
    scenario: &Scenario,
    model: &Model,
    equations: Box<dyn Equations>,
    sink: &mut dyn OutputSink,
    progress: impl FnMut(f64),
) -> Result<RunSummary, RunError> {
    let tables = ContactTableCache::new();
    run_scenario_with(scenario, model, equations, sink, progress, &tables)
}

/// [`run_scenario_into`] taking the wheel–rail contact tables from
/// `tables` and leaving the ones it builds there: the runs of a study on
/// one model and track build each table once (a table is the same whoever
/// builds it, so the results are too).
pub fn run_scenario_with(
    scenario: &Scenario,
    model: &Model,
    equations: Box<dyn Equations>,
    sink: &mut dyn OutputSink,
    mut progress: impl FnMut(f64),
    tables: &ContactTableCache,
) -> Result<RunSummary, RunError> {
    let engine = equations.engine_name().to_string();
    let ScenarioRun {
        mut system,
        q0,
        v0,
        breakpoints,
        columns,
    } = prepare(scenario, model, equations, tables)?;
    let runner = Runner {
        integrator: &scenario.integrator,
        breakpoints: &breakpoints,
        t_end: scenario.end_time,
        interval: scenario.output.interval,
    };
    let mut summary = RunSummary::new(engine);
    let start = CpuClock::start();
    // Restart at each kink with continuous absolute velocities.
    let (rows, last_step, assessment) = runner.run(
        &mut system,
        (&q0, &v0),
        &columns,
        sink,
        &mut summary,
        &mut progress,
        scenario::continuous_velocities,
    )?;
    let cpu_time = start.seconds();
    summary.finish(cpu_time, rows, last_step, assessment);
    Ok(summary)
}
