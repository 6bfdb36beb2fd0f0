//! A ladder job's parts (`POST /v1/jobs?uncertainty=true`). The job's own row runs the
//! user's level; its coarser levels and ensemble members are rows of their own
//! ([`JobRow::parent`]), queued with it and claimed by whichever workers are free, each
//! run (checkpointed, resumed, retried) like any job. When the user's level has run, the
//! job's worker runs the parts nobody has claimed yet, waits for the others, and
//! combines them into the half-widths ([`uncertainty::conclude`]): the same files as
//! `mpsfsi run --uncertainty`, which runs the parts one after another.

use super::{run_claimed, JobObserver, Jobs};
use crate::case::{parse_case_str, CaseError, ValidCase};
use crate::run::uncertainty;
use crate::run::{Observer, RunError, RunStatus, Summary};
use crate::service::series;
use crate::service::store::{JobRow, JobStatus};
use std::future::Future;
use std::path::{Path, PathBuf};
use std::pin::Pin;
use std::sync::Arc;
use std::time::Duration;

/// How often the job's worker looks at its parts while others run them.
const PART_POLL: Duration = Duration::from_millis(500);

/// The files of a part the half-widths are computed from.
const PART_FILES: [&str; 3] = [series::LOADS.file, series::PROBES.file, series::BODIES.file];

/// Part `k` of the ladder of `case`: its case, its run directory and its lattice
/// placement. Without a shared store it runs under its job's directory `dir`, where
/// the CLI puts it (`levels/<name>`); with one, in `dir`, its own.
pub(super) fn part_case(
    case: &ValidCase,
    k: i64,
    dir: PathBuf,
    shared: bool,
) -> Result<(ValidCase, PathBuf, Option<crate::math::Real>), CaseError> {
    let (parts, mut cases) = uncertainty::ladder(case)?;
    let k = usize::try_from(k)
        .ok()
        .filter(|k| (1..parts.len()).contains(k))
        .ok_or_else(|| {
            CaseError::new(
                "uncertainty",
                format!(
                    "part {k} is not a coarser part of a {}-part ladder",
                    parts.len()
                ),
            )
        })?;
    let dir = match shared {
        true => dir,
        false => uncertainty::part_dir(&dir, &parts[k]),
    };
    Ok((cases.swap_remove(k), dir, parts[k].phase))
}

/// The end of ladder job `row`, whose user's level ran in `dir` with summary `user`:
/// once every part has ended, the ladder's summary (written to `dir`, with the
/// uncertainty files beside it), or the first part that did not succeed as the job's
/// status and reason. A stop the observer asks for (cancel, shutdown, lost lease) ends
/// the wait with the observer's status.
///
/// Boxed with its type spelled out: it runs parts, which are jobs, whose run may call it.
pub(super) fn finish_ladder<'a>(
    jobs: &'a Arc<Jobs>,
    row: &'a JobRow,
    case_json: &'a str,
    dir: &'a Path,
    user: Summary,
    observer: &'a JobObserver,
) -> Pin<Box<dyn Future<Output = Result<Summary, sqlx::Error>> + Send + 'a>> {
    Box::pin(wait_and_conclude(jobs, row, case_json, dir, user, observer))
}

async fn wait_and_conclude(
    jobs: &Arc<Jobs>,
    row: &JobRow,
    case_json: &str,
    dir: &Path,
    mut user: Summary,
    observer: &JobObserver,
) -> Result<Summary, sqlx::Error> {
    // the user's level counts in the progress at once, not at the next throttled write
    jobs.store
        .set_progress(row.id, row.attempts, user.steps, user.simulated_time)
        .await?;
    let rows = loop {
        if observer.is_cancelled() {
            let (status, reason) = observer.stop_reason(user.steps, user.simulated_time);
            user.status = status;
            user.reason = Some(reason);
            return Ok(user);
        }
        if let Some(part) = jobs.store.claim_next(&jobs.claimant, Some(row.id)).await? {
            tracing::info!(part = part.row.part, "running a part of this ladder");
            run_claimed(jobs, part).await?;
            continue;
        }
        let rows = jobs.store.parts(row.id).await?;
        if rows.iter().all(|r| r.status.is_finished()) {
            break rows;
        }
        tokio::time::sleep(PART_POLL).await;
    };
    match conclude(jobs, case_json, dir, user.clone(), &rows).await {
        Ok(summary) => Ok(summary),
        Err(e) => {
            tracing::error!(error = %e, "cannot combine the ladder's parts");
            user.status = RunStatus::Failed;
            user.reason = Some(format!("cannot combine the ladder's parts: {e}"));
            Ok(user)
        }
    }
}

/// Combine the user's level (`dir`) and the ended parts `rows` (their files fetched from
/// the shared store into `dir/levels/<name>`, or there already on one node).
async fn conclude(
    jobs: &Arc<Jobs>,
    case_json: &str,
    dir: &Path,
    user: Summary,
    rows: &[JobRow],
) -> Result<Summary, RunError> {
    let invalid = |e: String| RunError::Io(std::io::Error::other(e));
    let case = parse_case_str(case_json)
        .and_then(|c| ValidCase::new(c, &jobs.config.limits()))
        .map_err(|e| invalid(e.to_string()))?;
    let (parts, _) = uncertainty::ladder(&case).map_err(|e| invalid(e.to_string()))?;
    if rows.len() + 1 != parts.len() {
        return Err(invalid(format!(
            "{} parts stored for a {}-part ladder",
            rows.len(),
            parts.len()
        )));
    }
    if let Some(bad) = rows.iter().find(|r| r.status != JobStatus::Succeeded) {
        let status = match bad.status {
            JobStatus::Cancelled => RunStatus::Cancelled,
            _ => RunStatus::Failed,
        };
        let k = bad.part as usize;
        let dir = dir.to_path_buf();
        let reason = bad.reason.clone();
        return tokio::task::spawn_blocking(move || {
            uncertainty::part_stopped(&dir, &parts, user, k, status, reason.as_deref())
        })
        .await
        .map_err(|e| invalid(e.to_string()))?
        .map_err(RunError::Io);
    }
    let mut dirs = vec![dir.to_path_buf()];
    let mut summaries = vec![user];
    for (row, part) in rows.iter().zip(&parts[1..]) {
        let part_dir = uncertainty::part_dir(dir, part);
        fetch_part_files(jobs, row, &part_dir).await?;
        let summary = row
            .summary
            .as_deref()
            .and_then(|s| serde_json::from_str(s).ok())
            .ok_or_else(|| invalid(format!("part {} ended without a summary", row.part)))?;
        dirs.push(part_dir);
        summaries.push(summary);
    }
    let dir = dir.to_path_buf();
    tokio::task::spawn_blocking(move || {
        uncertainty::conclude(&case, &dir, &parts, &dirs, summaries)
    })
    .await
    .map_err(|e| invalid(e.to_string()))?
}

/// With a shared store, a part's files as the store holds them, written to `part_dir`
/// (its worker removed its own copy); on one node they are there already.
async fn fetch_part_files(jobs: &Jobs, row: &JobRow, part_dir: &Path) -> Result<(), RunError> {
    if !jobs.store.is_shared() {
        return Ok(());
    }
    tokio::fs::create_dir_all(part_dir).await?;
    for file in PART_FILES {
        let bytes = jobs
            .store
            .read_series(row.id, file)
            .await
            .map_err(std::io::Error::other)?
            .unwrap_or_default();
        if !bytes.is_empty() {
            tokio::fs::write(part_dir.join(file), bytes).await?;
        }
    }
    Ok(())
}
