//! Bad input gets the right status, code and field path, and the server stays healthy.

use crate::helpers::{spawn_app, tiny_case, TestApp};
use crate::schema::assert_conforms;
use serde_json::{json, Value};

async fn refused(app: &TestApp, body: Vec<u8>) -> (u16, Value) {
    let r = app.post_raw(body).await;
    let status = r.status().as_u16();
    let body: Value = r.json().await.expect("errors are JSON");
    assert_conforms("POST", "/v1/jobs", status, &body);
    (status, body)
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn bad_submissions_are_refused_with_the_field_path() {
    let app = spawn_app("bad", |c| c.max_body_bytes = 64 * 1024).await;

    let (status, body) = refused(&app, b"{ \"name\": \"x\", ".to_vec()).await;
    assert_eq!(status, 400, "{body}");
    assert_eq!(body["error"]["code"], "malformed_json");
    // only an empty body submits the default case; whitespace is no JSON
    for blank in [&b"\n"[..], b" ", b"\r\n\t"] {
        let (status, body) = refused(&app, blank.to_vec()).await;
        assert_eq!(status, 400, "{blank:?}: {body}");
        assert_eq!(body["error"]["code"], "malformed_json");
    }

    let mut case = tiny_case(0.005);
    case["scheme"] = json!({ "laplacian": "magic" });
    let (status, body) = refused(&app, serde_json::to_vec(&case).unwrap()).await;
    assert_eq!(status, 422, "{body}");
    assert_eq!(body["error"]["path"], "scheme.laplacian", "{body}");
    assert!(
        body["error"]["message"].as_str().unwrap().contains("magic"),
        "{body}"
    );

    // Over the 64 KiB limit: valid JSON padded with a long name.
    let mut case = tiny_case(0.005);
    case["name"] = json!("x".repeat(100 * 1024));
    let (status, body) = refused(&app, serde_json::to_vec(&case).unwrap()).await;
    assert_eq!(status, 413, "{body}");
    assert_eq!(body["error"]["code"], "payload_too_large");

    let (status, body) = app.get_json("/v1/jobs/not-a-job").await;
    assert_eq!(status, 404);
    assert_conforms("GET", "/v1/jobs/{id}", 404, &body);
    let (status, _) = app
        .get_json(&format!("/v1/jobs/{}/loads", uuid::Uuid::new_v4()))
        .await;
    assert_eq!(status, 404);

    // Nothing was queued, and the server still works.
    let (status, health) = app.get_json("/v1/health").await;
    assert_eq!(status, 200);
    assert_conforms("GET", "/v1/health", 200, &health);
    assert_eq!(health["status"], "ok");
    let (_, list) = app.get_json("/v1/jobs").await;
    assert_eq!(list["total"], 0);
    let id = app.submit(&tiny_case(0.002)).await;
    assert_eq!(app.wait_finished(&id).await["status"], "succeeded");
    app.stop().await;
}

/// Needs the full case validation (negative density, self-intersecting polygons).
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn invalid_cases_are_refused_with_the_field_path() {
    let app = spawn_app("invalid", |_| {}).await;
    let mut case = tiny_case(0.005);
    case["fluid"]["density"] = json!(-1000.0);
    let (status, body) = refused(&app, serde_json::to_vec(&case).unwrap()).await;
    assert_eq!(status, 422, "{body}");
    assert_eq!(body["error"]["code"], "invalid_case");
    assert_eq!(body["error"]["path"], "fluid.density", "{body}");

    // A bow-tie: the edges (0,0)-(0.1,0.1) and (0.1,0)-(0,0.1) cross.
    let mut case = tiny_case(0.005);
    case["bodies"] = json!([{
        "name": "bowtie",
        "polygon": [[0.0, 0.0], [0.1, 0.1], [0.1, 0.0], [0.0, 0.1]],
        "position": [0.15, 0.15],
        "angle": 0.0,
        "motion": { "type": "prescribed", "velocity": [0.0, -1.0], "angular_velocity": 0.0 }
    }]);
    let (status, body) = refused(&app, serde_json::to_vec(&case).unwrap()).await;
    assert_eq!(status, 422, "{body}");
    assert!(
        body["error"]["path"]
            .as_str()
            .unwrap()
            .starts_with("bodies[0].polygon"),
        "{body}"
    );
    assert!(
        body["error"]["message"]
            .as_str()
            .unwrap()
            .contains("intersect"),
        "{body}"
    );

    let (_, list) = app.get_json("/v1/jobs").await;
    assert_eq!(list["total"], 0);
    app.stop().await;
}
