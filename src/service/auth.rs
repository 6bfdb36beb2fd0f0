//! Access once the service leaves loopback. With a bearer token configured (the
//! `MPSFSI_TOKEN` variable or `--token-file`), every request but `GET /v1/health` and the
//! sign-in form must carry `Authorization: Bearer <token>`; without it, or with another
//! token, the answer is 401 `unauthorized` with `WWW-Authenticate: Bearer`.
//! [`resolve_token`] refuses a listen address beyond loopback with no token; on loopback
//! a configured token is enforced too. The token is compared in constant time
//! ([`Token::matches`]) and never printed ([`Token`]'s `Debug` is `<redacted>`).
//!
//! A browser sends no bearer header, so a person signs in once (`/v1/sign-in`,
//! [`super::sign_in`]) and gets a cookie that authorises GET and HEAD requests only
//! (pages, pictures, JSON reads); every other method still needs the bearer header, so a
//! cross-site form cannot act with the cookie and no CSRF token is needed. The cookie
//! is `<expiry>.<HMAC-SHA-256 of the expiry keyed by the token>` ([`Access`]): it does
//! not reveal the token, it cannot be extended, every API node sharing the token accepts
//! it (a per-process random key would sign a person out whenever the load balancer picked
//! another node, or the node restarted), and changing the token signs everyone out.
//! Without a token a page needs no sign-in; an HTML page refused for want of one
//! answers 401 with a link to the sign-in form.

use super::config::{Config, Token};
use super::error::ApiError;
use axum::extract::{Request, State};
use axum::http::{header, HeaderMap, HeaderValue, Method, StatusCode};
use axum::middleware::{self, Next};
use axum::response::{IntoResponse, Response};
use axum::Router;
use hmac::{Hmac, Mac};
use sha2::Sha256;
use std::net::SocketAddr;
use std::sync::Arc;
use std::time::{Duration, SystemTime, UNIX_EPOCH};

/// The one route answered without a token (load balancers and liveness probes).
pub const OPEN_PATH: &str = "/v1/health";

/// The sign-in form (GET) and the token check that sets the cookie (POST): answered
/// without a token, since they are how a browser gets one.
pub const SIGN_IN_PATH: &str = "/v1/sign-in";

/// The cookie a sign-in sets.
pub const COOKIE_NAME: &str = "mpsfsi_read";

/// How long a sign-in lasts: a week, since the cookie only reads.
pub const SIGN_IN_LIFETIME: Duration = Duration::from_secs(7 * 24 * 3600);

/// The token a server enforces and the sign-in cookies it accepts.
#[derive(Debug)]
pub struct Access {
    token: Token,
}

impl Access {
    pub fn new(token: Token) -> Self {
        Self { token }
    }

    /// Whether `presented` is the token (constant time).
    pub fn token_matches(&self, presented: &[u8]) -> bool {
        self.token.matches(presented)
    }

    fn mac(&self, expires: u64) -> Hmac<Sha256> {
        let mut mac = Hmac::<Sha256>::new_from_slice(self.token.as_str().as_bytes())
            .expect("HMAC takes a key of any length");
        mac.update(format!("mpsfsi read cookie until {expires}").as_bytes());
        mac
    }

    /// A cookie value valid for [`SIGN_IN_LIFETIME`] from now.
    pub fn new_cookie_value(&self) -> String {
        let expires = unix_now() + SIGN_IN_LIFETIME.as_secs();
        let tag = self.mac(expires).finalize().into_bytes();
        let hex: String = tag.iter().map(|b| format!("{b:02x}")).collect();
        format!("{expires}.{hex}")
    }

    /// Whether `value` is a cookie this token signed and that has not expired (the tag
    /// is compared in constant time).
    pub fn cookie_value_valid(&self, value: &str) -> bool {
        let Some((expires, hex)) = value.split_once('.') else {
            return false;
        };
        let Ok(expires) = expires.parse::<u64>() else {
            return false;
        };
        if expires <= unix_now() || hex.len() != 64 {
            return false;
        }
        let tag: Option<Vec<u8>> = (0..32)
            .map(|k| u8::from_str_radix(hex.get(2 * k..2 * k + 2)?, 16).ok())
            .collect();
        tag.is_some_and(|tag| self.mac(expires).verify_slice(&tag).is_ok())
    }

    /// Whether the request's `Cookie` headers carry a valid sign-in cookie.
    fn signed_in(&self, headers: &HeaderMap) -> bool {
        headers
            .get_all(header::COOKIE)
            .iter()
            .filter_map(|v| v.to_str().ok())
            .flat_map(|v| v.split(';'))
            .filter_map(|pair| pair.trim().split_once('='))
            .any(|(name, value)| name == COOKIE_NAME && self.cookie_value_valid(value))
    }
}

fn unix_now() -> u64 {
    SystemTime::now()
        .duration_since(UNIX_EPOCH)
        .map_or(0, |d| d.as_secs())
}

#[derive(Debug, thiserror::Error)]
pub enum AccessError {
    #[error("refusing to listen on {addr} without a token: beyond loopback the API requires a bearer token; set MPSFSI_TOKEN or --token-file (MPSFSI_TOKEN_FILE)")]
    NoToken { addr: SocketAddr },
    #[error("both MPSFSI_TOKEN and --token-file ({path}) are set: set one of them")]
    TwoTokens { path: String },
    #[error("cannot read the token file {path}: {source}")]
    TokenFile {
        path: String,
        source: std::io::Error,
    },
    #[error("the token {from} is empty")]
    Empty { from: String },
    #[error("the token {from} has a character other than printable ASCII (no spaces or control characters: it is sent in a header)")]
    BadCharacter { from: String },
}

/// The token this server enforces, if any: `MPSFSI_TOKEN` or the contents of
/// `--token-file`, surrounding whitespace trimmed (a file's trailing newline). An error
/// when both are set, when the file cannot be read, when the token is empty or not
/// printable ASCII, and when no token is set but the address is not loopback.
pub fn resolve_token(config: &Config) -> Result<Option<Token>, AccessError> {
    let (token, from) = match (&config.token, &config.token_file) {
        (Some(_), Some(path)) => {
            return Err(AccessError::TwoTokens {
                path: path.display().to_string(),
            })
        }
        (Some(token), None) => (token.clone(), format!("in {}", Token::ENV)),
        (None, Some(path)) => {
            let text = std::fs::read_to_string(path).map_err(|source| AccessError::TokenFile {
                path: path.display().to_string(),
                source,
            })?;
            (Token::new(text), format!("in the file {}", path.display()))
        }
        (None, None) if config.addr.ip().is_loopback() => return Ok(None),
        (None, None) => return Err(AccessError::NoToken { addr: config.addr }),
    };
    let token = Token::new(token.as_str().trim());
    if token.as_str().is_empty() {
        return Err(AccessError::Empty { from });
    }
    if !token.as_str().bytes().all(|b| b.is_ascii_graphic()) {
        return Err(AccessError::BadCharacter { from });
    }
    Ok(Some(token))
}

/// `router` behind the token check when there is a token; as it is otherwise.
pub fn require_token(router: Router, access: Option<Arc<Access>>) -> Router {
    match access {
        Some(access) => router.layer(middleware::from_fn_with_state(access, check)),
        None => router,
    }
}

async fn check(State(access): State<Arc<Access>>, request: Request, next: Next) -> Response {
    let path = request.uri().path();
    let read = matches!(*request.method(), Method::GET | Method::HEAD);
    let sign_in = path == SIGN_IN_PATH && (read || request.method() == Method::POST);
    if (read && path == OPEN_PATH) || sign_in {
        return next.run(request).await;
    }
    let refusal = match bearer(request.headers()) {
        Some(presented) if access.token_matches(presented) => None,
        Some(_) => Some((
            "the bearer token is not valid",
            r#"Bearer error="invalid_token""#,
        )),
        // the cookie reads, nothing more
        None if read && access.signed_in(request.headers()) => None,
        None => Some((
            "this server requires a token: send Authorization: Bearer <token>",
            "Bearer",
        )),
    };
    let Some((message, challenge)) = refusal else {
        return next.run(request).await;
    };
    let mut response = if read && is_page_request(path, request.headers()) {
        let target = request
            .uri()
            .path_and_query()
            .map_or(path, |pq| pq.as_str());
        (
            StatusCode::UNAUTHORIZED,
            [(header::CONTENT_TYPE, "text/html; charset=utf-8")],
            super::page::sign_in_needed(SIGN_IN_PATH, target),
        )
            .into_response()
    } else {
        ApiError::Unauthorized(message).into_response()
    };
    response.headers_mut().insert(
        header::WWW_AUTHENTICATE,
        HeaderValue::from_static(challenge),
    );
    response
}

/// Whether the request asks for an HTML page: a job's page (`/v1/jobs/{id}`) with an
/// Accept header naming `text/html`, as a browser sends. Every other route keeps its
/// JSON 401.
fn is_page_request(path: &str, headers: &HeaderMap) -> bool {
    let job_page = path
        .strip_prefix("/v1/jobs/")
        .is_some_and(|id| !id.is_empty() && !id.contains('/'));
    job_page
        && headers
            .get_all(header::ACCEPT)
            .iter()
            .filter_map(|v| v.to_str().ok())
            .any(|v| {
                v.split(',')
                    .any(|part| part.trim().starts_with("text/html"))
            })
}

/// The credentials of an `Authorization: Bearer <token>` header (scheme in any case).
fn bearer(headers: &HeaderMap) -> Option<&[u8]> {
    let value = headers.get(header::AUTHORIZATION)?.as_bytes();
    let (scheme, rest) = value.split_at(value.iter().position(|&b| b == b' ')?);
    scheme
        .eq_ignore_ascii_case(b"bearer")
        .then(|| rest.trim_ascii_start())
}
