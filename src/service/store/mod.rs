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
//!
//! [`JobStore`] is the one interface. A query both dialects accept is written once, in
//! its method here, with `$1`-style parameters (sqlx's SQLite driver binds `$N` to the
//! N-th value, as Postgres does), and compiled for each pool by `either!`. The stores'
//! own modules hold only what differs: opening, claiming (Postgres: leases and
//! `FOR UPDATE SKIP LOCKED`), SQLite's recovery at startup, Postgres's submission lock,
//! cancellation flags and uploaded run files.
//!
//! With Postgres a submission is announced (`NOTIFY` on [`QUEUE_CHANNEL`], sent when its
//! insert commits) and workers listen ([`PgStore::queue_listener`]), so an idle worker
//! claims a new job at once; with SQLite the one process wakes its own workers.
//!
//! A worker's writes (`set_started`, `set_progress`, `finish`) name the attempt that
//! claimed the job and apply only while the job is `running` under that attempt. So the
//! first recorded end stands: a late finish (a second write, an attempt that lost its
//! lease, a process whose orphaned job was recovered) does not overwrite a job that was
//! cancelled, failed by recovery or already finished; it returns `false`. Nor does it
//! bring back a deleted job ([`JobStore::delete`]): its writes then match no row.

mod job;
mod postgres;
mod sqlite;

pub use job::{
    now_rfc3339, Admission, Claimant, ClaimedJob, JobRow, JobStatus, Renewal, ATTEMPTS_EXHAUSTED,
};
pub use postgres::{PgStore, QUEUE_CHANNEL};
pub use sqlite::SqliteStore;

use job::{parse_uuid, RawJob, COLUMNS};
use uuid::Uuid;

#[derive(Debug, Clone)]
pub enum JobStore {
    Sqlite(SqliteStore),
    Postgres(PgStore),
}

/// The same code on whichever database this is: `$store` is the [`SqliteStore`] or the
/// [`PgStore`], and `$call` is compiled once for each (a query's text and binds are
/// written once, its pool's type differs).
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
        either!(self, s => s.pool.close().await)
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

    /// Insert a queued job unless `capacity` jobs are already queued. A ladder
    /// (`ladder_parts`: `Some(n)`, from `?uncertainty=true`) also queues its coarser parts
    /// 1 to n - 1, as rows whose `parent` is the job, in the same transaction: the job's
    /// own row runs part 0, the user's level. Parts do not count against the capacity.
    pub async fn submit(
        &self,
        id: Uuid,
        name: &str,
        case_json: &str,
        end_time: f64,
        ladder_parts: Option<usize>,
        capacity: usize,
    ) -> Result<Admission, sqlx::Error> {
        // one statement, so that concurrent submissions to a SQLite file cannot overfill
        // the queue; Postgres also runs it under its submission lock, because there two
        // statements at once count the queue without each other's insert
        let sql = format!(
            "INSERT INTO jobs (id, name, status, case_json, created_at, end_time, uncertainty, parts)
             SELECT $1, $2, 'queued', $3, $4, $5, $6, $7
             WHERE (SELECT COUNT(*) FROM jobs WHERE status = 'queued' AND parent IS NULL) < $8
             RETURNING {COLUMNS}"
        );
        let part_sql = "INSERT INTO jobs (id, name, status, case_json, created_at, end_time, parent, part, parts)
             VALUES ($1, $2, 'queued', $3, $4, $5, $6, $7, $8)";
        let parts = ladder_parts.unwrap_or(1).max(1) as i64;
        let (id, now, capacity) = (id.to_string(), now_rfc3339(), capacity as i64);
        macro_rules! insert_on {
            ($tx:expr) => {{
                let row: Option<RawJob> = sqlx::query_as(&sql)
                    .bind(&id)
                    .bind(name)
                    .bind(case_json)
                    .bind(&now)
                    .bind(end_time)
                    .bind(ladder_parts.is_some())
                    .bind(parts)
                    .bind(capacity)
                    .fetch_optional(&mut *$tx)
                    .await?;
                if row.is_some() {
                    for part in 1..parts {
                        sqlx::query(part_sql)
                            .bind(Uuid::new_v4().to_string())
                            .bind(format!("{name} (part {part} of {parts})"))
                            .bind(case_json)
                            .bind(&now)
                            .bind(end_time)
                            .bind(&id)
                            .bind(part)
                            .bind(parts)
                            .execute(&mut *$tx)
                            .await?;
                    }
                }
                row
            }};
        }
        let row = match self {
            Self::Sqlite(s) => {
                let mut tx = s.pool.begin().await?;
                let row = insert_on!(tx);
                tx.commit().await?;
                row
            }
            Self::Postgres(s) => {
                let mut tx = s.lock_submissions().await?;
                let row = insert_on!(tx);
                if row.is_some() {
                    PgStore::announce_queued(&mut *tx).await?;
                }
                tx.commit().await?;
                row
            }
        };
        Ok(match row {
            Some(r) => Admission::Accepted(Box::new(r.into_row()?)),
            None => Admission::QueueFull,
        })
    }

    /// Claim the oldest waiting job (marks it `running`, counts the attempt); with
    /// `parts_of`, only a part of that job. A part whose job has ended is not claimed.
    pub async fn claim_next(
        &self,
        by: &Claimant,
        parts_of: Option<Uuid>,
    ) -> Result<Option<ClaimedJob>, sqlx::Error> {
        let parts_of = parts_of.map(|id| id.to_string());
        either!(self, s => s.claim_next(by, parts_of.as_deref()).await)
    }

    pub async fn get(&self, id: Uuid) -> Result<Option<JobRow>, sqlx::Error> {
        self.one_job(&format!("SELECT {COLUMNS} FROM jobs WHERE id = $1"), id)
            .await
    }

    /// The job row `sql` returns for `$1` = `id`, if any.
    async fn one_job(&self, sql: &str, id: Uuid) -> Result<Option<JobRow>, sqlx::Error> {
        let raw: Option<RawJob> = either!(self, s => {
            sqlx::query_as(sql)
                .bind(id.to_string())
                .fetch_optional(&s.pool)
                .await?
        });
        raw.map(RawJob::into_row).transpose()
    }

    /// The case text job `id` was submitted with.
    pub async fn case_text(&self, id: Uuid) -> Result<Option<String>, sqlx::Error> {
        let sql = "SELECT case_json FROM jobs WHERE id = $1";
        either!(self, s => {
            sqlx::query_scalar(sql)
                .bind(id.to_string())
                .fetch_optional(&s.pool)
                .await
        })
    }

    /// Newest first, with the total matching `status`.
    pub async fn list(
        &self,
        status: Option<JobStatus>,
        limit: i64,
        offset: i64,
    ) -> Result<(Vec<JobRow>, i64), sqlx::Error> {
        let filter = status.map(JobStatus::as_str);
        let page = format!(
            "SELECT {COLUMNS} FROM jobs WHERE ($1 IS NULL OR status = $1) AND parent IS NULL
             ORDER BY seq DESC LIMIT $2 OFFSET $3"
        );
        let count =
            "SELECT COUNT(*) FROM jobs WHERE ($1 IS NULL OR status = $1) AND parent IS NULL";
        let (rows, total): (Vec<RawJob>, i64) = either!(self, s => {
            let rows = sqlx::query_as(&page)
                .bind(filter)
                .bind(limit)
                .bind(offset)
                .fetch_all(&s.pool)
                .await?;
            let total = sqlx::query_scalar(count)
                .bind(filter)
                .fetch_one(&s.pool)
                .await?;
            (rows, total)
        });
        let jobs = rows
            .into_iter()
            .map(RawJob::into_row)
            .collect::<Result<_, _>>()?;
        Ok((jobs, total))
    }

    /// Cancel a job that is still queued; `true` if it was.
    pub async fn cancel_if_queued(&self, id: Uuid) -> Result<bool, sqlx::Error> {
        let sql = "UPDATE jobs SET status = 'cancelled', reason = 'cancelled before it started',
                 finished_at = $1
             WHERE id = $2 AND status = 'queued'";
        let done = either!(self, s => {
            sqlx::query(sql)
                .bind(now_rfc3339())
                .bind(id.to_string())
                .execute(&s.pool)
                .await?
                .rows_affected()
        });
        Ok(done == 1)
    }

    /// End the parts of ladder job `parent` with it: queued parts are cancelled, running
    /// ones asked to stop (Postgres: flagged for their workers, wherever they run). The
    /// running parts' ids, for the flags of this process's workers.
    pub async fn cancel_parts(&self, parent: Uuid) -> Result<Vec<Uuid>, sqlx::Error> {
        let queued = "UPDATE jobs SET status = 'cancelled', reason = 'its job ended',
                 finished_at = $1
             WHERE parent = $2 AND status = 'queued'";
        // Postgres flags them for their workers; SQLite's workers are this process's
        let running = match self {
            Self::Sqlite(_) => "SELECT id FROM jobs WHERE parent = $1 AND status = 'running'",
            Self::Postgres(_) => {
                "UPDATE jobs SET cancel_requested = TRUE
                 WHERE parent = $1 AND status = 'running' RETURNING id"
            }
        };
        let parent = parent.to_string();
        let ids: Vec<String> = either!(self, s => {
            sqlx::query(queued)
                .bind(now_rfc3339())
                .bind(&parent)
                .execute(&s.pool)
                .await?;
            sqlx::query_scalar(running).bind(&parent).fetch_all(&s.pool).await?
        });
        ids.iter().map(|id| parse_uuid(id)).collect()
    }

    /// The parts of ladder job `parent`, in the ladder's order.
    pub async fn parts(&self, parent: Uuid) -> Result<Vec<JobRow>, sqlx::Error> {
        let sql = format!("SELECT {COLUMNS} FROM jobs WHERE parent = $1 ORDER BY part");
        let raw: Vec<RawJob> = either!(self, s => {
            sqlx::query_as(&sql)
                .bind(parent.to_string())
                .fetch_all(&s.pool)
                .await?
        });
        raw.into_iter().map(RawJob::into_row).collect()
    }

    /// Count one more ended part on the row of ladder job `parent` (its progress).
    pub async fn part_ended(&self, parent: Uuid) -> Result<(), sqlx::Error> {
        let sql = "UPDATE jobs SET part = part + 1 WHERE id = $1 AND part + 1 < parts";
        either!(self, s => {
            sqlx::query(sql)
                .bind(parent.to_string())
                .execute(&s.pool)
                .await?;
        });
        Ok(())
    }

    /// Remove job `id` and everything stored with it (Postgres: its uploaded run files,
    /// by the `ON DELETE CASCADE` of `job_series`; its ladder's parts, by that of
    /// `parent`); the record as it was, `None` when there is no such job. A worker still running it can no longer write: its writes
    /// match no row (`finish` returns `false`, [`PgStore::append_series`] and `renew`
    /// report the claim lost), so nothing of the job reappears.
    pub async fn delete(&self, id: Uuid) -> Result<Option<JobRow>, sqlx::Error> {
        self.one_job(
            &format!("DELETE FROM jobs WHERE id = $1 AND parent IS NULL RETURNING {COLUMNS}"),
            id,
        )
        .await
    }

    /// Jobs that ended (succeeded, failed or cancelled) before `cutoff` (RFC 3339, UTC,
    /// as the records' timestamps), oldest first. Queued and running jobs never are.
    pub async fn finished_before(&self, cutoff: &str) -> Result<Vec<Uuid>, sqlx::Error> {
        let sql = "SELECT id FROM jobs
             WHERE status IN ('succeeded', 'failed', 'cancelled') AND finished_at < $1
               AND parent IS NULL
             ORDER BY finished_at";
        let ids: Vec<String> = either!(self, s => {
            sqlx::query_scalar(sql).bind(cutoff).fetch_all(&s.pool).await?
        });
        ids.iter().map(|id| parse_uuid(id)).collect()
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

    /// The particle count of the attempt's run (once its case is built).
    pub async fn set_started(
        &self,
        id: Uuid,
        attempt: i64,
        particles: usize,
    ) -> Result<(), sqlx::Error> {
        let sql = "UPDATE jobs SET particles = $1
             WHERE id = $2 AND attempts = $3 AND status = 'running'";
        either!(self, s => {
            sqlx::query(sql)
                .bind(particles as i64)
                .bind(id.to_string())
                .bind(attempt)
                .execute(&s.pool)
                .await?;
        });
        Ok(())
    }

    pub async fn set_progress(
        &self,
        id: Uuid,
        attempt: i64,
        step: u64,
        simulated_time: f64,
    ) -> Result<(), sqlx::Error> {
        let sql = "UPDATE jobs SET step = $1, simulated_time = $2
             WHERE id = $3 AND attempts = $4 AND status = 'running'";
        either!(self, s => {
            sqlx::query(sql)
                .bind(step as i64)
                .bind(simulated_time)
                .bind(id.to_string())
                .bind(attempt)
                .execute(&s.pool)
                .await?;
        });
        Ok(())
    }

    /// Record the end of an attempt; `false`, and nothing written, when the attempt no
    /// longer holds the job: another attempt claimed it, or it has ended (finished,
    /// cancelled, or failed by recovery or an expired lease), and that end stands.
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
        // a ladder job that succeeded has all its parts ended
        let sql = "UPDATE jobs SET status = $1, reason = $2, summary = $3, finished_at = $4,
                 step = $5, simulated_time = $6,
                 part = CASE WHEN $1 = 'succeeded' AND parent IS NULL THEN parts ELSE part END
             WHERE id = $7 AND attempts = $8 AND status = 'running'";
        let done = either!(self, s => {
            sqlx::query(sql)
                .bind(status.as_str())
                .bind(reason)
                .bind(summary)
                .bind(now_rfc3339())
                .bind(step as i64)
                .bind(simulated_time)
                .bind(id.to_string())
                .bind(attempt)
                .execute(&s.pool)
                .await?
                .rows_affected()
        });
        Ok(done == 1)
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
        either!(self, s => sqlx::query("SELECT 1").execute(&s.pool).await.map(|_| ()))
    }
}
