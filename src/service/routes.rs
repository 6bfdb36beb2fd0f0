//! HTTP handlers of api/openapi.yaml. The router is built from one table ([`endpoints`]),
//! which is also what the contract test compares with `api/openapi.yaml`.

use super::auth::{Access, SIGN_IN_PATH};
use super::error::ApiError;
use super::job_json::job_json;
use super::run_files::snapshot_dir;
use super::series::{self, SeriesFile};
use super::sign_in::{sign_in, sign_in_form, SignIn};
use super::store::{Admission, JobRow, JobStatus};
use super::workers::Jobs;
use crate::analysis::envelope::impact_advice;
use crate::case::{parse_case_str, parse_case_value, ValidCase};
use crate::output::flow::{
    flow_svg, parse_window, read_snapshot, snapshot_times, title, FlowField, Snapshot,
    SnapshotError,
};
use crate::output::plot::PlotError;
use crate::output::series::{complete_lines, csv_to_columns};
use crate::output::surface::{surface_svg, surface_title, Objects};
use crate::run::uncertainty as ladder;
use axum::body::Bytes;
use axum::extract::rejection::{BytesRejection, QueryRejection};
use axum::extract::{DefaultBodyLimit, Path, Query, State};
use axum::http::{header, HeaderMap, Method, StatusCode, Uri};
use axum::response::{IntoResponse, Response};
use axum::routing::{on, MethodFilter, MethodRouter};
use axum::{Json, Router};
use serde::Deserialize;
use serde_json::{json, Value};
use std::sync::Arc;
use uuid::Uuid;

/// What every handler sees.
#[derive(Debug, Clone)]
pub struct AppState {
    pub jobs: Arc<Jobs>,
    pub openapi: Arc<Value>,
    /// The token and its sign-in cookies, when the server has a token.
    pub access: Option<Arc<Access>>,
}

impl axum::extract::FromRef<AppState> for SignIn {
    fn from_ref(state: &AppState) -> Self {
        SignIn(state.access.clone())
    }
}

/// Seconds a client refused with 503 is told to wait.
const RETRY_AFTER_S: u64 = 5;

/// Every route: method, path (axum syntax, same as OpenAPI's), handler.
pub fn endpoints() -> Vec<(Method, &'static str, MethodRouter<AppState>)> {
    vec![
        (Method::POST, "/v1/jobs", on(MethodFilter::POST, submit_job)),
        (Method::GET, "/v1/jobs", on(MethodFilter::GET, list_jobs)),
        (Method::GET, "/v1/jobs/{id}", on(MethodFilter::GET, get_job)),
        (
            Method::DELETE,
            "/v1/jobs/{id}",
            on(MethodFilter::DELETE, delete_job),
        ),
        (
            Method::POST,
            "/v1/jobs/{id}/cancel",
            on(MethodFilter::POST, cancel_job),
        ),
        (
            Method::GET,
            "/v1/jobs/{id}/loads",
            on(MethodFilter::GET, get_loads),
        ),
        (
            Method::GET,
            "/v1/jobs/{id}/bodies",
            on(MethodFilter::GET, get_bodies),
        ),
        (
            Method::GET,
            "/v1/jobs/{id}/probes",
            on(MethodFilter::GET, get_probes),
        ),
        (
            Method::GET,
            "/v1/jobs/{id}/loads_uncertainty",
            on(MethodFilter::GET, get_loads_uncertainty),
        ),
        (
            Method::GET,
            "/v1/jobs/{id}/loads_filtered",
            on(MethodFilter::GET, get_loads_filtered),
        ),
        (
            Method::GET,
            "/v1/jobs/{id}/loads.svg",
            on(MethodFilter::GET, get_loads_svg),
        ),
        (
            Method::GET,
            "/v1/jobs/{id}/snapshot.svg",
            on(MethodFilter::GET, get_snapshot_svg),
        ),
        (
            Method::GET,
            "/v1/jobs/{id}/surface.svg",
            on(MethodFilter::GET, get_surface_svg),
        ),
        (
            Method::GET,
            SIGN_IN_PATH,
            on(MethodFilter::GET, sign_in_form),
        ),
        (Method::POST, SIGN_IN_PATH, on(MethodFilter::POST, sign_in)),
        (Method::GET, "/v1/health", on(MethodFilter::GET, health)),
        (
            Method::GET,
            "/v1/openapi.json",
            on(MethodFilter::GET, openapi),
        ),
    ]
}

/// `(method, path)` of every route the server answers.
pub fn route_table() -> Vec<(Method, &'static str)> {
    endpoints().into_iter().map(|(m, p, _)| (m, p)).collect()
}

pub fn router(state: AppState, max_body_bytes: usize) -> Router {
    let mut router = Router::new();
    for (_, path, handler) in endpoints() {
        router = router.route(path, handler);
    }
    router
        .fallback(|uri: Uri| async move { ApiError::RouteNotFound(uri.path().to_string()) })
        .method_not_allowed_fallback(|| async { ApiError::MethodNotAllowed })
        .layer(DefaultBodyLimit::max(max_body_bytes))
        .with_state(state)
}

/// Where a job's run directory is readable from this node: the directory its worker
/// recorded when this host can see it, else this node's own job directory (with the
/// snapshots a shared store holds copied there).
async fn run_dir(state: &AppState, row: &JobRow) -> Result<std::path::PathBuf, ApiError> {
    let local = state.jobs.config.job_dir(&row.id);
    let store = &state.jobs.store;
    Ok(snapshot_dir(store, row.id, row.run_dir.as_deref(), local).await?)
}

fn parse_id(id: &str) -> Result<Uuid, ApiError> {
    Uuid::parse_str(id).map_err(|_| ApiError::JobNotFound(id.to_string()))
}

async fn find_job(state: &AppState, id: &str) -> Result<JobRow, ApiError> {
    let uuid = parse_id(id)?;
    // a ladder's parts are rows of the store, not jobs
    state
        .jobs
        .store
        .get(uuid)
        .await?
        .filter(|row| row.parent.is_none())
        .ok_or_else(|| ApiError::JobNotFound(id.to_string()))
}

/// `POST /v1/jobs?uncertainty=true`: run the resolution ladder (`mpsfsi run --uncertainty`).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct SubmitQuery {
    #[serde(default)]
    uncertainty: bool,
}

#[tracing::instrument(name = "submit job", skip_all)]
async fn submit_job(
    State(state): State<AppState>,
    query: Result<Query<SubmitQuery>, QueryRejection>,
    body: Result<Bytes, BytesRejection>,
) -> Result<Response, ApiError> {
    let Query(SubmitQuery { uncertainty }) =
        query.map_err(|e| ApiError::BadRequest(e.body_text()))?;
    let config = &state.jobs.config;
    let body = body.map_err(|rejection| {
        if rejection.status() == StatusCode::PAYLOAD_TOO_LARGE {
            ApiError::PayloadTooLarge {
                limit: config.max_body_bytes,
            }
        } else {
            ApiError::BadRequest(rejection.body_text())
        }
    })?;
    // The job runs from the text as submitted, so it parses exactly as `mpsfsi run` would
    // parse the same file.
    // empty, not blank: a body of whitespace is not JSON, and is refused as such
    let case_text: String = if body.is_empty() {
        match super::DEFAULT_CASE {
            Some(text) => text.to_string(),
            None => {
                return Err(ApiError::MalformedJson(
                    "the body is empty (no default case is built in)".into(),
                ))
            }
        }
    } else {
        String::from_utf8(body.to_vec()).map_err(|e| ApiError::MalformedJson(e.to_string()))?
    };
    let value: Value =
        serde_json::from_str(&case_text).map_err(|e| ApiError::MalformedJson(e.to_string()))?;
    let case = parse_case_value(value)
        .and_then(|case| ValidCase::new(case, &config.limits()))
        .map_err(ApiError::InvalidCase)?;
    // every level of the ladder laid out and validated before the job is queued; its
    // parts are queued with it, to run on whichever workers are free
    let ladder_parts = match uncertainty {
        true => Some(
            ladder::ladder(&case)
                .map_err(ApiError::InvalidCase)?
                .0
                .len(),
        ),
        false => None,
    };
    if state.jobs.is_stopping() {
        return Err(ApiError::ShuttingDown);
    }

    let id = Uuid::new_v4();
    let dir = config.job_dir(&id);
    // with a shared store the worker writes the run directory, on its own host
    let shared = state.jobs.store.is_shared();
    if !shared {
        tokio::fs::create_dir_all(&dir).await?;
        tokio::fs::write(dir.join("case.json"), &case_text).await?;
    }
    let admission = state
        .jobs
        .store
        .submit(
            id,
            &case.name,
            &case_text,
            case.time.end,
            ladder_parts,
            config.queue_capacity,
        )
        .await;
    match admission {
        Ok(Admission::Accepted(row)) => {
            match ladder_parts {
                Some(_) => state.jobs.jobs_queued(),
                None => state.jobs.job_queued(),
            }
            tracing::info!(%id, name = %case.name, "job queued");
            let location = format!("/v1/jobs/{id}");
            // what `mpsfsi check` would advise, told at once rather than only in the
            // summary at the end of the run
            let mut body = job_json(&row);
            let advice = impact_advice(&case);
            if !advice.is_empty() {
                body["advice"] = json!(advice);
            }
            Ok((
                StatusCode::CREATED,
                [(header::LOCATION, location)],
                Json(body),
            )
                .into_response())
        }
        Ok(Admission::QueueFull) => {
            if !shared {
                let _ = tokio::fs::remove_dir_all(&dir).await;
            }
            Err(ApiError::QueueFull {
                capacity: config.queue_capacity,
                retry_after_s: RETRY_AFTER_S,
            })
        }
        Err(e) => {
            if !shared {
                let _ = tokio::fs::remove_dir_all(&dir).await;
            }
            Err(e.into())
        }
    }
}

#[derive(Debug, Deserialize)]
struct ListQuery {
    status: Option<String>,
    limit: Option<i64>,
    offset: Option<i64>,
}

const MAX_PAGE: i64 = 1000;
/// Largest `offset` of the job list (the contract's bound: an offset is an i64 here).
const MAX_OFFSET: i64 = 1_000_000_000;

#[tracing::instrument(name = "list jobs", skip_all)]
async fn list_jobs(
    State(state): State<AppState>,
    query: Result<Query<ListQuery>, QueryRejection>,
) -> Result<Json<Value>, ApiError> {
    let Query(query) = query.map_err(|e| ApiError::BadRequest(e.body_text()))?;
    let status = match query.status.as_deref() {
        None => None,
        Some(s) => Some(JobStatus::parse(s).ok_or_else(|| ApiError::BadParameter {
            path: "status",
            message: format!(
                "unknown status {s:?} (expected queued, running, succeeded, failed or cancelled)"
            ),
        })?),
    };
    let limit = query.limit.unwrap_or(50);
    let offset = query.offset.unwrap_or(0);
    if !(1..=MAX_PAGE).contains(&limit) {
        return Err(ApiError::BadParameter {
            path: "limit",
            message: format!("must be 1..={MAX_PAGE} (got {limit})"),
        });
    }
    if !(0..=MAX_OFFSET).contains(&offset) {
        return Err(ApiError::BadParameter {
            path: "offset",
            message: format!("must be 0..={MAX_OFFSET} (got {offset})"),
        });
    }
    let (rows, total) = state.jobs.store.list(status, limit, offset).await?;
    let jobs: Vec<Value> = rows.iter().map(job_json).collect();
    Ok(Json(
        json!({ "jobs": jobs, "total": total, "limit": limit, "offset": offset }),
    ))
}

/// The job record as JSON, or its page for a browser (`Accept: text/html`).
#[tracing::instrument(name = "get job", skip(state, headers))]
async fn get_job(
    State(state): State<AppState>,
    Path(id): Path<String>,
    headers: HeaderMap,
) -> Result<Response, ApiError> {
    let row = find_job(&state, &id).await?;
    if accepts(&headers, "text/html") {
        let dir = run_dir(&state, &row).await?;
        let times = tokio::task::spawn_blocking(move || snapshot_times(&dir))
            .await
            .map_err(ApiError::internal)?
            .map_err(ApiError::internal)?;
        // the advice `mpsfsi check` gives the case, on the page from submission on (the
        // summary carries it only once the run ends)
        let case = match state.jobs.store.case_text(row.id).await? {
            Some(text) => parse_case_str(&text).ok(),
            None => None,
        };
        let advice = case.as_ref().map(impact_advice).unwrap_or_default();
        let bodies: Vec<String> = case
            .iter()
            .flat_map(|c| c.bodies.iter().map(|b| b.name.clone()))
            .collect();
        let html = super::page::job_page(&row, &job_json(&row), &advice, &bodies, &times);
        return Ok(([(header::CONTENT_TYPE, "text/html; charset=utf-8")], html).into_response());
    }
    Ok(Json(job_json(&row)).into_response())
}

#[tracing::instrument(name = "cancel job", skip(state))]
async fn cancel_job(
    State(state): State<AppState>,
    Path(id): Path<String>,
) -> Result<Response, ApiError> {
    let row = find_job(&state, &id).await?;
    if row.status.is_finished() {
        return Err(ApiError::AlreadyFinished {
            id,
            status: row.status.as_str().to_string(),
        });
    }
    // its ladder's parts end with it, whichever worker runs them
    state.jobs.cancel_parts(row.id).await?;
    if state.jobs.store.cancel_if_queued(row.id).await? {
        let row = find_job(&state, &id).await?;
        return Ok((StatusCode::OK, Json(job_json(&row))).into_response());
    }
    // Running (or claimed since we looked): the run stops at its next step, here or on
    // the worker that holds it (at its next lease renewal).
    state.jobs.request_cancel(row.id);
    state.jobs.store.request_cancel(row.id).await?;
    let row = find_job(&state, &id).await?;
    if row.status.is_finished() {
        return Ok((StatusCode::OK, Json(job_json(&row))).into_response());
    }
    Ok((StatusCode::ACCEPTED, Json(job_json(&row))).into_response())
}

/// Remove the job, its record and its files; a running job is cancelled first (see
/// [`Jobs::delete`]). Then every route of the job answers 404.
#[tracing::instrument(name = "delete job", skip(state))]
async fn delete_job(
    State(state): State<AppState>,
    Path(id): Path<String>,
) -> Result<StatusCode, ApiError> {
    let uuid = parse_id(&id)?;
    if state.jobs.delete(uuid).await? {
        tracing::info!("job deleted");
        Ok(StatusCode::NO_CONTENT)
    } else {
        Err(ApiError::JobNotFound(id))
    }
}

/// Whether the Accept header names `media_type` (a browser's `text/html,...`; `*/*`
/// alone keeps JSON).
fn accepts(headers: &HeaderMap, media_type: &str) -> bool {
    headers
        .get_all(header::ACCEPT)
        .iter()
        .filter_map(|v| v.to_str().ok())
        .any(|v| v.split(',').any(|part| part.trim().starts_with(media_type)))
}

fn wants_csv(headers: &HeaderMap) -> bool {
    accepts(headers, "text/csv")
}

/// The complete lines of a job's CSV file, or the header alone when nothing exists yet.
async fn read_series(
    state: &AppState,
    row: &JobRow,
    file: SeriesFile,
) -> Result<Vec<u8>, ApiError> {
    if let Some(bytes) = state.jobs.store.read_series(row.id, file.file).await? {
        if bytes.is_empty() {
            return Ok(format!("{}\n", file.header).into_bytes());
        }
        return Ok(complete_lines(&bytes).to_vec());
    }
    let path = state.jobs.config.job_dir(&row.id).join(file.file);
    match tokio::fs::read(&path).await {
        Ok(bytes) => Ok(complete_lines(&bytes).to_vec()),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
            Ok(format!("{}\n", file.header).into_bytes())
        }
        Err(e) => Err(e.into()),
    }
}

async fn serve_series(
    state: AppState,
    id: String,
    headers: HeaderMap,
    file: SeriesFile,
) -> Result<Response, ApiError> {
    let row = find_job(&state, &id).await?;
    let text = read_series(&state, &row, file).await?;
    if wants_csv(&headers) {
        return Ok(([(header::CONTENT_TYPE, "text/csv; charset=utf-8")], text).into_response());
    }
    let columns = csv_to_columns(&text).map_err(ApiError::internal)?;
    let mut body = serde_json::Map::new();
    body.insert("job".into(), Value::String(row.id.to_string()));
    body.insert("status".into(), Value::String(row.status.as_str().into()));
    body.insert(file.group.into(), Value::Object(columns));
    Ok(Json(Value::Object(body)).into_response())
}

#[tracing::instrument(name = "get loads", skip(state, headers))]
async fn get_loads(
    State(state): State<AppState>,
    Path(id): Path<String>,
    headers: HeaderMap,
) -> Result<Response, ApiError> {
    serve_series(state, id, headers, series::LOADS).await
}

#[tracing::instrument(name = "get bodies", skip(state, headers))]
async fn get_bodies(
    State(state): State<AppState>,
    Path(id): Path<String>,
    headers: HeaderMap,
) -> Result<Response, ApiError> {
    serve_series(state, id, headers, series::BODIES).await
}

#[tracing::instrument(name = "get probes", skip(state, headers))]
async fn get_probes(
    State(state): State<AppState>,
    Path(id): Path<String>,
    headers: HeaderMap,
) -> Result<Response, ApiError> {
    serve_series(state, id, headers, series::PROBES).await
}

#[tracing::instrument(name = "get filtered loads", skip(state, headers))]
async fn get_loads_filtered(
    State(state): State<AppState>,
    Path(id): Path<String>,
    headers: HeaderMap,
) -> Result<Response, ApiError> {
    serve_series(state, id, headers, series::LOADS_FILTERED).await
}

#[tracing::instrument(name = "get loads uncertainty", skip(state, headers))]
async fn get_loads_uncertainty(
    State(state): State<AppState>,
    Path(id): Path<String>,
    headers: HeaderMap,
) -> Result<Response, ApiError> {
    serve_series(state, id, headers, series::LOADS_UNCERTAINTY).await
}

#[tracing::instrument(name = "get loads plot", skip(state))]
async fn get_loads_svg(
    State(state): State<AppState>,
    Path(id): Path<String>,
) -> Result<Response, ApiError> {
    let row = find_job(&state, &id).await?;
    let text = read_series(&state, &row, series::LOADS).await?;
    let text = String::from_utf8(text).map_err(ApiError::internal)?;
    // the band once the ladder has written it
    let band = match row.uncertainty {
        true => Some(read_series(&state, &row, series::LOADS_UNCERTAINTY).await?),
        false => None,
    }
    .map(String::from_utf8)
    .transpose()
    .map_err(ApiError::internal)?
    .filter(|b| b.lines().nth(1).is_some());
    let title = format!("{} ({}): loads", row.name, row.status.as_str());
    let svg = tokio::task::spawn_blocking(move || {
        crate::output::plot::loads_svg_with_band(&text, band.as_deref(), &title)
    })
    .await
    .map_err(ApiError::internal)?
    .map_err(ApiError::internal)?;
    Ok(([(header::CONTENT_TYPE, "image/svg+xml")], svg).into_response())
}

#[derive(Debug, Deserialize)]
struct SnapshotQuery {
    time: Option<f64>,
    field: Option<String>,
    window: Option<String>,
}

#[tracing::instrument(name = "get snapshot plot", skip(state))]
async fn get_snapshot_svg(
    State(state): State<AppState>,
    Path(id): Path<String>,
    query: Result<Query<SnapshotQuery>, QueryRejection>,
) -> Result<Response, ApiError> {
    let Query(query) = query.map_err(|e| ApiError::BadRequest(e.body_text()))?;
    let field = match query.field.as_deref() {
        None => FlowField::Pressure,
        Some(name) => {
            FlowField::parse(name).map_err(|e| ApiError::BadRequest(format!("field {e}")))?
        }
    };
    if query.time.is_some_and(|t| !t.is_finite()) {
        return Err(ApiError::BadRequest(
            "time must be a finite number of seconds".into(),
        ));
    }
    let window = query
        .window
        .as_deref()
        .map(parse_window)
        .transpose()
        .map_err(|e| ApiError::BadRequest(format!("window: {e}")))?;
    let row = find_job(&state, &id).await?;
    let dir = run_dir(&state, &row).await?;
    draw_snapshot(row, dir, id, query.time, move |snapshot, name| {
        flow_svg(snapshot, field, window, &title(name, snapshot)).map(|(svg, _)| svg)
    })
    .await
}

/// The picture `draw` makes of the job's snapshot nearest `time` (read and drawn off
/// the async threads), as an SVG response.
async fn draw_snapshot(
    row: JobRow,
    dir: std::path::PathBuf,
    id: String,
    time: Option<f64>,
    draw: impl FnOnce(&Snapshot, &str) -> Result<String, PlotError> + Send + 'static,
) -> Result<Response, ApiError> {
    let svg = tokio::task::spawn_blocking(move || {
        let snapshot =
            read_snapshot(&dir, time).map_err(|e| snapshot_error(e, &dir, row.clone(), id))?;
        draw(&snapshot, &row.name).map_err(plot_error)
    })
    .await
    .map_err(ApiError::internal)??;
    Ok(([(header::CONTENT_TYPE, "image/svg+xml")], svg).into_response())
}

/// The error of a snapshot that cannot be read: none written (or written on a worker
/// whose directory this node cannot read), or an I/O failure.
fn snapshot_error(e: SnapshotError, dir: &std::path::Path, row: JobRow, id: String) -> ApiError {
    match e {
        SnapshotError::None if !dir.is_dir() && row.run_dir.is_some() => {
            ApiError::SnapshotsElsewhere {
                id,
                worker: row.worker.unwrap_or_default(),
                dir: row.run_dir.unwrap_or_default(),
            }
        }
        SnapshotError::None => ApiError::NoSnapshots(id),
        SnapshotError::Io(e) => ApiError::internal(e),
    }
}

/// A picture that cannot be drawn: from what the request asked (400), or not (500).
fn plot_error(e: PlotError) -> ApiError {
    match e {
        PlotError::Data(m) => ApiError::BadRequest(m),
        e => ApiError::internal(e),
    }
}

/// The wall objects of a job, in the order of its loads: from the case it was submitted
/// with (every node has it), else from its run directory.
async fn job_objects(
    state: &AppState,
    row: &JobRow,
    dir: std::path::PathBuf,
) -> Result<Objects, ApiError> {
    if let Some(text) = state.jobs.store.case_text(row.id).await? {
        if let Ok(case) = parse_case_str(&text) {
            return Ok(Objects::of_case(&case));
        }
    }
    tokio::task::spawn_blocking(move || Objects::of_run(&dir))
        .await
        .map_err(ApiError::internal)?
        .map_err(ApiError::internal)
}

#[derive(Debug, Deserialize)]
struct SurfaceQuery {
    body: Option<String>,
    time: Option<f64>,
}

#[tracing::instrument(name = "get surface plot", skip(state))]
async fn get_surface_svg(
    State(state): State<AppState>,
    Path(id): Path<String>,
    query: Result<Query<SurfaceQuery>, QueryRejection>,
) -> Result<Response, ApiError> {
    let Query(query) = query.map_err(|e| ApiError::BadRequest(e.body_text()))?;
    let body = query.body.ok_or(ApiError::BadParameter {
        path: "body",
        message: "the name of a body (or wall) of the job is required".into(),
    })?;
    if query.time.is_some_and(|t| !t.is_finite()) {
        return Err(ApiError::BadRequest(
            "time must be a finite number of seconds".into(),
        ));
    }
    let row = find_job(&state, &id).await?;
    let dir = run_dir(&state, &row).await?;
    let object = job_objects(&state, &row, dir.clone())
        .await?
        .find(&body)
        .map_err(|message| ApiError::BodyNotFound {
            id: id.clone(),
            message,
        })?;
    draw_snapshot(row, dir, id, query.time, move |snapshot, name| {
        surface_svg(snapshot, object, &surface_title(name, &body, snapshot))
    })
    .await
}

async fn health(State(state): State<AppState>) -> Result<Json<Value>, ApiError> {
    state.jobs.store.ping().await?;
    Ok(Json(json!({
        "status": if state.jobs.is_stopping() { "stopping" } else { "ok" },
        "version": env!("CARGO_PKG_VERSION"),
        "workers": state.jobs.config.workers,
        "running_jobs": state.jobs.running_jobs(),
    })))
}

async fn openapi(State(state): State<AppState>) -> Json<Value> {
    Json((*state.openapi).clone())
}
