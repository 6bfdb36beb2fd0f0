//! Access once the service leaves loopback. With a bearer token configured (the
//! `MPSFSI_TOKEN` variable or `--token-file`), every request but `GET /v1/health` must
//! carry `Authorization: Bearer <token>`; without it, or with another token, the answer
//! is 401 `unauthorized` with `WWW-Authenticate: Bearer`. [`resolve_token`] refuses a
//! listen address beyond loopback with no token; on loopback a configured token is
//! enforced too. The token is compared in constant time ([`Token::matches`]) and never
//! printed ([`Token`]'s `Debug` is `<redacted>`).

use super::config::{Config, Token};
use super::error::ApiError;
use axum::extract::{Request, State};
use axum::http::{header, HeaderMap, HeaderValue, Method};
use axum::middleware::{self, Next};
use axum::response::{IntoResponse, Response};
use axum::Router;
use std::net::SocketAddr;
use std::sync::Arc;

/// The one route answered without a token (load balancers and liveness probes).
pub const OPEN_PATH: &str = "/v1/health";

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
pub fn require_token(router: Router, token: Option<Token>) -> Router {
    match token {
        Some(token) => router.layer(middleware::from_fn_with_state(Arc::new(token), check)),
        None => router,
    }
}

async fn check(State(token): State<Arc<Token>>, request: Request, next: Next) -> Response {
    if request.uri().path() == OPEN_PATH && matches!(*request.method(), Method::GET | Method::HEAD)
    {
        return next.run(request).await;
    }
    let refusal = match bearer(request.headers()) {
        Some(presented) if token.matches(presented) => None,
        Some(_) => Some((
            "the bearer token is not valid",
            r#"Bearer error="invalid_token""#,
        )),
        None => Some((
            "this server requires a token: send Authorization: Bearer <token>",
            "Bearer",
        )),
    };
    let Some((message, challenge)) = refusal else {
        return next.run(request).await;
    };
    let mut response = ApiError::Unauthorized(message).into_response();
    response.headers_mut().insert(
        header::WWW_AUTHENTICATE,
        HeaderValue::from_static(challenge),
    );
    response
}

/// The credentials of an `Authorization: Bearer <token>` header (scheme in any case).
fn bearer(headers: &HeaderMap) -> Option<&[u8]> {
    let value = headers.get(header::AUTHORIZATION)?.as_bytes();
    let (scheme, rest) = value.split_at(value.iter().position(|&b| b == b' ')?);
    scheme
        .eq_ignore_ascii_case(b"bearer")
        .then(|| rest.trim_ascii_start())
}
