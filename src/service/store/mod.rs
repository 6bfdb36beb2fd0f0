//! The job table, which is also the queue (see the module docs of [`crate::service`]),
//! in one of two databases chosen by URL:
//! - [`SqliteStore`] (`sqlite://…`, the default: `<data>/jobs.db`): one process serves
//!   and runs the jobs; the run's files stay in its run directory.
//! - [`PgStore`] (`postgres://…`): any number of API nodes and workers; workers claim
//!   under a lease, and the run's CSV files are uploaded to the database as they grow,
//!   so every node serves them. Snapshots stay on the worker's disk (`run_dir`).
//!
//! Timestamps are RFC 3339 strings in UTC in both. Schemas are sqlx migrations
//! (`migrations/sqlite`, `migrations/postgres`), applied when a store opens.

mod job;
mod postgres;
mod sqlite;

pub use job::{
    now_rfc3339, Admission, Claimant, ClaimedJob, JobRow, JobStatus, Renewal, ATTEMPTS_EXHAUSTED,
};
pub use postgres::PgStore;
pub use sqlite::SqliteStore;

use uuid::Uuid;

#[derive(Debug, Clone)]
pub enum JobStore {
    Sqlite(SqliteStore),
    Postgres(PgStore),
}

/// The same call on whichever database this is.
macro_rules! either {
    ($self:expr, $store:ident => $call:expr) => {
        match $self {
            JobStore::Sqlite($store) => $call,
            JobStore::Postgres($store) => $call,
        }
    };
}

/// Whether `url` names a Postgres database.
pub fn is_postgres_url(url: &str) -> bool {
    url.starts_with("postgres://") || url.starts_with("postgresql://")
}

impl JobStore {
    /// Open (creating the SQLite file if needed) and migrate.
    pub async fn open(url: &str) -> Result<Self, sqlx::Error> {
        Ok(if is_postgres_url(url) {
            Self::Postgres(PgStore::open(url).await?)
        } else {
            Self::Sqlite(SqliteStore::open(url).await?)
        })
    }

    /// Whether other processes share this store (Postgres): then jobs are claimed under
    /// leases, and results are read from the database rather than a local run directory.
    pub fn is_shared(&self) -> bool {
        matches!(self, Self::Postgres(_))
    }

    pub async fn close(&self) {
        either!(self, s => s.close().await)
    }

    /// SQLite: jobs left `running` by a previous process become `failed` /
    /// `interrupted` (queued ones run again); returns how many. Postgres: none, the
    /// leases of dead workers expire instead.
    pub async fn recover_interrupted(&self) -> Result<u64, sqlx::Error> {
        match self {
            Self::Sqlite(s) => s.recover_interrupted().await,
            Self::Postgres(_) => Ok(0),
        }
    }

    /// Insert a queued job unless `capacity` jobs are already queued.
    pub async fn submit(
        &self,
        id: Uuid,
        name: &str,
        case_json: &str,
        end_time: f64,
        capacity: usize,
    ) -> Result<Admission, sqlx::Error> {
        either!(self, s => s.submit(id, name, case_json, end_time, capacity).await)
    }

    /// Claim the oldest waiting job (marks it `running`, counts the attempt).
    pub async fn claim_next(&self, by: &Claimant) -> Result<Option<ClaimedJob>, sqlx::Error> {
        either!(self, s => s.claim_next(by).await)
    }

    pub async fn get(&self, id: Uuid) -> Result<Option<JobRow>, sqlx::Error> {
        either!(self, s => s.get(id).await)
    }

    /// The case text job `id` was submitted with.
    pub async fn case_text(&self, id: Uuid) -> Result<Option<String>, sqlx::Error> {
        either!(self, s => s.case_text(id).await)
    }

    /// Newest first, with the total matching `status`.
    pub async fn list(
        &self,
        status: Option<JobStatus>,
        limit: i64,
        offset: i64,
    ) -> Result<(Vec<JobRow>, i64), sqlx::Error> {
        either!(self, s => s.list(status, limit, offset).await)
    }

    /// Cancel a job that is still queued; `true` if it was.
    pub async fn cancel_if_queued(&self, id: Uuid) -> Result<bool, sqlx::Error> {
        either!(self, s => s.cancel_if_queued(id).await)
    }

    /// Postgres: flag a running job for its worker, wherever it runs. SQLite: nothing
    /// (the worker is in this process: [`super::workers::Jobs::request_cancel`]).
    pub async fn request_cancel(&self, id: Uuid) -> Result<(), sqlx::Error> {
        match self {
            Self::Sqlite(_) => Ok(()),
            Self::Postgres(s) => s.request_cancel(id).await,
        }
    }

    /// Extend the lease of a claim (always held with SQLite, which has no leases).
    pub async fn renew(
        &self,
        id: Uuid,
        attempt: i64,
        lease_s: f64,
    ) -> Result<Renewal, sqlx::Error> {
        match self {
            Self::Sqlite(_) => Ok(Renewal::Held { cancel: false }),
            Self::Postgres(s) => s.renew(id, attempt, lease_s).await,
        }
    }

    /// Postgres: give a claimed job back to the queue; `false` with SQLite, whose
    /// interrupted jobs are recorded `failed` / `interrupted` instead.
    pub async fn release(&self, id: Uuid, attempt: i64) -> Result<bool, sqlx::Error> {
        match self {
            Self::Sqlite(_) => Ok(false),
            Self::Postgres(s) => s.release(id, attempt).await,
        }
    }

    pub async fn set_started(
        &self,
        id: Uuid,
        attempt: i64,
        particles: usize,
    ) -> Result<(), sqlx::Error> {
        either!(self, s => s.set_started(id, attempt, particles).await)
    }

    pub async fn set_progress(
        &self,
        id: Uuid,
        attempt: i64,
        step: u64,
        simulated_time: f64,
    ) -> Result<(), sqlx::Error> {
        either!(self, s => s.set_progress(id, attempt, step, simulated_time).await)
    }

    /// Record the end of an attempt; `false` when the attempt no longer held the job.
    #[allow(clippy::too_many_arguments)]
    pub async fn finish(
        &self,
        id: Uuid,
        attempt: i64,
        status: JobStatus,
        reason: Option<&str>,
        summary: Option<&str>,
        step: u64,
        simulated_time: f64,
    ) -> Result<bool, sqlx::Error> {
        either!(self, s => s.finish(id, attempt, status, reason, summary, step, simulated_time).await)
    }

    /// A run file as the database holds it: `Some` with Postgres (possibly empty), `None`
    /// with SQLite, where the run directory is the place to read.
    pub async fn read_series(&self, id: Uuid, file: &str) -> Result<Option<Vec<u8>>, sqlx::Error> {
        match self {
            Self::Sqlite(_) => Ok(None),
            Self::Postgres(s) => s.read_series(id, file).await.map(Some),
        }
    }

    /// Cheap liveness check of the database.
    pub async fn ping(&self) -> Result<(), sqlx::Error> {
        either!(self, s => s.ping().await)
    }
}
