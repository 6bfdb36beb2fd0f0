//! `api/openapi.yaml` is the contract: the routes it lists are exactly the routes the
//! server answers, its examples and the server's real responses conform to its schemas,
//! and `GET /v1/openapi.json` serves it.

use crate::helpers::{spawn_app, tiny_case};
use crate::schema::{assert_conforms, check, OPENAPI};
use serde_json::Value;
use std::collections::BTreeSet;

const METHODS: &[&str] = &[
    "get", "post", "put", "delete", "patch", "head", "options", "trace",
];

fn documented_routes() -> BTreeSet<(String, String)> {
    let mut routes = BTreeSet::new();
    for (path, item) in OPENAPI["paths"].as_object().unwrap() {
        for method in item
            .as_object()
            .unwrap()
            .keys()
            .filter(|k| METHODS.contains(&k.as_str()))
        {
            routes.insert((method.to_uppercase(), path.clone()));
        }
    }
    routes
}

#[test]
fn the_documented_routes_are_the_routes_the_router_is_built_from() {
    let served: BTreeSet<(String, String)> = mpsfsi::service::routes::route_table()
        .into_iter()
        .map(|(m, p)| (m.as_str().to_string(), p.to_string()))
        .collect();
    assert_eq!(documented_routes(), served);
}

#[test]
fn every_json_example_conforms_to_its_schema() {
    let mut checked = 0;
    let mut walk = vec![(String::from("$"), &*OPENAPI)];
    while let Some((at, node)) = walk.pop() {
        match node {
            Value::Object(map) => {
                if let (Some(schema), Some(example)) = (map.get("schema"), map.get("example")) {
                    if at.ends_with("application/json") {
                        let errors = check(&OPENAPI, schema, example, &at);
                        assert!(errors.is_empty(), "example at {at}: {errors:#?}");
                        checked += 1;
                    }
                }
                for (k, v) in map {
                    walk.push((format!("{at}/{k}"), v));
                }
            }
            Value::Array(items) => walk.extend(items.iter().map(|v| (at.clone(), v))),
            _ => {}
        }
    }
    assert!(checked >= 5, "only {checked} examples found");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_server_answers_every_documented_route_and_no_other() {
    let app = spawn_app("contract", |_| {}).await;
    let id = app.submit(&tiny_case(0.002)).await;
    assert_eq!(app.wait_finished(&id).await["status"], "succeeded");

    for (method, path) in documented_routes() {
        let url = app.url(&path.replace("{id}", &id));
        let request = app.client.request(method.parse().unwrap(), url);
        let request = if method == "POST" {
            request.json(&tiny_case(0.002))
        } else {
            request
        };
        let response = request.send().await.unwrap();
        let status = response.status().as_u16();
        let content_type = response
            .headers()
            .get("content-type")
            .map(|v| v.to_str().unwrap().to_string())
            .unwrap_or_default();
        let body = response.bytes().await.unwrap();
        crate::schema::response_spec(&method, &path, status); // the status is documented
        if content_type.starts_with("application/json") {
            let json: Value = serde_json::from_slice(&body).unwrap();
            let code = json["error"]["code"].as_str().unwrap_or("");
            assert!(
                code != "route_not_found" && code != "method_not_allowed",
                "{method} {path}: {json}"
            );
            if path != "/v1/openapi.json" {
                assert_conforms(&method, &path, status, &json);
            } else {
                assert_eq!(json, *OPENAPI, "/v1/openapi.json serves api/openapi.yaml");
            }
        }
    }

    // Undocumented routes are not answered.
    let error_schema = serde_json::json!({ "$ref": "#/components/schemas/Error" });
    for (method, path, status, code) in [
        ("PUT", "/v1/jobs".to_string(), 405, "method_not_allowed"),
        ("PATCH", format!("/v1/jobs/{id}"), 405, "method_not_allowed"),
        ("GET", "/v1/nothing".to_string(), 404, "route_not_found"),
        (
            "GET",
            format!("/v1/jobs/{id}/snapshots"),
            404,
            "route_not_found",
        ),
    ] {
        let r = app
            .client
            .request(method.parse().unwrap(), app.url(&path))
            .send()
            .await
            .unwrap();
        assert_eq!(r.status().as_u16(), status, "{method} {path}");
        let json: Value = r.json().await.unwrap();
        assert_eq!(json["error"]["code"], code);
        assert!(
            check(&OPENAPI, &error_schema, &json, "$").is_empty(),
            "{json}"
        );
    }
    app.stop().await;
}
