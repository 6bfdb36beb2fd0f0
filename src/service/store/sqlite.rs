//! The embedded store: SQLite via sqlx, WAL, one process. The serving process runs the
//! jobs itself, so there are no leases: a job found `running` at startup was orphaned by
//! the previous process ([`SqliteStore::recover_interrupted`]). The queries both stores
//! share are in [`super::JobStore`].

use super::job::{
    now_rfc3339, Claimant, ClaimedJob, RawClaim, CANCEL_ORPHANED_PARTS, CLAIMABLE, COLUMNS,
};
use sqlx::sqlite::{
    SqliteConnectOptions, SqliteJournalMode, SqlitePool, SqlitePoolOptions, SqliteSynchronous,
};
use std::str::FromStr;
use std::time::Duration;

#[derive(Debug, Clone)]
pub struct SqliteStore {
    pub(super) pool: SqlitePool,
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

    pub async fn recover_interrupted(&self) -> Result<u64, sqlx::Error> {
        let done = sqlx::query(
            "UPDATE jobs SET status = 'failed', reason = 'interrupted', finished_at = $1
             WHERE status = 'running'",
        )
        .bind(now_rfc3339())
        .execute(&self.pool)
        .await?;
        Ok(done.rows_affected())
    }

    /// One statement: this process's workers are the only claimants.
    pub async fn claim_next(
        &self,
        by: &Claimant,
        parts_of: Option<&str>,
    ) -> Result<Option<ClaimedJob>, sqlx::Error> {
        // running parts stop through this process's flags (`Jobs::cancel_parts`)
        sqlx::query(CANCEL_ORPHANED_PARTS)
            .bind(now_rfc3339())
            .execute(&self.pool)
            .await?;
        let claimed: Option<RawClaim> = sqlx::query_as(&format!(
            "UPDATE jobs SET status = 'running', started_at = $1, attempts = attempts + 1,
                 worker = $2, run_dir = $3 || id
             WHERE seq = (SELECT seq FROM jobs WHERE status = 'queued' AND {CLAIMABLE}
                          ORDER BY seq LIMIT 1)
             RETURNING {COLUMNS}, case_json"
        ))
        .bind(now_rfc3339())
        .bind(&by.worker)
        .bind(&by.jobs_dir)
        .bind(parts_of)
        .fetch_optional(&self.pool)
        .await?;
        claimed.map(RawClaim::into_claimed).transpose()
    }
}
