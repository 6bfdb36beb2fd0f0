//! The shared store: Postgres, for API nodes and workers on many machines. Workers claim
//! under a lease ([`PgStore::claim_next`]: `FOR UPDATE SKIP LOCKED`) and renew it while
//! the job runs; a job whose lease expired is claimed again and re-run from the start,
//! up to the claimant's attempt limit. Every write of a worker names the attempt it
//! holds, so a worker that lost its lease (killed, or cut off and still running) can
//! no longer change the job. The run's CSV files live here too ([`PgStore::append_series`]).
//! The queries both stores share are in [`super::JobStore`]; `finish` there leaves
//! `lease_until` as it was, since a lease is read only while its job is `running`.

use super::job::{
    now_rfc3339, Claimant, ClaimedJob, RawClaim, Renewal, ATTEMPTS_EXHAUSTED, COLUMNS,
};
use sqlx::postgres::{PgListener, PgPool, PgPoolOptions, Postgres};
use sqlx::Transaction;
use std::time::Duration;
use uuid::Uuid;

/// The channel a submission (and a job given back to the queue) is announced on, so
/// that idle workers claim it at once rather than at their next poll.
pub const QUEUE_CHANNEL: &str = "mpsfsi_queue";

/// The advisory lock that serialises submissions, so that the queue's capacity holds
/// under concurrent submissions from many API nodes.
const SUBMIT_LOCK: i64 = 0x6d70_7366_7369;

#[derive(Debug, Clone)]
pub struct PgStore {
    pub(super) pool: PgPool,
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

    /// A transaction holding the submission lock: [`super::JobStore::submit`] counts the
    /// queue and inserts in it.
    pub(super) async fn lock_submissions(&self) -> Result<Transaction<'_, Postgres>, sqlx::Error> {
        let mut tx = self.pool.begin().await?;
        sqlx::query("SELECT pg_advisory_xact_lock($1)")
            .bind(SUBMIT_LOCK)
            .execute(&mut *tx)
            .await?;
        Ok(tx)
    }

    /// Announce on [`QUEUE_CHANNEL`] that a job is waiting; in a transaction, the
    /// announcement goes out when it commits.
    pub(super) async fn announce_queued<'c, E>(executor: E) -> Result<(), sqlx::Error>
    where
        E: sqlx::Executor<'c, Database = Postgres>,
    {
        sqlx::query("SELECT pg_notify($1, '')")
            .bind(QUEUE_CHANNEL)
            .execute(executor)
            .await?;
        Ok(())
    }

    /// A connection listening on [`QUEUE_CHANNEL`] (it holds one of the pool's
    /// connections; a lost one is reconnected by `try_recv`, which then returns
    /// `Ok(None)`: announcements made meanwhile are lost).
    pub async fn queue_listener(&self) -> Result<PgListener, sqlx::Error> {
        let mut listener = PgListener::connect_with(&self.pool).await?;
        listener.listen(QUEUE_CHANNEL).await?;
        Ok(listener)
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
        let claimed: Option<RawClaim> = sqlx::query_as(&format!(
            "WITH next AS (
                 SELECT seq FROM jobs
                 WHERE status = 'queued' OR (status = 'running' AND lease_until < now())
                 ORDER BY seq LIMIT 1 FOR UPDATE SKIP LOCKED)
             UPDATE jobs SET status = 'running', started_at = $1, attempts = jobs.attempts + 1,
                 worker = $2, run_dir = $3 || jobs.id,
                 lease_until = now() + make_interval(secs => $4),
                 step = 0, simulated_time = 0, particles = NULL
             FROM next WHERE jobs.seq = next.seq
             RETURNING {COLUMNS}, case_json"
        ))
        .bind(now_rfc3339())
        .bind(&by.worker)
        .bind(&by.jobs_dir)
        .bind(by.lease_s)
        .fetch_optional(&mut *tx)
        .await?;
        let Some(claimed) = claimed else {
            tx.commit().await?;
            return Ok(None);
        };
        let claimed = claimed.into_claimed()?;
        sqlx::query("DELETE FROM job_series WHERE job_id = $1")
            .bind(claimed.row.id.to_string())
            .execute(&mut *tx)
            .await?;
        tx.commit().await?;
        Ok(Some(claimed))
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

    /// Give a job back to the queue (a worker shutting down), and announce it; the
    /// claim stays counted.
    pub async fn release(&self, id: Uuid, attempt: i64) -> Result<bool, sqlx::Error> {
        let mut tx = self.pool.begin().await?;
        let done = sqlx::query(
            "UPDATE jobs SET status = 'queued', lease_until = NULL, step = 0, simulated_time = 0
             WHERE id = $1 AND attempts = $2 AND status = 'running'",
        )
        .bind(id.to_string())
        .bind(attempt)
        .execute(&mut *tx)
        .await?;
        let released = done.rows_affected() == 1;
        if released {
            Self::announce_queued(&mut *tx).await?;
        }
        tx.commit().await?;
        Ok(released)
    }

    /// Flag a running job; its worker sees the flag at its next lease renewal.
    pub async fn request_cancel(&self, id: Uuid) -> Result<(), sqlx::Error> {
        sqlx::query("UPDATE jobs SET cancel_requested = TRUE WHERE id = $1 AND status = 'running'")
            .bind(id.to_string())
            .execute(&self.pool)
            .await?;
        Ok(())
    }

    /// Append complete lines of a run file at `offset`; `false` when the attempt no
    /// longer holds the job or the job was deleted (nothing is written then).
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
        .await;
        match done {
            Ok(done) => Ok(done.rows_affected() == 1),
            // the job was deleted between the check and the insert
            Err(sqlx::Error::Database(e)) if e.is_foreign_key_violation() => Ok(false),
            Err(e) => Err(e),
        }
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
}
