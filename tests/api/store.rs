//! One behavioural suite for both job stores. Each case is an `async fn` written once;
//! `store_cases!` runs it on a fresh SQLite file (`store::sqlite::<case>`) and on a fresh
//! database of a throwaway Postgres (`store::postgres::<case>`, skipped without one
//! unless `MPSFSI_REQUIRE_POSTGRES` is set). What only one store has (SQLite's recovery
//! at startup, Postgres's leases and uploads) is tested at the end and in `postgres.rs`.

use crate::helpers::fresh_data_dir;
use crate::pg_server::PgServer;
use mpsfsi::service::store::{
    Admission, Claimant, ClaimedJob, JobRow, JobStatus, JobStore, Renewal,
};
use uuid::Uuid;

/// Each case once per store.
macro_rules! store_cases {
    ($($case:ident),* $(,)?) => {
        mod sqlite {
            $(
                #[tokio::test]
                async fn $case() {
                    let store = super::sqlite_store(stringify!($case)).await;
                    super::$case(&store).await;
                    store.close().await;
                }
            )*
        }
        mod postgres {
            $(
                #[tokio::test]
                async fn $case() {
                    let Some(pg) = crate::pg_server::PgServer::start_or_skip(stringify!($case)).await
                    else {
                        return;
                    };
                    let store = super::postgres_store(&pg).await;
                    super::$case(&store).await;
                    store.close().await;
                }
            )*
        }
    };
}

store_cases!(
    submit_admits_jobs_up_to_the_queue_capacity,
    claim_takes_the_oldest_queued_job,
    progress_is_written_only_by_the_attempt_holding_the_job,
    cancel_if_queued_cancels_only_a_queued_job,
    finish_records_the_outcome_of_the_running_attempt,
    a_late_finish_does_not_overwrite_a_finished_job,
    a_late_finish_does_not_overwrite_a_job_cancelled_in_the_queue,
    list_filters_by_status_and_pages_newest_first,
    list_counts_the_matching_jobs_beyond_the_page,
    case_text_is_the_submitted_text,
    delete_removes_the_job_and_its_rows_and_no_other_job_s,
    finished_before_lists_only_jobs_that_ended_before_the_cutoff,
    a_ladder_s_parts_run_after_their_job_and_end_with_it,
);

async fn sqlite_store(tag: &str) -> JobStore {
    let dir = fresh_data_dir(&format!("store-{tag}"));
    let url = format!("sqlite://{}?mode=rwc", dir.join("jobs.db").display());
    JobStore::open(&url).await.expect("the SQLite store opens")
}

async fn postgres_store(pg: &PgServer) -> JobStore {
    JobStore::open(&pg.fresh_database().await)
        .await
        .expect("the Postgres store opens")
}

fn claimant() -> Claimant {
    Claimant {
        worker: "test-host:1".into(),
        jobs_dir: "/data/jobs/".into(),
        lease_s: 600.0,
        max_attempts: 3,
    }
}

/// The case text of job `name` (any text: the store does not read it).
fn case_of(name: &str) -> String {
    format!("{{\"name\": \"{name}\"}}")
}

async fn try_submit(store: &JobStore, name: &str, capacity: usize) -> Option<JobRow> {
    match store
        .submit(Uuid::new_v4(), name, &case_of(name), 0.5, None, capacity)
        .await
        .expect("submit")
    {
        Admission::Accepted(row) => Some(*row),
        Admission::QueueFull => None,
    }
}

async fn submit(store: &JobStore, name: &str) -> Uuid {
    try_submit(store, name, 100)
        .await
        .expect("admitted under capacity 100")
        .id
}

async fn claim(store: &JobStore) -> ClaimedJob {
    store
        .claim_next(&claimant(), None)
        .await
        .expect("claim")
        .expect("a job to claim")
}

async fn row(store: &JobStore, id: Uuid) -> JobRow {
    store.get(id).await.expect("get").expect("the job exists")
}

/// A worker reporting success for `attempt` of job `id` after the fact: whether the
/// store wrote it.
async fn late_success(store: &JobStore, id: Uuid, attempt: i64) -> bool {
    store
        .finish(
            id,
            attempt,
            JobStatus::Succeeded,
            None,
            Some("{}"),
            250,
            0.5,
        )
        .await
        .unwrap()
}

fn names(rows: &[JobRow]) -> Vec<&str> {
    rows.iter().map(|r| r.name.as_str()).collect()
}

async fn submit_admits_jobs_up_to_the_queue_capacity(store: &JobStore) {
    let first = try_submit(store, "a", 2).await.expect("admitted");
    assert_eq!(first.name, "a");
    assert_eq!(first.status, JobStatus::Queued);
    assert_eq!(first.end_time, 0.5);
    assert_eq!((first.step, first.simulated_time), (0, 0.0));
    assert_eq!(first.attempts, 0);
    assert!(first.started_at.is_none() && first.finished_at.is_none());
    assert!(first.particles.is_none() && first.reason.is_none() && first.summary.is_none());
    assert!(first.worker.is_none() && first.run_dir.is_none());
    assert!(
        time::OffsetDateTime::parse(
            &first.created_at,
            &time::format_description::well_known::Rfc3339
        )
        .is_ok(),
        "created_at {:?}",
        first.created_at
    );
    assert_eq!(row(store, first.id).await.created_at, first.created_at);
    assert!(try_submit(store, "b", 2).await.is_some());
    assert!(
        try_submit(store, "c", 2).await.is_none(),
        "a third job in a queue of 2"
    );
    // the capacity counts queued jobs: a claimed one frees a place
    claim(store).await;
    assert!(try_submit(store, "c", 2).await.is_some());
    assert!(try_submit(store, "d", 2).await.is_none());
    let (_, total) = store.list(None, 10, 0).await.unwrap();
    assert_eq!(total, 3, "a refused job is not stored");
}

async fn claim_takes_the_oldest_queued_job(store: &JobStore) {
    assert!(store.claim_next(&claimant(), None).await.unwrap().is_none());
    let a = submit(store, "a").await;
    let b = submit(store, "b").await;
    let c = submit(store, "c").await;

    let first = claim(store).await;
    assert_eq!(first.row.id, a);
    assert_eq!(first.case_json, case_of("a"));
    assert_eq!(first.attempt(), 1);
    assert_eq!(first.row.status, JobStatus::Running);
    assert_eq!(first.row.worker.as_deref(), Some("test-host:1"));
    let run_dir = format!("/data/jobs/{a}");
    assert_eq!(first.row.run_dir.as_deref(), Some(run_dir.as_str()));
    assert!(first.row.started_at.is_some());
    let stored = row(store, a).await;
    assert_eq!(stored.status, JobStatus::Running);
    assert_eq!(stored.attempts, 1);

    assert!(store.cancel_if_queued(b).await.unwrap());
    let next = claim(store).await;
    assert_eq!(next.row.id, c, "a cancelled job is not claimed");
    assert_eq!(next.case_json, case_of("c"));
    assert!(
        store.claim_next(&claimant(), None).await.unwrap().is_none(),
        "running jobs are not claimed again"
    );
}

/// A ladder (`Some(3)`: the job and two parts) queues its parts behind it; they are not
/// listed and do not fill the queue, and a claim for the job's parts takes only them.
/// Once the job has ended without them (here a finish; a restart's recovery or an expired
/// lease alike) no claim takes its queued part, the next claim cancels it, and with
/// Postgres the running part is asked to stop at its next renewal.
async fn a_ladder_s_parts_run_after_their_job_and_end_with_it(store: &JobStore) {
    let id = Uuid::new_v4();
    let admitted = store
        .submit(id, "ladder", &case_of("ladder"), 0.5, Some(3), 1)
        .await
        .unwrap();
    assert!(matches!(admitted, Admission::Accepted(_)));
    assert!(
        try_submit(store, "after", 1).await.is_none(),
        "the job fills a queue of one; its parts do not count"
    );
    let (listed, total) = store.list(None, 10, 0).await.unwrap();
    assert_eq!((listed.len(), total), (1, 1));
    let parts = store.parts(id).await.unwrap();
    assert_eq!(parts.iter().map(|p| p.part).collect::<Vec<_>>(), [1, 2]);
    assert!(parts.iter().all(|p| p.parent == Some(id) && p.parts == 3));

    let job = claim(store).await;
    assert_eq!(job.row.id, id, "the job before its parts");
    assert_eq!((job.row.uncertainty, job.row.parts), (true, 3));
    let running = store
        .claim_next(&claimant(), Some(id))
        .await
        .unwrap()
        .expect("a part of the job");
    assert_eq!(running.row.id, parts[0].id);
    store.part_ended(id).await.unwrap();
    assert_eq!(row(store, id).await.part, 1);

    assert!(store
        .finish(
            id,
            job.attempt(),
            JobStatus::Failed,
            Some("x"),
            None,
            0,
            0.0
        )
        .await
        .unwrap());
    let other = submit(store, "other").await;
    assert_eq!(claim(store).await.row.id, other, "not the older part");
    let queued = store.get(parts[1].id).await.unwrap().unwrap();
    assert_eq!(queued.status, JobStatus::Cancelled);
    assert_eq!(queued.reason.as_deref(), Some("its job ended"));
    let renewal = store
        .renew(running.row.id, running.attempt(), 600.0)
        .await
        .unwrap();
    assert_eq!(
        renewal,
        Renewal::Held {
            cancel: store.is_shared()
        }
    );
}

async fn progress_is_written_only_by_the_attempt_holding_the_job(store: &JobStore) {
    let id = submit(store, "a").await;
    let attempt = claim(store).await.attempt();

    store.set_started(id, attempt, 1200).await.unwrap();
    store.set_progress(id, attempt, 40, 0.125).await.unwrap();
    let held = row(store, id).await;
    assert_eq!(held.particles, Some(1200));
    assert_eq!((held.step, held.simulated_time), (40, 0.125));

    // another attempt's writes change nothing
    for other in [attempt - 1, attempt + 1] {
        store.set_started(id, other, 7).await.unwrap();
        store.set_progress(id, other, 99, 0.4).await.unwrap();
    }
    let fenced = row(store, id).await;
    assert_eq!(fenced.particles, Some(1200));
    assert_eq!((fenced.step, fenced.simulated_time), (40, 0.125));

    // nor do the attempt's own writes once the job has ended
    assert!(store
        .finish(
            id,
            attempt,
            JobStatus::Failed,
            Some("diverged"),
            None,
            41,
            0.13
        )
        .await
        .unwrap());
    store.set_started(id, attempt, 7).await.unwrap();
    store.set_progress(id, attempt, 99, 0.4).await.unwrap();
    let ended = row(store, id).await;
    assert_eq!(ended.particles, Some(1200));
    assert_eq!((ended.step, ended.simulated_time), (41, 0.13));
}

async fn cancel_if_queued_cancels_only_a_queued_job(store: &JobStore) {
    let running = submit(store, "running").await;
    let queued = submit(store, "queued").await;
    claim(store).await;

    assert!(store.cancel_if_queued(queued).await.unwrap());
    let cancelled = row(store, queued).await;
    assert_eq!(cancelled.status, JobStatus::Cancelled);
    assert_eq!(
        cancelled.reason.as_deref(),
        Some("cancelled before it started")
    );
    assert!(cancelled.finished_at.is_some());
    assert!(
        !store.cancel_if_queued(queued).await.unwrap(),
        "cancelled twice"
    );

    assert!(!store.cancel_if_queued(running).await.unwrap());
    assert_eq!(row(store, running).await.status, JobStatus::Running);
    assert!(!store.cancel_if_queued(Uuid::new_v4()).await.unwrap());
}

async fn finish_records_the_outcome_of_the_running_attempt(store: &JobStore) {
    let id = submit(store, "a").await;
    let attempt = claim(store).await.attempt();
    assert!(
        !store
            .finish(id, attempt + 1, JobStatus::Succeeded, None, None, 1, 0.01)
            .await
            .unwrap(),
        "an attempt that does not hold the job finished it"
    );
    assert_eq!(row(store, id).await.status, JobStatus::Running);

    let summary = r#"{"status":"succeeded","steps":250}"#;
    assert!(store
        .finish(
            id,
            attempt,
            JobStatus::Succeeded,
            None,
            Some(summary),
            250,
            0.5
        )
        .await
        .unwrap());
    let done = row(store, id).await;
    assert_eq!(done.status, JobStatus::Succeeded);
    assert_eq!(done.summary.as_deref(), Some(summary));
    assert!(done.reason.is_none());
    assert_eq!((done.step, done.simulated_time), (250, 0.5));
    assert!(done.finished_at.is_some());
    assert_eq!(done.attempts, attempt);
}

/// The first recorded end stands: a second finish of the same attempt (a retried write,
/// or a process that outlived its store's recovery) is refused.
async fn a_late_finish_does_not_overwrite_a_finished_job(store: &JobStore) {
    let id = submit(store, "a").await;
    let attempt = claim(store).await.attempt();
    assert!(store
        .finish(
            id,
            attempt,
            JobStatus::Failed,
            Some("diverged"),
            None,
            12,
            0.02
        )
        .await
        .unwrap());
    let failed = row(store, id).await;

    assert!(
        !late_success(store, id, attempt).await,
        "a finished job was finished again"
    );
    let kept = row(store, id).await;
    assert_eq!(kept.status, JobStatus::Failed);
    assert_eq!(kept.reason.as_deref(), Some("diverged"));
    assert!(kept.summary.is_none());
    assert_eq!((kept.step, kept.simulated_time), (12, 0.02));
    assert_eq!(kept.finished_at, failed.finished_at);
}

/// A job cancelled before any claim still has `attempts = 0`, the attempt number a
/// finish could name; it stays cancelled.
async fn a_late_finish_does_not_overwrite_a_job_cancelled_in_the_queue(store: &JobStore) {
    let id = submit(store, "a").await;
    assert!(store.cancel_if_queued(id).await.unwrap());
    let cancelled = row(store, id).await;
    assert_eq!(cancelled.attempts, 0);

    assert!(
        !late_success(store, id, 0).await,
        "a cancelled job was finished"
    );
    let kept = row(store, id).await;
    assert_eq!(kept.status, JobStatus::Cancelled);
    assert_eq!(kept.reason, cancelled.reason);
    assert!(kept.summary.is_none());
    assert_eq!(kept.step, 0);
}

async fn list_filters_by_status_and_pages_newest_first(store: &JobStore) {
    for name in ["a", "b", "c", "d", "e"] {
        submit(store, name).await;
    }
    let running = claim(store).await.row.id; // a
    let c = store.list(None, 10, 0).await.unwrap().0[2].id;
    assert!(store.cancel_if_queued(c).await.unwrap());

    let (all, total) = store.list(None, 10, 0).await.unwrap();
    assert_eq!(names(&all), ["e", "d", "c", "b", "a"]);
    assert_eq!(total, 5);
    let (page, total) = store.list(None, 2, 2).await.unwrap();
    assert_eq!(names(&page), ["c", "b"]);
    assert_eq!(total, 5);

    let (queued, total) = store.list(Some(JobStatus::Queued), 10, 0).await.unwrap();
    assert_eq!(names(&queued), ["e", "d", "b"]);
    assert_eq!(total, 3);
    let (page, total) = store.list(Some(JobStatus::Queued), 1, 1).await.unwrap();
    assert_eq!(names(&page), ["d"]);
    assert_eq!(total, 3);
    let (on, total) = store.list(Some(JobStatus::Running), 10, 0).await.unwrap();
    assert_eq!((on.len(), on[0].id, total), (1, running, 1));
    let (cancelled, total) = store.list(Some(JobStatus::Cancelled), 10, 0).await.unwrap();
    assert_eq!((names(&cancelled), total), (vec!["c"], 1));
    let (none, total) = store.list(Some(JobStatus::Succeeded), 10, 0).await.unwrap();
    assert!(none.is_empty());
    assert_eq!(total, 0);
}

async fn list_counts_the_matching_jobs_beyond_the_page(store: &JobStore) {
    let (empty, total) = store.list(None, 10, 0).await.unwrap();
    assert!(empty.is_empty());
    assert_eq!(total, 0);
    for i in 0..7 {
        submit(store, &format!("job-{i}")).await;
    }
    claim(store).await;
    let (rows, total) = store.list(None, 3, 0).await.unwrap();
    assert_eq!((rows.len(), total), (3, 7));
    let (rows, total) = store.list(None, 3, 6).await.unwrap();
    assert_eq!((names(&rows), total), (vec!["job-0"], 7));
    let (rows, total) = store.list(None, 3, 100).await.unwrap();
    assert_eq!((rows.len(), total), (0, 7));
    let (rows, total) = store.list(Some(JobStatus::Queued), 0, 0).await.unwrap();
    assert_eq!((rows.len(), total), (0, 6));
}

async fn case_text_is_the_submitted_text(store: &JobStore) {
    // byte for byte: whitespace, key order and non-ASCII text are kept
    let text =
        "{ \"name\":  \"ke\u{00ef}l\u{2014}w\u{00e9}dge\",\n  \"b\": 1,\n  \"a\": [0.5e-3]\n}\n";
    let id = Uuid::new_v4();
    let admitted = store.submit(id, "keel", text, 0.5, None, 10).await.unwrap();
    assert!(matches!(admitted, Admission::Accepted(_)));
    assert_eq!(store.case_text(id).await.unwrap().as_deref(), Some(text));
    assert_eq!(claim(store).await.case_json, text);
    assert_eq!(store.case_text(Uuid::new_v4()).await.unwrap(), None);
    assert!(store.get(Uuid::new_v4()).await.unwrap().is_none());
    store.ping().await.unwrap();
}

async fn delete_removes_the_job_and_its_rows_and_no_other_job_s(store: &JobStore) {
    const LOADS: &[u8] = b"time,fx\n0,1\n";
    let kept = submit(store, "kept").await;
    let gone = submit(store, "gone").await;
    let kept_attempt = claim(store).await.attempt();
    let gone_attempt = claim(store).await.attempt();
    store
        .set_progress(gone, gone_attempt, 10, 0.01)
        .await
        .unwrap();
    if let JobStore::Postgres(pg) = store {
        for (id, attempt) in [(kept, kept_attempt), (gone, gone_attempt)] {
            assert!(pg
                .append_series(id, attempt, "loads.csv", 0, LOADS)
                .await
                .unwrap());
            assert!(pg
                .append_series(id, attempt, "probes.csv", 0, b"time\n")
                .await
                .unwrap());
        }
    }

    let deleted = store.delete(gone).await.unwrap().expect("the job existed");
    assert_eq!((deleted.id, deleted.status), (gone, JobStatus::Running));
    assert!(store.get(gone).await.unwrap().is_none());
    assert!(store.case_text(gone).await.unwrap().is_none());
    assert!(store.delete(gone).await.unwrap().is_none(), "deleted twice");
    assert!(store.delete(Uuid::new_v4()).await.unwrap().is_none());

    // the worker still running it writes nothing and brings nothing back
    store.set_started(gone, gone_attempt, 7).await.unwrap();
    store
        .set_progress(gone, gone_attempt, 20, 0.02)
        .await
        .unwrap();
    assert!(!late_success(store, gone, gone_attempt).await);
    assert!(!store.release(gone, gone_attempt).await.unwrap());
    if let JobStore::Postgres(pg) = store {
        assert_eq!(
            store.renew(gone, gone_attempt, 600.0).await.unwrap(),
            Renewal::Lost
        );
        assert!(!pg
            .append_series(
                gone,
                gone_attempt,
                "loads.csv",
                LOADS.len() as u64,
                b"1,2\n"
            )
            .await
            .unwrap());
        for file in ["loads.csv", "probes.csv"] {
            assert!(
                pg.read_series(gone, file).await.unwrap().is_empty(),
                "{file}"
            );
        }
        assert_eq!(pg.read_series(kept, "loads.csv").await.unwrap(), LOADS);
        assert_eq!(pg.read_series(kept, "probes.csv").await.unwrap(), b"time\n");
    }
    assert!(
        store.get(gone).await.unwrap().is_none(),
        "nothing reappears"
    );
    assert!(store.claim_next(&claimant(), None).await.unwrap().is_none());

    // the other job is untouched
    let (rows, total) = store.list(None, 10, 0).await.unwrap();
    assert_eq!((names(&rows), total), (vec!["kept"], 1));
    assert_eq!(row(store, kept).await.status, JobStatus::Running);
    assert!(late_success(store, kept, kept_attempt).await);

    // a queued job and a finished one are deleted the same way
    let queued = submit(store, "queued").await;
    let status = |row: Option<JobRow>| row.expect("the job existed").status;
    assert_eq!(
        status(store.delete(queued).await.unwrap()),
        JobStatus::Queued
    );
    assert_eq!(
        status(store.delete(kept).await.unwrap()),
        JobStatus::Succeeded
    );
    if let JobStore::Postgres(pg) = store {
        assert!(pg.read_series(kept, "loads.csv").await.unwrap().is_empty());
    }
    assert_eq!(store.list(None, 10, 0).await.unwrap().1, 0);
}

/// SQLite only: a job found `running` when a process opens the store was orphaned by an
/// earlier one and is recorded `failed` / `interrupted`; if that process was in fact
/// still running it, its late finish is refused.
#[tokio::test]
async fn sqlite_recovery_is_not_overwritten_by_the_orphaned_run() {
    let store = sqlite_store("recovery").await;
    let id = submit(&store, "a").await;
    let queued = submit(&store, "b").await;
    let attempt = claim(&store).await.attempt();
    assert_eq!(store.recover_interrupted().await.unwrap(), 1);
    let recovered = row(&store, id).await;
    assert_eq!(recovered.status, JobStatus::Failed);
    assert_eq!(recovered.reason.as_deref(), Some("interrupted"));
    assert_eq!(row(&store, queued).await.status, JobStatus::Queued);

    assert!(!late_success(&store, id, attempt).await);
    let kept = row(&store, id).await;
    assert_eq!(kept.status, JobStatus::Failed);
    assert_eq!(kept.reason.as_deref(), Some("interrupted"));
    assert_eq!(kept.finished_at, recovered.finished_at);
    store.close().await;
}

/// What retention (`--keep-days`) removes: jobs that ended before the cutoff, oldest
/// first; never a queued or running one.
async fn finished_before_lists_only_jobs_that_ended_before_the_cutoff(store: &JobStore) {
    let done = submit(store, "done").await;
    let cancelled = submit(store, "cancelled").await;
    let running = submit(store, "running").await;
    submit(store, "queued").await;
    let claimed = claim(store).await;
    assert_eq!(claimed.row.id, done);
    assert!(late_success(store, done, claimed.attempt()).await);
    assert!(store.cancel_if_queued(cancelled).await.unwrap());
    assert_eq!(claim(store).await.row.id, running);
    let all = store.finished_before("9999-12-31T23:59:59Z").await.unwrap();
    assert_eq!(all, vec![done, cancelled]);
    let none = store.finished_before("2000-01-01T00:00:00Z").await.unwrap();
    assert!(none.is_empty(), "{none:?}");
}
