//! API tests: the service spawned in-process on 127.0.0.1:0 (and as a child process for
//! the kill-and-restart test), each with its own data directory.

mod auth;
mod bad_input;
mod burst;
mod cancel;
mod contract;
mod delete;
#[cfg(all(target_os = "linux", target_env = "gnu"))]
mod devtools;
mod helpers;
mod limits;
mod page;
mod parts;
mod pg_server;
mod postgres;
mod restart;
mod resume;
mod retention;
mod schema;
mod sign_in;
mod store;
mod submit;
mod uncertainty;
mod wake;
