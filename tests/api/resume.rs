//! Checkpoints on a shared store (Postgres): a job whose worker is killed (-9) resumes
//! on another worker from its last checkpoint, a worker stopped with SIGTERM saves one
//! and gives the job back without spending an attempt, and either way the job's loads,
//! probes and filtered loads (served by an API node that shares no disk with the
//! workers) are byte for byte those of a run that was never interrupted.

use crate::helpers::{fresh_data_dir, tiny_case, Api};
use crate::pg_server::PgServer;
use crate::postgres::{node, stop, terminate};
use mpsfsi::case::{parse_case_str, Limits, ValidCase};
use mpsfsi::run::{run_case, Quiet, RunStatus};
use serde_json::Value;
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// The loads, probes and filtered loads of `case` run in this process, uninterrupted.
fn uninterrupted(case: &Value, tag: &str) -> (String, String, String) {
    let case = parse_case_str(&case.to_string()).unwrap();
    let case = ValidCase::new(case, &Limits::default()).unwrap();
    let dir = fresh_data_dir(tag);
    let summary = run_case(&case, &dir, &mut Quiet).unwrap();
    assert_eq!(summary.status, RunStatus::Succeeded);
    let read = |f: &str| std::fs::read_to_string(dir.join(f)).unwrap();
    (
        read("loads.csv"),
        read("probes.csv"),
        read("loads_filtered.csv"),
    )
}

/// `mpsfsi worker` with its log in `data/worker.log`.
fn worker(url: &str, data: &Path, flags: &[&str]) -> Child {
    let log = std::fs::File::create(data.join("worker.log")).unwrap();
    Command::new(env!("CARGO_BIN_EXE_mpsfsi"))
        .args(["worker", "--database", url, "--data"])
        .arg(data)
        .args(flags)
        .stdout(Stdio::null())
        .stderr(log)
        .spawn()
        .expect("worker process starts")
}

/// Wait until the worker's log says it stored a checkpoint.
async fn wait_checkpoint(data: &Path) {
    let start = Instant::now();
    while !std::fs::read_to_string(data.join("worker.log"))
        .unwrap_or_default()
        .contains("checkpoint stored")
    {
        assert!(start.elapsed() < Duration::from_secs(60), "no checkpoint");
        tokio::time::sleep(Duration::from_millis(20)).await;
    }
}

async fn assert_uninterrupted_results(api: &Api, id: &str, expected: &(String, String, String)) {
    let (_, _, loads) = api.get_csv(&format!("/v1/jobs/{id}/loads")).await;
    let (_, _, probes) = api.get_csv(&format!("/v1/jobs/{id}/probes")).await;
    let (_, _, filtered) = api.get_csv(&format!("/v1/jobs/{id}/loads_filtered")).await;
    assert!(
        filtered == expected.2,
        "the filtered loads differ from an uninterrupted run's"
    );
    assert_eq!(
        loads.lines().count(),
        expected.0.lines().count(),
        "rows of loads"
    );
    assert!(
        loads == expected.0,
        "the resumed job's loads differ from an uninterrupted run's"
    );
    assert!(
        probes == expected.1,
        "the resumed job's probes differ from an uninterrupted run's"
    );
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_killed_worker_s_job_resumes_from_its_checkpoint_with_the_uninterrupted_loads() {
    let Some(pg) = PgServer::start_or_skip("resume_killed").await else {
        return;
    };
    let case = tiny_case(4.0);
    let expected = uninterrupted(&case, "resume-killed-reference");
    let url = pg.fresh_database().await;
    let api = node(&url, "pg-resume-kill").await;
    let first_data = fresh_data_dir("pg-resume-w1");
    let mut first = worker(
        &url,
        &first_data,
        &["--lease-s", "1.5", "--checkpoint-s", "0.3"],
    );
    let id = api.submit(&case).await;
    api.wait_running(&id).await;
    wait_checkpoint(&first_data).await;
    first.kill().unwrap(); // SIGKILL: no last checkpoint, no release
    first.wait().unwrap();
    let killed = api.job(&id).await;
    assert_eq!(killed["status"], "running", "{killed}");
    assert!(killed["resumed_from"].is_null(), "{killed}");

    let second = worker(&url, &fresh_data_dir("pg-resume-w2"), &["--lease-s", "1.5"]);
    let job = api
        .wait_for(&id, Duration::from_secs(90), |j| j["attempts"] == 2)
        .await;
    let resumed_from = job["resumed_from"].as_f64().unwrap_or(0.0);
    assert!(resumed_from > 0.0 && resumed_from < 4.0, "{job}");
    let job = api.wait_finished(&id).await;
    stop(second);
    assert_eq!(job["status"], "succeeded", "{job}");
    assert_eq!(job["resumed_from"].as_f64(), Some(resumed_from), "{job}");
    eprintln!("the killed worker's job resumed from t = {resumed_from} s");
    assert_uninterrupted_results(&api, &id, &expected).await;
    api.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_sigterm_ed_worker_s_job_resumes_without_using_up_an_attempt() {
    let Some(pg) = PgServer::start_or_skip("resume_sigterm").await else {
        return;
    };
    let case = tiny_case(4.0);
    let expected = uninterrupted(&case, "resume-term-reference");
    let url = pg.fresh_database().await;
    let api = node(&url, "pg-resume-term").await;
    // two attempts allowed: the SIGTERM's release must not count, or the kill below
    // would exhaust them
    let flags = [
        "--lease-s",
        "1.5",
        "--max-attempts",
        "2",
        "--shutdown-grace-s",
        "0",
    ];
    let first_data = fresh_data_dir("pg-resume-term-w1");
    let mut first = worker(&url, &first_data, &flags);
    let id = api.submit(&case).await;
    api.wait_running(&id).await;
    tokio::time::sleep(Duration::from_millis(500)).await;
    terminate(&mut first);
    let log = std::fs::read_to_string(first_data.join("worker.log")).unwrap();
    assert!(
        log.contains("checkpoint stored"),
        "SIGTERM saves a checkpoint: {log}"
    );
    let job = api.job(&id).await;
    assert_eq!(job["status"], "queued", "{job}");

    // the second worker resumes it and is killed after a checkpoint of its own
    let second_data = fresh_data_dir("pg-resume-term-w2");
    let mut second = worker(
        &url,
        &second_data,
        &[&flags[..], &["--checkpoint-s", "0.3"]].concat(),
    );
    let job = api
        .wait_for(&id, Duration::from_secs(60), |j| j["attempts"] == 2)
        .await;
    let first_resume = job["resumed_from"].as_f64().unwrap_or(0.0);
    assert!(first_resume > 0.0, "{job}");
    wait_checkpoint(&second_data).await;
    second.kill().unwrap();
    second.wait().unwrap();

    let third = worker(&url, &fresh_data_dir("pg-resume-term-w3"), &flags);
    let job = api
        .wait_for(&id, Duration::from_secs(90), |j| {
            matches!(
                j["status"].as_str(),
                Some("succeeded" | "failed" | "cancelled")
            )
        })
        .await;
    stop(third);
    assert_eq!(
        job["status"], "succeeded",
        "a release spent an attempt: {job}"
    );
    assert_eq!(job["attempts"], 3, "{job}");
    assert!(
        job["resumed_from"].as_f64().unwrap() > first_resume,
        "{job}"
    );
    assert_uninterrupted_results(&api, &id, &expected).await;
    api.stop().await;
}
