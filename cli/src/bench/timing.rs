//! How `umsim bench` times: a stopwatch on the thread's CPU clock (or on the
//! process's, for runs that use worker threads), the batch-doubling loop for
//! evaluations and the median of repeated runs.

use std::time::Instant;

/// Minimum duration of one timed batch, s.
pub const BATCH_SECONDS: f64 = 0.04;
/// Number of timed batches (the median is reported).
pub const BATCHES: usize = 5;
/// Scenario runs stop repeating once they took this long in all, s.
pub const RUN_SECONDS: f64 = 1.0;
/// Most scenario runs per engine.
pub const MAX_RUNS: usize = 5;

/// The CPU clock a [`Stopwatch`] reads.
enum CpuClock {
    /// The calling thread's: other processes on a busy machine do not count.
    Thread(cpu_time::ThreadTime),
    /// The whole process's, summed over its threads: for work that runs on
    /// worker threads (a train with `threads` > 1), which the calling
    /// thread's clock would not see.
    Process(cpu_time::ProcessTime),
    /// None available: the wall clock stands in.
    Wall,
}

/// A stopwatch on a CPU clock (the `cpu-time` crate), or on the wall clock
/// where the platform has none, that also keeps the wall time.
pub(crate) struct Stopwatch {
    cpu: CpuClock,
    wall: Instant,
}

impl Stopwatch {
    /// On the calling thread's CPU clock.
    pub(crate) fn start() -> Self {
        Self {
            cpu: cpu_time::ThreadTime::try_now().map_or(CpuClock::Wall, CpuClock::Thread),
            wall: Instant::now(),
        }
    }
    /// On the process's CPU clock (all its threads).
    pub(crate) fn start_process() -> Self {
        Self {
            cpu: cpu_time::ProcessTime::try_now().map_or(CpuClock::Wall, CpuClock::Process),
            wall: Instant::now(),
        }
    }
    /// CPU seconds since the start.
    pub(crate) fn seconds(&self) -> f64 {
        match &self.cpu {
            CpuClock::Thread(t) => t.elapsed().as_secs_f64(),
            CpuClock::Process(t) => t.elapsed().as_secs_f64(),
            CpuClock::Wall => self.wall_seconds(),
        }
    }
    /// Wall-clock seconds since the start.
    pub(crate) fn wall_seconds(&self) -> f64 {
        self.wall.elapsed().as_secs_f64()
    }
}

/// Median ns per call of `f(k)` (k the running call index), by the batch
/// method of the module documentation of [`crate::bench`]. The first error
/// stops the timing.
pub fn time_per_call<E>(mut f: impl FnMut(usize) -> Result<(), E>) -> Result<f64, E> {
    let mut calls = 1usize;
    let mut k = 0usize;
    let mut batch = |calls: usize, f: &mut dyn FnMut(usize) -> Result<(), E>| {
        let watch = Stopwatch::start();
        for _ in 0..calls {
            f(k)?;
            k += 1;
        }
        Ok(watch.seconds())
    };
    // Calibration: double the batch until it lasts BATCH_SECONDS.
    loop {
        let t = batch(calls, &mut f)?;
        if t >= BATCH_SECONDS || calls >= 1 << 40 {
            break;
        }
        calls *= 2;
    }
    let mut per_call = Vec::with_capacity(BATCHES);
    for _ in 0..BATCHES {
        let t = batch(calls, &mut f)?;
        per_call.push(1e9 * t / calls as f64);
    }
    per_call.sort_by(f64::total_cmp);
    Ok(per_call[BATCHES / 2])
}

/// Median time of `run` (one simulation: its seconds and steps), repeated
/// until [`MAX_RUNS`] runs or [`RUN_SECONDS`] in all, and the steps of a run.
pub(crate) fn median_run(
    mut run: impl FnMut() -> Result<(f64, usize), String>,
) -> Result<(f64, usize), String> {
    let mut steps = 0;
    let mut times = Vec::new();
    let mut total = 0.0;
    while times.len() < MAX_RUNS && (times.is_empty() || total < RUN_SECONDS) {
        let (seconds, n) = run()?;
        steps = n;
        total += seconds;
        times.push(seconds);
    }
    times.sort_by(f64::total_cmp);
    Ok((times[times.len() / 2], steps))
}
