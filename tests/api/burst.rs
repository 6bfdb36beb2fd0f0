//! 200 concurrent submissions: each is accepted and succeeds, or is refused with 503;
//! none is lost or duplicated.

use crate::helpers::{spawn_app, tiny_case};
use std::collections::BTreeSet;

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_burst_of_submissions_loses_and_duplicates_nothing() {
    let app = spawn_app("burst", |c| {
        c.workers = 2;
        c.queue_capacity = 40;
    })
    .await;
    let case = tiny_case(0.001);
    let requests = (0..200).map(|_| {
        let (client, url, case) = (app.client.clone(), app.url("/v1/jobs"), case.clone());
        tokio::spawn(async move {
            let r = client
                .post(url)
                .json(&case)
                .send()
                .await
                .expect("request sent");
            let status = r.status().as_u16();
            let body: serde_json::Value = r.json().await.unwrap();
            (status, body)
        })
    });
    let mut accepted = Vec::new();
    let mut refused = 0;
    for request in requests.collect::<Vec<_>>() {
        let (status, body) = request.await.unwrap();
        match status {
            201 => accepted.push(body["id"].as_str().unwrap().to_string()),
            503 => {
                assert_eq!(body["error"]["code"], "queue_full");
                refused += 1;
            }
            other => panic!("unexpected {other}: {body}"),
        }
    }
    assert_eq!(accepted.len() + refused, 200);
    assert!(
        accepted.len() >= 40,
        "at least the queue capacity is accepted ({})",
        accepted.len()
    );
    let unique: BTreeSet<String> = accepted.iter().cloned().collect();
    assert_eq!(unique.len(), accepted.len(), "duplicate ids");

    for id in &accepted {
        let job = app.wait_finished(id).await;
        assert_eq!(job["status"], "succeeded", "{job}");
    }
    let (_, list) = app.get_json("/v1/jobs?limit=1000").await;
    assert_eq!(list["total"].as_u64().unwrap() as usize, accepted.len());
    let listed: BTreeSet<String> = list["jobs"]
        .as_array()
        .unwrap()
        .iter()
        .map(|j| j["id"].as_str().unwrap().to_string())
        .collect();
    assert_eq!(listed, unique, "the job list is exactly the accepted jobs");
    // Refused submissions left no run directory behind.
    let dirs = std::fs::read_dir(app.data_dir.join("jobs"))
        .unwrap()
        .count();
    assert_eq!(dirs, accepted.len());
    app.stop().await;
}
