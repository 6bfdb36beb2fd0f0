//! A ladder job's parts (`?uncertainty=true`) run on whichever workers are free: they
//! run at the same time, give exactly the half-widths of `mpsfsi run --uncertainty`
//! (which runs them one after another), are never listed or served as jobs, end with
//! their job (cancel, delete), and a part killed with its worker runs again.

use crate::helpers::{fresh_data_dir, spawn_app, tiny_case, Api, TestApp};
use mpsfsi::case::{parse_case_value, Limits, ValidCase};
use mpsfsi::run::{uncertainty::run_with_uncertainty, Quiet};
use mpsfsi::service::store::{JobRow, JobStatus, JobStore};
use serde_json::Value;
use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};
use uuid::Uuid;

/// The ladder run by the CLI's code, one part after another, in a fresh directory.
fn cli_ladder(case: &Value, tag: &str) -> PathBuf {
    let case = parse_case_value(case.clone()).unwrap();
    let case = ValidCase::new(case, &Limits::default()).unwrap();
    let dir = fresh_data_dir(tag).join("run");
    let summary = run_with_uncertainty(&case, &dir, &mut Quiet).unwrap();
    assert!(summary.uncertainty.is_some(), "{:?}", summary.reason);
    dir
}

async fn submit_ladder(api: &Api, case: &Value) -> String {
    let response = api
        .post_case_at("/v1/jobs?uncertainty=true", case, None)
        .await;
    assert_eq!(response.status().as_u16(), 201);
    let body: Value = response.json().await.unwrap();
    body["id"].as_str().unwrap().to_string()
}

/// The SQLite store of an in-process app, opened beside it.
async fn sqlite_store(app: &TestApp) -> JobStore {
    let url = format!("sqlite://{}", app.data_dir.join("jobs.db").display());
    JobStore::open(&url).await.unwrap()
}

/// The job's row and its parts' rows.
async fn rows(store: &JobStore, id: &str) -> (JobRow, Vec<JobRow>) {
    let id = Uuid::parse_str(id).unwrap();
    let job = store.get(id).await.unwrap().expect("the job's row");
    (job, store.parts(id).await.unwrap())
}

/// Poll the rows every 10 ms until the job has ended: the largest number of its rows
/// (the job's own and its parts') running at one time.
async fn most_running_at_once(store: &JobStore, id: &str) -> usize {
    let start = Instant::now();
    let mut most = 0;
    loop {
        let (job, parts) = rows(store, id).await;
        if job.status.is_finished() {
            return most;
        }
        let running = std::iter::once(&job)
            .chain(&parts)
            .filter(|r| r.status == JobStatus::Running)
            .count();
        most = most.max(running);
        assert!(start.elapsed() < Duration::from_secs(120), "{job:?}");
        tokio::time::sleep(Duration::from_millis(10)).await;
    }
}

/// Assert that the uncertainty blocks of two summaries agree, wall times aside (they
/// differ per run): numbers to 1e-14 relative, the last digit a JSON text read twice
/// (the store's summary, then the route's) may lose.
fn assert_same_half_widths(served: &Value, cli: &Value) {
    fn same(a: &Value, b: &Value, path: &str) {
        match (a, b) {
            (Value::Number(x), Value::Number(y)) => {
                let (x, y) = (x.as_f64().unwrap(), y.as_f64().unwrap());
                assert!(
                    (x - y).abs() <= 1e-14 * x.abs().max(y.abs()),
                    "{path}: {x} {y}"
                );
            }
            (Value::Array(x), Value::Array(y)) => {
                assert_eq!(x.len(), y.len(), "{path}");
                for (k, (x, y)) in x.iter().zip(y).enumerate() {
                    same(x, y, &format!("{path}[{k}]"));
                }
            }
            (Value::Object(x), Value::Object(y)) => {
                assert_eq!(
                    x.keys().collect::<Vec<_>>(),
                    y.keys().collect::<Vec<_>>(),
                    "{path}"
                );
                for (k, x) in x {
                    same(x, &y[k], &format!("{path}.{k}"));
                }
            }
            _ => assert_eq!(a, b, "{path}"),
        }
    }
    for block in ["bodies", "probes", "notes"] {
        same(
            &served["uncertainty"][block],
            &cli["uncertainty"][block],
            block,
        );
    }
}

fn read(path: &Path) -> String {
    std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()))
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_ladder_s_parts_run_at_once_and_give_the_cli_s_half_widths() {
    let case = tiny_case(0.5);
    let app = spawn_app("parts", |c| c.workers = 2).await;
    let store = sqlite_store(&app).await;
    let id = submit_ladder(&app, &case).await;
    let most = most_running_at_once(&store, &id).await;
    let job = app.wait_finished(&id).await;
    assert_eq!(job["status"], "succeeded", "{job:#}");
    assert!(
        most >= 2,
        "two workers ran parts at one time: at most {most}"
    );
    assert_eq!(job["progress"]["part"], 7);
    assert_eq!(job["progress"]["parts"], 7);
    let page = app.page(&id).await;
    assert!(
        page.contains("error bars: 6 of 6 coarser runs ended"),
        "{page}"
    );

    // the same files as the CLI's ladder, byte for byte
    let cli = cli_ladder(&case, "parts-cli");
    let (_, _, served) = app
        .get_csv(&format!("/v1/jobs/{id}/loads_uncertainty"))
        .await;
    assert_eq!(served, read(&cli.join("loads_uncertainty.csv")));
    let dir = app.data_dir.join("jobs").join(&id);
    for file in ["probes_uncertainty.csv", "levels/level_1/loads.csv"] {
        assert_eq!(read(&dir.join(file)), read(&cli.join(file)), "{file}");
    }
    let cli_summary: Value = serde_json::from_str(&read(&cli.join("summary.json"))).unwrap();
    assert_same_half_widths(&job["summary"], &cli_summary);

    // parts are rows of the store, not jobs
    let (_, parts) = rows(&store, &id).await;
    assert_eq!(parts.len(), 6);
    assert!(parts.iter().all(|p| p.status == JobStatus::Succeeded));
    let (_, list) = app.get_json("/v1/jobs").await;
    assert_eq!(list["total"], 1, "{list:#}");
    let part = parts[0].id;
    assert_eq!(app.get_json(&format!("/v1/jobs/{part}")).await.0, 404);
    let deleted = app
        .client
        .delete(app.url(&format!("/v1/jobs/{part}")))
        .send()
        .await
        .unwrap();
    assert_eq!(deleted.status().as_u16(), 404);
    assert_eq!(
        rows(&store, &id).await.1.len(),
        6,
        "the part is still there"
    );

    // deleting the job deletes its parts
    let deleted = app
        .client
        .delete(app.url(&format!("/v1/jobs/{id}")))
        .send()
        .await
        .unwrap();
    assert_eq!(deleted.status().as_u16(), 204);
    let uuid = Uuid::parse_str(&id).unwrap();
    assert!(store.parts(uuid).await.unwrap().is_empty());
    assert!(store.get(part).await.unwrap().is_none());
    store.close().await;
    app.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn cancelling_a_ladder_ends_its_parts() {
    let app = spawn_app("parts-cancel", |c| c.workers = 2).await;
    let store = sqlite_store(&app).await;
    let id = submit_ladder(&app, &tiny_case(100.0)).await;
    // both workers busy: the job's own level and its first part
    wait_rows(&store, &id, |_, parts| {
        parts.iter().any(|p| p.status == JobStatus::Running)
    })
    .await;
    let cancelled = app
        .client
        .post(app.url(&format!("/v1/jobs/{id}/cancel")))
        .send()
        .await
        .unwrap();
    assert_eq!(cancelled.status().as_u16(), 202);
    let job = app.wait_finished(&id).await;
    assert_eq!(job["status"], "cancelled", "{job:#}");
    // the running part stops at its next step, the queued ones never start
    let (_, parts) = wait_rows(&store, &id, |_, parts| {
        parts.iter().all(|p| p.status == JobStatus::Cancelled)
    })
    .await;
    assert_eq!(parts.len(), 6);
    store.close().await;
    app.stop().await;
}

/// With Postgres: the parts spread over the workers, a part killed with its worker
/// runs again on another, and the half-widths are still the CLI's.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_ladder_s_parts_spread_over_workers_and_a_killed_one_runs_again() {
    use crate::pg_server::PgServer;
    use crate::postgres::{node, stop, worker_process};
    let Some(pg) = PgServer::start_or_skip("parts").await else {
        return;
    };
    let url = pg.fresh_database().await;
    let api = node(&url, "pg-parts").await;
    let store = JobStore::open(&url).await.unwrap();
    let case = tiny_case(2.0);
    let first = worker_process(&url, &fresh_data_dir("pg-parts-a"), 2.0);
    let id = submit_ladder(&api, &case).await;
    let (job, _) = wait_rows(&store, &id, |job, _| job.status == JobStatus::Running).await;
    let holder = job.worker.clone().unwrap();
    // a second worker takes a part; it is killed while that part runs
    let second = worker_process(&url, &fresh_data_dir("pg-parts-b"), 2.0);
    let (_, parts) = wait_rows(&store, &id, |_, parts| {
        parts
            .iter()
            .any(|p| p.status == JobStatus::Running && p.worker.as_deref() != Some(&holder))
    })
    .await;
    let killed = parts
        .iter()
        .find(|p| p.status == JobStatus::Running && p.worker.as_deref() != Some(&holder))
        .unwrap()
        .id;
    stop(second);
    let third = worker_process(&url, &fresh_data_dir("pg-parts-c"), 2.0);
    let job = api
        .wait_for(&id, Duration::from_secs(180), |j| {
            j["status"] != "queued" && j["status"] != "running"
        })
        .await;
    stop(first);
    stop(third);
    assert_eq!(job["status"], "succeeded", "{job:#}");
    let (_, parts) = rows(&store, &id).await;
    let again = parts.iter().find(|p| p.id == killed).unwrap();
    assert_eq!(again.status, JobStatus::Succeeded);
    assert_eq!(again.attempts, 2, "the killed part ran again: {again:?}");
    let workers: std::collections::HashSet<_> =
        parts.iter().filter_map(|p| p.worker.clone()).collect();
    assert!(workers.len() >= 2, "{workers:?}");

    let cli = cli_ladder(&case, "pg-parts-cli");
    let (_, _, served) = api
        .get_csv(&format!("/v1/jobs/{id}/loads_uncertainty"))
        .await;
    assert_eq!(served, read(&cli.join("loads_uncertainty.csv")));
    let cli_summary: Value = serde_json::from_str(&read(&cli.join("summary.json"))).unwrap();
    assert_same_half_widths(&job["summary"], &cli_summary);
    store.close().await;
    api.stop().await;
}

/// Poll the job's rows until `done` holds (at most 60 s).
async fn wait_rows(
    store: &JobStore,
    id: &str,
    done: impl Fn(&JobRow, &[JobRow]) -> bool,
) -> (JobRow, Vec<JobRow>) {
    let start = Instant::now();
    loop {
        let (job, parts) = rows(store, id).await;
        if done(&job, &parts) {
            return (job, parts);
        }
        assert!(
            start.elapsed() < Duration::from_secs(60),
            "{job:?} {parts:#?}"
        );
        tokio::time::sleep(Duration::from_millis(20)).await;
    }
}

/// With Postgres, cancelling a ladder reaches its parts on other worker processes (at
/// their next lease renewal) and its queued parts.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn cancelling_a_ladder_reaches_its_parts_on_other_workers() {
    use crate::pg_server::PgServer;
    use crate::postgres::{node, stop, worker_process};
    let Some(pg) = PgServer::start_or_skip("parts_cancel").await else {
        return;
    };
    let url = pg.fresh_database().await;
    let api = node(&url, "pg-parts-cancel").await;
    let store = JobStore::open(&url).await.unwrap();
    let workers = [
        worker_process(&url, &fresh_data_dir("pg-parts-cancel-a"), 1.5),
        worker_process(&url, &fresh_data_dir("pg-parts-cancel-b"), 1.5),
    ];
    let id = submit_ladder(&api, &tiny_case(100.0)).await;
    wait_rows(&store, &id, |job, parts| {
        job.status == JobStatus::Running && parts.iter().any(|p| p.status == JobStatus::Running)
    })
    .await;
    let cancelled = api
        .client
        .post(api.url(&format!("/v1/jobs/{id}/cancel")))
        .send()
        .await
        .unwrap();
    assert_eq!(cancelled.status().as_u16(), 202);
    let (job, parts) = wait_rows(&store, &id, |job, parts| {
        job.status.is_finished() && parts.iter().all(|p| p.status.is_finished())
    })
    .await;
    workers.into_iter().for_each(stop);
    assert_eq!(job.status, JobStatus::Cancelled, "{job:?}");
    assert!(
        parts.iter().all(|p| p.status == JobStatus::Cancelled),
        "{parts:#?}"
    );
    store.close().await;
    api.stop().await;
}
