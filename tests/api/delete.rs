//! `DELETE /v1/jobs/{id}` removes the job, its record and its files (a running job is
//! cancelled first); every route of the job answers 404 afterwards.

use crate::helpers::{long_case, spawn_app, tiny_case, TestApp};
use crate::schema::assert_conforms;
use serde_json::Value;
use std::time::{Duration, Instant};

/// Every route of the job (`""` is the job itself).
const JOB_ROUTES: [&str; 9] = [
    "",
    "/loads",
    "/loads_filtered",
    "/loads_uncertainty",
    "/bodies",
    "/probes",
    "/loads.svg",
    "/snapshot.svg",
    "/surface.svg?body=tank",
];

/// DELETE job `id`: the status and the body's bytes.
async fn delete(app: &TestApp, id: &str) -> (u16, Vec<u8>) {
    let r = app
        .client
        .delete(app.url(&format!("/v1/jobs/{id}")))
        .send()
        .await
        .unwrap();
    (r.status().as_u16(), r.bytes().await.unwrap().to_vec())
}

/// Every route of job `id` answers 404 `job_not_found`, as documented.
async fn assert_gone(app: &TestApp, id: &str) {
    for route in JOB_ROUTES {
        let (status, body) = app.get_json(&format!("/v1/jobs/{id}{route}")).await;
        assert_eq!(status, 404, "GET {route}: {body}");
        assert_eq!(body["error"]["code"], "job_not_found", "GET {route}");
        let documented = route.split('?').next().unwrap();
        assert_conforms("GET", &format!("/v1/jobs/{{id}}{documented}"), 404, &body);
    }
    let page = app
        .client
        .get(app.url(&format!("/v1/jobs/{id}")))
        .header("accept", "text/html")
        .send()
        .await
        .unwrap();
    assert_eq!(page.status().as_u16(), 404, "the job's page");
    let r = app
        .client
        .post(app.url(&format!("/v1/jobs/{id}/cancel")))
        .send()
        .await
        .unwrap();
    assert_eq!(r.status().as_u16(), 404, "POST .../cancel");
    let (status, body) = delete(app, id).await;
    assert_eq!(status, 404, "a second DELETE");
    let body: Value = serde_json::from_slice(&body).unwrap();
    assert_conforms("DELETE", "/v1/jobs/{id}", 404, &body);
    let (_, list) = app.get_json("/v1/jobs?limit=1000").await;
    assert!(
        list["jobs"]
            .as_array()
            .unwrap()
            .iter()
            .all(|j| j["id"] != id),
        "listed after its deletion: {list:#}"
    );
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn deleting_a_finished_job_removes_its_record_and_its_files() {
    let app = spawn_app("delete-finished", |c| c.workers = 1).await;
    let id = app.submit(&tiny_case(0.002)).await;
    let kept = app.submit(&tiny_case(0.002)).await;
    assert_eq!(app.wait_finished(&id).await["status"], "succeeded");
    assert_eq!(app.wait_finished(&kept).await["status"], "succeeded");
    let dir = app.data_dir.join("jobs").join(&id);
    assert!(dir.join("loads.csv").is_file());

    let (status, body) = delete(&app, &id).await;
    assert_eq!(status, 204);
    assert!(body.is_empty(), "a 204 has no body: {body:?}");
    assert_gone(&app, &id).await;
    assert!(!dir.exists(), "{} is left", dir.display());

    // the other job is untouched
    assert_eq!(app.job(&kept).await["status"], "succeeded");
    let (status, _, csv) = app.get_csv(&format!("/v1/jobs/{kept}/loads")).await;
    assert_eq!(status, 200);
    assert!(csv.lines().count() > 1, "{csv}");
    assert!(app.data_dir.join("jobs").join(&kept).is_dir());
    app.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn deleting_a_running_job_stops_it_and_nothing_of_it_reappears() {
    let app = spawn_app("delete-running", |c| {
        c.workers = 1;
        c.queue_capacity = 1;
    })
    .await;
    let running = app.submit(&long_case()).await;
    app.wait_running(&running).await;
    let dir = app.data_dir.join("jobs").join(&running);
    assert!(dir.is_dir());
    // a queued job goes at once, and frees its place in the queue
    let queued = app.submit(&tiny_case(0.002)).await;
    assert_eq!(delete(&app, &queued).await.0, 204);
    assert_gone(&app, &queued).await;
    let next = app.submit(&tiny_case(0.002)).await;

    let (status, body) = delete(&app, &running).await;
    assert_eq!(status, 204);
    assert!(body.is_empty(), "a 204 has no body: {body:?}");
    assert_gone(&app, &running).await;

    // the worker stops the run and takes the next job (there is one worker)
    assert_eq!(app.wait_finished(&next).await["status"], "succeeded");
    // its run directory goes when its run has stopped, and nothing comes back
    let start = Instant::now();
    while start.elapsed() < Duration::from_secs(2) {
        assert_gone(&app, &running).await;
        assert!(!dir.exists(), "{} is left", dir.display());
        tokio::time::sleep(Duration::from_millis(100)).await;
    }
    let (_, list) = app.get_json("/v1/jobs").await;
    assert_eq!(list["total"], 1, "{list:#}");
    assert_eq!(list["jobs"][0]["id"], next.as_str());
    app.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn deleting_an_unknown_job_answers_404() {
    let app = spawn_app("delete-unknown", |c| c.workers = 0).await;
    for id in ["5f0c7f3e-3a4b-4c2d-9e8f-0a1b2c3d4e5f", "not-a-uuid"] {
        let (status, body) = delete(&app, id).await;
        assert_eq!(status, 404);
        let body: Value = serde_json::from_slice(&body).unwrap();
        assert_eq!(body["error"]["code"], "job_not_found");
        assert_conforms("DELETE", "/v1/jobs/{id}", 404, &body);
    }
    app.stop().await;
}
