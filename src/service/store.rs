//! The job table (SQLite via sqlx, WAL). It is also the queue: see the module docs of
//! [`crate::service`]. Timestamps are RFC 3339 strings in UTC.

use serde::{Deserialize, Serialize};
use sqlx::sqlite::{
    SqliteConnectOptions, SqliteJournalMode, SqlitePool, SqlitePoolOptions, SqliteSynchronous,
};
use sqlx::Row;
use std::str::FromStr;
use std::time::Duration;
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
}

/// A claimed job: its row and the case to run.
#[derive(Debug, Clone)]
pub struct ClaimedJob {
    pub row: JobRow,
    pub case_json: String,
}

pub fn now_rfc3339() -> String {
    OffsetDateTime::now_utc()
        .format(&Rfc3339)
        .unwrap_or_default()
}

const COLUMNS: &str =
    "id, name, status, created_at, started_at, finished_at, step, simulated_time, end_time, particles, reason, summary";

fn row_to_job(row: &sqlx::sqlite::SqliteRow) -> Result<JobRow, sqlx::Error> {
    let id: String = row.try_get("id")?;
    let status: String = row.try_get("status")?;
    Ok(JobRow {
        id: Uuid::parse_str(&id).map_err(|e| sqlx::Error::Decode(Box::new(e)))?,
        name: row.try_get("name")?,
        status: JobStatus::parse(&status)
            .ok_or_else(|| sqlx::Error::Decode(format!("unknown job status {status:?}").into()))?,
        created_at: row.try_get("created_at")?,
        started_at: row.try_get("started_at")?,
        finished_at: row.try_get("finished_at")?,
        step: row.try_get("step")?,
        simulated_time: row.try_get("simulated_time")?,
        end_time: row.try_get("end_time")?,
        particles: row.try_get("particles")?,
        reason: row.try_get("reason")?,
        summary: row.try_get("summary")?,
    })
}

#[derive(Debug, Clone)]
pub struct JobStore {
    pool: SqlitePool,
}

/// Outcome of a submission.
pub enum Admission {
    Accepted(JobRow),
    QueueFull,
}

impl JobStore {
    /// Open (creating if needed) the database and its schema.
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
        sqlx::raw_sql(
            "CREATE TABLE IF NOT EXISTS jobs (
                seq INTEGER PRIMARY KEY AUTOINCREMENT,
                id TEXT NOT NULL UNIQUE,
                name TEXT NOT NULL,
                status TEXT NOT NULL,
                case_json TEXT NOT NULL,
                created_at TEXT NOT NULL,
                started_at TEXT,
                finished_at TEXT,
                step INTEGER NOT NULL DEFAULT 0,
                simulated_time REAL NOT NULL DEFAULT 0,
                end_time REAL NOT NULL,
                particles INTEGER,
                reason TEXT,
                summary TEXT
            );
            CREATE INDEX IF NOT EXISTS jobs_by_status ON jobs (status, seq);",
        )
        .execute(&pool)
        .await?;
        Ok(Self { pool })
    }

    pub async fn close(&self) {
        self.pool.close().await;
    }

    /// Jobs left `running` by a previous process become `failed` / `interrupted`;
    /// `queued` ones stay queued and run again. Returns the number interrupted.
    pub async fn recover_interrupted(&self) -> Result<u64, sqlx::Error> {
        let done = sqlx::query(
            "UPDATE jobs SET status = 'failed', reason = 'interrupted', finished_at = ? WHERE status = 'running'",
        )
        .bind(now_rfc3339())
        .execute(&self.pool)
        .await?;
        Ok(done.rows_affected())
    }

    /// Insert a queued job unless `capacity` jobs are already queued (one statement, so
    /// concurrent submissions cannot overfill the queue).
    pub async fn submit(
        &self,
        id: Uuid,
        name: &str,
        case_json: &str,
        end_time: f64,
        capacity: usize,
    ) -> Result<Admission, sqlx::Error> {
        let row = sqlx::query(&format!(
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
            Some(r) => Admission::Accepted(row_to_job(&r)?),
            None => Admission::QueueFull,
        })
    }

    /// Claim the oldest queued job (marks it `running`).
    pub async fn claim_next(&self) -> Result<Option<ClaimedJob>, sqlx::Error> {
        let row = sqlx::query(&format!(
            "UPDATE jobs SET status = 'running', started_at = ?
             WHERE seq = (SELECT seq FROM jobs WHERE status = 'queued' ORDER BY seq LIMIT 1)
             RETURNING {COLUMNS}, case_json"
        ))
        .bind(now_rfc3339())
        .fetch_optional(&self.pool)
        .await?;
        match row {
            None => Ok(None),
            Some(r) => Ok(Some(ClaimedJob {
                row: row_to_job(&r)?,
                case_json: r.try_get("case_json")?,
            })),
        }
    }

    pub async fn get(&self, id: Uuid) -> Result<Option<JobRow>, sqlx::Error> {
        let row = sqlx::query(&format!("SELECT {COLUMNS} FROM jobs WHERE id = ?"))
            .bind(id.to_string())
            .fetch_optional(&self.pool)
            .await?;
        row.as_ref().map(row_to_job).transpose()
    }

    /// Newest first.
    pub async fn list(
        &self,
        status: Option<JobStatus>,
        limit: i64,
        offset: i64,
    ) -> Result<(Vec<JobRow>, i64), sqlx::Error> {
        let filter = status.map(|s| s.as_str());
        let rows = sqlx::query(&format!(
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
        let jobs = rows.iter().map(row_to_job).collect::<Result<Vec<_>, _>>()?;
        Ok((jobs, total))
    }

    /// Cancel a job that is still queued; `true` if it was.
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

    pub async fn set_started(&self, id: Uuid, particles: usize) -> Result<(), sqlx::Error> {
        sqlx::query("UPDATE jobs SET particles = ? WHERE id = ?")
            .bind(particles as i64)
            .bind(id.to_string())
            .execute(&self.pool)
            .await?;
        Ok(())
    }

    pub async fn set_progress(
        &self,
        id: Uuid,
        step: u64,
        simulated_time: f64,
    ) -> Result<(), sqlx::Error> {
        sqlx::query(
            "UPDATE jobs SET step = ?, simulated_time = ? WHERE id = ? AND status = 'running'",
        )
        .bind(step as i64)
        .bind(simulated_time)
        .bind(id.to_string())
        .execute(&self.pool)
        .await?;
        Ok(())
    }

    /// Record the end of a run.
    pub async fn finish(
        &self,
        id: Uuid,
        status: JobStatus,
        reason: Option<&str>,
        summary: Option<&str>,
        step: u64,
        simulated_time: f64,
    ) -> Result<(), sqlx::Error> {
        sqlx::query(
            "UPDATE jobs SET status = ?, reason = ?, summary = ?, finished_at = ?, step = ?, simulated_time = ?
             WHERE id = ?",
        )
        .bind(status.as_str())
        .bind(reason)
        .bind(summary)
        .bind(now_rfc3339())
        .bind(step as i64)
        .bind(simulated_time)
        .bind(id.to_string())
        .execute(&self.pool)
        .await?;
        Ok(())
    }

    /// Cheap liveness check of the database.
    pub async fn ping(&self) -> Result<(), sqlx::Error> {
        sqlx::query("SELECT 1")
            .execute(&self.pool)
            .await
            .map(|_| ())
    }
}
