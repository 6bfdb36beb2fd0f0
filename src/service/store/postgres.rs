//! The shared store: Postgres, for API nodes and workers on many machines. Workers claim
//! under a lease ([`PgStore::claim_next`]: `FOR UPDATE SKIP LOCKED`) and renew it while
//! the job runs; a job whose lease expired is claimed again and resumes from its last
//! checkpoint ([`PgStore::save_checkpoint`]) or from the start, up to the claimant's
//! attempt limit. Every write of a worker names the attempt it
//! holds, so a worker that lost its lease (killed, or cut off and still running) can
//! no longer change the job. The run's CSV files live here too ([`PgStore::append_series`]).
//! The queries both stores share are in [`super::JobStore`]; `finish` there leaves
//! `lease_until` as it was, since a lease is read only while its job is `running`.

use super::job::{
    now_rfc3339, Claimant, ClaimedJob, RawClaim, Renewal, ATTEMPTS_EXHAUSTED,
    CANCEL_ORPHANED_PARTS, CLAIMABLE, COLUMNS, STOP_ORPHANED_PARTS,
};
use sqlx::postgres::{PgListener, PgPool, PgPoolOptions, Postgres};
use sqlx::Transaction;
use std::collections::BTreeMap;
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
    /// or `max_attempts` claims spent) and the parts of ended jobs, then claim the oldest queued or expired job and
    /// discard what an earlier attempt uploaded.
    pub async fn claim_next(
        &self,
        by: &Claimant,
        parts_of: Option<&str>,
    ) -> Result<Option<ClaimedJob>, sqlx::Error> {
        let mut tx = self.pool.begin().await?;
        sqlx::query(&format!(
            "UPDATE jobs SET
                 status = CASE WHEN cancel_requested THEN 'cancelled' ELSE 'failed' END,
                 reason = CASE WHEN cancel_requested THEN 'cancelled by request' ELSE '{ATTEMPTS_EXHAUSTED}' END,
                 finished_at = $1, lease_until = NULL
             WHERE status = 'running' AND lease_until < now()
               AND (cancel_requested OR attempts - releases >= $2)"
        ))
        .bind(now_rfc3339())
        .bind(i64::from(by.max_attempts))
        .execute(&mut *tx)
        .await?;
        sqlx::query(CANCEL_ORPHANED_PARTS)
            .bind(now_rfc3339())
            .execute(&mut *tx)
            .await?;
        sqlx::query(STOP_ORPHANED_PARTS).execute(&mut *tx).await?;
        let claimed: Option<RawClaim> = sqlx::query_as(&format!(
            "WITH next AS (
                 SELECT seq FROM jobs
                 WHERE (status = 'queued' OR (status = 'running' AND lease_until < now()))
                   AND {CLAIMABLE}
                 ORDER BY seq LIMIT 1 FOR UPDATE OF jobs SKIP LOCKED)
             UPDATE jobs SET status = 'running', started_at = $1, attempts = jobs.attempts + 1,
                 worker = $2, run_dir = $3 || jobs.id,
                 lease_until = now() + make_interval(secs => $5),
                 step = COALESCE((SELECT c.step FROM job_checkpoints c WHERE c.job_id = jobs.id), 0),
                 simulated_time = COALESCE(
                     (SELECT c.simulated_time FROM job_checkpoints c WHERE c.job_id = jobs.id), 0),
                 resumed_from = (SELECT c.simulated_time FROM job_checkpoints c WHERE c.job_id = jobs.id),
                 particles = NULL
             FROM next WHERE jobs.seq = next.seq
             RETURNING {COLUMNS}, case_json"
        ))
        .bind(now_rfc3339())
        .bind(&by.worker)
        .bind(&by.jobs_dir)
        .bind(parts_of)
        .bind(by.lease_s)
        .fetch_optional(&mut *tx)
        .await?;
        let Some(claimed) = claimed else {
            tx.commit().await?;
            return Ok(None);
        };
        let claimed = claimed.into_claimed()?;
        let id = claimed.row.id.to_string();
        let lengths: Option<(String,)> =
            sqlx::query_as("SELECT series_lengths FROM job_checkpoints WHERE job_id = $1")
                .bind(&id)
                .fetch_optional(&mut *tx)
                .await?;
        Self::cut_series(&mut tx, &id, lengths.map(|(l,)| l).as_deref()).await?;
        tx.commit().await?;
        Ok(Some(claimed))
    }

    /// Drop what an earlier attempt uploaded after its checkpoint: each file cut to the
    /// length `lengths` (the checkpoint's JSON map) gives it, all of it without one.
    async fn cut_series(
        tx: &mut Transaction<'_, Postgres>,
        id: &str,
        lengths: Option<&str>,
    ) -> Result<(), sqlx::Error> {
        let lengths: BTreeMap<String, i64> = match lengths.map(serde_json::from_str) {
            Some(Ok(map)) => map,
            Some(Err(e)) => return Err(sqlx::Error::Decode(Box::new(e))),
            None => BTreeMap::new(),
        };
        let files: Vec<String> = lengths.keys().cloned().collect();
        sqlx::query("DELETE FROM job_series WHERE job_id = $1 AND NOT (file = ANY($2))")
            .bind(id)
            .bind(&files)
            .execute(&mut **tx)
            .await?;
        for (file, length) in &lengths {
            sqlx::query(
                "DELETE FROM job_series WHERE job_id = $1 AND file = $2 AND byte_offset >= $3",
            )
            .bind(id)
            .bind(file)
            .bind(length)
            .execute(&mut **tx)
            .await?;
            // a chunk across the cut keeps its head (chunks are whole lines, and so is the
            // checkpoint's cut)
            sqlx::query(
                "UPDATE job_series SET data = substring(data FROM 1 FOR ($3 - byte_offset)::int)
                 WHERE job_id = $1 AND file = $2 AND byte_offset < $3
                   AND byte_offset + length(data) > $3",
            )
            .bind(id)
            .bind(file)
            .bind(length)
            .execute(&mut **tx)
            .await?;
        }
        Ok(())
    }

    /// Store the checkpoint of the attempt held (replacing the last one), with the byte
    /// length of each run file at its step; `false` when the attempt no longer holds
    /// the job.
    pub async fn save_checkpoint(
        &self,
        id: Uuid,
        attempt: i64,
        simulated_time: f64,
        step: u64,
        series_lengths: &BTreeMap<String, u64>,
        data: &[u8],
    ) -> Result<bool, sqlx::Error> {
        let lengths = serde_json::to_string(series_lengths).expect("a map of lengths serialises");
        let done = sqlx::query(
            "INSERT INTO job_checkpoints (job_id, simulated_time, step, series_lengths, data)
             SELECT $1, $2, $3, $4, $5
             WHERE EXISTS (SELECT 1 FROM jobs WHERE id = $1 AND attempts = $6 AND status = 'running')
             ON CONFLICT (job_id) DO UPDATE SET simulated_time = EXCLUDED.simulated_time,
                 step = EXCLUDED.step, series_lengths = EXCLUDED.series_lengths, data = EXCLUDED.data",
        )
        .bind(id.to_string())
        .bind(simulated_time)
        .bind(step as i64)
        .bind(lengths)
        .bind(data)
        .bind(attempt)
        .execute(&self.pool)
        .await;
        inserted_for_attempt(done)
    }

    /// The job's last checkpoint, if it has one.
    pub async fn checkpoint(&self, id: Uuid) -> Result<Option<Vec<u8>>, sqlx::Error> {
        let row: Option<(Vec<u8>,)> =
            sqlx::query_as("SELECT data FROM job_checkpoints WHERE job_id = $1")
                .bind(id.to_string())
                .fetch_optional(&self.pool)
                .await?;
        Ok(row.map(|(d,)| d))
    }

    /// A checkpoint the attempt held cannot use (damaged, or of another version): the
    /// attempt starts from t = 0, without it and without anything uploaded before.
    pub async fn discard_checkpoint(&self, id: Uuid, attempt: i64) -> Result<bool, sqlx::Error> {
        let mut tx = self.pool.begin().await?;
        let held = sqlx::query(
            "UPDATE jobs SET resumed_from = NULL, step = 0, simulated_time = 0
             WHERE id = $1 AND attempts = $2 AND status = 'running'",
        )
        .bind(id.to_string())
        .bind(attempt)
        .execute(&mut *tx)
        .await?
        .rows_affected()
            == 1;
        if held {
            sqlx::query("DELETE FROM job_checkpoints WHERE job_id = $1")
                .bind(id.to_string())
                .execute(&mut *tx)
                .await?;
            Self::cut_series(&mut tx, &id.to_string(), None).await?;
        }
        tx.commit().await?;
        Ok(held)
    }

    /// Store (or replace) a file of the attempt's run directory, gzip-compressed by the
    /// caller; `false` when the attempt no longer holds the job.
    pub async fn put_file(
        &self,
        id: Uuid,
        attempt: i64,
        name: &str,
        data: &[u8],
    ) -> Result<bool, sqlx::Error> {
        let done = sqlx::query(
            "INSERT INTO job_files (job_id, name, data)
             SELECT $1, $2, $3
             WHERE EXISTS (SELECT 1 FROM jobs WHERE id = $1 AND attempts = $4 AND status = 'running')
             ON CONFLICT (job_id, name) DO UPDATE SET data = EXCLUDED.data",
        )
        .bind(id.to_string())
        .bind(name)
        .bind(data)
        .bind(attempt)
        .execute(&self.pool)
        .await;
        inserted_for_attempt(done)
    }

    /// The names of a job's stored files.
    pub async fn file_names(&self, id: Uuid) -> Result<Vec<String>, sqlx::Error> {
        sqlx::query_scalar("SELECT name FROM job_files WHERE job_id = $1 ORDER BY name")
            .bind(id.to_string())
            .fetch_all(&self.pool)
            .await
    }

    /// One stored file (gzip-compressed), if there is one.
    pub async fn file(&self, id: Uuid, name: &str) -> Result<Option<Vec<u8>>, sqlx::Error> {
        let row: Option<(Vec<u8>,)> =
            sqlx::query_as("SELECT data FROM job_files WHERE job_id = $1 AND name = $2")
                .bind(id.to_string())
                .bind(name)
                .fetch_optional(&self.pool)
                .await?;
        Ok(row.map(|(d,)| d))
    }

    /// Remove a job's checkpoint (its run ended: nothing will resume it).
    pub async fn drop_checkpoint(&self, id: Uuid) -> Result<(), sqlx::Error> {
        sqlx::query("DELETE FROM job_checkpoints WHERE job_id = $1")
            .bind(id.to_string())
            .execute(&self.pool)
            .await?;
        Ok(())
    }

    /// How many bytes of a run file the store holds (0 when none).
    pub async fn series_length(&self, id: Uuid, file: &str) -> Result<u64, sqlx::Error> {
        let (length,): (Option<i64>,) = sqlx::query_as(
            "SELECT max(byte_offset + length(data))::bigint FROM job_series WHERE job_id = $1 AND file = $2",
        )
        .bind(id.to_string())
        .bind(file)
        .fetch_one(&self.pool)
        .await?;
        Ok(length.unwrap_or(0).max(0) as u64)
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

    /// Give a job back to the queue (a worker shutting down, after its checkpoint), and
    /// announce it; the claim stays counted as a fence, not against `max_attempts`.
    pub async fn release(&self, id: Uuid, attempt: i64) -> Result<bool, sqlx::Error> {
        let mut tx = self.pool.begin().await?;
        let done = sqlx::query(
            "UPDATE jobs SET status = 'queued', lease_until = NULL, releases = releases + 1
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
        inserted_for_attempt(done)
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

/// The outcome of an insert fenced by the attempt (`WHERE EXISTS` the running attempt):
/// `false` when the attempt no longer holds the job, or the job was deleted between
/// the check and the insert (the foreign key).
fn inserted_for_attempt(
    done: Result<sqlx::postgres::PgQueryResult, sqlx::Error>,
) -> Result<bool, sqlx::Error> {
    match done {
        Ok(done) => Ok(done.rows_affected() == 1),
        Err(sqlx::Error::Database(e)) if e.is_foreign_key_violation() => Ok(false),
        Err(e) => Err(e),
    }
}
