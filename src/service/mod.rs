//! The job service (api/openapi.yaml, docs/service.md): submit cases over HTTP, run them on a bounded
//! worker pool, persist the job records (SQLite, or Postgres shared by many API nodes
//! and `mpsfsi worker` processes: [`store`]) and run directories under the data
//! directory, and serve the load histories.
//!
//! Layout, after zero-to-production:
//! - [`config`]: typed [`Config`] from flags and `MPSFSI_*` environment variables.
//! - [`startup`]: [`App::build`] binds the listener (port 0 in tests), [`serve`] runs
//!   until SIGTERM / Ctrl-C and shuts down gracefully.
//! - [`routes`]: the HTTP handlers; [`error`]: the one [`ApiError`].
//! - [`auth`]: the bearer token, required beyond loopback (all routes but the health and
//!   the sign-in), and the read cookie a browser gets by signing in ([`sign_in`]).
//! - [`store`]: the job table. The table *is* the queue: a job is admitted by an insert
//!   that checks the number of queued jobs in the same statement, and a worker claims the
//!   oldest queued job with one `UPDATE ... RETURNING`, so a job is never lost between a
//!   channel and the database, and a restart re-queues what was waiting.
//! - [`workers`]: the worker pool; `run_case` runs on blocking threads, one job at a time
//!   per worker, with cancellation and progress through the run [`crate::run::Observer`].
//! - [`retention`]: `--keep-days`, the periodic removal of jobs that ended long ago.
//! - `run_files`: a running job's CSV files and checkpoints in the shared store.
//! - [`series`]: the run directory's CSV files as JSON columns; `loads.svg` is
//!   [`crate::output::plot::loads_svg`] of the same complete lines.
//!
//! Restart semantics: a job found `running` when the service starts was interrupted by
//! the death of the previous process and is marked `failed` with reason `interrupted`
//! (its partial files are kept and still served); a job found `queued` is run again.

pub mod auth;
pub mod config;
pub mod contract;
pub mod error;
pub mod job_json;
pub mod page;
pub mod retention;
pub mod routes;
pub mod run_files;
pub mod series;
pub mod sign_in;
pub mod startup;
pub mod store;
pub mod workers;

pub use config::{Config, DatabaseUrl, Token, WorkerArgs};
pub use error::ApiError;
pub use startup::{run_worker, serve, App, ServeError, ShutdownHandle};

/// The HTTP contract, served as JSON by `GET /v1/openapi.json`.
pub const OPENAPI_YAML: &str = include_str!("../../api/openapi.yaml");

/// The case a `POST /v1/jobs` with an empty body runs (cases/README.md: the 30° wedge, the
/// shipped default job); `None` would make an empty body a 400.
pub const DEFAULT_CASE: Option<&str> = Some(include_str!(
    "../../cases/wedge_30deg_constant_velocity.json"
));
