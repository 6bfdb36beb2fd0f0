//! `mpsfsi bench`: studies of the engine that report results; the tests assert them
//! against the papers. One file per study:
//!
//! - [`error_study`]: run time against error of each scheme variant on the reference
//!   cases (default), scored by [`score`], written by [`error_report`] (`results.csv`,
//!   `report.md`, one `<case>.svg` of error against wall time per case, `runs/` with
//!   every run directory);
//! - [`stress`] (`--stress`): scenes that push the scheme and the CFL sweep of the dam
//!   break (`stress.md`);
//! - [`scaling`] (`--scaling`): step cost, memory and threads against the scene size
//!   (`scaling.csv`, `scaling.md`);
//! - [`features`] (`--features`): what each optional feature adds to a step
//!   (`features.csv`, `features.md`);
//! - [`operators`] (`--operators`): the operator convergence study of Imoto (2022) §5
//!   (`operators.md`);
//! - [`uncertainty`] (`--uncertainty`): the band of `run --uncertainty` beside the
//!   measured error of each case (`uncertainty.csv`, `uncertainty.md`).
//!
//! Shared by the studies: the scenes they start from ([`cases`]), seeded lattice
//! disorder ([`perturb`]), statistics ([`stats`]), the process's memory and CPU time
//! ([`resources`]), table cells ([`table`]) and panic isolation ([`unwind`]). The error
//! estimators and references live in [`crate::analysis`], which the tests use too.

pub mod cases;
pub mod error_report;
pub mod error_study;
pub mod features;
pub mod operators;
pub mod perturb;
pub mod resources;
pub mod scaling;
pub mod score;
pub mod stats;
pub mod stress;
pub mod table;
pub mod uncertainty;
pub mod unwind;

use error_study::{bench_cases, run_one, variants};
use std::io;
use std::path::PathBuf;
use std::time::Instant;

/// What `mpsfsi bench` runs.
#[derive(Debug, Clone)]
pub struct BenchOptions {
    /// Coarse spacings and short end times (< 5 min on 2 cores; CI).
    pub quick: bool,
    /// Also the operator convergence study of [`operators`] (`operators.md`).
    pub operators: bool,
    /// Also the stability stress runs ([`stress`]: long dam break, fast and heeled
    /// wedges, perturbed lattice, long hydrostatic) and the CFL sweep; `stress.md`.
    pub stress: bool,
    /// The scaling study of [`scaling`] (`scaling.csv`, `scaling.md`).
    pub scaling: bool,
    /// The feature-cost study of [`features`] (`features.csv`, `features.md`).
    pub features: bool,
    /// The band of `--uncertainty` beside the measured error, per case ([`uncertainty`]:
    /// `uncertainty.csv`, `uncertainty.md`).
    pub uncertainty: bool,
    /// Skip the run-time-against-error study (it is skipped anyway with `scaling` or
    /// `features`).
    pub no_study: bool,
    /// Only the study cases with these names; empty: all.
    pub cases: Vec<String>,
    /// Only the scheme variants with these names (study and CFL sweep); empty: all.
    pub variants: Vec<String>,
    /// Sizes, steps and repeats of [`scaling`] / [`features`].
    pub scaling_options: scaling::ScalingOptions,
    pub out_dir: PathBuf,
}

impl BenchOptions {
    /// The options of the run-time-against-error study alone (`quick` or not).
    pub fn study(quick: bool, out_dir: PathBuf) -> Self {
        Self {
            quick,
            operators: false,
            stress: false,
            scaling: false,
            features: false,
            uncertainty: false,
            no_study: false,
            cases: Vec::new(),
            variants: Vec::new(),
            scaling_options: scaling::ScalingOptions::default(),
            out_dir,
        }
    }

    /// Whether the run-time-against-error study runs: not when an instrument
    /// (`scaling`, `features`) was asked for, or `no_study`.
    pub fn runs_study(&self) -> bool {
        !(self.no_study || self.scaling || self.features)
    }
}

/// The items whose names are in `wanted` (all when it is empty); an unknown name is an
/// error listing the known ones.
fn select<T>(
    what: &str,
    mut items: Vec<T>,
    wanted: &[String],
    name: impl Fn(&T) -> &'static str,
) -> io::Result<Vec<T>> {
    if wanted.is_empty() {
        return Ok(items);
    }
    let known: Vec<&str> = items.iter().map(&name).collect();
    if let Some(unknown) = wanted.iter().find(|n| !known.contains(&n.as_str())) {
        return Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            format!("unknown {what} {unknown:?}; the study has {known:?}"),
        ));
    }
    items.retain(|item| wanted.iter().any(|n| n == name(item)));
    Ok(items)
}

/// Run the benchmark and write its report into `options.out_dir`.
pub fn run(options: BenchOptions) -> io::Result<()> {
    let started = Instant::now();
    std::fs::create_dir_all(&options.out_dir)?;
    let runs_dir = options.out_dir.join("runs");
    if options.scaling {
        scaling::write_scaling(&options.out_dir, &options.scaling_options)?;
    }
    if options.features {
        features::write_features(&options.out_dir, options.scaling_options.repeats)?;
    }
    let mut results = Vec::new();
    let cases = select("case", bench_cases(options.quick)?, &options.cases, |c| {
        c.name
    })?;
    let variants = select("variant", variants(), &options.variants, |v| v.name)?;
    if options.runs_study() {
        for bench in &cases {
            for variant in &variants {
                for &spacing in &bench.spacings {
                    let r = run_one(bench, variant, spacing, &runs_dir);
                    eprintln!(
                        "bench {:<12} {:<14} l0 = {:<9.5} {:>7} particles {:>6} steps {:>8.2} s  error {:.4e}  {}",
                        r.case, r.variant, r.spacing, r.particles, r.steps, r.wall_time_s, r.error, r.note
                    );
                    results.push(r);
                    error_report::write_results_csv(
                        &options.out_dir.join("results.csv"),
                        &results,
                    )?;
                }
            }
        }
    }
    let mut cfl = Vec::new();
    let mut stress_rows = Vec::new();
    if options.stress {
        stress_rows = stress::run_all(options.quick, &runs_dir.join("stress"))?;
        std::fs::write(
            options.out_dir.join("stress.md"),
            stress::stress_markdown(&stress_rows, &[], options.quick),
        )?;
        cfl = stress::cfl_sweep(&cases, &variants, &runs_dir.join("stress"));
        std::fs::write(
            options.out_dir.join("stress.md"),
            stress::stress_markdown(&stress_rows, &cfl, options.quick),
        )?;
    }
    if options.uncertainty {
        uncertainty::run_all(&cases, &runs_dir.join("uncertainty"), &options.out_dir)?;
    }
    let total = started.elapsed().as_secs_f64();
    if options.runs_study() {
        error_report::write_report(
            &options.out_dir,
            &cases,
            &results,
            &cfl,
            &stress_rows,
            options.quick,
            total,
        )?;
    }
    if options.operators {
        operators::write_operators(&options.out_dir)?;
    }
    Ok(())
}
