//! Retention (`mpsfsi serve --keep-days D`): a job that ended (succeeded, failed or
//! cancelled) more than D days ago is removed exactly as `DELETE /v1/jobs/{id}` removes
//! it ([`Jobs::delete`]): its record, what the store holds of its run (Postgres: the
//! uploaded CSV rows) and its run directory. Queued and running jobs are never removed.
//!
//! It runs in `serve`, not in `mpsfsi worker`: the API nodes are where a job's record
//! and its files are deleted, and with SQLite `serve` is the only process. With many API
//! nodes each one sweeps; a job is removed by whichever deletes its row first (the
//! others find nothing to delete). The sweep runs at start-up and then every
//! [`SWEEP_EVERY`].

use super::workers::Jobs;
use std::sync::Arc;
use std::time::Duration;
use time::format_description::well_known::Rfc3339;
use time::OffsetDateTime;

/// Time between sweeps: an hour, so a job outlives its `--keep-days` by at most 1/24 of a
/// day, for one query on the job table an hour.
pub const SWEEP_EVERY: Duration = Duration::from_secs(3600);

/// Remove the jobs that ended more than `keep` before `now`; how many were removed.
pub async fn remove_expired(
    jobs: &Jobs,
    keep: Duration,
    now: OffsetDateTime,
) -> Result<usize, sqlx::Error> {
    let cutoff = now
        .checked_sub(time::Duration::try_from(keep).unwrap_or(time::Duration::MAX))
        .and_then(|t| t.format(&Rfc3339).ok());
    // a cutoff before any representable date: nothing is that old
    let Some(cutoff) = cutoff else {
        return Ok(0);
    };
    let mut removed = 0;
    for id in jobs.store.finished_before(&cutoff).await? {
        if jobs.delete(id).await? {
            tracing::info!(%id, "retention: job removed");
            removed += 1;
        }
    }
    Ok(removed)
}

/// Sweep at once, then every [`SWEEP_EVERY`], until the task is aborted (at shutdown).
pub fn spawn(jobs: Arc<Jobs>, keep: Duration) -> tokio::task::JoinHandle<()> {
    tokio::spawn(async move {
        let mut ticks = tokio::time::interval(SWEEP_EVERY);
        ticks.set_missed_tick_behavior(tokio::time::MissedTickBehavior::Delay);
        loop {
            ticks.tick().await;
            match remove_expired(&jobs, keep, OffsetDateTime::now_utc()).await {
                Ok(0) => {}
                Ok(removed) => tracing::info!(
                    removed,
                    keep_days = keep.as_secs_f64() / 86_400.0,
                    "retention: removed the jobs that ended before the cutoff"
                ),
                Err(e) => tracing::warn!(error = %e, "retention: cannot sweep the job table"),
            }
        }
    })
}
