//! The worker pool. Each worker claims the oldest queued job from the [`JobStore`],
//! runs `run_case` on a blocking thread (the simulation is CPU-bound and uses the rayon
//! pool), and records the outcome. [`try_execute_job`] is one step of a worker, so tests
//! can drive the queue without sleeping.
//!
//! Cancellation and shutdown reach a run through its [`Observer`], which the engine polls
//! once per time step: `DELETE` sets the job's cancel flag (the job ends `cancelled`); a
//! shutdown past its grace period sets the pool's interrupt flag (the job ends `failed`
//! with reason `interrupted`, exactly as if the process had died). The decision is the
//! observer's ([`Observer::stop_reason`]), so the job's summary.json says the same as its
//! record.

use super::store::{ClaimedJob, JobStatus, JobStore};
use super::Config;
use crate::case::{parse_case_str, CaseError, ValidCase};
use crate::engine::SimError;
use crate::math::Real;
use crate::run::{run_case, Observer, Progress, RunError, RunStatus};
use std::collections::HashMap;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};
use tokio::sync::Notify;
use tracing::Instrument;
use uuid::Uuid;

/// Reason recorded for a job whose run was stopped by a shutdown or a dead process.
pub const INTERRUPTED: &str = "interrupted";

/// State shared by the routes and the workers.
#[derive(Debug)]
pub struct Jobs {
    pub store: JobStore,
    pub config: Config,
    /// A job was queued (or the pool is stopping).
    wake: Notify,
    /// Cancel flags of running jobs (and of jobs a DELETE raced with the claim).
    cancel_flags: Mutex<HashMap<Uuid, Arc<AtomicBool>>>,
    /// No new job is claimed once set.
    stopping: AtomicBool,
    /// Running jobs stop at their next step once set.
    interrupt: Arc<AtomicBool>,
    running: AtomicUsize,
}

/// What one worker step did.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ExecutionOutcome {
    JobFinished(Uuid, JobStatus),
    EmptyQueue,
}

impl Jobs {
    pub fn new(store: JobStore, config: Config) -> Self {
        Self {
            store,
            config,
            wake: Notify::new(),
            cancel_flags: Mutex::new(HashMap::new()),
            stopping: AtomicBool::new(false),
            interrupt: Arc::new(AtomicBool::new(false)),
            running: AtomicUsize::new(0),
        }
    }

    /// Tell a sleeping worker that a job is waiting.
    pub fn job_queued(&self) {
        self.wake.notify_one();
    }

    fn cancel_flag(&self, id: Uuid) -> Arc<AtomicBool> {
        let mut flags = self.cancel_flags.lock().unwrap_or_else(|p| p.into_inner());
        flags.entry(id).or_default().clone()
    }

    fn forget_cancel_flag(&self, id: Uuid) {
        let mut flags = self.cancel_flags.lock().unwrap_or_else(|p| p.into_inner());
        flags.remove(&id);
    }

    /// Ask a running job to stop at its next step.
    pub fn request_cancel(&self, id: Uuid) {
        self.cancel_flag(id).store(true, Ordering::SeqCst);
    }

    pub fn is_stopping(&self) -> bool {
        self.stopping.load(Ordering::SeqCst)
    }

    pub fn running_jobs(&self) -> usize {
        self.running.load(Ordering::SeqCst)
    }

    /// Stop claiming jobs and wake the idle workers so they exit.
    pub fn stop_claiming(&self) {
        self.stopping.store(true, Ordering::SeqCst);
        self.wake.notify_waiters();
    }

    /// Make running jobs stop at their next step (recorded `failed` / `interrupted`).
    pub fn interrupt_running(&self) {
        self.interrupt.store(true, Ordering::SeqCst);
    }
}

/// The run observer of one job: cancel/interrupt flags and throttled progress writes.
struct JobObserver {
    id: Uuid,
    store: JobStore,
    runtime: tokio::runtime::Handle,
    cancel: Arc<AtomicBool>,
    interrupt: Arc<AtomicBool>,
    last_write: Instant,
}

const PROGRESS_EVERY: Duration = Duration::from_millis(250);

impl Observer for JobObserver {
    fn started(&mut self, particles: usize, estimated_steps: u64) {
        tracing::info!(particles, estimated_steps, "run started");
        if let Err(e) = self
            .runtime
            .block_on(self.store.set_started(self.id, particles))
        {
            tracing::warn!(error = %e, "cannot record the particle count");
        }
    }

    fn progress(&mut self, p: &Progress) {
        if self.last_write.elapsed() >= PROGRESS_EVERY {
            self.last_write = Instant::now();
            if let Err(e) =
                self.runtime
                    .block_on(self.store.set_progress(self.id, p.step, p.simulated_time))
            {
                tracing::warn!(error = %e, "cannot record progress");
            }
        }
    }

    fn is_cancelled(&self) -> bool {
        self.cancel.load(Ordering::Relaxed) || self.interrupt.load(Ordering::Relaxed)
    }

    /// A user's DELETE: `cancelled`. Otherwise the service's shutdown stopped the run:
    /// `failed` / `interrupted`, the contract for a job the service gave up on (as after a
    /// crash), in summary.json as in the record.
    fn stop_reason(&self, step: u64, time: Real) -> (RunStatus, String) {
        if self.cancel.load(Ordering::SeqCst) {
            (
                RunStatus::Cancelled,
                SimError::Cancelled { step, time }.to_string(),
            )
        } else {
            (RunStatus::Failed, INTERRUPTED.to_string())
        }
    }
}

/// Claim and run one job. `EmptyQueue` when nothing is waiting (or the pool is stopping).
pub async fn try_execute_job(jobs: &Arc<Jobs>) -> Result<ExecutionOutcome, sqlx::Error> {
    if jobs.is_stopping() {
        return Ok(ExecutionOutcome::EmptyQueue);
    }
    let Some(job) = jobs.store.claim_next().await? else {
        return Ok(ExecutionOutcome::EmptyQueue);
    };
    let id = job.row.id;
    let span = tracing::info_span!("job", %id, name = %job.row.name);
    jobs.running.fetch_add(1, Ordering::SeqCst);
    let status = execute(jobs, job).instrument(span).await;
    jobs.running.fetch_sub(1, Ordering::SeqCst);
    jobs.forget_cancel_flag(id);
    Ok(ExecutionOutcome::JobFinished(id, status?))
}

async fn execute(jobs: &Arc<Jobs>, job: ClaimedJob) -> Result<JobStatus, sqlx::Error> {
    let id = job.row.id;
    let observer = JobObserver {
        id,
        store: jobs.store.clone(),
        runtime: tokio::runtime::Handle::current(),
        cancel: jobs.cancel_flag(id),
        interrupt: jobs.interrupt.clone(),
        last_write: Instant::now(),
    };
    let dir = jobs.config.job_dir(&id);
    let limits = jobs.config.limits();
    let span = tracing::Span::current();
    let outcome = tokio::task::spawn_blocking(move || -> Result<_, CaseError> {
        let _entered = span.enter();
        let mut observer = observer;
        // this service's limits, which may differ from those the job was submitted under
        let case = ValidCase::new(parse_case_str(&job.case_json)?, &limits)?;
        Ok(run_case(&case, &dir, &mut observer))
    })
    .await;

    let (status, reason, summary, steps, time) = match outcome {
        Ok(Ok(Ok(summary))) => {
            // the observer decided cancelled (a DELETE) or failed / interrupted (shutdown)
            let (status, reason) = match summary.status {
                RunStatus::Succeeded => (JobStatus::Succeeded, None),
                RunStatus::Failed => (JobStatus::Failed, summary.reason.clone()),
                RunStatus::Cancelled => (
                    JobStatus::Cancelled,
                    Some("cancelled by request".to_string()),
                ),
            };
            let text = serde_json::to_string(&summary).ok();
            (status, reason, text, summary.steps, summary.simulated_time)
        }
        Ok(Err(e)) => (
            JobStatus::Failed,
            Some(format!("invalid case: {e}")),
            None,
            0,
            0.0,
        ),
        Ok(Ok(Err(RunError::Io(e)))) => {
            tracing::error!(error = %e, "cannot write the run directory");
            (
                JobStatus::Failed,
                Some("cannot write the run directory".to_string()),
                None,
                0,
                0.0,
            )
        }
        Err(join) => {
            tracing::error!(error = %join, "the run panicked");
            (
                JobStatus::Failed,
                Some("internal error: the run panicked".to_string()),
                None,
                0,
                0.0,
            )
        }
    };
    tracing::info!(
        status = status.as_str(),
        reason = reason.as_deref().unwrap_or(""),
        steps,
        "run finished"
    );
    jobs.store
        .finish(
            id,
            status,
            reason.as_deref(),
            summary.as_deref(),
            steps,
            time,
        )
        .await?;
    Ok(status)
}

/// A worker: run jobs until the pool stops claiming.
pub async fn run_worker_until_stopped(jobs: Arc<Jobs>) {
    while !jobs.is_stopping() {
        match try_execute_job(&jobs).await {
            Ok(ExecutionOutcome::JobFinished(..)) => {}
            Ok(ExecutionOutcome::EmptyQueue) => {
                // A missed wake-up costs at most the timeout.
                let _ = tokio::time::timeout(Duration::from_secs(1), jobs.wake.notified()).await;
            }
            Err(e) => {
                tracing::error!(error = %e, "worker cannot reach the job store");
                tokio::time::sleep(Duration::from_secs(1)).await;
            }
        }
    }
}
