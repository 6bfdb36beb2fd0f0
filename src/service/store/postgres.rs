//! The shared store: Postgres, for API nodes and workers on many machines. Workers claim
//! under a lease ([`PgStore::claim_next`]: `FOR UPDATE SKIP LOCKED`) and renew it while
//! the job runs; a job whose lease expired is claimed again and re-run from the start,
//! up to the claimant's attempt limit. Every write of a worker names the attempt it
//! holds, so a worker that lost its lease (killed, or cut off and still running) can
//! no longer change the job. The run's CSV files live here too ([`PgStore::append_series`]).

use super::job::{
    now_rfc3339, Admission, Claimant, ClaimedJob, JobRow, JobStatus, RawJob, Renewal,
    ATTEMPTS_EXHAUSTED, COLUMNS,
};
use sqlx::postgres::{PgPool, PgPoolOptions};
use std::time::Duration;
use uuid::Uuid;

/// The advisory lock that serialises submissions, so that the queue's capacity holds
/// under concurrent submissions from many API nodes.
const SUBMIT_LOCK: i64 = 0x6d70_7366_7369;

#[derive(Debug, Clone)]
pub struct PgStore {
    pool: PgPool,
}

impl PgStore {
    /// Connect and migrate the schema (sqlx holds an advisory lock while it migrates,
    /// so nodes may start together).
    pub async fn open(url: &str) -> Result<Self, sqlx::Error> {
        let pool = PgPoolOptions::new()
            .max_connections(8)
            .acquire_timeout(Duration::from_secs(30))
            .connect(url)
            .await?;
        sqlx::migrate!("migrations/postgres").run(&pool).await?;
        Ok(Self { pool })
    }

    pub async fn close(&self) {
        self.pool.close().await;
    }

    pub async fn submit(
        &self,
        id: Uuid,
        name: &str,
        case_json: &str,
        end_time: f64,
        capacity: usize,
    ) -> Result<Admission, sqlx::Error> {
        let mut tx = self.pool.begin().await?;
        sqlx::query("SELECT pg_advisory_xact_lock($1)")
            .bind(SUBMIT_LOCK)
            .execute(&mut *tx)
            .await?;
        let row: Option<RawJob> = sqlx::query_as(&format!(
            "INSERT INTO jobs (id, name, status, case_json, created_at, end_time)
             SELECT $1, $2, 'queued', $3, $4, $5
             WHERE (SELECT COUNT(*) FROM jobs WHERE status = 'queued') < $6
             RETURNING {COLUMNS}"
        ))
        .bind(id.to_string())
        .bind(name)
        .bind(case_json)
        .bind(now_rfc3339())
        .bind(end_time)
        .bind(capacity as i64)
        .fetch_optional(&mut *tx)
        .await?;
        tx.commit().await?;
        Ok(match row {
            Some(r) => Admission::Accepted(Box::new(r.into_row()?)),
            None => Admission::QueueFull,
        })
    }

    /// End the jobs whose lease expired and that must not run again (cancel requested,
    /// or `max_attempts` claims spent), then claim the oldest queued or expired job and
    /// discard what an earlier attempt uploaded.
    pub async fn claim_next(&self, by: &Claimant) -> Result<Option<ClaimedJob>, sqlx::Error> {
        let mut tx = self.pool.begin().await?;
        sqlx::query(&format!(
            "UPDATE jobs SET
                 status = CASE WHEN cancel_requested THEN 'cancelled' ELSE 'failed' END,
                 reason = CASE WHEN cancel_requested THEN 'cancelled by request' ELSE '{ATTEMPTS_EXHAUSTED}' END,
                 finished_at = $1, lease_until = NULL
             WHERE status = 'running' AND lease_until < now()
               AND (cancel_requested OR attempts >= $2)"
        ))
        .bind(now_rfc3339())
        .bind(i64::from(by.max_attempts))
        .execute(&mut *tx)
        .await?;
        let claimed: Option<(String, String)> = sqlx::query_as(
            "WITH next AS (
                 SELECT seq FROM jobs
                 WHERE status = 'queued' OR (status = 'running' AND lease_until < now())
                 ORDER BY seq LIMIT 1 FOR UPDATE SKIP LOCKED)
             UPDATE jobs SET status = 'running', started_at = $1, attempts = jobs.attempts + 1,
                 worker = $2, run_dir = $3 || jobs.id,
                 lease_until = now() + make_interval(secs => $4),
                 step = 0, simulated_time = 0, particles = NULL
             FROM next WHERE jobs.seq = next.seq
             RETURNING jobs.id, jobs.case_json",
        )
        .bind(now_rfc3339())
        .bind(&by.worker)
        .bind(&by.jobs_dir)
        .bind(by.lease_s)
        .fetch_optional(&mut *tx)
        .await?;
        let Some((id, case_json)) = claimed else {
            tx.commit().await?;
            return Ok(None);
        };
        sqlx::query("DELETE FROM job_series WHERE job_id = $1")
            .bind(&id)
            .execute(&mut *tx)
            .await?;
        let raw: RawJob = sqlx::query_as(&format!("SELECT {COLUMNS} FROM jobs WHERE id = $1"))
            .bind(&id)
            .fetch_one(&mut *tx)
            .await?;
        tx.commit().await?;
        Ok(Some(ClaimedJob {
            row: raw.into_row()?,
            case_json,
        }))
    }

    /// Extend the lease of the attempt held; also reports a cancellation request.
    pub async fn renew(
        &self,
        id: Uuid,
        attempt: i64,
        lease_s: f64,
    ) -> Result<Renewal, sqlx::Error> {
        let row: Option<(bool,)> = sqlx::query_as(
            "UPDATE jobs SET lease_until = now() + make_interval(secs => $3)
             WHERE id = $1 AND attempts = $2 AND status = 'running'
             RETURNING cancel_requested",
        )
        .bind(id.to_string())
        .bind(attempt)
        .bind(lease_s)
        .fetch_optional(&self.pool)
        .await?;
        Ok(match row {
            Some((cancel,)) => Renewal::Held { cancel },
            None => Renewal::Lost,
        })
    }

    /// Give a job back to the queue (a worker shutting down); the claim stays counted.
    pub async fn release(&self, id: Uuid, attempt: i64) -> Result<bool, sqlx::Error> {
        let done = sqlx::query(
            "UPDATE jobs SET status = 'queued', lease_until = NULL, step = 0, simulated_time = 0
             WHERE id = $1 AND attempts = $2 AND status = 'running'",
        )
        .bind(id.to_string())
        .bind(attempt)
        .execute(&self.pool)
        .await?;
        Ok(done.rows_affected() == 1)
    }

    pub async fn get(&self, id: Uuid) -> Result<Option<JobRow>, sqlx::Error> {
        let raw: Option<RawJob> =
            sqlx::query_as(&format!("SELECT {COLUMNS} FROM jobs WHERE id = $1"))
                .bind(id.to_string())
                .fetch_optional(&self.pool)
                .await?;
        raw.map(RawJob::into_row).transpose()
    }

    pub async fn case_text(&self, id: Uuid) -> Result<Option<String>, sqlx::Error> {
        let row: Option<(String,)> = sqlx::query_as("SELECT case_json FROM jobs WHERE id = $1")
            .bind(id.to_string())
            .fetch_optional(&self.pool)
            .await?;
        Ok(row.map(|(text,)| text))
    }

    pub async fn list(
        &self,
        status: Option<JobStatus>,
        limit: i64,
        offset: i64,
    ) -> Result<(Vec<JobRow>, i64), sqlx::Error> {
        let filter = status.map(|s| s.as_str());
        let rows: Vec<RawJob> = sqlx::query_as(&format!(
            "SELECT {COLUMNS} FROM jobs WHERE ($1::text IS NULL OR status = $1)
             ORDER BY seq DESC LIMIT $2 OFFSET $3"
        ))
        .bind(filter)
        .bind(limit)
        .bind(offset)
        .fetch_all(&self.pool)
        .await?;
        let total: i64 =
            sqlx::query_scalar("SELECT COUNT(*) FROM jobs WHERE ($1::text IS NULL OR status = $1)")
                .bind(filter)
                .fetch_one(&self.pool)
                .await?;
        let jobs = rows
            .into_iter()
            .map(RawJob::into_row)
            .collect::<Result<_, _>>()?;
        Ok((jobs, total))
    }

    pub async fn cancel_if_queued(&self, id: Uuid) -> Result<bool, sqlx::Error> {
        let done = sqlx::query(
            "UPDATE jobs SET status = 'cancelled', reason = 'cancelled before it started', finished_at = $1
             WHERE id = $2 AND status = 'queued'",
        )
        .bind(now_rfc3339())
        .bind(id.to_string())
        .execute(&self.pool)
        .await?;
        Ok(done.rows_affected() == 1)
    }

    /// Flag a running job; its worker sees the flag at its next lease renewal.
    pub async fn request_cancel(&self, id: Uuid) -> Result<(), sqlx::Error> {
        sqlx::query("UPDATE jobs SET cancel_requested = TRUE WHERE id = $1 AND status = 'running'")
            .bind(id.to_string())
            .execute(&self.pool)
            .await?;
        Ok(())
    }

    pub async fn set_started(
        &self,
        id: Uuid,
        attempt: i64,
        particles: usize,
    ) -> Result<(), sqlx::Error> {
        sqlx::query(
            "UPDATE jobs SET particles = $1 WHERE id = $2 AND attempts = $3 AND status = 'running'",
        )
        .bind(particles as i64)
        .bind(id.to_string())
        .bind(attempt)
        .execute(&self.pool)
        .await?;
        Ok(())
    }

    pub async fn set_progress(
        &self,
        id: Uuid,
        attempt: i64,
        step: u64,
        simulated_time: f64,
    ) -> Result<(), sqlx::Error> {
        sqlx::query(
            "UPDATE jobs SET step = $1, simulated_time = $2
             WHERE id = $3 AND attempts = $4 AND status = 'running'",
        )
        .bind(step as i64)
        .bind(simulated_time)
        .bind(id.to_string())
        .bind(attempt)
        .execute(&self.pool)
        .await?;
        Ok(())
    }

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
        let done = sqlx::query(
            "UPDATE jobs SET status = $1, reason = $2, summary = $3, finished_at = $4, step = $5,
                 simulated_time = $6, lease_until = NULL
             WHERE id = $7 AND attempts = $8 AND status = 'running'",
        )
        .bind(status.as_str())
        .bind(reason)
        .bind(summary)
        .bind(now_rfc3339())
        .bind(step as i64)
        .bind(simulated_time)
        .bind(id.to_string())
        .bind(attempt)
        .execute(&self.pool)
        .await?;
        Ok(done.rows_affected() == 1)
    }

    /// Append complete lines of a run file at `offset`; `false` when the attempt no
    /// longer holds the job (nothing is written then).
    pub async fn append_series(
        &self,
        id: Uuid,
        attempt: i64,
        file: &str,
        offset: u64,
        data: &[u8],
    ) -> Result<bool, sqlx::Error> {
        let done = sqlx::query(
            "INSERT INTO job_series (job_id, file, byte_offset, data)
             SELECT $1, $2, $3, $4
             WHERE EXISTS (SELECT 1 FROM jobs WHERE id = $1 AND attempts = $5 AND status = 'running')",
        )
        .bind(id.to_string())
        .bind(file)
        .bind(offset as i64)
        .bind(data)
        .bind(attempt)
        .execute(&self.pool)
        .await?;
        Ok(done.rows_affected() == 1)
    }

    /// A run file as uploaded so far (empty when nothing is).
    pub async fn read_series(&self, id: Uuid, file: &str) -> Result<Vec<u8>, sqlx::Error> {
        let chunks: Vec<(Vec<u8>,)> = sqlx::query_as(
            "SELECT data FROM job_series WHERE job_id = $1 AND file = $2 ORDER BY byte_offset",
        )
        .bind(id.to_string())
        .bind(file)
        .fetch_all(&self.pool)
        .await?;
        Ok(chunks.into_iter().flat_map(|(c,)| c).collect())
    }

    pub async fn ping(&self) -> Result<(), sqlx::Error> {
        sqlx::query("SELECT 1")
            .execute(&self.pool)
            .await
            .map(|_| ())
    }
}
