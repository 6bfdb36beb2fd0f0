//! `spawn_app`, tiny cases and request helpers.

use crate::schema::assert_conforms;
use mpsfsi::service::{App, Config, ServeError, ShutdownHandle};
use serde_json::{json, Value};
use std::path::PathBuf;
use std::sync::LazyLock;
use std::time::{Duration, Instant};

static TRACING: LazyLock<()> = LazyLock::new(|| {
    if std::env::var("TEST_LOG").is_ok() {
        let _ = tracing_subscriber::fmt()
            .with_env_filter("info")
            .with_test_writer()
            .try_init();
    }
});

/// Request helpers against a server at `address` (in-process or a child process).
pub struct Api {
    pub address: String,
    pub client: reqwest::Client,
}

/// A server spawned in this process.
pub struct TestApp {
    pub api: Api,
    pub data_dir: PathBuf,
    pub shutdown: ShutdownHandle,
    pub task: tokio::task::JoinHandle<Result<(), ServeError>>,
}

impl std::ops::Deref for TestApp {
    type Target = Api;
    fn deref(&self) -> &Api {
        &self.api
    }
}

/// A fresh data directory under the cargo target's temporary directory.
pub fn fresh_data_dir(tag: &str) -> PathBuf {
    let dir = PathBuf::from(env!("CARGO_TARGET_TMPDIR"))
        .join(format!("api-{tag}-{}", uuid::Uuid::new_v4()));
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

/// A port nothing listens on right now (for a server started as a child process).
pub fn free_port() -> u16 {
    std::net::TcpListener::bind("127.0.0.1:0")
        .unwrap()
        .local_addr()
        .unwrap()
        .port()
}

pub async fn spawn_app(tag: &str, tweak: impl FnOnce(&mut Config)) -> TestApp {
    spawn_app_on(fresh_data_dir(tag), tweak).await
}

pub async fn spawn_app_on(data_dir: PathBuf, tweak: impl FnOnce(&mut Config)) -> TestApp {
    LazyLock::force(&TRACING);
    let mut config = Config::for_tests(&data_dir);
    tweak(&mut config);
    let app = App::build(config).await.expect("app builds");
    let address = format!("http://127.0.0.1:{}", app.port());
    let shutdown = app.shutdown_handle();
    let task = tokio::spawn(app.run_until_stopped());
    TestApp {
        api: Api {
            address,
            client: reqwest::Client::new(),
        },
        data_dir,
        shutdown,
        task,
    }
}

impl TestApp {
    pub async fn stop(self) {
        self.shutdown.shutdown();
        let _ = self.task.await;
    }
}

impl Api {
    pub fn url(&self, path: &str) -> String {
        format!("{}{path}", self.address)
    }

    pub async fn post_case(&self, case: &Value) -> reqwest::Response {
        self.post_raw(serde_json::to_vec(case).unwrap()).await
    }

    pub async fn post_raw(&self, body: Vec<u8>) -> reqwest::Response {
        self.client
            .post(self.url("/v1/jobs"))
            .header("content-type", "application/json")
            .body(body)
            .send()
            .await
            .expect("request sent")
    }

    pub async fn get_json(&self, path: &str) -> (u16, Value) {
        let r = self
            .client
            .get(self.url(path))
            .send()
            .await
            .expect("request sent");
        let status = r.status().as_u16();
        (status, r.json().await.expect("a JSON body"))
    }

    pub async fn get_csv(&self, path: &str) -> (u16, String, String) {
        let r = self
            .client
            .get(self.url(path))
            .header("accept", "text/csv")
            .send()
            .await
            .expect("request sent");
        let status = r.status().as_u16();
        let ct = r
            .headers()
            .get("content-type")
            .map(|v| v.to_str().unwrap().to_string())
            .unwrap_or_default();
        (status, ct, r.text().await.unwrap())
    }

    /// GET an SVG (asserting 200 and its content type).
    pub async fn get_svg(&self, path: &str) -> String {
        let r = self
            .client
            .get(self.url(path))
            .send()
            .await
            .expect("request sent");
        assert_eq!(r.status().as_u16(), 200);
        assert_eq!(r.headers()["content-type"], "image/svg+xml");
        r.text().await.unwrap()
    }

    pub async fn job(&self, id: &str) -> Value {
        let (status, body) = self.get_json(&format!("/v1/jobs/{id}")).await;
        assert_eq!(status, 200, "{body}");
        body
    }

    /// The job page, as a browser asks for it.
    pub async fn page(&self, id: &str) -> String {
        let r = self
            .client
            .get(self.url(&format!("/v1/jobs/{id}")))
            .header("accept", "text/html")
            .send()
            .await
            .expect("request sent");
        assert_eq!(r.status().as_u16(), 200);
        r.text().await.unwrap()
    }

    /// POST `case` to `path` (`/v1/jobs`, with a query), with `token` as the bearer
    /// when given.
    pub async fn post_case_at(
        &self,
        path: &str,
        case: &Value,
        token: Option<&str>,
    ) -> reqwest::Response {
        let mut request = self.client.post(self.url(path)).json(case);
        if let Some(token) = token {
            request = request.bearer_auth(token);
        }
        request.send().await.expect("request sent")
    }

    /// Submit with the bearer `token` and return the created job (asserting 201).
    pub async fn submit_with_token(&self, token: &str, case: &Value) -> Value {
        let r = self.post_case_at("/v1/jobs", case, Some(token)).await;
        let status = r.status().as_u16();
        let body: Value = r.json().await.unwrap();
        assert_eq!(status, 201, "{body}");
        body
    }

    /// Submit and return the job id (asserting 201).
    pub async fn submit(&self, case: &Value) -> String {
        let r = self.post_case(case).await;
        let status = r.status().as_u16();
        let body: Value = r.json().await.unwrap();
        assert_eq!(status, 201, "{body}");
        body["id"].as_str().unwrap().to_string()
    }

    /// Poll until the job's status satisfies `done` (or panic after `timeout`).
    pub async fn wait_for(
        &self,
        id: &str,
        timeout: Duration,
        done: impl Fn(&Value) -> bool,
    ) -> Value {
        let start = Instant::now();
        loop {
            let job = self.job(id).await;
            if done(&job) {
                return job;
            }
            assert!(
                start.elapsed() < timeout,
                "job {id} did not get there in {timeout:?}: {job}"
            );
            tokio::time::sleep(Duration::from_millis(20)).await;
        }
    }

    pub async fn wait_finished(&self, id: &str) -> Value {
        self.wait_for(id, Duration::from_secs(60), |j| {
            matches!(
                j["status"].as_str(),
                Some("succeeded" | "failed" | "cancelled")
            )
        })
        .await
    }

    /// Wait until the job runs and has taken at least one step.
    pub async fn wait_running(&self, id: &str) -> Value {
        self.wait_for(id, Duration::from_secs(60), |j| {
            j["status"] == "running" && j["progress"]["step"].as_u64().unwrap_or(0) > 0
        })
        .await
    }
}

/// A still-water tank of 30 x 10 particles; `end` seconds of simulated time.
pub fn tiny_case(end: f64) -> Value {
    json!({
        "name": "tiny-tank",
        "fluid": { "density": 1000.0, "kinematic_viscosity": 1.0e-6, "gravity": [0.0, -9.81] },
        "particle_spacing": 0.01,
        "domain": { "min": [-0.05, -0.05], "max": [0.35, 0.3] },
        "fluid_blocks": [ { "polygon": [[0.0, 0.0], [0.3, 0.0], [0.3, 0.1], [0.0, 0.1]] } ],
        "walls": [ { "name": "tank", "polyline": [[0.0, 0.2], [0.0, 0.0], [0.3, 0.0], [0.3, 0.2]] } ],
        "time": { "end": end, "cfl": 0.2, "max_dt": 0.0005 },
        "output": { "load_interval": 0.001, "probes": [ { "name": "mid", "position": [0.15, 0.05] } ] },
        "scheme": {}
    })
}

/// The shipped wedge at 2 cm: 25 spacings across its breadth, outside the validated
/// envelope, so its submission and page carry advice ("25 spacings across").
pub fn advised_wedge() -> Value {
    let text = std::fs::read_to_string(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/cases/wedge_30deg_constant_velocity.json"
    ))
    .unwrap();
    let mut case: Value = serde_json::from_str(&text).unwrap();
    case["particle_spacing"] = json!(0.02);
    case
}

/// The advice list of a job page (the text inside `<ul id="advice">`); panics when the
/// page has none.
pub fn advice_on_page(page: &str) -> &str {
    page.split("<ul id=\"advice\">")
        .nth(1)
        .expect("an advice list on the page")
        .split("</ul>")
        .next()
        .unwrap()
}

/// Cancel a running job (POST /v1/jobs/{id}/cancel): 202 while the run is still
/// stopping, or 200 with status `cancelled` when it stopped between the request and the
/// handler's re-read (a step of the test tank is well under a millisecond; the cancel
/// tests met that race in full suite runs). Either answer conforms to the API description.
pub async fn cancel_running(app: &TestApp, id: &str) {
    let r = app
        .client
        .post(app.url(&format!("/v1/jobs/{id}/cancel")))
        .send()
        .await
        .unwrap();
    let code = r.status().as_u16();
    let body: Value = r.json().await.unwrap();
    assert!(
        code == 202 || (code == 200 && body["status"] == "cancelled"),
        "{code}: {body:#}"
    );
    assert_conforms("POST", "/v1/jobs/{id}/cancel", code, &body);
}

/// A job that runs far longer than any test waits (to be cancelled or killed).
pub fn long_case() -> Value {
    let mut case = tiny_case(100.0);
    case["name"] = json!("long-tank");
    case
}
