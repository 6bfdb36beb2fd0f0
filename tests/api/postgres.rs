//! Many API nodes and workers on one Postgres (docs/service.md, README "Many machines"):
//! nodes are in-process with `--workers 0`, workers are `mpsfsi worker` processes, each
//! test has its own throwaway server ([`PgServer`]).

use crate::helpers::{
    advice_on_page, advised_wedge, fresh_data_dir, long_case, spawn_app, tiny_case, Api, TestApp,
};
use crate::pg_server::PgServer;
use mpsfsi::service::store::{Claimant, JobStatus, JobStore, ATTEMPTS_EXHAUSTED};
use mpsfsi::service::DatabaseUrl;
use serde_json::Value;
use std::collections::{BTreeMap, HashSet};
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// An API node on `url` that runs no job.
pub async fn node(url: &str, tag: &str) -> TestApp {
    let url = url.to_string();
    spawn_app(tag, move |c| {
        c.database = Some(DatabaseUrl::new(url));
        c.workers = 0;
        c.queue_capacity = 1000;
    })
    .await
}

/// `mpsfsi worker` on `url`, its log in `data/worker.log`.
pub fn worker_process(url: &str, data: &Path, lease_s: f64) -> Child {
    worker_process_with(url, data, lease_s, &[])
}

/// The same with more flags.
fn worker_process_with(url: &str, data: &Path, lease_s: f64, flags: &[&str]) -> Child {
    let log = std::fs::File::create(data.join("worker.log")).unwrap();
    Command::new(env!("CARGO_BIN_EXE_mpsfsi"))
        .args(["worker", "--database", url, "--data"])
        .arg(data)
        .args(["--lease-s", &lease_s.to_string()])
        .args(flags)
        .stdout(Stdio::null())
        .stderr(log)
        .spawn()
        .expect("worker process starts")
}

pub fn stop(mut child: Child) {
    let _ = child.kill();
    let _ = child.wait();
}

/// Send a worker SIGTERM and wait for it: it must exit cleanly (status 0).
pub fn terminate(child: &mut Child) {
    let term = Command::new("kill")
        .args(["-TERM", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(term.success());
    assert!(child.wait().unwrap().success(), "the worker exits cleanly");
}

/// Rows of a loads CSV per (time, object) text: each must appear once.
fn load_rows(csv: &str) -> BTreeMap<(String, String), usize> {
    let mut rows = BTreeMap::new();
    for line in csv.lines().skip(1) {
        let mut fields = line.split(',');
        let key = (
            fields.next().unwrap().to_string(),
            fields.next().unwrap().to_string(),
        );
        *rows.entry(key).or_insert(0) += 1;
    }
    rows
}

async fn wait_rows(api: &Api, id: &str, at_least: usize) -> usize {
    let start = Instant::now();
    loop {
        let (_, _, csv) = api.get_csv(&format!("/v1/jobs/{id}/loads")).await;
        let n = csv.lines().count().saturating_sub(1);
        if n >= at_least {
            return n;
        }
        assert!(
            start.elapsed() < Duration::from_secs(60),
            "no loads for {id}"
        );
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_job_submitted_to_one_node_is_served_by_another_while_it_runs_and_after() {
    let Some(pg) = PgServer::start_or_skip("node_to_node").await else {
        return;
    };
    let url = pg.fresh_database().await;
    let a = node(&url, "pg-a").await;
    let b = node(&url, "pg-b").await;
    let (_, health) = b.get_json("/v1/health").await;
    assert_eq!(health["workers"], 0, "{health}");
    let data = fresh_data_dir("pg-worker");
    let worker = worker_process(&url, &data, 3.0);

    let id = a.submit(&tiny_case(1.0)).await;
    // partial loads on the node that did not take the submission
    let partial = wait_rows(&b, &id, 1).await;
    let job = b.job(&id).await;
    assert!(partial >= 1);
    let finished = b.wait_finished(&id).await;
    assert_eq!(finished["status"], "succeeded", "{finished}");
    assert_eq!(finished["attempts"], 1);
    assert_eq!(finished["summary"]["status"], "succeeded");
    let run_dir = finished["run_dir"].as_str().unwrap();
    assert!(run_dir.starts_with(data.to_str().unwrap()), "{run_dir}");
    // the worker removes its directory just after it records the outcome
    let removed = wait_until(Duration::from_secs(10), || !Path::new(run_dir).exists()).await;
    stop(worker);
    assert!(
        removed,
        "the worker removed its run directory once the store held everything"
    );
    assert!(job["worker"].as_str().unwrap().contains(':'), "{job}");

    // every node serves the same complete loads: one row per 1 ms sample and object
    let (_, _, from_a) = a.get_csv(&format!("/v1/jobs/{id}/loads")).await;
    let (_, _, from_b) = b.get_csv(&format!("/v1/jobs/{id}/loads")).await;
    assert_eq!(from_a, from_b);
    let rows = load_rows(&from_a);
    assert_eq!(rows.len(), 1000, "1 s at 1 ms, one wall");
    assert!(rows.values().all(|&n| n == 1));
    let (status, probes) = a.get_json(&format!("/v1/jobs/{id}/probes")).await;
    assert_eq!(status, 200);
    assert_eq!(
        probes["probes"]["mid"]["time"].as_array().unwrap().len(),
        1000
    );
    // neither node shares a disk with the worker, whose directory is gone: the
    // snapshots come from the store, the same pictures on both
    let svg = a
        .get_svg(&format!("/v1/jobs/{id}/snapshot.svg?time=0.5"))
        .await;
    assert!(svg.starts_with("<svg"), "{}", &svg[..svg.len().min(200)]);
    assert_eq!(
        svg,
        b.get_svg(&format!("/v1/jobs/{id}/snapshot.svg?time=0.5"))
            .await
    );
    let surface = b
        .get_svg(&format!("/v1/jobs/{id}/surface.svg?body=tank"))
        .await;
    assert!(
        surface.starts_with("<svg"),
        "{}",
        &surface[..surface.len().min(200)]
    );
    a.stop().await;
    b.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_queued_job_s_page_on_another_node_carries_its_advice() {
    let Some(pg) = PgServer::start_or_skip("page_advice").await else {
        return;
    };
    let url = pg.fresh_database().await;
    let a = node(&url, "pg-advice-a").await;
    let b = node(&url, "pg-advice-b").await;
    // advised, and no worker runs it
    let id = a.submit(&advised_wedge()).await;
    assert_eq!(b.job(&id).await["status"], "queued");
    let page = b.page(&id).await;
    let list = advice_on_page(&page);
    assert!(list.contains("25 spacings across"), "{list}");
    a.stop().await;
    b.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_worker_killed_mid_job_loses_it_to_another_and_the_job_succeeds_once() {
    let Some(pg) = PgServer::start_or_skip("killed_worker").await else {
        return;
    };
    let url = pg.fresh_database().await;
    let api = node(&url, "pg-kill").await;
    let lease_s = 1.5;
    let first_data = fresh_data_dir("pg-w1");
    let mut first = worker_process(&url, &first_data, lease_s);
    let id = api.submit(&tiny_case(3.0)).await;
    api.wait_running(&id).await;
    wait_rows(&api, &id, 1).await;
    first.kill().unwrap(); // SIGKILL: the lease is not given back
    first.wait().unwrap();
    let killed_at = Instant::now();

    let second_data = fresh_data_dir("pg-w2");
    let second = worker_process(&url, &second_data, lease_s);
    let pid = second.id();
    let job = api
        .wait_for(&id, Duration::from_secs(90), |j| {
            j["status"] != "running" || j["attempts"] == 2
        })
        .await;
    assert_eq!(job["attempts"], 2, "{job}");
    let reclaimed_after = killed_at.elapsed().as_secs_f64();
    eprintln!("killed worker's job claimed again after {reclaimed_after:.2} s (lease {lease_s} s)");
    assert!(
        reclaimed_after >= lease_s * 0.5,
        "claimed again after {reclaimed_after} s"
    );
    let job = api.wait_finished(&id).await;
    stop(second);
    assert_eq!(job["status"], "succeeded", "{job}");
    assert_eq!(job["attempts"], 2);
    assert!(
        job["worker"]
            .as_str()
            .unwrap()
            .ends_with(&format!(":{pid}")),
        "{job}"
    );
    let (_, list) = api.get_json("/v1/jobs?status=succeeded").await;
    assert_eq!(list["total"], 1, "{list}");

    // one set of loads: the killed attempt's rows were discarded
    let (_, _, loads) = api.get_csv(&format!("/v1/jobs/{id}/loads")).await;
    let rows = load_rows(&loads);
    assert_eq!(rows.len(), 3000, "3 s at 1 ms, one wall");
    assert!(rows.values().all(|&n| n == 1), "a sample appears twice");
    api.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn two_hundred_concurrent_submissions_across_two_nodes_are_kept_once_each() {
    let Some(pg) = PgServer::start_or_skip("burst").await else {
        return;
    };
    let url = pg.fresh_database().await;
    let nodes = [
        node(&url, "pg-burst-a").await,
        node(&url, "pg-burst-b").await,
    ];
    let mut tasks = Vec::new();
    for i in 0..200 {
        let address = nodes[i % 2].address.clone();
        tasks.push(tokio::spawn(async move {
            let api = Api {
                address,
                client: reqwest::Client::new(),
            };
            let r = api.post_case(&tiny_case(0.01)).await;
            let status = r.status().as_u16();
            let body: Value = r.json().await.unwrap();
            assert_eq!(status, 201, "{body}");
            body["id"].as_str().unwrap().to_string()
        }));
    }
    let mut submitted = HashSet::new();
    for t in tasks {
        assert!(
            submitted.insert(t.await.unwrap()),
            "an id was returned twice"
        );
    }
    assert_eq!(submitted.len(), 200);
    for n in &nodes {
        let (_, list) = n.get_json("/v1/jobs?limit=1000&status=queued").await;
        assert_eq!(list["total"], 200, "{}", list["total"]);
        let listed: HashSet<String> = list["jobs"]
            .as_array()
            .unwrap()
            .iter()
            .map(|j| j["id"].as_str().unwrap().to_string())
            .collect();
        assert_eq!(listed, submitted);
    }
    for n in nodes {
        n.stop().await;
    }
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_job_whose_worker_dies_every_time_fails_with_attempts_exhausted() {
    let Some(pg) = PgServer::start_or_skip("attempts").await else {
        return;
    };
    let url = pg.fresh_database().await;
    let store = JobStore::open(&url).await.unwrap();
    let id = uuid::Uuid::new_v4();
    let case = serde_json::to_string(&tiny_case(0.01)).unwrap();
    store
        .submit(id, "tiny-tank", &case, 0.01, None, 10)
        .await
        .unwrap();
    // a claimant that never renews: its lease runs out as a killed worker's would
    let dies = Claimant {
        worker: "doomed:1".into(),
        jobs_dir: "/nowhere/".into(),
        lease_s: 0.3,
        max_attempts: 2,
    };
    let first = store
        .claim_next(&dies, None)
        .await
        .unwrap()
        .expect("claimed");
    assert_eq!(first.attempt(), 1);
    assert!(
        store.claim_next(&dies, None).await.unwrap().is_none(),
        "the lease still holds"
    );
    tokio::time::sleep(Duration::from_millis(500)).await;
    let second = store
        .claim_next(&dies, None)
        .await
        .unwrap()
        .expect("claimed again");
    assert_eq!(second.attempt(), 2);
    // the first attempt can no longer write
    let late = store
        .finish(id, 1, JobStatus::Succeeded, None, None, 10, 0.01)
        .await
        .unwrap();
    assert!(!late, "a stale attempt recorded its outcome");
    tokio::time::sleep(Duration::from_millis(500)).await;
    assert!(store.claim_next(&dies, None).await.unwrap().is_none());
    let row = store.get(id).await.unwrap().unwrap();
    assert_eq!(row.status, JobStatus::Failed);
    assert_eq!(row.reason.as_deref(), Some(ATTEMPTS_EXHAUSTED));
    assert_eq!(row.attempts, 2);
    store.close().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_cancel_on_a_node_stops_the_job_on_a_worker_process_within_a_renewal() {
    let Some(pg) = PgServer::start_or_skip("cancel").await else {
        return;
    };
    let url = pg.fresh_database().await;
    let api = node(&url, "pg-cancel").await;
    let lease_s = 1.5;
    let data = fresh_data_dir("pg-cancel-worker");
    let worker = worker_process(&url, &data, lease_s);
    let id = api.submit(&long_case()).await;
    api.wait_running(&id).await;
    let asked = Instant::now();
    let r = api
        .client
        .post(api.url(&format!("/v1/jobs/{id}/cancel")))
        .send()
        .await
        .unwrap();
    assert_eq!(r.status().as_u16(), 202);
    let job = api.wait_finished(&id).await;
    let took = asked.elapsed().as_secs_f64();
    eprintln!(
        "cancelled {took:.2} s after the request (renewal every {:.2} s)",
        lease_s / 3.0
    );
    stop(worker);
    assert_eq!(job["status"], "cancelled", "{job}");
    assert_eq!(job["reason"], "cancelled by request");
    assert_eq!(job["summary"]["status"], "cancelled");
    // one renewal interval (lease / 3) plus a step, plus the polling of this test
    assert!(took < lease_s / 3.0 + 1.0, "cancelled after {took:.2} s");
    api.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_delete_on_a_node_stops_the_job_on_a_worker_process_which_removes_its_files() {
    let Some(pg) = PgServer::start_or_skip("delete").await else {
        return;
    };
    let url = pg.fresh_database().await;
    let api = node(&url, "pg-delete").await;
    let lease_s = 1.5;
    let data = fresh_data_dir("pg-delete-worker");
    let worker = worker_process(&url, &data, lease_s);
    let id = api.submit(&long_case()).await;
    api.wait_running(&id).await;
    wait_rows(&api, &id, 1).await;
    let dir = data.join("jobs").join(&id);
    assert!(dir.is_dir());

    let r = api
        .client
        .delete(api.url(&format!("/v1/jobs/{id}")))
        .send()
        .await
        .unwrap();
    assert_eq!(r.status().as_u16(), 204);
    // the worker stops at its next renewal and removes its run directory
    let asked = Instant::now();
    while dir.exists() {
        assert!(
            asked.elapsed() < Duration::from_secs(10),
            "{} is left",
            dir.display()
        );
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
    // it is free for the next job, and nothing of the deleted one comes back
    let next = api.submit(&tiny_case(0.002)).await;
    assert_eq!(api.wait_finished(&next).await["status"], "succeeded");
    stop(worker);
    for route in ["", "/loads", "/bodies", "/probes", "/loads.svg"] {
        let (status, body) = api.get_json(&format!("/v1/jobs/{id}{route}")).await;
        assert_eq!(status, 404, "GET {route}: {body}");
    }
    let store = JobStore::open(&url).await.unwrap();
    assert!(store.get(id.parse().unwrap()).await.unwrap().is_none());
    let JobStore::Postgres(pg_store) = &store else {
        unreachable!("a Postgres URL")
    };
    for file in ["loads.csv", "bodies.csv", "probes.csv"] {
        let id = id.parse().unwrap();
        assert!(
            pg_store.read_series(id, file).await.unwrap().is_empty(),
            "{file}"
        );
    }
    let log = std::fs::read_to_string(data.join("worker.log")).unwrap();
    assert!(log.contains("the job was deleted"), "{log}");
    assert!(!log.contains("ERROR") && !log.contains("WARN"), "{log}");
    store.close().await;
    api.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_worker_stopped_with_sigterm_gives_its_job_back_at_once() {
    let Some(pg) = PgServer::start_or_skip("sigterm").await else {
        return;
    };
    let url = pg.fresh_database().await;
    let api = node(&url, "pg-term").await;
    let lease_s = 30.0; // long: the job must come back without waiting for it
    let data = fresh_data_dir("pg-term-w1");
    let mut first = worker_process_with(&url, &data, lease_s, &["--shutdown-grace-s", "0"]);
    let id = api.submit(&tiny_case(2.0)).await;
    api.wait_running(&id).await;
    terminate(&mut first);
    let job = api.job(&id).await;
    assert_eq!(job["status"], "queued", "{job}");

    let second = worker_process(&url, &fresh_data_dir("pg-term-w2"), lease_s);
    let job = api.wait_finished(&id).await;
    stop(second);
    assert_eq!(job["status"], "succeeded", "{job}");
    assert_eq!(job["attempts"], 2);
    let (_, _, loads) = api.get_csv(&format!("/v1/jobs/{id}/loads")).await;
    let rows = load_rows(&loads);
    assert_eq!(rows.len(), 2000);
    assert!(rows.values().all(|&n| n == 1));
    api.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn two_nodes_two_workers_twelve_jobs_and_a_worker_killed_all_succeed_once() {
    let Some(pg) = PgServer::start_or_skip("twelve").await else {
        return;
    };
    let url = pg.fresh_database().await;
    let nodes = [node(&url, "pg-12-a").await, node(&url, "pg-12-b").await];
    let lease_s = 1.5;
    let mut doomed = worker_process(&url, &fresh_data_dir("pg-12-w1"), lease_s);
    let survivor = worker_process(&url, &fresh_data_dir("pg-12-w2"), lease_s);
    let mut ids = Vec::new();
    for i in 0..12 {
        ids.push(nodes[i % 2].submit(&tiny_case(0.5)).await);
    }
    // kill the first worker while it runs a job that has written loads
    let marker = format!(":{}", doomed.id());
    let start = Instant::now();
    let victim = 'found: loop {
        for id in &ids {
            let job = nodes[0].job(id).await;
            let mine = job["worker"].as_str().is_some_and(|w| w.ends_with(&marker));
            if job["status"] == "running" && mine && job["progress"]["step"].as_u64() > Some(50) {
                break 'found id.clone();
            }
        }
        assert!(
            start.elapsed() < Duration::from_secs(60),
            "the first worker ran nothing"
        );
        tokio::time::sleep(Duration::from_millis(10)).await;
    };
    doomed.kill().unwrap();
    doomed.wait().unwrap();

    for id in &ids {
        let job = nodes[0]
            .wait_for(id, Duration::from_secs(120), |j| {
                j["status"] == "succeeded" || j["status"] == "failed"
            })
            .await;
        assert_eq!(job["status"], "succeeded", "{job}");
        let expected_attempts = if *id == victim { 2 } else { 1 };
        assert_eq!(job["attempts"], expected_attempts, "{job}");
        let (_, _, from_a) = nodes[0].get_csv(&format!("/v1/jobs/{id}/loads")).await;
        let (_, _, from_b) = nodes[1].get_csv(&format!("/v1/jobs/{id}/loads")).await;
        assert_eq!(from_a, from_b, "job {id} reads the same on both nodes");
        let rows = load_rows(&from_a);
        assert_eq!(rows.len(), 500, "job {id}: 0.5 s at 1 ms");
        assert!(
            rows.values().all(|&n| n == 1),
            "job {id}: a sample appears twice"
        );
        assert_eq!(nodes[1].job(id).await["status"], "succeeded");
    }
    stop(survivor);
    let (_, list) = nodes[1]
        .get_json("/v1/jobs?status=succeeded&limit=100")
        .await;
    assert_eq!(list["total"], 12);
    for n in nodes {
        n.stop().await;
    }
}

#[test]
fn a_database_url_prints_without_its_password() {
    let url = DatabaseUrl::new("postgres://mpsfsi:hunter2@db.example:5432/jobs?sslmode=disable");
    assert_eq!(
        url.redacted(),
        "postgres://mpsfsi:***@db.example:5432/jobs?sslmode=disable"
    );
    assert_eq!(url.password(), Some("hunter2"));
    let mut config = mpsfsi::service::Config::for_tests("/tmp/x");
    config.database = Some(url.clone());
    assert!(!format!("{config:?}").contains("hunter2"));
    assert!(!format!("{url}").contains("hunter2"));
    let param =
        DatabaseUrl::new("postgres://db.example/jobs?user=a&password=hunter2&sslmode=require");
    assert_eq!(
        param.redacted(),
        "postgres://db.example/jobs?user=a&password=***&sslmode=require"
    );
    assert_eq!(param.scrub("x hunter2 y"), "x *** y");
    let none = DatabaseUrl::new("postgres://mpsfsi@db.example/jobs");
    assert_eq!(none.redacted(), "postgres://mpsfsi@db.example/jobs");
    assert_eq!(none.password(), None);
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_database_password_never_appears_in_logs_errors_or_the_health_route() {
    let Some(pg) = PgServer::start_or_skip("password").await else {
        return;
    };
    const SECRET: &str = "pw-7f3a9c-never-shown";
    let url = pg.fresh_database().await;
    let with_password = url.replacen("postgres@", &format!("postgres:{SECRET}@"), 1);
    let missing_db = format!(
        "postgres://postgres:{SECRET}@127.0.0.1:{}/no_such_database",
        pg.port
    );

    // a node that cannot open its database: the error names it without the password
    let out = Command::new(env!("CARGO_BIN_EXE_mpsfsi"))
        .args([
            "serve",
            "--addr",
            "127.0.0.1:0",
            "--database",
            &missing_db,
            "--data",
        ])
        .arg(fresh_data_dir("pg-pw-bad"))
        .output()
        .unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(!out.status.success());
    assert!(stderr.contains("no_such_database"), "{stderr}");
    assert!(stderr.contains("***"), "{stderr}");
    assert!(!stderr.contains(SECRET), "{stderr}");

    // a worker's log (info level: it names its database) and a node's health route
    let data = fresh_data_dir("pg-pw-worker");
    let worker = Command::new(env!("CARGO_BIN_EXE_mpsfsi"))
        .args(["worker", "--database", &with_password, "--data"])
        .arg(&data)
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let api = node(&with_password, "pg-pw-node").await;
    let id = api.submit(&tiny_case(0.05)).await;
    let job = api.wait_finished(&id).await;
    assert_eq!(job["status"], "succeeded", "{job}");
    let (_, health) = api.get_json("/v1/health").await;
    assert!(!health.to_string().contains(SECRET), "{health}");
    assert!(!job.to_string().contains(SECRET), "{job}");
    let _ = Command::new("kill")
        .args(["-TERM", &worker.id().to_string()])
        .status();
    let out = worker.wait_with_output().unwrap();
    let log = String::from_utf8_lossy(&out.stderr);
    assert!(log.contains("mpsfsi worker running"), "{log}");
    assert!(log.contains("***"), "{log}");
    assert!(!log.contains(SECRET), "{log}");
    api.stop().await;
}

/// Poll `done` every 50 ms until it holds or `limit` passes; whether it held.
async fn wait_until(limit: Duration, done: impl Fn() -> bool) -> bool {
    let start = Instant::now();
    while !done() {
        if start.elapsed() > limit {
            return false;
        }
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
    true
}
