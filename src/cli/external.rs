//! Seams to the subcommands whose engines live in other modules (`service`, `bench`).
//! Until they land on this branch these print "not built yet" and exit 3.
//!
//! Merging `service` (whose `service::Config` is a `clap::Args` with the same flags
//! and `MPSFSI_*` variables): replace `Serve(ServeArgs)` in `cli/mod.rs` by
//! `Serve(mpsfsi::service::Config)` and this function's body by
//!
//! ```ignore
//! let runtime = match tokio::runtime::Runtime::new() {
//!     Ok(r) => r,
//!     Err(e) => { eprintln!("error: cannot start the async runtime: {e}"); return EXIT_ERROR; }
//! };
//! match runtime.block_on(mpsfsi::service::serve(config)) {
//!     Ok(()) => 0,
//!     Err(e) => { eprintln!("error: {e}"); EXIT_ERROR }
//! }
//! ```

use super::{BenchArgs, ServeArgs, EXIT_ERROR};

/// `mpsfsi serve`: runs `mpsfsi::service::serve(config)` once the service has landed.
pub fn serve(args: ServeArgs) -> i32 {
    let _ = args;
    eprintln!("error: `mpsfsi serve` is not built yet in this build (the service module has not landed)");
    EXIT_ERROR
}

/// `mpsfsi bench`: runs `mpsfsi::bench::run(options)` once the benchmark has landed.
pub fn bench(args: BenchArgs) -> i32 {
    let _ = args;
    eprintln!("error: `mpsfsi bench` is not built yet in this build (the bench runner has not landed)");
    EXIT_ERROR
}
