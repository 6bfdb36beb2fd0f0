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
    /// Data directory: jobs.db (unless --database) and one run directory per job under
    /// jobs/<id>/.
    #[arg(long = "data", env = "MPSFSI_DATA", default_value = "mpsfsi-data")]
    pub data_dir: PathBuf,
    /// Job database: `postgres://…` shares the queue and the results with other API
    /// nodes and `mpsfsi worker` processes; the default is SQLite in the data directory.
    #[arg(long, env = "MPSFSI_DATABASE", value_name = "URL")]
    pub database: Option<DatabaseUrl>,
    /// Jobs run at the same time (each one also uses the rayon thread pool); 0 serves
    /// without running jobs (with --database postgres://…, workers elsewhere run them).
    #[arg(long, env = "MPSFSI_WORKERS", default_value_t = 1)]
    pub workers: usize,
    /// Postgres only: seconds a worker's claim on a job lasts without renewal (renewed
    /// every third of it; a killed worker's job is claimed again after it).
    #[arg(long = "lease-s", env = "MPSFSI_LEASE_S", default_value_t = 30.0,
          value_parser = positive_seconds)]
    pub lease_s: f64,
    /// Postgres only: claims of one job before an expired lease fails it with reason
    /// `attempts exhausted` (a job that kills its worker every time).
    #[arg(long, env = "MPSFSI_MAX_ATTEMPTS", default_value_t = 3,
          value_parser = clap::value_parser!(u32).range(1..))]
    pub max_attempts: u32,
    /// Postgres only: seconds of wall time between checkpoints of a running job (its
    /// complete state, stored in the database); a job whose worker died resumes from the
    /// last one. 120 s: a checkpoint costs about 1.5 us per particle to write plus its
    /// upload (4.4 MB at 20 000 particles), under 1 % of the run up to 300 000
    /// particles when the database takes 100 MB/s, and a killed worker loses at most
    /// two minutes of its job.
    #[arg(long = "checkpoint-s", env = "MPSFSI_CHECKPOINT_S", default_value_t = 120.0,
          value_parser = positive_seconds)]
    pub checkpoint_s: f64,
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
    /// Remove finished jobs (succeeded, failed or cancelled) this many days after they
    /// finished, with their run directories and stored results, as DELETE does; checked
    /// at start-up and every hour. Unset: jobs are kept until deleted.
    #[arg(long = "keep-days", env = "MPSFSI_KEEP_DAYS", value_name = "DAYS",
          value_parser = positive_days)]
    pub keep_days: Option<f64>,
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

/// A job database URL. Its `Debug` and `Display` hide the password (in the user-info
/// part and in a `password=` parameter), so a printed [`Config`], a log line or an error
/// never shows it; [`DatabaseUrl::expose`] is for connecting only.
#[derive(Clone, PartialEq, Eq)]
pub struct DatabaseUrl(String);

impl DatabaseUrl {
    pub fn new(url: impl Into<String>) -> Self {
        Self(url.into())
    }

    /// The URL with its password, to connect with.
    pub fn expose(&self) -> &str {
        &self.0
    }

    /// The password the URL carries (user-info or a `password=` parameter), if any.
    pub fn password(&self) -> Option<&str> {
        let url = &self.0;
        let rest = &url[url.find("://")? + 3..];
        let authority = &rest[..rest.find(['/', '?']).unwrap_or(rest.len())];
        if let Some(at) = authority.rfind('@') {
            if let Some((_, password)) = authority[..at].split_once(':') {
                return Some(password);
            }
        }
        let query = &rest[rest.find('?')? + 1..];
        query
            .split('&')
            .filter_map(|p| p.split_once('='))
            .find(|(k, _)| k.eq_ignore_ascii_case("password"))
            .map(|(_, v)| v)
    }

    /// `text` with the password replaced by `***` (for an error from the driver).
    pub fn scrub(&self, text: &str) -> String {
        match self.password() {
            Some(p) if !p.is_empty() => text.replace(p, "***"),
            _ => text.to_string(),
        }
    }

    /// The URL with any password replaced by `***`.
    pub fn redacted(&self) -> String {
        let url = &self.0;
        let mut out = match url.find("://") {
            Some(scheme_end) => {
                let rest = &url[scheme_end + 3..];
                let authority_end = rest.find(['/', '?']).unwrap_or(rest.len());
                let authority = &rest[..authority_end];
                match authority.rfind('@') {
                    Some(at) if authority[..at].contains(':') => {
                        let user = &authority[..authority[..at].find(':').unwrap_or(at)];
                        format!("{}{user}:***{}", &url[..scheme_end + 3], &rest[at..])
                    }
                    _ => url.clone(),
                }
            }
            None => url.clone(),
        };
        if let Some(query) = out.find('?') {
            let params: Vec<String> = out[query + 1..]
                .split('&')
                .map(|p| match p.split_once('=') {
                    Some((k, _)) if k.eq_ignore_ascii_case("password") => format!("{k}=***"),
                    _ => p.to_string(),
                })
                .collect();
            out = format!("{}?{}", &out[..query], params.join("&"));
        }
        out
    }
}

impl std::str::FromStr for DatabaseUrl {
    type Err = std::convert::Infallible;
    fn from_str(s: &str) -> Result<Self, Self::Err> {
        Ok(Self(s.to_string()))
    }
}

impl std::fmt::Debug for DatabaseUrl {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{:?}", self.redacted())
    }
}

impl std::fmt::Display for DatabaseUrl {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.redacted())
    }
}

impl Config {
    /// Defaults with the given data directory, on 127.0.0.1 with port 0.
    pub fn for_tests(data_dir: impl Into<PathBuf>) -> Self {
        Self {
            addr: SocketAddr::from(([127, 0, 0, 1], 0)),
            data_dir: data_dir.into(),
            database: None,
            workers: 1,
            lease_s: 30.0,
            max_attempts: 3,
            checkpoint_s: 120.0,
            queue_capacity: 64,
            max_particles: 500_000,
            max_body_bytes: 1 << 20,
            shutdown_grace_s: 0.0,
            keep_days: None,
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

    /// How long a finished job is kept (`--keep-days`); `None`: until deleted.
    pub fn keep(&self) -> Option<Duration> {
        self.keep_days
            .map(|d| Duration::from_secs_f64(d * 86_400.0))
    }

    pub fn shutdown_grace(&self) -> Duration {
        Duration::from_secs_f64(self.shutdown_grace_s.max(0.0))
    }

    /// The job database: the configured URL, or SQLite in the data directory.
    pub fn database_url(&self) -> DatabaseUrl {
        match &self.database {
            Some(url) => url.clone(),
            None => DatabaseUrl::new(format!(
                "sqlite://{}?mode=rwc",
                self.data_dir.join("jobs.db").display()
            )),
        }
    }

    pub fn job_dir(&self, id: &uuid::Uuid) -> PathBuf {
        self.data_dir.join("jobs").join(id.to_string())
    }
}

fn positive_seconds(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 => Ok(v),
        Ok(_) => Err("must be a positive number of seconds".into()),
        Err(e) => Err(e.to_string()),
    }
}

/// Largest `--keep-days`: beyond it a cutoff would predate any job (and the seconds
/// overflow a date).
const MAX_KEEP_DAYS: f64 = 1.0e6;

fn positive_days(s: &str) -> Result<f64, String> {
    match s.parse::<f64>() {
        Ok(v) if v.is_finite() && v > 0.0 && v <= MAX_KEEP_DAYS => Ok(v),
        Ok(_) => Err(format!(
            "must be a positive number of days, at most {MAX_KEEP_DAYS}"
        )),
        Err(e) => Err(format!("must be a positive number of days: {e}")),
    }
}

/// `mpsfsi worker`: runs jobs from a shared (Postgres) store, serves nothing.
#[derive(Debug, Clone, clap::Args)]
pub struct WorkerArgs {
    /// The job database the API nodes use: `postgres://…`.
    #[arg(long, env = "MPSFSI_DATABASE", value_name = "URL")]
    pub database: DatabaseUrl,
    /// Where run directories go (jobs/<id>/; snapshots stay here, the job record says
    /// where).
    #[arg(long = "data", env = "MPSFSI_DATA", default_value = "mpsfsi-data")]
    pub data_dir: PathBuf,
    /// Jobs this process runs at the same time.
    #[arg(long, env = "MPSFSI_WORKERS", default_value_t = 1,
          value_parser = clap::value_parser!(u64).range(1..))]
    pub workers: u64,
    /// Seconds a claim lasts without renewal (renewed every third of it).
    #[arg(long = "lease-s", env = "MPSFSI_LEASE_S", default_value_t = 30.0,
          value_parser = positive_seconds)]
    pub lease_s: f64,
    /// Claims of one job before an expired lease fails it (`attempts exhausted`).
    #[arg(long, env = "MPSFSI_MAX_ATTEMPTS", default_value_t = 3,
          value_parser = clap::value_parser!(u32).range(1..))]
    pub max_attempts: u32,
    /// Seconds of wall time between checkpoints of a running job (its
    /// complete state, stored in the database); a job whose worker died resumes from the
    /// last one. 120 s: a checkpoint costs about 1.5 us per particle to write plus its
    /// upload (4.4 MB at 20 000 particles), under 1 % of the run up to 300 000
    /// particles when the database takes 100 MB/s, and a killed worker loses at most
    /// two minutes of its job.
    #[arg(long = "checkpoint-s", env = "MPSFSI_CHECKPOINT_S", default_value_t = 120.0,
          value_parser = positive_seconds)]
    pub checkpoint_s: f64,
    /// Largest number of fluid particles a case may create (checked again at claim).
    #[arg(long, env = "MPSFSI_MAX_PARTICLES", default_value_t = 500_000)]
    pub max_particles: usize,
    /// Seconds a shutdown waits for running jobs before giving them back to the queue
    /// (each saves a checkpoint first, from which the next claim resumes).
    #[arg(long, env = "MPSFSI_SHUTDOWN_GRACE_S", default_value_t = 10.0)]
    pub shutdown_grace_s: f64,
}

impl From<WorkerArgs> for Config {
    fn from(w: WorkerArgs) -> Self {
        Self {
            database: Some(w.database),
            workers: w.workers as usize,
            lease_s: w.lease_s,
            max_attempts: w.max_attempts,
            checkpoint_s: w.checkpoint_s,
            max_particles: w.max_particles,
            shutdown_grace_s: w.shutdown_grace_s,
            data_dir: w.data_dir,
            // a worker serves nothing
            addr: SocketAddr::from(([127, 0, 0, 1], 0)),
            queue_capacity: 0,
            max_body_bytes: 0,
            keep_days: None,
            token_file: None,
            token: None,
        }
    }
}
