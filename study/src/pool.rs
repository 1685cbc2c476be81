//! The local pool: the pending cases of a study on threads of this process,
//! each result appended to the table as it finishes.

use crate::{CaseOptions, CaseResult, CaseStatus, ResultStore, Study, StudyEngine, StudyError};
use std::path::PathBuf;
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};

/// Options of [`run_local`].
#[derive(Debug, Clone, Default)]
pub struct PoolOptions {
    /// Threads (0: one per core).
    pub jobs: usize,
    /// Folder of the cases' time series (`<case id>.csv`), if written.
    pub series_dir: Option<PathBuf>,
    /// Stops the study when set: running cases stop at their next output
    /// row and are not recorded, no new case starts.
    pub stop: Option<Arc<AtomicBool>>,
}

/// What [`run_local`] did.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct PoolSummary {
    /// Cases skipped because the table held them already.
    pub skipped: usize,
    /// Cases run and recorded.
    pub recorded: usize,
    /// Of those, the failed ones.
    pub failed: usize,
    /// Whether the study was interrupted before every case ran.
    pub interrupted: bool,
}

/// The number of threads for `jobs` (0: the machine's cores).
pub fn threads(jobs: usize) -> usize {
    if jobs > 0 {
        jobs
    } else {
        std::thread::available_parallelism().map_or(1, |n| n.get())
    }
}

/// Runs the cases of `study` that `store` does not hold yet on a pool of
/// threads sharing `engine`, appending each result to `store` as it
/// finishes (so nothing finished is lost when the process is interrupted or
/// killed) and passing it to `on_result` (a progress bar). The cases start
/// in index order.
///
/// # Errors
/// A fault of the study (a reduction that fits no output column) or of the
/// table (it cannot be written); cases finished before are recorded.
pub fn run_local(
    study: &Study,
    engine: &StudyEngine,
    store: &mut ResultStore,
    options: &PoolOptions,
    mut on_result: impl FnMut(&CaseResult),
) -> Result<PoolSummary, StudyError> {
    let pending: Vec<&crate::Case> = study
        .cases()
        .iter()
        .filter(|c| !store.finished().contains(&c.id))
        .collect();
    let mut summary = PoolSummary {
        skipped: study.cases().len() - pending.len(),
        ..PoolSummary::default()
    };
    let stop = options.stop.clone().unwrap_or_default();
    // Set when the study must end (a fault, or the caller's stop flag).
    let abort = Arc::new(AtomicBool::new(false));
    let next = AtomicUsize::new(0);
    let case_options = CaseOptions {
        series_dir: options.series_dir.clone(),
        stop: Some(abort.clone()),
    };
    let (send, receive) = std::sync::mpsc::channel::<Result<CaseResult, StudyError>>();
    let workers = threads(options.jobs).min(pending.len().max(1));
    let mut fault = None;
    std::thread::scope(|scope| {
        for _ in 0..workers {
            let send = send.clone();
            let (next, abort, pending, case_options) = (&next, &abort, &pending, &case_options);
            scope.spawn(move || {
                loop {
                    if abort.load(Ordering::Relaxed) {
                        break;
                    }
                    let k = next.fetch_add(1, Ordering::Relaxed);
                    let Some(case) = pending.get(k) else { break };
                    let result = engine.run_case(study, case, case_options);
                    if send.send(result).is_err() {
                        break;
                    }
                }
            });
        }
        drop(send);
        // Results arrive here as the cases finish; the caller's flag is
        // passed on to the running cases.
        loop {
            if stop.load(Ordering::Relaxed) {
                abort.store(true, Ordering::Relaxed);
            }
            match receive.recv_timeout(std::time::Duration::from_millis(100)) {
                Ok(Ok(result)) => {
                    if let Err(e) = store.append(&result) {
                        abort.store(true, Ordering::Relaxed);
                        fault.get_or_insert(e);
                        continue;
                    }
                    summary.recorded += 1;
                    summary.failed += usize::from(result.status == CaseStatus::Failed);
                    on_result(&result);
                }
                Ok(Err(StudyError::Interrupted)) => summary.interrupted = true,
                Ok(Err(e)) => {
                    abort.store(true, Ordering::Relaxed);
                    fault.get_or_insert(e);
                }
                Err(std::sync::mpsc::RecvTimeoutError::Timeout) => {}
                Err(std::sync::mpsc::RecvTimeoutError::Disconnected) => break,
            }
        }
    });
    if let Some(e) = fault {
        return Err(e);
    }
    summary.interrupted |=
        stop.load(Ordering::Relaxed) && summary.recorded + summary.skipped < study.cases().len();
    Ok(summary)
}
