//! The embedded store: SQLite via sqlx, WAL, one process. The serving process runs the
//! jobs itself, so there are no leases: a job found `running` at startup was orphaned by
//! the previous process ([`SqliteStore::recover_interrupted`]).

use super::job::{
    now_rfc3339, Admission, Claimant, ClaimedJob, JobRow, JobStatus, RawJob, COLUMNS,
};
use sqlx::sqlite::{
    SqliteConnectOptions, SqliteJournalMode, SqlitePool, SqlitePoolOptions, SqliteSynchronous,
};
use std::str::FromStr;
use std::time::Duration;
use uuid::Uuid;

#[derive(Debug, Clone)]
pub struct SqliteStore {
    pool: SqlitePool,
}

impl SqliteStore {
    /// Open (creating if needed) the database and migrate its schema.
    pub async fn open(url: &str) -> Result<Self, sqlx::Error> {
        let options = SqliteConnectOptions::from_str(url)?
            .create_if_missing(true)
            .journal_mode(SqliteJournalMode::Wal)
            .synchronous(SqliteSynchronous::Normal)
            .busy_timeout(Duration::from_secs(30));
        let pool = SqlitePoolOptions::new()
            .max_connections(4)
            .acquire_timeout(Duration::from_secs(60))
            .connect_with(options)
            .await?;
        sqlx::migrate!("migrations/sqlite").run(&pool).await?;
        Ok(Self { pool })
    }

    pub async fn close(&self) {
        self.pool.close().await;
    }

    pub async fn recover_interrupted(&self) -> Result<u64, sqlx::Error> {
        let done = sqlx::query(
            "UPDATE jobs SET status = 'failed', reason = 'interrupted', finished_at = ? WHERE status = 'running'",
        )
        .bind(now_rfc3339())
        .execute(&self.pool)
        .await?;
        Ok(done.rows_affected())
    }

    pub async fn submit(
        &self,
        id: Uuid,
        name: &str,
        case_json: &str,
        end_time: f64,
        capacity: usize,
    ) -> Result<Admission, sqlx::Error> {
        // one statement, so concurrent submissions cannot overfill the queue
        let row: Option<RawJob> = sqlx::query_as(&format!(
            "INSERT INTO jobs (id, name, status, case_json, created_at, end_time)
             SELECT ?, ?, 'queued', ?, ?, ?
             WHERE (SELECT COUNT(*) FROM jobs WHERE status = 'queued') < ?
             RETURNING {COLUMNS}"
        ))
        .bind(id.to_string())
        .bind(name)
        .bind(case_json)
        .bind(now_rfc3339())
        .bind(end_time)
        .bind(capacity as i64)
        .fetch_optional(&self.pool)
        .await?;
        Ok(match row {
            Some(r) => Admission::Accepted(Box::new(r.into_row()?)),
            None => Admission::QueueFull,
        })
    }

    pub async fn claim_next(&self, by: &Claimant) -> Result<Option<ClaimedJob>, sqlx::Error> {
        let row: Option<(String,)> = sqlx::query_as(
            "UPDATE jobs SET status = 'running', started_at = ?, attempts = attempts + 1,
                 worker = ?, run_dir = ? || id
             WHERE seq = (SELECT seq FROM jobs WHERE status = 'queued' ORDER BY seq LIMIT 1)
             RETURNING id",
        )
        .bind(now_rfc3339())
        .bind(&by.worker)
        .bind(&by.jobs_dir)
        .fetch_optional(&self.pool)
        .await?;
        let Some((id,)) = row else { return Ok(None) };
        let case_json = self
            .case_text_of(&id)
            .await?
            .ok_or(sqlx::Error::RowNotFound)?;
        let row = self.get_text(&id).await?.ok_or(sqlx::Error::RowNotFound)?;
        Ok(Some(ClaimedJob { row, case_json }))
    }

    async fn get_text(&self, id: &str) -> Result<Option<JobRow>, sqlx::Error> {
        let raw: Option<RawJob> =
            sqlx::query_as(&format!("SELECT {COLUMNS} FROM jobs WHERE id = ?"))
                .bind(id)
                .fetch_optional(&self.pool)
                .await?;
        raw.map(RawJob::into_row).transpose()
    }

    pub async fn get(&self, id: Uuid) -> Result<Option<JobRow>, sqlx::Error> {
        self.get_text(&id.to_string()).await
    }

    pub async fn case_text(&self, id: Uuid) -> Result<Option<String>, sqlx::Error> {
        self.case_text_of(&id.to_string()).await
    }

    async fn case_text_of(&self, id: &str) -> Result<Option<String>, sqlx::Error> {
        let row: Option<(String,)> = sqlx::query_as("SELECT case_json FROM jobs WHERE id = ?")
            .bind(id)
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
            "SELECT {COLUMNS} FROM jobs WHERE (?1 IS NULL OR status = ?1) ORDER BY seq DESC LIMIT ?2 OFFSET ?3"
        ))
        .bind(filter)
        .bind(limit)
        .bind(offset)
        .fetch_all(&self.pool)
        .await?;
        let total: i64 =
            sqlx::query_scalar("SELECT COUNT(*) FROM jobs WHERE (?1 IS NULL OR status = ?1)")
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
            "UPDATE jobs SET status = 'cancelled', reason = 'cancelled before it started', finished_at = ?
             WHERE id = ? AND status = 'queued'",
        )
        .bind(now_rfc3339())
        .bind(id.to_string())
        .execute(&self.pool)
        .await?;
        Ok(done.rows_affected() == 1)
    }

    pub async fn set_started(
        &self,
        id: Uuid,
        attempt: i64,
        particles: usize,
    ) -> Result<(), sqlx::Error> {
        sqlx::query("UPDATE jobs SET particles = ? WHERE id = ? AND attempts = ?")
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
            "UPDATE jobs SET step = ?, simulated_time = ? WHERE id = ? AND attempts = ? AND status = 'running'",
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
            "UPDATE jobs SET status = ?, reason = ?, summary = ?, finished_at = ?, step = ?, simulated_time = ?
             WHERE id = ? AND attempts = ?",
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

    pub async fn ping(&self) -> Result<(), sqlx::Error> {
        sqlx::query("SELECT 1")
            .execute(&self.pool)
            .await
            .map(|_| ())
    }
}
