//! Cancellation of running and queued jobs, and the bounded queue.

use crate::helpers::{cancel_running, long_case, spawn_app, tiny_case};
use crate::schema::assert_conforms;
use serde_json::Value;

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn cancelling_a_running_job_stops_it_and_keeps_its_files() {
    let app = spawn_app("cancel", |c| c.workers = 1).await;
    let id = app.submit(&long_case()).await;
    let running = app.wait_running(&id).await;
    assert!(running["particles"].as_u64().unwrap() > 0);

    cancel_running(&app, &id).await;

    let job = app.wait_finished(&id).await;
    assert_eq!(job["status"], "cancelled", "{job:#}");
    assert_eq!(job["summary"]["status"], "cancelled");
    let steps = job["summary"]["steps"].as_u64().unwrap();
    assert!(
        steps > 0 && job["progress"]["fraction"].as_f64().unwrap() < 0.5,
        "{job:#}"
    );
    // What it wrote is kept and served.
    let (status, _, csv) = app.get_csv(&format!("/v1/jobs/{id}/loads")).await;
    assert_eq!(status, 200);
    let on_disk =
        std::fs::read_to_string(app.data_dir.join("jobs").join(&id).join("loads.csv")).unwrap();
    assert_eq!(csv, on_disk);
    // The worker is free again.
    let next = app.submit(&tiny_case(0.002)).await;
    assert_eq!(app.wait_finished(&next).await["status"], "succeeded");
    app.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_full_queue_answers_503_with_retry_after() {
    let app = spawn_app("queue", |c| {
        c.workers = 1;
        c.queue_capacity = 1;
    })
    .await;
    let running = app.submit(&long_case()).await;
    app.wait_running(&running).await;
    let queued = app.submit(&tiny_case(0.002)).await;

    let r = app.post_case(&tiny_case(0.002)).await;
    assert_eq!(r.status().as_u16(), 503);
    let retry_after: u64 = r.headers()["retry-after"]
        .to_str()
        .unwrap()
        .parse()
        .unwrap();
    assert!(retry_after > 0);
    let body: Value = r.json().await.unwrap();
    assert_conforms("POST", "/v1/jobs", 503, &body);
    assert_eq!(body["error"]["code"], "queue_full");

    // Partial results of the running job are served while it runs.
    let (status, loads) = app.get_json(&format!("/v1/jobs/{running}/loads")).await;
    assert_eq!(status, 200);
    assert_eq!(loads["status"], "running");

    // A queued job is cancelled at once, which frees its place.
    let r = app
        .client
        .post(app.url(&format!("/v1/jobs/{queued}/cancel")))
        .send()
        .await
        .unwrap();
    assert_eq!(r.status().as_u16(), 200);
    let body: Value = r.json().await.unwrap();
    assert_conforms("POST", "/v1/jobs/{id}/cancel", 200, &body);
    assert_eq!(body["status"], "cancelled");
    let again = app.submit(&tiny_case(0.002)).await;

    cancel_running(&app, &running).await;
    assert_eq!(app.wait_finished(&running).await["status"], "cancelled");
    assert_eq!(app.wait_finished(&again).await["status"], "succeeded");
    assert_eq!(app.job(&queued).await["status"], "cancelled");
    app.stop().await;
}
