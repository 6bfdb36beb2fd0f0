//! Typed service configuration: every field is a `serve` flag and an `MPSFSI_*`
//! environment variable (flags win). `mpsfsi serve` flattens [`Config`] into its
//! arguments; tests build one with [`Config::for_tests`]. The one exception is the
//! bearer token itself: `MPSFSI_TOKEN` only, never a flag (it would show in `ps`).

use crate::case::Limits;
use std::net::SocketAddr;
use std::path::PathBuf;
use std::time::Duration;
use subtle::ConstantTimeEq;

#[derive(Debug, Clone, clap::Args)]
pub struct Config {
    /// Address to listen on (port 0 picks a free port).
    #[arg(long, env = "MPSFSI_ADDR", default_value = "127.0.0.1:8080")]
    pub addr: SocketAddr,
    /// Data directory: jobs.db and one run directory per job under jobs/<id>/.
    #[arg(long = "data", env = "MPSFSI_DATA", default_value = "mpsfsi-data")]
    pub data_dir: PathBuf,
    /// Jobs run at the same time (each one also uses the rayon thread pool).
    #[arg(long, env = "MPSFSI_WORKERS", default_value_t = 1)]
    pub workers: usize,
    /// Jobs that may wait in the queue; beyond it submissions get 503 + Retry-After.
    #[arg(long, env = "MPSFSI_QUEUE_CAPACITY", default_value_t = 64)]
    pub queue_capacity: usize,
    /// Largest number of fluid particles a submitted case may create.
    #[arg(long, env = "MPSFSI_MAX_PARTICLES", default_value_t = 500_000)]
    pub max_particles: usize,
    /// Largest request body in bytes (413 beyond).
    #[arg(long, env = "MPSFSI_MAX_BODY_BYTES", default_value_t = 1 << 20)]
    pub max_body_bytes: usize,
    /// Seconds a shutdown waits for running jobs before interrupting them (they are then
    /// recorded `failed` with reason `interrupted`; queued jobs stay queued).
    #[arg(long, env = "MPSFSI_SHUTDOWN_GRACE_S", default_value_t = 10.0)]
    pub shutdown_grace_s: f64,
    /// File holding the bearer token clients must send (`Authorization: Bearer <token>`);
    /// or put the token itself in MPSFSI_TOKEN. Required when --addr is not loopback.
    #[arg(long, env = "MPSFSI_TOKEN_FILE", value_name = "PATH")]
    pub token_file: Option<PathBuf>,
    /// The token from MPSFSI_TOKEN (see [`super::auth`]).
    #[arg(skip = Token::from_env())]
    pub token: Option<Token>,
}

/// A bearer token. Its `Debug` prints `<redacted>`, so a logged or printed [`Config`]
/// never shows it; [`Token::matches`] compares in constant time.
#[derive(Clone)]
pub struct Token(String);

impl Token {
    pub const ENV: &'static str = "MPSFSI_TOKEN";

    pub fn new(token: impl Into<String>) -> Self {
        Self(token.into())
    }

    /// `MPSFSI_TOKEN`, when set.
    pub fn from_env() -> Option<Self> {
        std::env::var_os(Self::ENV).map(|v| Self(v.to_string_lossy().into_owned()))
    }

    pub(super) fn as_str(&self) -> &str {
        &self.0
    }

    /// Whether `presented` is this token, in a time that does not depend on where they
    /// differ (`subtle`; a length mismatch answers at once: the length is no secret).
    pub fn matches(&self, presented: &[u8]) -> bool {
        self.0.as_bytes().ct_eq(presented).into()
    }
}

impl std::fmt::Debug for Token {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("<redacted>")
    }
}

impl Config {
    /// Defaults with the given data directory, on 127.0.0.1 with port 0.
    pub fn for_tests(data_dir: impl Into<PathBuf>) -> Self {
        Self {
            addr: SocketAddr::from(([127, 0, 0, 1], 0)),
            data_dir: data_dir.into(),
            workers: 1,
            queue_capacity: 64,
            max_particles: 500_000,
            max_body_bytes: 1 << 20,
            shutdown_grace_s: 0.0,
            token_file: None,
            token: None,
        }
    }

    /// The case limits of this service: a case is validated against them when submitted
    /// and again when a worker runs it (a job queued before a restart met the old ones).
    pub fn limits(&self) -> Limits {
        Limits {
            max_particles: self.max_particles,
        }
    }

    pub fn shutdown_grace(&self) -> Duration {
        Duration::from_secs_f64(self.shutdown_grace_s.max(0.0))
    }

    pub fn database_url(&self) -> String {
        format!(
            "sqlite://{}?mode=rwc",
            self.data_dir.join("jobs.db").display()
        )
    }

    pub fn job_dir(&self, id: &uuid::Uuid) -> PathBuf {
        self.data_dir.join("jobs").join(id.to_string())
    }
}
