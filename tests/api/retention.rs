//! Retention (`serve --keep-days D`): at start-up (and every hour) a job that ended more
//! than D days ago is removed with its run directory and stored rows, as DELETE removes
//! it; a recent one, a running one and a queued one are kept, however old. On SQLite and
//! on a throwaway Postgres; the finish times are moved back in the database itself.

use crate::helpers::{fresh_data_dir, spawn_app_on, tiny_case, TestApp};
use crate::pg_server::PgServer;
use mpsfsi::service::store::{Admission, Claimant, JobStore};
use mpsfsi::service::DatabaseUrl;
use std::path::Path;
use std::time::{Duration, Instant};
use uuid::Uuid;

/// 30 days ago, as the records write times.
fn long_ago() -> String {
    let t = time::OffsetDateTime::now_utc() - time::Duration::days(30);
    t.format(&time::format_description::well_known::Rfc3339)
        .unwrap()
}

/// Run `sql` with `$1` = a time and `$2` = a job id on the job database at `url`.
async fn set_time(url: &str, sql: &str, at: &str, id: &str) {
    if url.starts_with("postgres") {
        let pool = sqlx::PgPool::connect(url).await.unwrap();
        let done = sqlx::query(sql).bind(at).bind(id).execute(&pool).await;
        assert_eq!(done.unwrap().rows_affected(), 1, "{sql}");
        pool.close().await;
    } else {
        let pool = sqlx::SqlitePool::connect(url).await.unwrap();
        let done = sqlx::query(sql).bind(at).bind(id).execute(&pool).await;
        assert_eq!(done.unwrap().rows_affected(), 1, "{sql}");
        pool.close().await;
    }
}

/// Rows of uploaded run files job `id` has in Postgres.
/// Rows of job `id` in a Postgres table of run files (`job_series`, `job_files`).
async fn stored_rows(url: &str, table: &str, id: &str) -> i64 {
    let pool = sqlx::PgPool::connect(url).await.unwrap();
    let sql = format!("SELECT COUNT(*) FROM {table} WHERE job_id = $1");
    let n: i64 = sqlx::query_scalar(&sql)
        .bind(id)
        .fetch_one(&pool)
        .await
        .unwrap();
    pool.close().await;
    n
}

async fn status_of(app: &TestApp, id: &str) -> u16 {
    app.get_json(&format!("/v1/jobs/{id}")).await.0
}

/// A job queued and one claimed through the store, as if long ago: ids (queued, running).
async fn queued_and_running(url: &str) -> (String, String) {
    let store = JobStore::open(url).await.unwrap();
    let mut ids = Vec::new();
    for name in ["running", "queued"] {
        let id = Uuid::new_v4();
        let case = format!("{{\"name\": \"{name}\"}}");
        let admitted = store.submit(id, name, &case, 1.0, None, 100).await.unwrap();
        assert!(matches!(admitted, Admission::Accepted(_)));
        if name == "running" {
            let claimant = Claimant {
                worker: "elsewhere:1".into(),
                jobs_dir: "/elsewhere/jobs/".into(),
                lease_s: 3600.0,
                max_attempts: 3,
            };
            let claimed = store.claim_next(&claimant, None).await.unwrap().unwrap();
            assert_eq!(claimed.row.id, id);
        }
        ids.push(id.to_string());
    }
    store.close().await;
    for id in &ids {
        let sql = "UPDATE jobs SET created_at = $1, started_at = $1 WHERE id = $2";
        set_time(url, sql, &long_ago(), id).await;
    }
    (ids[1].clone(), ids[0].clone())
}

async fn old_jobs_go_with_their_files_and_the_others_stay(database: Option<String>, tag: &str) {
    let data = fresh_data_dir(tag);
    let url = database
        .clone()
        .unwrap_or_else(|| format!("sqlite://{}?mode=rwc", data.join("jobs.db").display()));
    let configure = |workers: usize, keep_days: Option<f64>| {
        let database = database.clone();
        move |c: &mut mpsfsi::service::Config| {
            c.database = database.map(DatabaseUrl::new);
            c.workers = workers;
            c.keep_days = keep_days;
        }
    };
    let app = spawn_app_on(data.clone(), configure(1, None)).await;
    let old = app.submit(&tiny_case(0.002)).await;
    let recent = app.submit(&tiny_case(0.002)).await;
    for id in [&old, &recent] {
        assert_eq!(app.wait_finished(id).await["status"], "succeeded");
    }
    app.stop().await;
    let dir = |id: &str| data.join("jobs").join(id);
    let shared = database.is_some();
    // with Postgres the store holds everything and the worker removed its directory
    assert_eq!(dir(&old).join("loads.csv").is_file(), !shared);
    assert_eq!(dir(&recent).is_dir(), !shared);
    if shared {
        for table in ["job_series", "job_files"] {
            assert!(stored_rows(&url, table, &old).await > 0, "{table}");
        }
    }
    let sql = "UPDATE jobs SET finished_at = $1 WHERE id = $2";
    set_time(&url, sql, &long_ago(), &old).await;
    let (queued, running) = queued_and_running(&url).await;

    let app = spawn_app_on(data.clone(), configure(0, Some(7.0))).await;
    // the sweep removes the record, then the directory (the same path as DELETE): wait
    // for both, within the same 20 s
    let start = Instant::now();
    while status_of(&app, &old).await != 404 || dir(&old).exists() {
        assert!(
            start.elapsed() < Duration::from_secs(20),
            "the old job is still there (status {}), or {} is left",
            status_of(&app, &old).await,
            dir(&old).display()
        );
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
    if shared {
        for table in ["job_series", "job_files"] {
            let left = stored_rows(&url, table, &old).await;
            assert_eq!(left, 0, "its uploaded rows are left in {table}");
            assert!(stored_rows(&url, table, &recent).await > 0, "{table}");
        }
    } else {
        assert!(dir(&recent).join("loads.csv").is_file());
    }
    assert_eq!(app.job(&recent).await["status"], "succeeded");
    let (_, _, csv) = app.get_csv(&format!("/v1/jobs/{recent}/loads")).await;
    assert!(csv.lines().count() > 1, "{csv}");
    assert_eq!(app.job(&queued).await["status"], "queued");
    // SQLite's restart fails a job left running (now: recent); Postgres keeps it running
    let expected = if shared { "running" } else { "failed" };
    assert_eq!(app.job(&running).await["status"], expected);
    let (_, list) = app.get_json("/v1/jobs").await;
    assert_eq!(list["total"], 3, "{list:#}");
    app.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn sqlite_retention_removes_old_finished_jobs_with_their_files() {
    old_jobs_go_with_their_files_and_the_others_stay(None, "retention-sqlite").await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn postgres_retention_removes_old_finished_jobs_with_their_files() {
    let Some(pg) = PgServer::start_or_skip("postgres_retention").await else {
        return;
    };
    let url = pg.fresh_database().await;
    old_jobs_go_with_their_files_and_the_others_stay(Some(url), "retention-pg").await;
}

/// `--keep-days` takes a positive number of days, and says so otherwise.
#[test]
fn keep_days_must_be_a_positive_number_of_days() {
    let data = fresh_data_dir("retention-flag");
    for bad in ["0", "-1", "abc", "inf", "NaN", "1e9"] {
        let out = std::process::Command::new(env!("CARGO_BIN_EXE_mpsfsi"))
            .args([
                "serve",
                "--addr",
                "127.0.0.1:0",
                &format!("--keep-days={bad}"),
                "--data",
            ])
            .arg(&data)
            .output()
            .unwrap();
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{bad}: {stderr}");
        assert!(
            stderr.contains("--keep-days") && stderr.contains("positive number of days"),
            "{bad}: {stderr}"
        );
    }
    assert!(!Path::new(&data).join("jobs.db").exists());
}

/// The sweep on an injected clock: jobs that ended just now are kept at `now + 6 days`
/// and removed, with their run directories, at `now + 8 days` (D = 7).
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_cutoff_is_the_sweep_s_clock_minus_d_days() {
    use mpsfsi::service::retention::remove_expired;
    use mpsfsi::service::workers::Jobs;
    let data = fresh_data_dir("retention-clock");
    let app = spawn_app_on(data.clone(), |c| c.workers = 1).await;
    let ids = [
        app.submit(&tiny_case(0.002)).await,
        app.submit(&tiny_case(0.002)).await,
    ];
    for id in &ids {
        assert_eq!(app.wait_finished(id).await["status"], "succeeded");
    }
    app.stop().await;
    let config = mpsfsi::service::Config::for_tests(&data);
    let store = JobStore::open(config.database_url().expose())
        .await
        .unwrap();
    let jobs = Jobs::new(store, config);
    let keep = Duration::from_secs(7 * 86_400);
    let now = time::OffsetDateTime::now_utc();
    let early = remove_expired(&jobs, keep, now + time::Duration::days(6)).await;
    assert_eq!(early.unwrap(), 0);
    let late = remove_expired(&jobs, keep, now + time::Duration::days(8)).await;
    assert_eq!(late.unwrap(), 2);
    for id in &ids {
        assert!(jobs.store.get(id.parse().unwrap()).await.unwrap().is_none());
        assert!(!data.join("jobs").join(id).exists());
    }
    jobs.store.close().await;
}
