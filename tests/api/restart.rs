//! Persistence across restarts: a server process killed (SIGKILL) mid-job, and a graceful
//! shutdown mid-job, both restarted on the same data directory.

use crate::helpers::{free_port, fresh_data_dir, long_case, spawn_app_on, tiny_case, Api};
use mpsfsi::service::{serve, Config};
use std::path::Path;
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// Run by [`a_killed_server_restarts_with_finished_jobs_intact`] as a child process when
/// the binary has no `serve` subcommand: `MPSFSI_*` variables configure it.
#[test]
#[ignore = "a server process for the restart test"]
fn child_server() {
    if std::env::var("MPSFSI_TEST_CHILD").is_err() {
        return;
    }
    #[derive(clap::Parser)]
    struct Args {
        #[command(flatten)]
        config: Config,
    }
    let args = <Args as clap::Parser>::parse_from(["child_server"]);
    let runtime = tokio::runtime::Runtime::new().unwrap();
    runtime.block_on(serve(args.config)).unwrap();
}

/// `mpsfsi serve` when the binary has it, else this test binary's [`child_server`];
/// returns once the server answers `/v1/health`.
async fn spawn_server_process(data: &Path, port: u16, api: &Api) -> Child {
    let addr = format!("127.0.0.1:{port}");
    let mut real = Command::new(env!("CARGO_BIN_EXE_mpsfsi"));
    real.args(["serve", "--addr", &addr, "--data"])
        .arg(data)
        .args(["--workers", "1"]);
    let mut fallback = Command::new(std::env::current_exe().unwrap());
    fallback
        .args([
            "restart::child_server",
            "--exact",
            "--ignored",
            "--nocapture",
        ])
        .env("MPSFSI_TEST_CHILD", "1")
        .env("MPSFSI_ADDR", &addr)
        .env("MPSFSI_DATA", data)
        .env("MPSFSI_WORKERS", "1");
    for mut cmd in [real, fallback] {
        let mut child = cmd
            .stdout(Stdio::null())
            .stderr(Stdio::null())
            .spawn()
            .expect("server process starts");
        let start = Instant::now();
        loop {
            if let Ok(r) = api.client.get(api.url("/v1/health")).send().await {
                if r.status().is_success() {
                    return child;
                }
            }
            if child.try_wait().unwrap().is_some() {
                break; // this binary has no working `serve`: try the next command
            }
            assert!(
                start.elapsed() < Duration::from_secs(30),
                "server did not come up"
            );
            tokio::time::sleep(Duration::from_millis(50)).await;
        }
    }
    panic!("no server process could be started");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_killed_server_restarts_with_finished_jobs_intact() {
    let data = fresh_data_dir("killed");
    let port = free_port();
    let api = Api {
        address: format!("http://127.0.0.1:{port}"),
        client: reqwest::Client::new(),
    };
    let mut child = spawn_server_process(&data, port, &api).await;

    let finished = api.submit(&tiny_case(0.005)).await;
    assert_eq!(api.wait_finished(&finished).await["status"], "succeeded");
    let (_, _, loads_before) = api.get_csv(&format!("/v1/jobs/{finished}/loads")).await;
    let interrupted = api.submit(&long_case()).await;
    api.wait_running(&interrupted).await;
    let waiting = api.submit(&tiny_case(0.002)).await;
    assert_eq!(api.job(&waiting).await["status"], "queued");

    child.kill().unwrap(); // SIGKILL: no chance to clean up
    child.wait().unwrap();

    let app = spawn_app_on(data, |c| c.workers = 1).await;
    let job = app.job(&finished).await;
    assert_eq!(job["status"], "succeeded");
    assert_eq!(job["summary"]["status"], "succeeded");
    let (status, _, loads_after) = app.get_csv(&format!("/v1/jobs/{finished}/loads")).await;
    assert_eq!(status, 200);
    assert_eq!(loads_after, loads_before);

    let job = app.job(&interrupted).await;
    assert_eq!(job["status"], "failed", "{job:#}");
    assert_eq!(job["reason"], "interrupted");
    assert!(job["finished_at"].is_string());
    let (status, _, partial) = app.get_csv(&format!("/v1/jobs/{interrupted}/loads")).await;
    assert_eq!(status, 200);
    assert!(partial.starts_with(mpsfsi::output::LOADS_HEADER));

    // The queued job was re-queued and runs.
    assert_eq!(app.wait_finished(&waiting).await["status"], "succeeded");
    let (_, list) = app.get_json("/v1/jobs").await;
    assert_eq!(list["total"], 3);
    app.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_graceful_shutdown_interrupts_running_jobs_and_keeps_queued_ones() {
    let data = fresh_data_dir("graceful");
    let app = spawn_app_on(data.clone(), |c| c.workers = 1).await;
    let running = app.submit(&long_case()).await;
    app.wait_running(&running).await;
    let waiting = app.submit(&tiny_case(0.002)).await;
    let started = Instant::now();
    app.stop().await;
    assert!(
        started.elapsed() < Duration::from_secs(20),
        "shutdown took {:?}",
        started.elapsed()
    );

    let app = spawn_app_on(data.clone(), |c| c.workers = 1).await;
    let job = app.job(&running).await;
    assert_eq!(job["status"], "failed", "{job:#}");
    assert_eq!(job["reason"], "interrupted");
    // the run's own summary.json, as served and on disk, says the same as the record
    assert_eq!(job["summary"]["status"], "failed", "{job:#}");
    assert_eq!(job["summary"]["reason"], "interrupted", "{job:#}");
    let path = data.join("jobs").join(&running).join("summary.json");
    let on_disk: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&path).expect("summary.json")).unwrap();
    assert_eq!(on_disk["status"], "failed", "{on_disk:#}");
    assert_eq!(on_disk["reason"], "interrupted", "{on_disk:#}");
    assert!(
        on_disk["simulated_time"].as_f64().unwrap() > 0.0,
        "{on_disk:#}"
    );
    assert_eq!(app.wait_finished(&waiting).await["status"], "succeeded");
    app.stop().await;
}

/// A data directory written before the job table was migrated by sqlx (no migration
/// table, no `attempts` column) opens, keeps its jobs and runs new ones.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_job_database_from_before_migrations_is_upgraded_in_place() {
    let data = fresh_data_dir("upgrade");
    let url = format!("sqlite://{}?mode=rwc", data.join("jobs.db").display());
    let old = sqlx::SqlitePool::connect(&url).await.unwrap();
    sqlx::raw_sql(
        "CREATE TABLE jobs (
            seq INTEGER PRIMARY KEY AUTOINCREMENT, id TEXT NOT NULL UNIQUE, name TEXT NOT NULL,
            status TEXT NOT NULL, case_json TEXT NOT NULL, created_at TEXT NOT NULL,
            started_at TEXT, finished_at TEXT, step INTEGER NOT NULL DEFAULT 0,
            simulated_time REAL NOT NULL DEFAULT 0, end_time REAL NOT NULL, particles INTEGER,
            reason TEXT, summary TEXT);
         CREATE INDEX jobs_by_status ON jobs (status, seq);
         INSERT INTO jobs (id, name, status, case_json, created_at, finished_at, step,
                           simulated_time, end_time, particles)
         VALUES ('0b7e9f3c-4a51-4c1e-9d2f-6f0e8a1b2c3d', 'old-tank', 'succeeded', '{}',
                 '2026-11-01T00:00:00Z', '2026-11-01T00:01:00Z', 40, 0.02, 0.02, 300);",
    )
    .execute(&old)
    .await
    .unwrap();
    old.close().await;

    let app = spawn_app_on(data, |c| c.workers = 1).await;
    let job = app.job("0b7e9f3c-4a51-4c1e-9d2f-6f0e8a1b2c3d").await;
    assert_eq!(job["status"], "succeeded", "{job}");
    assert_eq!(job["name"], "old-tank");
    assert_eq!(job["attempts"], 0);
    assert_eq!(job["progress"]["step"], 40);
    let new = app.submit(&tiny_case(0.002)).await;
    let done = app.wait_finished(&new).await;
    assert_eq!(done["status"], "succeeded", "{done}");
    assert_eq!(done["attempts"], 1);
    app.stop().await;
}
