//! The worker pool. Each worker claims the oldest queued job from the [`JobStore`],
//! runs `run_case` on a blocking thread (the simulation is CPU-bound and uses the rayon
//! pool), and records the outcome. [`try_execute_job`] is one step of a worker, so tests
//! can drive the queue without sleeping.
//!
//! Cancellation and shutdown reach a run through its [`Observer`], which the engine polls
//! once per time step: a cancel request (`POST .../cancel`, or a `DELETE`, which then
//! deletes the job) sets the job's cancel flag (the job ends `cancelled`); a shutdown past
//! its grace period sets the pool's interrupt flag (the job ends `failed` with reason
//! `interrupted`, exactly as if the process had died). The decision is the
//! observer's ([`Observer::stop_reason`]), so the job's summary.json says the same as its
//! record.
//!
//! With a shared store (Postgres) a worker holds its job under a lease that a task
//! renews every third of the lease ([`LeaseKeeper`]); the renewal also carries a
//! cancellation requested through any API node, and a lost lease stops the run. The
//! run's CSV files are uploaded as they grow ([`SeriesUpload`]), and a worker shutting
//! down gives its job back to the queue instead of failing it.
//!
//! A deleted job ([`Jobs::delete`]) is gone from the store at once; a run of it stops at
//! its next step (in this process: its cancel flag; on another worker: at its next lease
//! renewal, which finds no job), its later writes match no row, and its worker removes the
//! run directory when the run has stopped.

mod parts;

use super::run_files::{Saved, SeriesUpload};
use super::store::{Claimant, ClaimedJob, JobStatus, JobStore, Renewal};
use super::Config;
use crate::case::{parse_case_str, CaseError, ValidCase};
use crate::engine::SimError;
use crate::math::Real;
use crate::run::{run_case_with, Checkpoint, Observer, Progress, RunError, RunOptions, RunStatus};
use std::collections::HashMap;
use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};
use tokio::sync::Notify;
use tracing::Instrument;
use uuid::Uuid;

/// Reason recorded for a job whose run was stopped by a shutdown or a dead process.
pub const INTERRUPTED: &str = "interrupted";

/// Reason a run stops with when its worker lost the lease (never recorded: the job
/// belongs to another attempt by then).
const LEASE_LOST: &str = "lease lost";

/// State shared by the routes and the workers.
#[derive(Debug)]
pub struct Jobs {
    pub store: JobStore,
    pub config: Config,
    /// A job was queued (or the pool is stopping).
    wake: Notify,
    /// Cancel flags of running jobs (and of jobs a cancel request raced with the claim).
    cancel_flags: Mutex<HashMap<Uuid, Arc<AtomicBool>>>,
    /// No new job is claimed once set.
    stopping: AtomicBool,
    /// Running jobs stop at their next step once set.
    interrupt: Arc<AtomicBool>,
    running: AtomicUsize,
    claimant: Claimant,
}

/// What one worker step did.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum ExecutionOutcome {
    JobFinished(Uuid, JobStatus),
    EmptyQueue,
}

impl Jobs {
    pub fn new(store: JobStore, config: Config) -> Self {
        let claimant = Claimant {
            worker: worker_name(),
            jobs_dir: format!("{}/", config.data_dir.join("jobs").display()),
            lease_s: config.lease_s,
            max_attempts: config.max_attempts,
        };
        Self {
            claimant,
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

    /// Tell every sleeping worker that jobs are waiting: a ladder's parts, or an
    /// announcement from another node, which may be a ladder's (the workers that find
    /// nothing to claim sleep again).
    pub fn jobs_queued(&self) {
        self.wake.notify_waiters();
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

    /// End the parts of ladder job `id` with it ([`JobStore::cancel_parts`]); those a
    /// worker of this process runs stop at their next step.
    pub async fn cancel_parts(&self, id: Uuid) -> Result<(), sqlx::Error> {
        let running = self.store.cancel_parts(id).await?;
        let flags = self.cancel_flags.lock().unwrap_or_else(|p| p.into_inner());
        for part in running {
            if let Some(flag) = flags.get(&part) {
                flag.store(true, Ordering::SeqCst);
            }
        }
        Ok(())
    }

    /// Delete job `id`: its record, what the store holds of its run, and its run
    /// directory on this node; `false` when there is no such job. A run of it stops at its
    /// next step; when this process runs it, its worker removes the run directory once the
    /// run has stopped (it may still be writing there until then).
    pub async fn delete(&self, id: Uuid) -> Result<bool, sqlx::Error> {
        // a ladder's part is not a job: it goes with its job only
        if let Some(row) = self.store.get(id).await? {
            if row.parent.is_some() {
                return Ok(false);
            }
        }
        // raised before the record goes, so that a worker of this process that claimed
        // the job in the meantime stops too
        self.request_cancel(id);
        self.cancel_parts(id).await?;
        let deleted = self.store.delete(id).await;
        let runs_here = matches!(&deleted, Ok(Some(row))
            if row.status == JobStatus::Running
                && row.worker.as_deref() == Some(self.claimant.worker.as_str()));
        if !runs_here {
            // no worker of this process holds the job, nor can claim it now
            self.forget_cancel_flag(id);
        }
        let Some(_) = deleted? else {
            return Ok(false);
        };
        if !runs_here {
            remove_run_dir(&self.config.job_dir(&id)).await;
        }
        Ok(true)
    }

    /// After a run of job `id` stopped: `true`, with the run directory removed, when the
    /// job was deleted meanwhile.
    async fn removed_if_deleted(&self, id: Uuid, dir: &std::path::Path) -> bool {
        match self.store.get(id).await {
            Ok(None) => {
                tracing::info!("the job was deleted: its run directory is removed");
                remove_run_dir(dir).await;
                true
            }
            Ok(Some(_)) => false,
            Err(e) => {
                tracing::warn!(error = %e, "cannot tell whether the job still exists");
                false
            }
        }
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

/// Remove a job's run directory, if there is one.
async fn remove_run_dir(dir: &std::path::Path) {
    match tokio::fs::remove_dir_all(dir).await {
        Ok(()) => {}
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {}
        Err(e) => {
            tracing::warn!(error = %e, dir = %dir.display(), "cannot remove the run directory")
        }
    }
}

/// `host:pid` of this process, as job records name the worker that ran them.
fn worker_name() -> String {
    let host = std::fs::read_to_string("/proc/sys/kernel/hostname")
        .ok()
        .map(|h| h.trim().to_string())
        .filter(|h| !h.is_empty())
        .or_else(|| std::env::var("HOSTNAME").ok())
        .unwrap_or_else(|| "localhost".to_string());
    format!("{host}:{}", std::process::id())
}

/// The run observer of one job: cancel/interrupt flags and throttled progress writes.
pub(super) struct JobObserver {
    id: Uuid,
    attempt: i64,
    store: JobStore,
    runtime: tokio::runtime::Handle,
    cancel: Arc<AtomicBool>,
    interrupt: Arc<AtomicBool>,
    lease_lost: Arc<AtomicBool>,
    last_write: Instant,
    /// With a shared store: the run's CSV files still to upload.
    pub(super) upload: Option<SeriesUpload>,
    last_upload: Instant,
}

const PROGRESS_EVERY: Duration = Duration::from_millis(250);
/// A running job's loads reach the shared store at most this late.
const UPLOAD_EVERY: Duration = Duration::from_secs(1);

impl Observer for JobObserver {
    fn started(&mut self, particles: usize, estimated_steps: u64) {
        tracing::info!(particles, estimated_steps, "run started");
        if let Err(e) =
            self.runtime
                .block_on(self.store.set_started(self.id, self.attempt, particles))
        {
            tracing::warn!(error = %e, "cannot record the particle count");
        }
    }

    fn progress(&mut self, p: &Progress) {
        if self.last_write.elapsed() >= PROGRESS_EVERY {
            self.last_write = Instant::now();
            if let Err(e) = self.runtime.block_on(self.store.set_progress(
                self.id,
                self.attempt,
                p.step,
                p.simulated_time,
            )) {
                tracing::warn!(error = %e, "cannot record progress");
            }
        }
        if self.last_upload.elapsed() >= UPLOAD_EVERY {
            self.last_upload = Instant::now();
            if let Some(upload) = &mut self.upload {
                match self
                    .runtime
                    .block_on(upload.sync(&self.store, self.id, self.attempt))
                {
                    Ok(true) => {}
                    Ok(false) => self.lease_lost.store(true, Ordering::SeqCst),
                    Err(e) => tracing::warn!(error = %e, "cannot upload the run's files"),
                }
            }
        }
    }

    fn is_cancelled(&self) -> bool {
        self.cancel.load(Ordering::Relaxed)
            || self.interrupt.load(Ordering::Relaxed)
            || self.lease_lost.load(Ordering::Relaxed)
    }

    /// With a shared store, the checkpoint goes there (after the files written up to
    /// it), for the next claim to resume from; a cancelled job's does not.
    fn checkpoint_saved(&mut self, path: &std::path::Path, time: Real, steps: u64, bytes: u64) {
        let Some(upload) = &mut self.upload else {
            return;
        };
        if self.cancel.load(Ordering::SeqCst) || self.lease_lost.load(Ordering::SeqCst) {
            return;
        }
        let started = Instant::now();
        let saved = Saved { path, time, steps };
        let stored = upload.checkpoint(&self.store, self.id, self.attempt, saved);
        match self.runtime.block_on(stored) {
            Ok(true) => tracing::info!(
                simulated_time = time,
                steps,
                bytes,
                seconds = started.elapsed().as_secs_f64(),
                "checkpoint stored"
            ),
            Ok(false) => self.lease_lost.store(true, Ordering::SeqCst),
            Err(e) => tracing::warn!(error = %e, "cannot store the checkpoint"),
        }
    }

    /// A user's cancel request (or DELETE): `cancelled`. Otherwise the service's shutdown
    /// stopped the run: `failed` / `interrupted`, the contract for a job the service gave
    /// up on (as after a crash), in summary.json as in the record.
    fn stop_reason(&self, step: u64, time: Real) -> (RunStatus, String) {
        if self.cancel.load(Ordering::SeqCst) {
            (
                RunStatus::Cancelled,
                SimError::Cancelled { step, time }.to_string(),
            )
        } else if self.lease_lost.load(Ordering::SeqCst) {
            (RunStatus::Failed, LEASE_LOST.to_string())
        } else {
            (RunStatus::Failed, INTERRUPTED.to_string())
        }
    }
}

/// Renews a shared store's lease every third of it while the run goes on: a cancel
/// request sets the job's cancel flag, a lost lease stops the run.
struct LeaseKeeper(tokio::task::JoinHandle<()>);

impl LeaseKeeper {
    fn start(
        store: JobStore,
        id: Uuid,
        attempt: i64,
        lease_s: f64,
        cancel: Arc<AtomicBool>,
        lost: Arc<AtomicBool>,
    ) -> Self {
        let every = Duration::from_secs_f64((lease_s / 3.0).max(0.05));
        Self(tokio::spawn(async move {
            loop {
                tokio::time::sleep(every).await;
                match store.renew(id, attempt, lease_s).await {
                    Ok(Renewal::Held { cancel: true }) => cancel.store(true, Ordering::SeqCst),
                    Ok(Renewal::Held { cancel: false }) => {}
                    Ok(Renewal::Lost) => {
                        if matches!(store.get(id).await, Ok(None)) {
                            tracing::info!("the job was deleted: stopping its run");
                        } else {
                            tracing::warn!("the job's lease was lost: stopping its run");
                        }
                        lost.store(true, Ordering::SeqCst);
                        return;
                    }
                    Err(e) => tracing::warn!(error = %e, "cannot renew the lease"),
                }
            }
        }))
    }
}

impl Drop for LeaseKeeper {
    fn drop(&mut self) {
        self.0.abort();
    }
}

/// Claim and run one job. `EmptyQueue` when nothing is waiting (or the pool is stopping).
pub async fn try_execute_job(jobs: &Arc<Jobs>) -> Result<ExecutionOutcome, sqlx::Error> {
    if jobs.is_stopping() {
        return Ok(ExecutionOutcome::EmptyQueue);
    }
    let Some(job) = jobs.store.claim_next(&jobs.claimant, None).await? else {
        return Ok(ExecutionOutcome::EmptyQueue);
    };
    let id = job.row.id;
    Ok(ExecutionOutcome::JobFinished(
        id,
        run_claimed(jobs, job).await?,
    ))
}

/// Run a claimed job (or a ladder's part) and record its end.
pub(super) async fn run_claimed(
    jobs: &Arc<Jobs>,
    job: ClaimedJob,
) -> Result<JobStatus, sqlx::Error> {
    let id = job.row.id;
    let span = tracing::info_span!("job", %id, name = %job.row.name);
    jobs.running.fetch_add(1, Ordering::SeqCst);
    let status = execute(jobs, job).instrument(span).await;
    jobs.running.fetch_sub(1, Ordering::SeqCst);
    jobs.forget_cancel_flag(id);
    status
}

async fn execute(jobs: &Arc<Jobs>, job: ClaimedJob) -> Result<JobStatus, sqlx::Error> {
    let id = job.row.id;
    let attempt = job.attempt();
    let shared = jobs.store.is_shared();
    // a part runs in its job's directory (`levels/<name>`) on the one node SQLite has
    let dir = match (shared, job.row.parent) {
        (false, Some(parent)) => jobs.config.job_dir(&parent),
        _ => jobs.config.job_dir(&id),
    };
    let (row, case_json) = (job.row.clone(), job.case_json.clone());
    if shared {
        // this worker may hold an earlier attempt's files; the case comes from the store
        let _ = tokio::fs::remove_dir_all(&dir).await;
        let written = async {
            tokio::fs::create_dir_all(&dir).await?;
            tokio::fs::write(dir.join("case.json"), &job.case_json).await
        };
        if let Err(e) = written.await {
            tracing::error!(error = %e, dir = %dir.display(), "cannot create the run directory");
        }
    }
    let cancel = jobs.cancel_flag(id);
    let lease_lost = Arc::new(AtomicBool::new(false));
    let _lease = shared.then(|| {
        LeaseKeeper::start(
            jobs.store.clone(),
            id,
            attempt,
            jobs.config.lease_s,
            cancel.clone(),
            lease_lost.clone(),
        )
    });
    let mut observer = JobObserver {
        id,
        attempt,
        store: jobs.store.clone(),
        runtime: tokio::runtime::Handle::current(),
        cancel: cancel.clone(),
        interrupt: jobs.interrupt.clone(),
        lease_lost: lease_lost.clone(),
        last_write: Instant::now(),
        upload: shared.then(|| SeriesUpload::new(dir.clone())),
        last_upload: Instant::now(),
    };
    let saved = match &jobs.store {
        JobStore::Postgres(pg) => pg.checkpoint(id).await?,
        _ => None,
    };
    let checkpoint_every = Duration::from_secs_f64(jobs.config.checkpoint_s);
    let store = jobs.store.clone();
    let limits = jobs.config.limits();
    let span = tracing::Span::current();
    let run_dir = dir.clone();
    let outcome = tokio::task::spawn_blocking(move || -> Result<_, CaseError> {
        let _entered = span.enter();
        let dir = run_dir;
        // this service's limits, which may differ from those the job was submitted under
        let case = ValidCase::new(parse_case_str(&job.case_json)?, &limits)?;
        // a ladder job runs the user's level, its parts the others
        let (case, dir, phase) = match job.row.parent {
            Some(_) => parts::part_case(&case, job.row.part, dir, shared)?,
            None => (case, dir, None),
        };
        let run = {
            let resume = saved.and_then(|bytes| match Checkpoint::from_bytes(&bytes) {
                Ok(saved) => {
                    tracing::info!(
                        simulated_time = saved.header.time,
                        "resuming from the checkpoint"
                    );
                    Some(saved)
                }
                Err(e) => {
                    tracing::warn!(error = %e, "the checkpoint is unusable: starting from t = 0");
                    if let JobStore::Postgres(pg) = &store {
                        let discarded = observer
                            .runtime
                            .block_on(pg.discard_checkpoint(id, attempt));
                        if let Err(e) = discarded {
                            tracing::warn!(error = %e, "cannot discard the checkpoint");
                        }
                    }
                    None
                }
            });
            let options = RunOptions {
                phase,
                checkpoint_every: shared.then_some(checkpoint_every),
                checkpoint_on_stop: shared,
                resume,
            };
            run_case_with(&case, &dir, &mut observer, options)
        };
        Ok((run, observer))
    })
    .await;
    let (outcome, upload) = match outcome {
        Ok(Ok((Ok(user), observer))) if row.uncertainty && user.status == RunStatus::Succeeded => {
            // the user's level ran: the job ends with its parts
            let ladder =
                parts::finish_ladder(jobs, &row, &case_json, &dir, user, &observer).await?;
            (Ok(Ok(Ok(ladder))), observer.upload)
        }
        Ok(Ok((run, observer))) => (Ok(Ok(run)), observer.upload),
        Ok(Err(e)) => (Ok(Err(e)), None),
        Err(join) => (Err(join), None),
    };
    if lease_lost.load(Ordering::SeqCst) {
        if jobs.removed_if_deleted(id, &dir).await {
            return Ok(JobStatus::Cancelled);
        }
        tracing::warn!("the lease was lost: this attempt's outcome is discarded");
        return Ok(JobStatus::Failed);
    }
    // everything written reaches the store first: the snapshots before a checkpoint
    // are the next attempt's too
    if let Some(mut upload) = upload {
        if let Err(e) = upload.sync(&jobs.store, id, attempt).await {
            tracing::error!(error = %e, "cannot upload the run's files");
        }
    }
    let interrupted = jobs.interrupt.load(Ordering::SeqCst) && !cancel.load(Ordering::SeqCst);
    if shared && interrupted && jobs.store.release(id, attempt).await? {
        tracing::info!("the job went back to the queue");
        remove_run_dir(&dir).await;
        return Ok(JobStatus::Queued);
    }

    let (status, reason, summary, steps, time) = match outcome {
        Ok(Ok(Ok(summary))) => {
            // the observer decided cancelled (a cancel request) or failed / interrupted (shutdown)
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
        Ok(Ok(Err(RunError::Resume(e)))) => {
            tracing::error!(error = %e, "cannot resume from the checkpoint");
            (
                JobStatus::Failed,
                Some(format!("cannot resume: {e}")),
                None,
                0,
                0.0,
            )
        }
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
    let recorded = jobs
        .store
        .finish(
            id,
            attempt,
            status,
            reason.as_deref(),
            summary.as_deref(),
            steps,
            time,
        )
        .await?;
    if !recorded && !jobs.removed_if_deleted(id, &dir).await {
        tracing::warn!("another attempt holds the job: this outcome is discarded");
    }
    match (recorded, row.parent) {
        (true, Some(parent)) => jobs.store.part_ended(parent).await?,
        // a ladder job that did not succeed takes its parts with it
        (true, None) if row.uncertainty && status != JobStatus::Succeeded => {
            jobs.cancel_parts(id).await?
        }
        _ => {}
    }
    if let (true, JobStore::Postgres(pg)) = (recorded, &jobs.store) {
        pg.drop_checkpoint(id).await?;
        // the store holds what every node serves: the worker keeps nothing
        remove_run_dir(&dir).await;
    }
    Ok(status)
}

/// Longest an idle worker waits for a wake-up before it looks at the queue itself (at
/// most a third of the lease). Wake-ups come at once for a submission (from this
/// process's routes, and with Postgres from any node through [`spawn_queue_listener`]),
/// so this poll only bounds what nothing announces: a wake-up lost with the listening
/// connection, and a dead worker's expired lease. 5 s against a 30 s default lease.
const IDLE_POLL: Duration = Duration::from_secs(5);

/// A worker: run jobs until the pool stops claiming.
pub async fn run_worker_until_stopped(jobs: Arc<Jobs>) {
    let idle_poll = IDLE_POLL.min(Duration::from_secs_f64(jobs.config.lease_s / 3.0));
    while !jobs.is_stopping() {
        match try_execute_job(&jobs).await {
            Ok(ExecutionOutcome::JobFinished(..)) => {}
            Ok(ExecutionOutcome::EmptyQueue) => {
                let _ = tokio::time::timeout(idle_poll, jobs.wake.notified()).await;
            }
            Err(e) => {
                tracing::error!(error = %e, "worker cannot reach the job store");
                tokio::time::sleep(Duration::from_secs(1)).await;
            }
        }
    }
}

/// With a shared store (Postgres): wake an idle worker of this process whenever a job is
/// announced on the queue channel (a submission on any node, a job given back), until
/// the task is aborted. After (re)connecting, when announcements may have been missed,
/// it wakes one too. `None` with SQLite, whose submissions wake the workers directly.
pub fn spawn_queue_listener(jobs: &Arc<Jobs>) -> Option<tokio::task::JoinHandle<()>> {
    let JobStore::Postgres(pg) = &jobs.store else {
        return None;
    };
    let (jobs, pg) = (jobs.clone(), pg.clone());
    Some(tokio::spawn(async move {
        loop {
            let mut listener = match pg.queue_listener().await {
                Ok(listener) => listener,
                Err(sqlx::Error::PoolClosed) => return,
                Err(e) => {
                    tracing::warn!(error = %e, "cannot listen for queued jobs: polling meanwhile");
                    tokio::time::sleep(IDLE_POLL).await;
                    continue;
                }
            };
            jobs.job_queued();
            loop {
                match listener.try_recv().await {
                    Ok(Some(_)) => jobs.jobs_queued(),
                    // the connection was lost and is back: what was announced meanwhile is not
                    Ok(None) => jobs.job_queued(),
                    Err(sqlx::Error::PoolClosed) => return,
                    Err(e) => {
                        tracing::warn!(error = %e, "lost the queue listener: reconnecting");
                        break;
                    }
                }
            }
            tokio::time::sleep(Duration::from_secs(1)).await;
        }
    }))
}
