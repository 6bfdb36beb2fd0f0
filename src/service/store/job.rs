//! The job record shared by both stores: status, row, the claim a worker holds.

use serde::{Deserialize, Serialize};
use time::format_description::well_known::Rfc3339;
use time::OffsetDateTime;
use uuid::Uuid;

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum JobStatus {
    Queued,
    Running,
    Succeeded,
    Failed,
    Cancelled,
}

impl JobStatus {
    pub fn as_str(self) -> &'static str {
        match self {
            Self::Queued => "queued",
            Self::Running => "running",
            Self::Succeeded => "succeeded",
            Self::Failed => "failed",
            Self::Cancelled => "cancelled",
        }
    }

    pub fn parse(s: &str) -> Option<Self> {
        Some(match s {
            "queued" => Self::Queued,
            "running" => Self::Running,
            "succeeded" => Self::Succeeded,
            "failed" => Self::Failed,
            "cancelled" => Self::Cancelled,
            _ => return None,
        })
    }

    pub fn is_finished(self) -> bool {
        matches!(self, Self::Succeeded | Self::Failed | Self::Cancelled)
    }
}

/// Reason recorded for a job whose expired lease could not be claimed again.
pub const ATTEMPTS_EXHAUSTED: &str = "attempts exhausted";

/// One row of the job table.
#[derive(Debug, Clone)]
pub struct JobRow {
    pub id: Uuid,
    pub name: String,
    pub status: JobStatus,
    pub created_at: String,
    pub started_at: Option<String>,
    pub finished_at: Option<String>,
    pub step: i64,
    pub simulated_time: f64,
    pub end_time: f64,
    pub particles: Option<i64>,
    pub reason: Option<String>,
    /// summary.json of the run, as JSON text.
    pub summary: Option<String>,
    /// Times a worker claimed the job (a run killed with its worker counts).
    pub attempts: i64,
    /// The worker that claimed it last (`host:pid`) and its run directory on that host.
    pub worker: Option<String>,
    pub run_dir: Option<String>,
    /// Submitted with `?uncertainty=true`: the run is the resolution ladder.
    pub uncertainty: bool,
    /// A ladder's parts in all (1 without a ladder) and, on the job's row, how many of
    /// its coarser parts have ended (all of them once the job succeeded).
    pub part: i64,
    pub parts: i64,
    /// On a part's row: the job it belongs to (its `part` is then its index in the
    /// ladder). Parts run as jobs but are never listed or served.
    pub parent: Option<Uuid>,
    /// The simulated time the current attempt resumed from (a checkpoint), or `None`
    /// from t = 0.
    pub resumed_from: Option<f64>,
}

/// The columns of [`JobRow`], in the order of [`RawJob`].
pub(super) const COLUMNS: &str = "id, name, status, created_at, started_at, finished_at, step, \
     simulated_time, end_time, particles, reason, summary, attempts, worker, run_dir, uncertainty, part, parts, resumed_from, parent";

/// The condition a claimable row meets besides its status, in a claim whose fourth
/// parameter is `parts_of` (a job's id, or null): a job, or a part whose job has not
/// ended; with `parts_of`, only that job's parts.
pub(super) const CLAIMABLE: &str = "(CAST($4 AS TEXT) IS NULL OR jobs.parent = $4)
     AND (jobs.parent IS NULL OR EXISTS (SELECT 1 FROM jobs AS owner
          WHERE owner.id = jobs.parent AND owner.status IN ('queued', 'running')))";

/// Before a claim, the queued parts of a job that has ended are cancelled (no claim
/// would take them); `$1` is the time. A job ends without its worker's help when a
/// restart or an expired lease fails it.
pub(super) const CANCEL_ORPHANED_PARTS: &str = "UPDATE jobs SET status = 'cancelled',
         reason = 'its job ended', finished_at = $1
     WHERE parent IS NOT NULL AND status = 'queued' AND NOT EXISTS (SELECT 1 FROM jobs AS owner
           WHERE owner.id = jobs.parent AND owner.status IN ('queued', 'running'))";

/// With Postgres, the running parts of a job that has ended are flagged to stop, as a
/// cancel request is (read at their next lease renewal).
pub(super) const STOP_ORPHANED_PARTS: &str = "UPDATE jobs SET cancel_requested = TRUE
     WHERE parent IS NOT NULL AND status = 'running' AND NOT cancel_requested
       AND NOT EXISTS (SELECT 1 FROM jobs AS owner
           WHERE owner.id = jobs.parent AND owner.status IN ('queued', 'running'))";

/// A row as both databases return it (text ids and statuses); [`RawJob::into_row`]
/// checks them.
#[derive(sqlx::FromRow)]
pub(super) struct RawJob {
    id: String,
    name: String,
    status: String,
    created_at: String,
    started_at: Option<String>,
    finished_at: Option<String>,
    step: i64,
    simulated_time: f64,
    end_time: f64,
    particles: Option<i64>,
    reason: Option<String>,
    summary: Option<String>,
    attempts: i64,
    worker: Option<String>,
    run_dir: Option<String>,
    uncertainty: bool,
    part: i64,
    parts: i64,
    resumed_from: Option<f64>,
    parent: Option<String>,
}

/// A stored id as a [`Uuid`].
pub(super) fn parse_uuid(id: &str) -> Result<Uuid, sqlx::Error> {
    Uuid::parse_str(id).map_err(|e| sqlx::Error::Decode(Box::new(e)))
}

impl RawJob {
    pub(super) fn into_row(self) -> Result<JobRow, sqlx::Error> {
        let status = JobStatus::parse(&self.status).ok_or_else(|| {
            sqlx::Error::Decode(format!("unknown job status {:?}", self.status).into())
        })?;
        Ok(JobRow {
            id: parse_uuid(&self.id)?,
            name: self.name,
            status,
            created_at: self.created_at,
            started_at: self.started_at,
            finished_at: self.finished_at,
            step: self.step,
            simulated_time: self.simulated_time,
            end_time: self.end_time,
            particles: self.particles,
            reason: self.reason,
            summary: self.summary,
            attempts: self.attempts,
            worker: self.worker,
            run_dir: self.run_dir,
            uncertainty: self.uncertainty,
            part: self.part,
            parts: self.parts,
            resumed_from: self.resumed_from,
            parent: self.parent.as_deref().map(parse_uuid).transpose()?,
        })
    }
}

/// A claimed job: its row (whose `attempts` fences every later write) and the case.
#[derive(Debug, Clone)]
pub struct ClaimedJob {
    pub row: JobRow,
    pub case_json: String,
}

/// What a claim returns: [`COLUMNS`], then `case_json`.
#[derive(sqlx::FromRow)]
pub(super) struct RawClaim {
    #[sqlx(flatten)]
    job: RawJob,
    case_json: String,
}

impl RawClaim {
    pub(super) fn into_claimed(self) -> Result<ClaimedJob, sqlx::Error> {
        Ok(ClaimedJob {
            row: self.job.into_row()?,
            case_json: self.case_json,
        })
    }
}

impl ClaimedJob {
    pub fn attempt(&self) -> i64 {
        self.row.attempts
    }
}

/// Who claims: the worker's name, where its run directories go, its lease.
#[derive(Debug, Clone)]
pub struct Claimant {
    pub worker: String,
    /// `<data>/jobs/`: a job runs in `<jobs_dir>/<id>`.
    pub jobs_dir: String,
    pub lease_s: f64,
    pub max_attempts: u32,
}

/// Outcome of a submission.
pub enum Admission {
    Accepted(Box<JobRow>),
    QueueFull,
}

/// Outcome of a lease renewal.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Renewal {
    /// Still ours; `cancel` when a client asked (through any API node) to cancel it.
    Held { cancel: bool },
    /// The lease expired and another worker claimed the job, or it ended: stop.
    Lost,
}

pub fn now_rfc3339() -> String {
    OffsetDateTime::now_utc()
        .format(&Rfc3339)
        .unwrap_or_default()
}
