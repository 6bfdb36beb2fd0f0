//! Access beyond loopback (issue 22 item 4): with a token, every route but the health
//! answers 401 `unauthorized` without `Authorization: Bearer <token>`; beyond loopback the
//! server refuses to start with no token; the token comes from MPSFSI_TOKEN or a file and
//! is never printed.

use crate::helpers::{fresh_data_dir, spawn_app, tiny_case, Api};
use crate::schema::{assert_conforms, OPENAPI};
use mpsfsi::service::auth::{OPEN_PATH, SIGN_IN_PATH};
use mpsfsi::service::{App, Config, Token};
use serde_json::{json, Value};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

const TOKEN: &str = "t0ken-3f9c1d2e-8a7b";

/// GET `path` with `Authorization: <authorization>` when given: status, WWW-Authenticate,
/// body.
async fn get(api: &Api, path: &str, authorization: Option<&str>) -> (u16, String, String) {
    let mut request = api.client.get(api.url(path));
    if let Some(a) = authorization {
        request = request.header("authorization", a);
    }
    let r = request.send().await.expect("request sent");
    let challenge = r
        .headers()
        .get("www-authenticate")
        .map(|v| v.to_str().unwrap().to_string())
        .unwrap_or_default();
    (r.status().as_u16(), challenge, r.text().await.unwrap())
}

fn bearer(token: &str) -> String {
    format!("Bearer {token}")
}

/// The body of a 401: the service's error, code `unauthorized`, without the token.
fn assert_unauthorized(body: &str) {
    let json: Value = serde_json::from_str(body).expect("a JSON body");
    assert_eq!(json["error"]["code"], "unauthorized", "{json}");
    assert_eq!(json["error"]["path"], Value::Null);
    assert!(!body.contains(TOKEN), "{body}");
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn a_server_with_a_token_answers_only_requests_that_carry_it() {
    let app = spawn_app("auth-token", |c| c.token = Some(Token::new(TOKEN))).await;

    let (status, challenge, body) = get(&app, "/v1/jobs", None).await;
    assert_eq!((status, challenge.as_str()), (401, "Bearer"), "{body}");
    assert_unauthorized(&body);
    assert!(body.contains("Authorization: Bearer"), "{body}");

    for wrong in [
        bearer("not-the-token"),
        bearer(&TOKEN[..TOKEN.len() - 1]),
        bearer(&format!("{TOKEN}x")),
        bearer(""),
        format!("Basic {TOKEN}"),
        TOKEN.to_string(),
    ] {
        let (status, challenge, body) = get(&app, "/v1/jobs", Some(&wrong)).await;
        assert_eq!(status, 401, "{wrong}: {body}");
        assert!(challenge.starts_with("Bearer"), "{wrong}: {challenge}");
        assert_unauthorized(&body);
    }
    let (_, challenge, _) = get(&app, "/v1/jobs", Some(&bearer("nope"))).await;
    assert_eq!(challenge, r#"Bearer error="invalid_token""#);

    // the right token, in either case of the scheme
    for good in [bearer(TOKEN), format!("bearer {TOKEN}")] {
        let (status, _, body) = get(&app, "/v1/jobs", Some(&good)).await;
        assert_eq!(status, 200, "{body}");
    }
    let job = app.submit_with_token(TOKEN, &tiny_case(0.002)).await;
    let id = job["id"].as_str().unwrap().to_string();
    let (status, _, body) = get(&app, &format!("/v1/jobs/{id}"), Some(&bearer(TOKEN))).await;
    assert_eq!(status, 200, "{body}");
    let (status, _, body) = get(&app, &format!("/v1/jobs/{id}"), None).await;
    assert_eq!(status, 401, "{body}");

    // the health needs none, and an unknown route is 401, not 404, without the token
    let (status, challenge, body) = get(&app, "/v1/health", None).await;
    assert_eq!((status, challenge.as_str()), (200, ""), "{body}");
    assert!(!body.contains(TOKEN));
    let (status, _, _) = get(&app, "/v1/nothing", None).await;
    assert_eq!(status, 401);
    let (status, _, _) = get(&app, "/v1/nothing", Some(&bearer(TOKEN))).await;
    assert_eq!(status, 404);
    app.stop().await;
}

/// Every documented route but the health and the sign-in answers the documented 401
/// without the token, and api/openapi.yaml marks exactly those as open (`security: []`).
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn every_route_but_the_health_documents_and_answers_401() {
    let app = spawn_app("auth-routes", |c| c.token = Some(Token::new(TOKEN))).await;
    let id = uuid::Uuid::new_v4().to_string();
    let mut checked = 0;
    for (path, item) in OPENAPI["paths"].as_object().unwrap() {
        for (method, op) in item.as_object().unwrap() {
            if method == "parameters" {
                continue;
            }
            let open = path == OPEN_PATH || path == SIGN_IN_PATH;
            assert_eq!(op.get("security") == Some(&json!([])), open, "{path}");
            let r = app
                .client
                .request(
                    method.to_uppercase().parse().unwrap(),
                    app.url(&path.replace("{id}", &id)),
                )
                .send()
                .await
                .unwrap();
            let status = r.status().as_u16();
            if open {
                // the sign-in's POST without a form is a bad request, not a 401
                let expected = if method == "post" { 400 } else { 200 };
                assert_eq!(status, expected, "{method} {path}");
                continue;
            }
            assert_eq!(status, 401, "{method} {path}");
            assert!(r.headers().contains_key("www-authenticate"));
            let body: Value = r.json().await.unwrap();
            assert_conforms(method, path, 401, &body);
            checked += 1;
        }
    }
    assert!(checked >= 10, "{checked}");
    app.stop().await;
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn beyond_loopback_the_server_refuses_to_start_without_a_token() {
    for addr in ["0.0.0.0:0", "192.0.2.1:8080", "[::]:0"] {
        let data = fresh_data_dir("auth-open");
        let mut config = Config::for_tests(&data);
        config.addr = addr.parse().unwrap();
        let error = App::build(config).await.unwrap_err().to_string();
        for needle in ["MPSFSI_TOKEN", "--token-file", addr] {
            assert!(error.contains(needle), "{needle} not in: {error}");
        }
        assert!(!data.join("jobs").exists(), "refused before anything");
    }

    // with a token it listens on every interface and asks for the token
    let app = spawn_app("auth-any", |c| {
        c.addr = "0.0.0.0:0".parse().unwrap();
        c.token = Some(Token::new(TOKEN));
    })
    .await;
    let (status, _, body) = get(&app, "/v1/jobs", None).await;
    assert_eq!(status, 401);
    assert_unauthorized(&body);
    let (status, _, _) = get(&app, "/v1/jobs", Some(&bearer(TOKEN))).await;
    assert_eq!(status, 200);
    let (status, _, _) = get(&app, "/v1/health", None).await;
    assert_eq!(status, 200);
    app.stop().await;
}

async fn build_error(tweak: impl FnOnce(&mut Config)) -> String {
    let mut config = Config::for_tests(fresh_data_dir("auth-refused"));
    tweak(&mut config);
    App::build(config).await.unwrap_err().to_string()
}

#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn the_token_file_is_read_trimmed_and_must_hold_a_token() {
    let dir = fresh_data_dir("auth-file-dir");
    let file = dir.join("token");
    std::fs::write(&file, format!("{TOKEN}\n")).unwrap();
    let app = spawn_app("auth-file", |c| c.token_file = Some(file.clone())).await;
    let (status, _, _) = get(&app, "/v1/jobs", None).await;
    assert_eq!(status, 401);
    let (status, _, body) = get(&app, "/v1/jobs", Some(&bearer(TOKEN))).await;
    assert_eq!(status, 200, "{body}");
    app.stop().await;

    for text in ["", "\n", "  \r\n"] {
        std::fs::write(&file, text).unwrap();
        let error = build_error(|c| c.token_file = Some(file.clone())).await;
        assert!(
            error.contains("empty") && error.contains(&file.display().to_string()),
            "{error}"
        );
    }
    let missing = dir.join("no-such-token");
    let error = build_error(|c| c.token_file = Some(missing.clone())).await;
    assert!(
        error.contains("cannot read the token file")
            && error.contains(&missing.display().to_string()),
        "{error}"
    );

    // a token that cannot be sent in a header, or two tokens, are refused too; the
    // error does not print the token
    std::fs::write(&file, "two words\n").unwrap();
    let error = build_error(|c| c.token_file = Some(file.clone())).await;
    assert!(error.contains("printable ASCII") && !error.contains("two words"));
    let error = build_error(|c| c.token = Some(Token::new("  "))).await;
    assert!(
        error.contains("empty") && error.contains("MPSFSI_TOKEN"),
        "{error}"
    );
    let error = build_error(|c| {
        c.token = Some(Token::new(TOKEN));
        c.token_file = Some(file.clone());
    })
    .await;
    assert!(error.contains("both") && !error.contains(TOKEN), "{error}");
}

#[test]
fn the_token_never_appears_in_debug_output() {
    let mut config = Config::for_tests("data");
    config.token = Some(Token::new(TOKEN));
    for printed in [format!("{config:?}"), format!("{config:#?}")] {
        assert!(!printed.contains(TOKEN), "{printed}");
        assert!(printed.contains("<redacted>"), "{printed}");
    }
    assert!(Config::for_tests("data").token.is_none());
}

/// Kills the child if the test fails before it does.
struct KillOnDrop(Child);

impl Drop for KillOnDrop {
    fn drop(&mut self) {
        let _ = self.0.kill();
        let _ = self.0.wait();
    }
}

/// `mpsfsi serve` itself: refuses 0.0.0.0 without a token (exit 3, naming MPSFSI_TOKEN);
/// takes the token from MPSFSI_TOKEN; its log, at trace level, never shows the token.
#[tokio::test(flavor = "multi_thread", worker_threads = 2)]
async fn mpsfsi_serve_takes_the_token_from_its_environment_and_never_logs_it() {
    let data = fresh_data_dir("auth-env");
    let serve = |addr: &str| {
        let mut cmd = Command::new(env!("CARGO_BIN_EXE_mpsfsi"));
        cmd.args(["serve", "--addr", addr, "--data"])
            .arg(&data)
            .env_remove("MPSFSI_TOKEN")
            .env_remove("MPSFSI_TOKEN_FILE");
        cmd
    };
    let out = serve("0.0.0.0:0").output().unwrap();
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(3), "{stderr}");
    assert!(stderr.contains("MPSFSI_TOKEN"), "{stderr}");

    let port = std::net::TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port();
    let log = data.join("serve.log");
    let child = serve(&format!("127.0.0.1:{port}"))
        .env("MPSFSI_TOKEN", TOKEN)
        .env("RUST_LOG", "trace")
        .stdout(Stdio::null())
        .stderr(std::fs::File::create(&log).unwrap())
        .spawn()
        .unwrap();
    let mut child = KillOnDrop(child);
    let api = Api {
        address: format!("http://127.0.0.1:{port}"),
        client: reqwest::Client::new(),
    };
    let start = Instant::now();
    while !matches!(api.client.get(api.url("/v1/health")).send().await, Ok(r) if r.status() == 200)
    {
        assert!(child.0.try_wait().unwrap().is_none(), "the server exited");
        assert!(start.elapsed() < Duration::from_secs(30), "no server");
        tokio::time::sleep(Duration::from_millis(50)).await;
    }
    assert_eq!(get(&api, "/v1/jobs", None).await.0, 401);
    assert_eq!(get(&api, "/v1/jobs", Some(&bearer("wrong"))).await.0, 401);
    assert_eq!(get(&api, "/v1/jobs", Some(&bearer(TOKEN))).await.0, 200);
    child.0.kill().unwrap();
    child.0.wait().unwrap();
    let log = std::fs::read_to_string(&log).unwrap();
    assert!(log.contains("listening"), "{log}");
    assert!(!log.contains(TOKEN), "the token is in the log:\n{log}");
}
