//! Seams to the subcommands whose engines live in other modules (`service`, `bench`):
//! the argument types stay here, the call adapts to their entry points.

use super::{BenchArgs, ServeArgs, EXIT_ERROR};

/// `mpsfsi serve`: would build `mpsfsi::service::Config` from the flags and run
/// `mpsfsi::service::serve(config)` on a tokio runtime.
pub fn serve(args: ServeArgs) -> i32 {
    let _ = args;
    eprintln!("error: `mpsfsi serve` is not built yet in this build (the service module has not landed)");
    EXIT_ERROR
}

/// `mpsfsi bench`: would call `mpsfsi::bench::run(options)`.
pub fn bench(args: BenchArgs) -> i32 {
    let _ = args;
    eprintln!("error: `mpsfsi bench` is not built yet in this build (the bench module has not landed)");
    EXIT_ERROR
}
