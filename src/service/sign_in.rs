//! `/v1/sign-in`: how a person opens the pages of a server that has a token
//! ([`super::auth`]). `GET` serves a small form; `POST` (form-encoded `token` and `next`)
//! with the server's token sets the read cookie and answers 303 to `next` (the jobs list
//! by default); a wrong token answers the form again with 401.
//!
//! The cookie is `HttpOnly` (no script reads it), `SameSite=Strict` (no other site's page
//! sends it), `Path=/`, and lasts [`SIGN_IN_LIFETIME`]. It is `Secure` when the request
//! came over TLS: the service speaks plain HTTP, so that is what a TLS-terminating proxy
//! says in `X-Forwarded-Proto: https` (or `Forwarded: proto=https`); the header only ever
//! restricts the cookie, so a client forging it gains nothing.
//!
//! `next` must be a path of this service: it starts with `/v1/` and is printable ASCII
//! (no spaces), so the redirect never leaves the site; anything else is a 400. Without a
//! token, the form says nothing needs signing in and a `POST` just redirects.

use super::auth::{Access, COOKIE_NAME, SIGN_IN_LIFETIME, SIGN_IN_PATH};
use super::error::ApiError;
use super::page;
use axum::extract::rejection::{FormRejection, QueryRejection};
use axum::extract::{Query, State};
use axum::http::{header, HeaderMap, StatusCode};
use axum::response::{IntoResponse, Response};
use axum::Form;
use serde::Deserialize;
use std::sync::Arc;

/// What the sign-in handlers need of the app's state: the token and its cookies, when
/// the server has a token.
#[derive(Debug, Clone)]
pub struct SignIn(pub Option<Arc<Access>>);

/// Where a sign-in goes when the form names no `next`.
pub const DEFAULT_NEXT: &str = "/v1/jobs";

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SignInQuery {
    next: Option<String>,
}

#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SignInForm {
    token: String,
    next: Option<String>,
}

/// Whether `next` is a path of this service (the contract's pattern `^/v1/[!-~]*$`).
pub fn is_local_path(next: &str) -> bool {
    next.starts_with("/v1/") && next.bytes().all(|b| b.is_ascii_graphic())
}

fn checked_next(next: Option<String>) -> Result<String, ApiError> {
    match next {
        None => Ok(DEFAULT_NEXT.to_string()),
        Some(next) if is_local_path(&next) => Ok(next),
        Some(_) => Err(ApiError::BadParameter {
            path: "next",
            message: "must be a path of this service: /v1/… in printable ASCII, no spaces".into(),
        }),
    }
}

fn html(status: StatusCode, body: String) -> Response {
    (
        status,
        [(header::CONTENT_TYPE, "text/html; charset=utf-8")],
        body,
    )
        .into_response()
}

/// `GET /v1/sign-in`: the form.
pub async fn sign_in_form(
    State(SignIn(access)): State<SignIn>,
    query: Result<Query<SignInQuery>, QueryRejection>,
) -> Result<Response, ApiError> {
    let Query(query) = query.map_err(|e| ApiError::BadRequest(e.body_text()))?;
    let next = checked_next(query.next)?;
    let form = page::sign_in_form(SIGN_IN_PATH, &next, access.is_some(), false);
    Ok(html(StatusCode::OK, form))
}

/// `POST /v1/sign-in`: check the token; the cookie and a 303 to `next`, or the form
/// again with 401.
#[tracing::instrument(name = "sign in", skip_all)]
pub async fn sign_in(
    State(SignIn(access)): State<SignIn>,
    headers: HeaderMap,
    form: Result<Form<SignInForm>, FormRejection>,
) -> Result<Response, ApiError> {
    let Form(form) = form.map_err(|e| ApiError::BadRequest(e.body_text()))?;
    let next = checked_next(form.next)?;
    if form.token.is_empty() {
        return Err(ApiError::BadParameter {
            path: "token",
            message: "the token is empty".into(),
        });
    }
    let Some(access) = access else {
        return Ok((StatusCode::SEE_OTHER, [(header::LOCATION, next)]).into_response());
    };
    if !access.token_matches(form.token.as_bytes()) {
        tracing::info!("sign-in refused: wrong token");
        let mut response = html(
            StatusCode::UNAUTHORIZED,
            page::sign_in_form(SIGN_IN_PATH, &next, true, true),
        );
        response.headers_mut().insert(
            header::WWW_AUTHENTICATE,
            header::HeaderValue::from_static("Bearer"),
        );
        return Ok(response);
    }
    let secure = if behind_tls(&headers) { "; Secure" } else { "" };
    let cookie = format!(
        "{COOKIE_NAME}={}; Path=/; Max-Age={}; HttpOnly; SameSite=Strict{secure}",
        access.new_cookie_value(),
        SIGN_IN_LIFETIME.as_secs()
    );
    tracing::info!("signed in");
    Ok((
        StatusCode::SEE_OTHER,
        [(header::LOCATION, next), (header::SET_COOKIE, cookie)],
    )
        .into_response())
}

/// Whether a proxy in front says the request came over TLS.
fn behind_tls(headers: &HeaderMap) -> bool {
    let values = |name| {
        headers
            .get_all(name)
            .iter()
            .filter_map(|v| v.to_str().ok())
            .flat_map(|v| v.split(','))
            .map(str::trim)
            .collect::<Vec<_>>()
    };
    let forwarded_proto = values("x-forwarded-proto")
        .first()
        .is_some_and(|p| p.eq_ignore_ascii_case("https"));
    let forwarded = values("forwarded").iter().any(|element| {
        element.split(';').any(|pair| {
            pair.trim().split_once('=').is_some_and(|(k, v)| {
                k.eq_ignore_ascii_case("proto") && v.trim_matches('"').eq_ignore_ascii_case("https")
            })
        })
    });
    forwarded_proto || forwarded
}
