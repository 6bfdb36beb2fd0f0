//! The subcommands whose engines live in other modules and behind Cargo features: the
//! job service (`service`) and the run-time-versus-error benchmark (`bench`).

#[cfg(any(feature = "service", feature = "bench"))]
use super::EXIT_ERROR;

/// `mpsfsi serve`: the HTTP job service on a tokio runtime until SIGTERM / Ctrl-C.
#[cfg(feature = "service")]
pub fn serve(config: mpsfsi::service::Config) -> i32 {
    block_on(mpsfsi::service::serve(config))
}

/// `mpsfsi worker`: runs jobs of a shared database until SIGTERM / Ctrl-C.
#[cfg(feature = "service")]
pub fn worker(args: mpsfsi::service::WorkerArgs) -> i32 {
    block_on(mpsfsi::service::run_worker(args.into()))
}

#[cfg(feature = "service")]
fn block_on(
    service: impl std::future::Future<Output = Result<(), mpsfsi::service::ServeError>>,
) -> i32 {
    let runtime = match tokio::runtime::Runtime::new() {
        Ok(r) => r,
        Err(e) => {
            eprintln!("error: cannot start the async runtime: {e}");
            return EXIT_ERROR;
        }
    };
    match runtime.block_on(service) {
        Ok(()) => 0,
        Err(e) => {
            eprintln!("error: {e}");
            EXIT_ERROR
        }
    }
}

/// `mpsfsi bench`: the run-time-against-error study of docs/performance.md (report.md,
/// results.csv, SVG plots).
#[cfg(feature = "bench")]
pub fn bench(args: super::BenchArgs) -> i32 {
    let options = mpsfsi::bench::BenchOptions {
        quick: args.quick,
        operators: args.operators,
        stress: args.stress,
        scaling: args.scaling,
        features: args.features,
        uncertainty: args.uncertainty,
        no_study: args.no_study,
        cases: args.cases,
        variants: args.variants,
        scaling_options: mpsfsi::bench::scaling::ScalingOptions {
            max_particles: args.max_particles,
            steps: args.scaling_steps,
            threads_particles: args.threads_particles,
            repeats: args.repeats,
        },
        out_dir: args.out,
    };
    match mpsfsi::bench::run(options) {
        Ok(()) => 0,
        Err(e) => {
            eprintln!("error: {e}");
            EXIT_ERROR
        }
    }
}
