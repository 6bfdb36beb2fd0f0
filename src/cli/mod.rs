//! Command line (README.md; docs/contracts.md): `run`, `check`, `schema`, `serve`, `bench`, and
//! `plot` (a flow picture, or the pressure along a body, from a run directory's snapshots).
//!
//! Exit codes: 0 success; 1 a run that failed or was cancelled (the run directory
//! keeps what was written); 2 a rejected case or bad arguments; 3 an I/O or service error.

mod check;
mod external;
mod plot;
mod progress;
mod run;

use clap::{Parser, Subcommand};
use std::path::PathBuf;

pub const EXIT_FAILED_RUN: i32 = 1;
pub const EXIT_REJECTED: i32 = 2;
pub const EXIT_ERROR: i32 = 3;

#[derive(Parser, Debug)]
#[command(
    name = "mpsfsi",
    version,
    about = "2D MPS fluid-structure simulation: water-entry loads on rigid bodies"
)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Subcommand, Debug)]
pub enum Command {
    /// Run a case and write the run directory (loads.csv, bodies.csv, probes.csv, summary.json, snapshots/).
    Run {
        /// Case file (JSON; the format is in README.md, its schema in api/case.schema.json).
        #[arg(required_unless_present = "resume")]
        case: Option<PathBuf>,
        /// Run directory to write (created if missing).
        #[arg(long, required_unless_present = "resume")]
        out: Option<PathBuf>,
        /// Override one field by its dotted path, e.g. `--set time.end=0.01`,
        /// `--set scheme.laplacian=classic`, `--set bodies[0].motion.mass=12`. Repeatable.
        #[arg(long = "set", value_name = "PATH=VALUE")]
        set: Vec<String>,
        /// Also run three coarser spacings (ratio 1.25, the coarsest as a four-member
        /// lattice-offset ensemble) and write the 95 % half-width of every load and
        /// probe reading: loads_uncertainty.csv, probes_uncertainty.csv and summary.json's
        /// `uncertainty` (docs/uncertainty.md). About twice the run's time.
        #[arg(long)]
        uncertainty: bool,
        /// Save the run's complete state to RUN_DIR/checkpoint.bin every S seconds of
        /// wall time (Ctrl-C saves one whatever this says); `--resume` continues from it.
        /// Not with `--uncertainty`, whose levels are separate runs.
        #[arg(long, value_name = "S", value_parser = positive_seconds, conflicts_with = "uncertainty")]
        checkpoint_s: Option<f64>,
        /// Continue the run of this directory from its checkpoint.bin (left by Ctrl-C or
        /// `--checkpoint-s`): its loads are those of an uninterrupted run, byte for byte.
        #[arg(long, value_name = "RUN_DIR", conflicts_with_all = ["case", "out", "set", "uncertainty"])]
        resume: Option<PathBuf>,
    },
    /// Validate a case and print its particle count, estimated steps and kernel parameters.
    Check {
        case: PathBuf,
        #[arg(long = "set", value_name = "PATH=VALUE")]
        set: Vec<String>,
        /// Particle limit to validate against (the service's limit may be lower).
        #[arg(long)]
        max_particles: Option<usize>,
    },
    /// Draw a run's flow: the particles of the snapshot nearest `--time` coloured by a
    /// field, with the walls and bodies at their pose, as an SVG picture; or, with
    /// `--surface BODY`, the pressure along that body's surface; or, with `--loads`,
    /// the load history (with its 95 % band after `run --uncertainty`).
    Plot {
        /// Run directory (with `snapshots/`).
        run_dir: PathBuf,
        /// Simulated time in s (the nearest snapshot; default: the last).
        #[arg(long)]
        time: Option<f64>,
        /// pressure (Cp when a body moves), speed, velocity_x or velocity_y.
        #[arg(long, default_value = "pressure")]
        field: String,
        /// Region to draw, `X0,X1,Y0,Y1` in metres (default: one body size around the
        /// moving bodies, or everything without one).
        #[arg(long, allow_hyphen_values = true)]
        window: Option<String>,
        /// Draw the pressure along this body's (or wall's) surface instead: Cp = p / (½ρV²)
        /// (p in kPa when it does not move) against the arc length from its first vertex.
        #[arg(long, value_name = "BODY", conflicts_with_all = ["field", "window"])]
        surface: Option<String>,
        /// Draw the load history instead: fx, fy and mz of every body and named wall
        /// against time, each body's 95 % band shaded when the run has
        /// loads_uncertainty.csv.
        #[arg(long, conflicts_with_all = ["field", "window", "surface", "time"])]
        loads: bool,
        /// SVG file to write.
        #[arg(long)]
        out: PathBuf,
    },
    /// Print the JSON Schema of the case format (the text of api/case.schema.json).
    Schema,
    /// Run the HTTP job service (README.md, api/openapi.yaml).
    #[cfg(feature = "service")]
    Serve(mpsfsi::service::Config),
    /// Run jobs from a shared job database (`--database postgres://…`) without serving
    /// HTTP; API nodes are `mpsfsi serve` on the same database (README.md).
    #[cfg(feature = "service")]
    Worker(mpsfsi::service::WorkerArgs),
    /// Run the run-time-versus-error study and write its report (docs/performance.md).
    #[cfg(feature = "bench")]
    Bench(BenchArgs),
}

#[cfg(feature = "bench")]
#[derive(clap::Args, Debug, Clone)]
pub struct BenchArgs {
    /// Fewer spacings and variants (minutes, not hours).
    #[arg(long)]
    pub quick: bool,
    /// Include the operator convergence study.
    #[arg(long)]
    pub operators: bool,
    /// Include the stress runs (dam break to 5 s, wedges at 20 and 30 m/s and heeled 10°,
    /// perturbed lattice, long hydrostatic; `stress.md`) and the CFL sweep of the dam
    /// break per variant. With `--quick`: shorter and coarser.
    #[arg(long)]
    pub stress: bool,
    /// Scaling study: step cost, stage times, solver iterations and bytes per particle of
    /// a still tank at 10k, 40k, 160k, ... particles up to `--max-particles`, and 1 vs 2
    /// threads (`scaling.csv`, `scaling.md`). Skips the run-time-against-error study.
    #[arg(long)]
    pub scaling: bool,
    /// Feature-cost study: the same tank with and without a body, viscosity, probes,
    /// snapshots, repeated (`features.csv`, `features.md`). Skips the run-time-against-error study.
    #[arg(long)]
    pub features: bool,
    /// Also run each case's ladder (`run --uncertainty`, default scheme, the finest study
    /// spacing) and report the band beside the measured error (`uncertainty.md`).
    #[arg(long)]
    pub uncertainty: bool,
    /// Skip the run-time-against-error study (e.g. `--stress --no-study`).
    #[arg(long)]
    pub no_study: bool,
    /// Only these reference cases of the study (repeatable): hydrostatic, dam_break,
    /// wedge_30deg, wedge_free_fall, standing_wave. Default: all.
    #[arg(long = "case", value_name = "NAME")]
    pub cases: Vec<String>,
    /// Only these scheme variants of the study and the CFL sweep (repeatable): classic,
    /// default, uniform, chl, least_squares. Default: all.
    #[arg(long = "variant", value_name = "NAME")]
    pub variants: Vec<String>,
    /// Largest size of `--scaling` (640000 and 1300000 are the large sizes).
    #[arg(long, default_value_t = 160_000)]
    pub max_particles: usize,
    /// Timed steps per size of `--scaling` (after one warm-up step).
    #[arg(long, default_value_t = 20)]
    pub scaling_steps: u64,
    /// Size (particles) of the 1-vs-2-thread comparison of `--scaling`: the largest study
    /// size not above it.
    #[arg(long, default_value_t = 160_000)]
    pub threads_particles: usize,
    /// Repeats of each `--features` variant.
    #[arg(long, default_value_t = 3)]
    pub repeats: usize,
    /// Directory for report.md, results.csv and the plots.
    #[arg(long)]
    pub out: PathBuf,
}

/// A number of seconds, positive and finite.
fn positive_seconds(text: &str) -> Result<f64, String> {
    match text.parse::<f64>() {
        Ok(s) if s > 0.0 && s.is_finite() => Ok(s),
        _ => Err(format!(
            "expected a positive number of seconds, got `{text}`"
        )),
    }
}

/// Run one command; returns the process exit code.
pub fn main(cli: Cli) -> i32 {
    match cli.command {
        Command::Run {
            case,
            out,
            set,
            uncertainty,
            checkpoint_s,
            resume,
        } => {
            let every = checkpoint_s.map(std::time::Duration::from_secs_f64);
            match (resume, case, out) {
                (Some(dir), ..) => run::resume(&dir, every),
                (None, Some(case), Some(out)) => run::run(&case, &out, &set, uncertainty, every),
                _ => unreachable!("clap requires CASE and --out without --resume"),
            }
        }
        Command::Check {
            case,
            set,
            max_particles,
        } => check::check(&case, &set, max_particles),
        Command::Plot {
            run_dir,
            time,
            field,
            window,
            surface,
            loads,
            out,
        } => match surface {
            _ if loads => plot::plot_loads(&run_dir, &out),
            Some(body) => plot::plot_surface(&run_dir, time, &body, &out),
            None => plot::plot(&run_dir, time, &field, window.as_deref(), &out),
        },
        Command::Schema => {
            print!("{}", mpsfsi::case::schema::case_schema_json());
            0
        }
        #[cfg(feature = "service")]
        Command::Serve(args) => external::serve(args),
        #[cfg(feature = "service")]
        Command::Worker(args) => external::worker(args),
        #[cfg(feature = "bench")]
        Command::Bench(args) => external::bench(args),
    }
}

/// Print a rejected case as one line: `error: invalid case: PATH: reason`.
pub fn report_case_error(e: &mpsfsi::case::CaseError) -> i32 {
    if e.path.is_empty() {
        eprintln!("error: invalid case: {}", e.message);
    } else {
        eprintln!("error: invalid case: {}: {}", e.path, e.message);
    }
    EXIT_REJECTED
}
