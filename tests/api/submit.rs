//! The happy path: submit a real case, poll to `succeeded`, and check that the service
//! serves exactly what `run_case` writes for the same case (nothing added, nothing lost).

use crate::helpers::{
    advice_on_page, advised_wedge, cancel_running, fresh_data_dir, long_case, spawn_app, tiny_case,
};
use crate::schema::assert_conforms;
use mpsfsi::case::{parse_case_value, Limits, ValidCase};
use mpsfsi::run::{run_case, Quiet};
use serde_json::Value;

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn submitted_case_succeeds_and_serves_the_same_files_as_run_case() {
    let app = spawn_app("submit", |_| {}).await;
    let case = tiny_case(0.005);

    let response = app.post_case(&case).await;
    assert_eq!(response.status().as_u16(), 201);
    let location = response.headers()["location"].to_str().unwrap().to_string();
    let created: Value = response.json().await.unwrap();
    assert_conforms("POST", "/v1/jobs", 201, &created);
    assert_eq!(created["status"], "queued");
    let id = created["id"].as_str().unwrap().to_string();
    assert_eq!(location, format!("/v1/jobs/{id}"));

    let job = app.wait_finished(&id).await;
    assert_eq!(job["status"], "succeeded", "{job:#}");
    assert_conforms("GET", "/v1/jobs/{id}", 200, &job);
    assert_eq!(job["progress"]["fraction"], 1.0);
    assert_eq!(job["summary"]["status"], "succeeded");
    assert!(job["finished_at"].is_string() && job["started_at"].is_string());

    // The same case run directly, into another directory.
    let direct_dir = fresh_data_dir("direct");
    let parsed =
        ValidCase::new(parse_case_value(case.clone()).unwrap(), &Limits::default()).unwrap();
    let out = direct_dir.clone();
    let summary = tokio::task::spawn_blocking(move || run_case(&parsed, &out, &mut Quiet))
        .await
        .unwrap()
        .unwrap();
    assert_eq!(job["summary"]["steps"], summary.steps);
    assert_eq!(job["particles"], summary.particles);

    for (route, file) in [("loads", "loads.csv"), ("probes", "probes.csv")] {
        let (status, content_type, served) = app.get_csv(&format!("/v1/jobs/{id}/{route}")).await;
        assert_eq!(status, 200);
        assert!(content_type.starts_with("text/csv"), "{content_type}");
        let direct = std::fs::read_to_string(direct_dir.join(file)).unwrap();
        assert!(direct.lines().count() > 1, "{file} has rows");
        assert_eq!(
            served, direct,
            "{route} CSV differs from what run_case writes"
        );
    }

    // JSON columns hold the same numbers as the CSV rows.
    let (status, loads) = app.get_json(&format!("/v1/jobs/{id}/loads")).await;
    assert_eq!(status, 200);
    assert_conforms("GET", "/v1/jobs/{id}/loads", 200, &loads);
    let direct = std::fs::read_to_string(direct_dir.join("loads.csv")).unwrap();
    let rows: Vec<Vec<&str>> = direct
        .lines()
        .skip(1)
        .map(|l| l.split(',').collect())
        .collect();
    let tank = &loads["bodies"]["tank"];
    let tank_rows: Vec<&Vec<&str>> = rows.iter().filter(|r| r[1] == "tank").collect();
    assert_eq!(tank["time"].as_array().unwrap().len(), tank_rows.len());
    for (k, row) in tank_rows.iter().enumerate() {
        for (col, name) in [(0, "time"), (2, "fx"), (3, "fy"), (4, "mz")] {
            // serde_json's default float parser (client side) may be off by an ulp.
            let (served, written) = (
                tank[name][k].as_f64().unwrap(),
                row[col].parse::<f64>().unwrap(),
            );
            assert!(
                (served - written).abs() <= 1e-15 * written.abs(),
                "{name}[{k}]: {served} vs {written}"
            );
        }
    }
    let (status, probes) = app.get_json(&format!("/v1/jobs/{id}/probes")).await;
    assert_eq!(status, 200);
    assert_conforms("GET", "/v1/jobs/{id}/probes", 200, &probes);
    assert!(
        probes["probes"]["mid"]["pressure"]
            .as_array()
            .unwrap()
            .len()
            > 1
    );

    // No bodies in this case: bodies is an empty series, not an error.
    let (status, bodies) = app.get_json(&format!("/v1/jobs/{id}/bodies")).await;
    assert_eq!(status, 200);
    assert_conforms("GET", "/v1/jobs/{id}/bodies", 200, &bodies);

    // The plot is output::plot::loads_svg of loads.csv: an SVG naming the series, one
    // line (stroke width 2) per body and component, one point per row.
    let svg = app.get_svg(&format!("/v1/jobs/{id}/loads.svg")).await;
    assert!(
        svg.starts_with("<svg") && svg.contains("tank"),
        "{}",
        &svg[..svg.len().min(300)]
    );
    let title = format!("{} (succeeded): loads", case["name"].as_str().unwrap());
    assert_eq!(
        svg,
        mpsfsi::output::plot::loads_svg(&direct, &title).unwrap()
    );
    let lines = svg.matches("stroke-width=\"2\"").count();
    assert_eq!(lines, 3, "fx, fy and mz of the tank");
    for label in ["time (s)", "fx (N/m)", "fy (N/m)", "mz (N·m/m)"] {
        assert!(svg.contains(label), "label {label:?} missing");
    }
    // A partial last line (a running job mid-write) is left out, not an error.
    let loads_path = app.data_dir.join("jobs").join(&id).join("loads.csv");
    let mut partial = std::fs::read_to_string(&loads_path).unwrap();
    partial.push_str("1.0e-2,ta");
    std::fs::write(&loads_path, partial).unwrap();
    assert_eq!(app.get_svg(&format!("/v1/jobs/{id}/loads.svg")).await, svg);

    // The flow picture is output::flow::flow_svg of the snapshot nearest the time asked.
    let svg = app
        .get_svg(&format!(
            "/v1/jobs/{id}/snapshot.svg?time=0.002&field=velocity_y"
        ))
        .await;
    let dir = app.data_dir.join("jobs").join(&id);
    let snapshot = mpsfsi::output::flow::read_snapshot(&dir, Some(0.002)).unwrap();
    let title = mpsfsi::output::flow::title(case["name"].as_str().unwrap(), &snapshot);
    let (direct, _) = mpsfsi::output::flow::flow_svg(
        &snapshot,
        mpsfsi::output::flow::FlowField::VelocityY,
        None,
        &title,
    )
    .unwrap();
    assert_eq!(svg, direct);
    for (query, code) in [
        ("field=vorticity", "bad_request"),
        ("window=1,0,zero,1", "bad_request"),
        ("time=abc", "bad_request"),
    ] {
        let (status, body) = app
            .get_json(&format!("/v1/jobs/{id}/snapshot.svg?{query}"))
            .await;
        assert_eq!(
            (status, body["error"]["code"].as_str()),
            (400, Some(code)),
            "{query}: {body}"
        );
    }
    // The run directory keeps the case as submitted.
    let saved = std::fs::read(app.data_dir.join("jobs").join(&id).join("case.json")).unwrap();
    assert_eq!(saved, serde_json::to_vec(&case).unwrap());

    // Listing and filtering.
    let (status, list) = app.get_json("/v1/jobs?status=succeeded&limit=10").await;
    assert_eq!(status, 200);
    assert_conforms("GET", "/v1/jobs", 200, &list);
    assert_eq!(list["total"], 1);
    assert_eq!(list["jobs"][0]["id"], id.as_str());
    let (_, none) = app.get_json("/v1/jobs?status=running").await;
    assert_eq!(none["total"], 0);
    let (status, bad) = app.get_json("/v1/jobs?status=done").await;
    assert_eq!(status, 400);
    assert_conforms("GET", "/v1/jobs", 400, &bad);

    // A finished job cannot be cancelled.
    let r = app
        .client
        .post(app.url(&format!("/v1/jobs/{id}/cancel")))
        .send()
        .await
        .unwrap();
    assert_eq!(r.status().as_u16(), 409);
    let body: Value = r.json().await.unwrap();
    assert_conforms("POST", "/v1/jobs/{id}/cancel", 409, &body);
    app.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn listing_pages_newest_first() {
    let app = spawn_app("paging", |c| c.workers = 1).await;
    let mut ids = Vec::new();
    for _ in 0..5 {
        ids.push(app.submit(&tiny_case(0.001)).await);
    }
    for id in &ids {
        assert_eq!(app.wait_finished(id).await["status"], "succeeded");
    }
    let (_, page1) = app.get_json("/v1/jobs?limit=2").await;
    let (_, page2) = app.get_json("/v1/jobs?limit=2&offset=2").await;
    let (_, page3) = app.get_json("/v1/jobs?limit=2&offset=4").await;
    let listed: Vec<String> = [page1, page2, page3]
        .iter()
        .flat_map(|p| {
            p["jobs"]
                .as_array()
                .unwrap()
                .iter()
                .map(|j| j["id"].as_str().unwrap().to_string())
                .collect::<Vec<_>>()
        })
        .collect();
    let newest_first: Vec<String> = ids.iter().rev().cloned().collect();
    assert_eq!(listed, newest_first);
    app.stop().await;
}

#[tokio::test]
async fn a_job_without_snapshots_answers_404_for_its_flow_picture() {
    let app = spawn_app("no-snapshots", |_| {}).await;
    let mut quiet = tiny_case(0.002);
    quiet["output"]["snapshot_interval"] = serde_json::json!("none");
    let quiet_id = app.submit(&quiet).await;
    assert_eq!(app.wait_finished(&quiet_id).await["status"], "succeeded");
    let (status, body) = app
        .get_json(&format!("/v1/jobs/{quiet_id}/snapshot.svg"))
        .await;
    assert_eq!(status, 404);
    assert_eq!(body["error"]["code"], "no_snapshots");
    assert_conforms("GET", "/v1/jobs/{id}/snapshot.svg", 404, &body);
    let (status, body) = app
        .get_json(&format!("/v1/jobs/{quiet_id}/surface.svg?body=tank"))
        .await;
    assert_eq!(status, 404);
    assert_eq!(body["error"]["code"], "no_snapshots");
    assert_conforms("GET", "/v1/jobs/{id}/surface.svg", 404, &body);
    app.stop().await;
}

/// The pressure along a body is output::surface::surface_svg of the snapshot nearest the
/// time asked (the tiny tank with a box pushed into it); an unknown body answers 404 with
/// the job's bodies and walls named, and a request without `body` 400.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_surface_picture_draws_a_body_and_refuses_an_unknown_one() {
    use mpsfsi::output::surface::{surface_svg, surface_title};
    let app = spawn_app("surface", |_| {}).await;
    let mut case = tiny_case(0.004);
    case["bodies"] = serde_json::json!([{
        "name": "float",
        "polygon": [[-0.02, 0.0], [0.02, 0.0], [0.02, 0.02], [-0.02, 0.02]],
        "position": [0.15, 0.102],
        "motion": { "type": "prescribed", "velocity": [0.0, -1.0] }
    }]);
    let id = app.submit(&case).await;
    let job = app.wait_finished(&id).await;
    assert_eq!(job["status"], "succeeded", "{job:#}");
    assert_eq!(
        job["links"]["surface_svg"],
        format!("/v1/jobs/{id}/surface.svg")
    );

    let svg = app
        .get_svg(&format!("/v1/jobs/{id}/surface.svg?body=float&time=0.002"))
        .await;
    let dir = app.data_dir.join("jobs").join(&id);
    let snapshot = mpsfsi::output::flow::read_snapshot(&dir, Some(0.002)).unwrap();
    let name = case["name"].as_str().unwrap();
    // the box is the second object: the tank's loads come first
    let direct = surface_svg(&snapshot, 1, &surface_title(name, "float", &snapshot)).unwrap();
    assert_eq!(svg, direct);
    assert!(svg.contains("Cp = p"), "a moving body's pressure as Cp");
    // the last snapshot by default; a wall by its name
    let last = app
        .get_svg(&format!("/v1/jobs/{id}/surface.svg?body=float"))
        .await;
    assert!(last.contains("t = 4.0"), "the last snapshot, at 4 ms");
    assert!(app
        .get_svg(&format!("/v1/jobs/{id}/surface.svg?body=tank"))
        .await
        .contains("p (kPa)"));

    let (status, body) = app
        .get_json(&format!("/v1/jobs/{id}/surface.svg?body=hull"))
        .await;
    assert_eq!(status, 404, "{body}");
    assert_eq!(body["error"]["code"], "body_not_found");
    let message = body["error"]["message"].as_str().unwrap();
    assert!(
        message.contains("\"hull\"") && message.contains("bodies: float; walls: tank"),
        "{message}"
    );
    assert_conforms("GET", "/v1/jobs/{id}/surface.svg", 404, &body);
    let unknown_job = "00000000-0000-0000-0000-000000000000";
    let (status, body) = app
        .get_json(&format!("/v1/jobs/{unknown_job}/surface.svg?body=float"))
        .await;
    assert_eq!(
        (status, body["error"]["code"].as_str()),
        (404, Some("job_not_found"))
    );
    for (query, path) in [("", Some("body")), ("body=float&time=abc", None)] {
        let (status, body) = app
            .get_json(&format!("/v1/jobs/{id}/surface.svg?{query}"))
            .await;
        assert_eq!(
            (status, body["error"]["code"].as_str()),
            (400, Some("bad_request")),
            "{query}: {body}"
        );
        assert_eq!(body["error"]["path"].as_str(), path, "{query}");
        assert_conforms("GET", "/v1/jobs/{id}/surface.svg", 400, &body);
    }
    app.stop().await;
}

/// A case outside the validated impact envelope (the shipped wedge at 2 cm: 25 spacings
/// across) is told so in the response to its submission, and its job page lists the
/// advice while the job waits in the queue and after it has run; a case within it gets
/// no `advice` field and no list.
#[tokio::test]
async fn the_submission_and_the_job_page_carry_the_envelope_advice() {
    // one worker, kept busy, so that the advised job waits in the queue
    let app = spawn_app("advice", |c| c.workers = 1).await;
    let busy = app.submit(&long_case()).await;
    app.wait_running(&busy).await;
    let mut coarse = advised_wedge();
    coarse["time"]["end"] = serde_json::json!(0.0005);
    let r = app.post_case(&coarse).await;
    assert_eq!(r.status().as_u16(), 201);
    let body: Value = r.json().await.unwrap();
    assert_conforms("POST", "/v1/jobs", 201, &body);
    let advice = body["advice"].as_array().expect("an advice array");
    assert_eq!(advice.len(), 1, "{advice:?}");
    let line = advice[0].as_str().unwrap();
    assert!(line.contains("25 spacings across"), "{line}");
    let id = body["id"].as_str().unwrap().to_string();
    // queued: the page advises before the run has a summary
    assert_eq!(app.job(&id).await["status"], "queued");
    let page = app.page(&id).await;
    let list = advice_on_page(&page);
    assert!(list.contains("25 spacings across"), "{list}");

    cancel_running(&app, &busy).await;
    let job = app.wait_finished(&id).await;
    assert_eq!(job["status"], "succeeded", "{job}");
    assert_eq!(job["summary"]["advice"][0].as_str(), Some(line));
    let page = app.page(&id).await;
    let list = advice_on_page(&page);
    assert!(list.contains("25 spacings across"), "{list}");

    // a case inside the envelope gets none, in the response or on its page
    let r = app.post_case(&tiny_case(0.002)).await;
    let body: Value = r.json().await.unwrap();
    assert!(body.get("advice").is_none(), "{body}");
    let quiet = body["id"].as_str().unwrap().to_string();
    app.wait_finished(&quiet).await;
    assert!(!app.page(&quiet).await.contains("id=\"advice\""));
    app.stop().await;
}
