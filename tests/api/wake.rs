//! Claims without delay: an idle worker claims a new job when it is submitted, not at its
//! next poll. With Postgres the submission is announced (`NOTIFY`) and a remote
//! `mpsfsi worker` listens; with SQLite the routes wake the process's own workers. The
//! latency is the job record's `started_at - created_at` (both written on this machine's
//! clock), printed for each store.
//!
//! The idle poll is 5 s, so a claim under 1 s after the worker had been idle for 0.7 s
//! or more can only have come from the wake-up.

use crate::helpers::{fresh_data_dir, spawn_app, tiny_case, Api};
use crate::pg_server::PgServer;
use crate::postgres::{node, stop, worker_process};
use std::time::Duration;

/// Seconds from `from` to `to`, two RFC 3339 times.
fn seconds_between(from: &str, to: &str) -> f64 {
    let parse = |t: &str| {
        time::OffsetDateTime::parse(t, &time::format_description::well_known::Rfc3339).unwrap()
    };
    (parse(to) - parse(from)).as_seconds_f64()
}

/// Submit `n` jobs one at a time, each after the pool has been idle a while (0.7 s and
/// more, past the end of the previous job); the claim latency of each in seconds.
async fn claim_latencies(api: &Api, n: usize) -> Vec<f64> {
    let mut latencies = Vec::new();
    for k in 0..n {
        tokio::time::sleep(Duration::from_millis(700 + 100 * k as u64)).await;
        let id = api.submit(&tiny_case(0.002)).await;
        let job = api.wait_finished(&id).await;
        assert_eq!(job["status"], "succeeded", "{job:#}");
        let created = job["created_at"].as_str().unwrap();
        latencies.push(seconds_between(
            created,
            job["started_at"].as_str().unwrap(),
        ));
    }
    latencies
}

/// Print the latencies and assert that each is under 1 s.
fn report(what: &str, latencies: &[f64]) {
    let mut sorted = latencies.to_vec();
    sorted.sort_by(f64::total_cmp);
    let ms: Vec<String> = latencies
        .iter()
        .map(|s| format!("{:.1}", s * 1e3))
        .collect();
    eprintln!(
        "claim latency, {what}: median {:.1} ms, max {:.1} ms ({} ms)",
        sorted[sorted.len() / 2] * 1e3,
        sorted[sorted.len() - 1] * 1e3,
        ms.join(", ")
    );
    assert!(
        sorted[sorted.len() - 1] < 1.0,
        "{what}: an idle worker took over 1 s to claim a job: {ms:?} ms"
    );
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn an_idle_remote_worker_claims_a_new_job_within_a_second() {
    let Some(pg) = PgServer::start_or_skip("idle_remote_worker").await else {
        return;
    };
    let url = pg.fresh_database().await;
    let api = node(&url, "wake-node").await;
    let data = fresh_data_dir("wake-worker");
    let worker = worker_process(&url, &data, 30.0);
    // the worker is up and has claimed once
    let first = api.submit(&tiny_case(0.002)).await;
    assert_eq!(api.wait_finished(&first).await["status"], "succeeded");

    let latencies = claim_latencies(&api, 5).await;
    report(
        "Postgres, a remote mpsfsi worker (LISTEN/NOTIFY)",
        &latencies,
    );

    // its listening connection killed: the listener reconnects, and no job is stranded
    let admin = sqlx::PgPool::connect(&url).await.unwrap();
    let killed: Vec<bool> = sqlx::query_scalar(
        "SELECT pg_terminate_backend(pid) FROM pg_stat_activity
         WHERE datname = current_database() AND query LIKE 'LISTEN%'",
    )
    .fetch_all(&admin)
    .await
    .unwrap();
    admin.close().await;
    assert_eq!(killed, vec![true], "one listening connection");
    let id = api.submit(&tiny_case(0.002)).await;
    let job = api.wait_finished(&id).await;
    assert_eq!(job["status"], "succeeded", "{job:#}");
    let latencies = claim_latencies(&api, 2).await;
    report(
        "Postgres, after the listening connection was killed",
        &latencies,
    );
    stop(worker);
    api.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn an_idle_local_worker_claims_a_new_job_within_a_second() {
    let app = spawn_app("wake-sqlite", |c| c.workers = 1).await;
    let latencies = claim_latencies(&app, 5).await;
    report("SQLite, the serving process's own worker", &latencies);
    app.stop().await;
}
