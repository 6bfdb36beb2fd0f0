//! Startup and shutdown. [`App::build`] resolves the access token ([`super::auth`]:
//! required beyond loopback), opens the data directory and database, recovers
//! jobs a previous process left behind, and binds the listener (port 0 in tests; the real
//! port is [`App::port`]). [`App::run_until_stopped`] serves and runs the workers until
//! SIGTERM, Ctrl-C or a [`ShutdownHandle`], then shuts down in order: stop accepting and
//! finish in-flight requests; stop claiming jobs; give running jobs the grace period;
//! interrupt the rest at their next step (recorded `failed` / `interrupted`); close the
//! database. Queued jobs stay queued and run after the next start. [`run_worker`] is the
//! same without the listener: `mpsfsi worker` on a shared store.

use super::auth::{self, Access, AccessError};
use super::config::DatabaseUrl;
use super::retention;
use super::routes::{router, AppState};
use super::store::JobStore;
use super::workers::{run_worker_until_stopped, spawn_queue_listener, Jobs};
use super::Config;
use std::sync::Arc;
use std::time::Instant;
use tokio::net::TcpListener;
use tokio::sync::watch;

#[derive(Debug, thiserror::Error)]
pub enum ServeError {
    #[error(transparent)]
    Access(#[from] AccessError),
    #[error("cannot create the data directory {path}: {source}")]
    DataDir {
        path: String,
        source: std::io::Error,
    },
    #[error("mpsfsi worker needs a shared job database: --database postgres://… (with the embedded SQLite store, `mpsfsi serve` runs the jobs itself)")]
    NotShared,
    #[error("cannot open the job database {url}: {message}")]
    OpenDatabase { url: String, message: String },
    #[error("job database: {0}")]
    Database(#[from] sqlx::Error),
    #[error("cannot listen on {addr}: {source}")]
    Bind {
        addr: String,
        source: std::io::Error,
    },
    #[error("the OpenAPI document: {0}")]
    OpenApi(String),
    #[error("the server stopped with an error: {0}")]
    Serve(std::io::Error),
}

/// Triggers the graceful shutdown of a running [`App`] (tests; signals do the same).
#[derive(Debug, Clone)]
pub struct ShutdownHandle(watch::Sender<bool>);

impl ShutdownHandle {
    pub fn shutdown(&self) {
        self.0.send_replace(true);
    }
}

#[derive(Debug)]
pub struct App {
    port: u16,
    listener: TcpListener,
    jobs: Arc<Jobs>,
    state: AppState,
    shutdown: watch::Sender<bool>,
}

impl App {
    pub async fn build(config: Config) -> Result<App, ServeError> {
        let access = auth::resolve_token(&config)?.map(|t| Arc::new(Access::new(t)));
        let jobs_dir = config.data_dir.join("jobs");
        std::fs::create_dir_all(&jobs_dir).map_err(|source| ServeError::DataDir {
            path: jobs_dir.display().to_string(),
            source,
        })?;
        let openapi = super::contract::openapi_document().map_err(ServeError::OpenApi)?;
        let store = open_store(&config.database_url()).await?;
        let interrupted = store.recover_interrupted().await?;
        if interrupted > 0 {
            tracing::warn!(
                interrupted,
                "jobs left running by a previous process are now failed (interrupted)"
            );
        }
        let listener = TcpListener::bind(config.addr)
            .await
            .map_err(|source| ServeError::Bind {
                addr: config.addr.to_string(),
                source,
            })?;
        let port = listener.local_addr().map_err(ServeError::Serve)?.port();
        let jobs = Arc::new(Jobs::new(store, config));
        let state = AppState {
            jobs: jobs.clone(),
            openapi: Arc::new(openapi),
            access,
        };
        let (shutdown, _) = watch::channel(false);
        Ok(App {
            port,
            listener,
            jobs,
            state,
            shutdown,
        })
    }

    pub fn port(&self) -> u16 {
        self.port
    }

    pub fn shutdown_handle(&self) -> ShutdownHandle {
        ShutdownHandle(self.shutdown.clone())
    }

    /// Serve and run the workers until a signal or the shutdown handle, then shut down.
    pub async fn run_until_stopped(self) -> Result<(), ServeError> {
        let App {
            listener,
            jobs,
            state,
            shutdown,
            ..
        } = self;
        let config = jobs.config.clone();
        let workers = spawn_workers(&jobs);
        let retention = config
            .keep()
            .map(|keep| retention::spawn(jobs.clone(), keep));

        let mut stop = shutdown.subscribe();
        let signal = async move {
            tokio::select! {
                _ = os_signal() => tracing::info!("shutdown signal received"),
                _ = stop.wait_for(|v| *v) => tracing::info!("shutdown requested"),
            }
        };
        let access = state.access.clone();
        let app = auth::require_token(router(state, config.max_body_bytes), access)
            .layer(tower_http::trace::TraceLayer::new_for_http());
        let served = axum::serve(listener, app)
            .with_graceful_shutdown(signal)
            .await;

        if let Some(retention) = retention {
            retention.abort();
            let _ = retention.await;
        }
        drain(&jobs, workers).await;
        served.map_err(ServeError::Serve)
    }
}

/// Open and migrate the job store; an error names the database without its password.
async fn open_store(url: &DatabaseUrl) -> Result<JobStore, ServeError> {
    JobStore::open(url.expose())
        .await
        .map_err(|e| ServeError::OpenDatabase {
            url: url.redacted(),
            message: url.scrub(&e.to_string()),
        })
}

/// The worker loops of a process, and what wakes them with a shared store.
struct Workers {
    loops: Vec<tokio::task::JoinHandle<()>>,
    listener: Option<tokio::task::JoinHandle<()>>,
}

/// `config.workers` worker loops (none with `--workers 0`), and with Postgres the task
/// that wakes them when a job is queued anywhere.
fn spawn_workers(jobs: &Arc<Jobs>) -> Workers {
    let loops = (0..jobs.config.workers)
        .map(|_| tokio::spawn(run_worker_until_stopped(jobs.clone())))
        .collect::<Vec<_>>();
    let listener = if loops.is_empty() {
        None
    } else {
        spawn_queue_listener(jobs)
    };
    jobs.job_queued(); // jobs re-queued from a previous process
    Workers { loops, listener }
}

/// Stop claiming; give running jobs the grace period; interrupt the rest at their next
/// step (SQLite: `failed` / `interrupted`; Postgres: back to the queue); close the store.
async fn drain(jobs: &Arc<Jobs>, workers: Workers) {
    jobs.stop_claiming();
    let deadline = Instant::now() + jobs.config.shutdown_grace();
    while jobs.running_jobs() > 0 && Instant::now() < deadline {
        tokio::time::sleep(std::time::Duration::from_millis(50)).await;
    }
    if jobs.running_jobs() > 0 {
        tracing::warn!(running = jobs.running_jobs(), "interrupting running jobs");
    }
    jobs.interrupt_running();
    if let Some(listener) = workers.listener {
        listener.abort();
        let _ = listener.await;
    }
    for worker in workers.loops {
        let _ = worker.await;
    }
    jobs.store.close().await;
    tracing::info!("stopped");
}

async fn os_signal() {
    let ctrl_c = async {
        if tokio::signal::ctrl_c().await.is_err() {
            std::future::pending::<()>().await;
        }
    };
    #[cfg(unix)]
    let terminate = async {
        match tokio::signal::unix::signal(tokio::signal::unix::SignalKind::terminate()) {
            Ok(mut s) => {
                s.recv().await;
            }
            Err(_) => std::future::pending::<()>().await,
        }
    };
    #[cfg(not(unix))]
    let terminate = std::future::pending::<()>();
    tokio::select! {
        _ = ctrl_c => {}
        _ = terminate => {}
    }
}

fn log_to_stderr() {
    let filter = tracing_subscriber::EnvFilter::try_from_default_env()
        .unwrap_or_else(|_| tracing_subscriber::EnvFilter::new("info"));
    let _ = tracing_subscriber::fmt()
        .with_env_filter(filter)
        .with_writer(std::io::stderr)
        .try_init();
}

/// `mpsfsi worker`: claim and run jobs of a shared (Postgres) store until SIGTERM or
/// Ctrl-C; then finish or give back the running jobs (the grace period) and stop.
pub async fn run_worker(config: Config) -> Result<(), ServeError> {
    log_to_stderr();
    let url = config.database_url();
    if !super::store::is_postgres_url(url.expose()) {
        return Err(ServeError::NotShared);
    }
    let jobs_dir = config.data_dir.join("jobs");
    std::fs::create_dir_all(&jobs_dir).map_err(|source| ServeError::DataDir {
        path: jobs_dir.display().to_string(),
        source,
    })?;
    let store = open_store(&url).await?;
    let jobs = Arc::new(Jobs::new(store, config));
    tracing::info!(
        database = %url,
        data = %jobs.config.data_dir.display(),
        workers = jobs.config.workers,
        lease_s = jobs.config.lease_s,
        "mpsfsi worker running"
    );
    let workers = spawn_workers(&jobs);
    os_signal().await;
    tracing::info!("shutdown signal received");
    drain(&jobs, workers).await;
    Ok(())
}

/// `mpsfsi serve`: log to stderr (`RUST_LOG`, default `info`), build, serve until SIGTERM
/// or Ctrl-C, shut down gracefully.
pub async fn serve(config: Config) -> Result<(), ServeError> {
    log_to_stderr();
    let app = App::build(config.clone()).await?;
    tracing::info!(
        addr = %format!("{}:{}", config.addr.ip(), app.port()),
        data = %config.data_dir.display(),
        database = %config.database_url(),
        workers = config.workers,
        keep_days = config.keep_days,
        token = config.token.is_some() || config.token_file.is_some(),
        "mpsfsi service listening"
    );
    app.run_until_stopped().await
}
