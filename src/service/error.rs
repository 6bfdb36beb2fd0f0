//! The one error type of the HTTP layer. Every error answers
//! `{ "error": { "code", "message", "path" } }`; internal failures are logged with their
//! cause and answered with a generic message.

use crate::case::CaseError;
use axum::http::{header, HeaderValue, StatusCode};
use axum::response::{IntoResponse, Response};
use axum::Json;

#[derive(Debug, thiserror::Error)]
pub enum ApiError {
    #[error("the body is not valid JSON: {0}")]
    MalformedJson(String),
    #[error("{}", .0.message)]
    InvalidCase(CaseError),
    #[error("the request body is larger than the limit of {limit} bytes")]
    PayloadTooLarge { limit: usize },
    #[error("the job queue is full ({capacity} jobs waiting); retry later")]
    QueueFull { capacity: usize, retry_after_s: u64 },
    #[error("the request is invalid: {0}")]
    BadRequest(String),
    /// A query parameter outside what the contract allows (`path`: its name).
    #[error("the request is invalid: {path}: {message}")]
    BadParameter { path: &'static str, message: String },
    #[error("{0}")]
    Unauthorized(&'static str),
    #[error("no job with id {0}")]
    JobNotFound(String),
    #[error("job {id} has already finished ({status})")]
    AlreadyFinished { id: String, status: String },
    #[error("job {0} has no snapshots (yet): its case sets output.snapshot_interval to \"none\", or no snapshot has been written")]
    NoSnapshots(String),
    #[error("job {id} ran on worker {worker}: its snapshots are in {dir} on that host, which this node cannot read (the loads, bodies and probes are served by every node)")]
    SnapshotsElsewhere {
        id: String,
        worker: String,
        dir: String,
    },
    /// `message` names the bodies and walls the job has.
    #[error("job {id}: {message}")]
    BodyNotFound { id: String, message: String },
    #[error("no route for {0}")]
    RouteNotFound(String),
    #[error("method not allowed")]
    MethodNotAllowed,
    #[error("the service is shutting down")]
    ShuttingDown,
    #[error("internal error")]
    Internal(#[source] Box<dyn std::error::Error + Send + Sync>),
}

impl ApiError {
    pub fn internal(e: impl Into<Box<dyn std::error::Error + Send + Sync>>) -> Self {
        Self::Internal(e.into())
    }

    pub fn status(&self) -> StatusCode {
        match self {
            Self::MalformedJson(_) | Self::BadRequest(_) | Self::BadParameter { .. } => {
                StatusCode::BAD_REQUEST
            }
            Self::InvalidCase(_) => StatusCode::UNPROCESSABLE_ENTITY,
            Self::PayloadTooLarge { .. } => StatusCode::PAYLOAD_TOO_LARGE,
            Self::QueueFull { .. } | Self::ShuttingDown => StatusCode::SERVICE_UNAVAILABLE,
            Self::JobNotFound(_)
            | Self::RouteNotFound(_)
            | Self::NoSnapshots(_)
            | Self::SnapshotsElsewhere { .. }
            | Self::BodyNotFound { .. } => StatusCode::NOT_FOUND,
            Self::Unauthorized(_) => StatusCode::UNAUTHORIZED,
            Self::AlreadyFinished { .. } => StatusCode::CONFLICT,
            Self::MethodNotAllowed => StatusCode::METHOD_NOT_ALLOWED,
            Self::Internal(_) => StatusCode::INTERNAL_SERVER_ERROR,
        }
    }

    /// Stable machine-readable code (documented in api/openapi.yaml).
    pub fn code(&self) -> &'static str {
        match self {
            Self::MalformedJson(_) => "malformed_json",
            Self::InvalidCase(_) => "invalid_case",
            Self::PayloadTooLarge { .. } => "payload_too_large",
            Self::QueueFull { .. } => "queue_full",
            Self::BadRequest(_) | Self::BadParameter { .. } => "bad_request",
            Self::Unauthorized(_) => "unauthorized",
            Self::JobNotFound(_) => "job_not_found",
            Self::AlreadyFinished { .. } => "job_finished",
            Self::NoSnapshots(_) | Self::SnapshotsElsewhere { .. } => "no_snapshots",
            Self::BodyNotFound { .. } => "body_not_found",
            Self::RouteNotFound(_) => "route_not_found",
            Self::MethodNotAllowed => "method_not_allowed",
            Self::ShuttingDown => "shutting_down",
            Self::Internal(_) => "internal",
        }
    }
}

impl From<sqlx::Error> for ApiError {
    fn from(e: sqlx::Error) -> Self {
        Self::internal(e)
    }
}

impl From<std::io::Error> for ApiError {
    fn from(e: std::io::Error) -> Self {
        Self::internal(e)
    }
}

impl IntoResponse for ApiError {
    fn into_response(self) -> Response {
        let status = self.status();
        if let Self::Internal(cause) = &self {
            tracing::error!(error = %cause, debug = ?cause, "internal error");
        } else {
            tracing::debug!(code = self.code(), message = %self, "request refused");
        }
        let path = match &self {
            Self::InvalidCase(e) => serde_json::Value::String(e.path.clone()),
            Self::BadParameter { path, .. } => serde_json::Value::String(path.to_string()),
            _ => serde_json::Value::Null,
        };
        let body = serde_json::json!({
            "error": { "code": self.code(), "message": self.to_string(), "path": path }
        });
        let mut response = (status, Json(body)).into_response();
        if let Self::QueueFull { retry_after_s, .. } = self {
            response
                .headers_mut()
                .insert(header::RETRY_AFTER, HeaderValue::from(retry_after_s));
        }
        response
    }
}
