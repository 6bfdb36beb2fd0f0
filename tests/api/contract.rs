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

/// The served document carries the whole case schema: the shipped cases conform to it,
/// and a case the old placeholder accepted (empty objects, a zero spacing, null blocks)
/// does not, at each of the fields the server would reject.
#[test]
fn the_served_contract_carries_the_full_case_schema() {
    let case_schema = serde_json::json!({ "$ref": "#/components/schemas/Case" });
    let cases = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("cases");
    let mut shipped = 0;
    for entry in std::fs::read_dir(cases).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_some_and(|e| e == "json") {
            let case: Value =
                serde_json::from_str(&std::fs::read_to_string(&path).unwrap()).unwrap();
            let errors = check(&OPENAPI, &case_schema, &case, "$");
            assert!(errors.is_empty(), "{}: {errors:#?}", path.display());
            shipped += 1;
        }
    }
    assert!(shipped >= 5);
    let stub = serde_json::json!({
        "domain": {}, "fluid": {}, "fluid_blocks": [null, null], "name": "",
        "particle_spacing": 0, "time": {}
    });
    let errors = check(&OPENAPI, &case_schema, &stub, "$").join("\n");
    for expected in [
        "$.domain: missing required \"min\"",
        "$.particle_spacing: 0 <= exclusive minimum 0",
        "$.time: missing required \"end\"",
        "$.fluid_blocks",
    ] {
        assert!(errors.contains(expected), "{expected} not in:\n{errors}");
    }
    // and the server agrees with the contract on each of them
    let parsed = mpsfsi::case::parse_case_value(stub);
    assert!(parsed.is_err());
    // every positive quantity carries its bound
    for (schema, field, keyword) in [
        ("Case", "particle_spacing", "exclusiveMinimum"),
        ("Fluid", "density", "exclusiveMinimum"),
        ("Fluid", "kinematic_viscosity", "minimum"),
        ("TimeControl", "end", "exclusiveMinimum"),
        ("TimeControl", "cfl", "exclusiveMinimum"),
        ("TimeControl", "max_dt", "exclusiveMinimum"),
        ("Output", "load_interval", "exclusiveMinimum"),
    ] {
        let property = &OPENAPI["components"]["schemas"][schema]["properties"][field];
        assert!(
            property.get(keyword).is_some(),
            "{schema}.{field}: {property}"
        );
    }
    let motion = serde_json::to_string(&OPENAPI["components"]["schemas"]["Motion"]).unwrap();
    assert!(
        motion.contains("exclusiveMinimum"),
        "the free body's mass: {motion}"
    );
}

/// `POST /v1/jobs` links to every operation that takes a job id, with the id from its
/// response body.
#[test]
fn submitting_links_to_every_route_of_a_job() {
    let links = OPENAPI["paths"]["/v1/jobs"]["post"]["responses"]["201"]["links"]
        .as_object()
        .expect("links on the 201 response");
    let mut with_id = BTreeSet::new();
    for (path, item) in OPENAPI["paths"].as_object().unwrap() {
        if path.contains("{id}") {
            for (method, operation) in item.as_object().unwrap() {
                // a deprecated operation would be reachable but not advertised
                if METHODS.contains(&method.as_str()) && operation["deprecated"] != true {
                    with_id.insert(operation["operationId"].as_str().unwrap().to_string());
                }
            }
        }
    }
    let linked: BTreeSet<String> = links
        .values()
        .map(|l| {
            assert_eq!(l["parameters"]["id"], "$response.body#/id");
            l["operationId"].as_str().unwrap().to_string()
        })
        .collect();
    assert_eq!(linked, with_id);
}

#[tokio::test]
async fn the_status_filter_rejects_values_outside_its_enum() {
    let app = spawn_app("status-filter", |_| {}).await;
    for value in ["", "done", "SUCCEEDED"] {
        let (status, body) = app.get_json(&format!("/v1/jobs?status={value}")).await;
        assert_eq!(status, 400, "{value:?}: {body}");
        assert_eq!(body["error"]["code"], "bad_request");
        assert_eq!(body["error"]["path"], "status");
        assert_conforms("GET", "/v1/jobs", 400, &body);
    }
    let (status, _) = app.get_json("/v1/jobs?status=queued").await;
    assert_eq!(status, 200);
    app.stop().await;
}

#[test]
fn the_window_parameter_has_the_pattern_the_server_parses() {
    let parameters = OPENAPI["paths"]["/v1/jobs/{id}/snapshot.svg"]["get"]["parameters"]
        .as_array()
        .unwrap();
    let window = parameters.iter().find(|p| p["name"] == "window").unwrap();
    assert_eq!(
        window["schema"]["pattern"],
        mpsfsi::output::flow::WINDOW_PATTERN
    );
}
