//! `POST /v1/jobs?uncertainty=true`: the job runs the resolution ladder; its record,
//! summary, `loads_uncertainty` and `loads.svg` carry the half-widths. A bad flag is a
//! 400, a case the ladder cannot lay out a 422 on `particle_spacing`, before queuing.

use crate::helpers::{spawn_app, tiny_case};
use crate::schema::assert_conforms;
use serde_json::Value;

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_job_with_uncertainty_serves_the_half_widths() {
    let app = spawn_app("uncertainty", |_| {}).await;
    let post = |query: &'static str, case: Value| {
        let app = &app;
        async move {
            app.post_case_at(&format!("/v1/jobs{query}"), &case, None)
                .await
        }
    };
    let bad = post("?uncertainty=maybe", tiny_case(0.005)).await;
    assert_eq!(bad.status().as_u16(), 400);
    let mut shallow = tiny_case(0.005);
    shallow["particle_spacing"] = serde_json::json!(0.05);
    let refused = post("?uncertainty=true", shallow).await;
    assert_eq!(refused.status().as_u16(), 422);
    let body: Value = refused.json().await.unwrap();
    assert_eq!(body["error"]["path"], "particle_spacing", "{body}");

    let created = post("?uncertainty=true", tiny_case(0.005)).await;
    assert_eq!(created.status().as_u16(), 201);
    let created: Value = created.json().await.unwrap();
    assert_conforms("POST", "/v1/jobs", 201, &created);
    assert_eq!(created["uncertainty"], true);
    let id = created["id"].as_str().unwrap().to_string();
    let job = app.wait_finished(&id).await;
    assert_eq!(job["status"], "succeeded", "{job:#}");
    assert_conforms("GET", "/v1/jobs/{id}", 200, &job);
    let levels = job["summary"]["uncertainty"]["levels"].as_array().unwrap();
    assert_eq!(levels.len(), 4, "{job:#}");
    // the progress counted the ladder's seven parts, all ended
    assert_eq!(job["progress"]["parts"], 7, "{job:#}");
    assert_eq!(job["progress"]["part"], 7, "{job:#}");

    let (status, content_type, csv) = app
        .get_csv(&format!("/v1/jobs/{id}/loads_uncertainty"))
        .await;
    assert_eq!(status, 200);
    assert!(content_type.starts_with("text/csv"), "{content_type}");
    assert!(
        csv.starts_with("time,body,fx,fy,mz,u_fx,u_fy,u_mz\n"),
        "{csv}"
    );
    let (_, _, loads) = app.get_csv(&format!("/v1/jobs/{id}/loads")).await;
    assert_eq!(
        csv.lines().count(),
        loads.lines().count(),
        "one row per load row"
    );
    let (status, json) = app
        .get_json(&format!("/v1/jobs/{id}/loads_uncertainty"))
        .await;
    assert_eq!(status, 200);
    assert_conforms("GET", "/v1/jobs/{id}/loads_uncertainty", 200, &json);
    assert!(json["bodies"]["tank"]["u_fy"].is_array(), "{json}");
    let svg = app.get_svg(&format!("/v1/jobs/{id}/loads.svg")).await;
    assert_eq!(
        svg.matches("<polygon").count(),
        3,
        "the tank's band in three panels"
    );

    // a job without the option: no band, and the route serves the header alone
    let plain = app.submit(&tiny_case(0.002)).await;
    let job = app.wait_finished(&plain).await;
    assert_eq!(job["uncertainty"], false);
    assert_eq!(job["progress"]["parts"], 1);
    let (_, _, csv) = app
        .get_csv(&format!("/v1/jobs/{plain}/loads_uncertainty"))
        .await;
    assert_eq!(csv, "time,body,fx,fy,mz,u_fx,u_fy,u_mz\n");
    let svg = app.get_svg(&format!("/v1/jobs/{plain}/loads.svg")).await;
    assert_eq!(svg.matches("<polygon").count(), 0);
    app.stop().await;
}

/// With Postgres, a remote worker runs the ladder; the node that took the submission
/// (which shares no directory with the worker) serves the half-widths, uploaded like the
/// loads, and shades the band.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_remote_worker_s_half_widths_are_served_by_the_node() {
    use crate::helpers::fresh_data_dir;
    use crate::pg_server::PgServer;
    use crate::postgres::{node, stop, worker_process};
    let Some(pg) = PgServer::start_or_skip("uncertainty").await else {
        return;
    };
    let url = pg.fresh_database().await;
    let api = node(&url, "pg-uncertainty").await;
    let worker = worker_process(&url, &fresh_data_dir("pg-uncertainty-worker"), 3.0);
    let response = api
        .post_case_at("/v1/jobs?uncertainty=true", &tiny_case(0.005), None)
        .await;
    assert_eq!(response.status().as_u16(), 201);
    let id = response.json::<Value>().await.unwrap()["id"]
        .as_str()
        .unwrap()
        .to_string();
    let job = api.wait_finished(&id).await;
    stop(worker);
    assert_eq!(job["status"], "succeeded", "{job:#}");
    assert_eq!(job["uncertainty"], true);
    assert_eq!(
        job["summary"]["uncertainty"]["levels"]
            .as_array()
            .unwrap()
            .len(),
        4
    );
    let (_, _, csv) = api
        .get_csv(&format!("/v1/jobs/{id}/loads_uncertainty"))
        .await;
    let (_, _, loads) = api.get_csv(&format!("/v1/jobs/{id}/loads")).await;
    assert!(
        csv.starts_with("time,body,fx,fy,mz,u_fx,u_fy,u_mz\n"),
        "{csv}"
    );
    assert_eq!(csv.lines().count(), loads.lines().count());
    let svg = api.get_svg(&format!("/v1/jobs/{id}/loads.svg")).await;
    assert_eq!(svg.matches("<polygon").count(), 3);
    api.stop().await;
}
