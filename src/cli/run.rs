//! `mpsfsi run CASE --out DIR [--set PATH=VALUE]... [--checkpoint-s S]` and
//! `mpsfsi run --resume DIR`.
//!
//! Ctrl-C (SIGINT), SIGTERM or SIGHUP ends the run after the current step: everything
//! written stays, the state goes to DIR/checkpoint.bin (not for `--uncertainty`, whose
//! levels are separate runs), summary.json says `cancelled` with the step and time, exit
//! code 1; `--resume DIR` continues it. A second signal exits at once, without
//! summary.json.

use super::progress::ProgressBarObserver;
use super::{report_case_error, EXIT_ERROR, EXIT_FAILED_RUN};
use mpsfsi::analysis::envelope::impact_advice;
use mpsfsi::case::{load_case_file, Limits, ValidCase};
use mpsfsi::run::uncertainty as ladder;
use mpsfsi::run::{checkpoint, run_case_with, Checkpoint, RunOptions, RunStatus, Summary};
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Duration;

pub fn run(
    case_path: &Path,
    out: &Path,
    overrides: &[String],
    uncertainty: bool,
    checkpoint_every: Option<Duration>,
) -> i32 {
    let case = match load_case_file(case_path, overrides)
        .and_then(|case| ValidCase::new(case, &Limits::default()))
    {
        Ok(case) => case,
        Err(e) => return report_case_error(&e),
    };
    for advice in impact_advice(&case) {
        eprintln!("advice: {advice}");
    }
    if uncertainty {
        // every level laid out and validated before any work
        if let Err(e) = ladder::ladder(&case) {
            return report_case_error(&e);
        }
    }
    if let Err(e) = std::fs::create_dir_all(out) {
        eprintln!(
            "error: cannot create the run directory {}: {e}",
            out.display()
        );
        return EXIT_ERROR;
    }
    let options = RunOptions {
        checkpoint_every,
        checkpoint_on_stop: true,
        ..RunOptions::default()
    };
    execute(&case, out, uncertainty, options)
}

/// `mpsfsi run --resume DIR`: the case and the state come from DIR/checkpoint.bin.
pub fn resume(dir: &Path, checkpoint_every: Option<Duration>) -> i32 {
    let path = dir.join(checkpoint::FILE);
    if !path.exists() {
        let finished = std::fs::read_to_string(dir.join("summary.json"))
            .ok()
            .and_then(|t| serde_json::from_str::<Summary>(&t).ok())
            .is_some_and(|s| s.status == RunStatus::Succeeded);
        if finished {
            eprintln!(
                "error: the run in {} finished: there is nothing to resume",
                dir.display()
            );
        } else {
            eprintln!(
                "error: {} has no {}: the run stopped without saving one (killed, or interrupted twice); run it again with --checkpoint-s",
                dir.display(),
                checkpoint::FILE
            );
        }
        return EXIT_ERROR;
    }
    let saved = match Checkpoint::read(&path) {
        Ok(saved) => saved,
        Err(e) => {
            eprintln!("error: cannot resume from {}: {e}", path.display());
            return EXIT_ERROR;
        }
    };
    let case = match saved.case().map_err(|e| e.to_string()).and_then(|case| {
        ValidCase::new(case, &Limits::default())
            .map_err(|e| format!("invalid case: {}: {}", e.path, e.message))
    }) {
        Ok(case) => case,
        Err(e) => {
            eprintln!("error: cannot resume from {}: {e}", path.display());
            return EXIT_ERROR;
        }
    };
    eprintln!(
        "resuming {} at step {}, t = {:.6} s",
        case.name, saved.header.steps, saved.header.time
    );
    let options = RunOptions {
        checkpoint_every,
        checkpoint_on_stop: true,
        resume: Some(saved),
        ..RunOptions::default()
    };
    execute(&case, dir, false, options)
}

/// Run (or resume) with the progress bar and the signal handlers, and report.
fn execute(case: &ValidCase, out: &Path, uncertainty: bool, options: RunOptions) -> i32 {
    let interrupted = Arc::new(AtomicBool::new(false));
    let mut observer = ProgressBarObserver::for_stderr(interrupted.clone());
    stop_on_signals(interrupted, observer.line_printer());
    let result = if uncertainty {
        ladder::run_with_uncertainty(case, out, &mut observer)
    } else {
        run_case_with(case, out, &mut observer, options)
    };
    observer.finish();
    match result {
        Ok(summary) => {
            let runaway = match &summary.first_runaway {
                Some(first) => format!(
                    ", {} of them runaways (the first: {first})",
                    summary.particles_runaway
                ),
                None => String::new(),
            };
            let line = format!(
                "{} steps to t = {:.6} s, {} particles ({} removed{runaway}), max speed {:.3} m/s, {:.1} s wall time; results in {}",
                summary.steps,
                summary.simulated_time,
                summary.particles,
                summary.particles_removed,
                summary.max_velocity,
                summary.wall_time_s,
                out.display()
            );
            if let Some(u) = &summary.uncertainty {
                print_uncertainty(u);
            }
            match summary.status {
                RunStatus::Succeeded => {
                    println!("succeeded: {line}");
                    0
                }
                RunStatus::Failed | RunStatus::Cancelled => {
                    let status = if summary.status == RunStatus::Failed {
                        "failed"
                    } else {
                        "cancelled"
                    };
                    let reason = summary.reason.as_deref().unwrap_or("no reason given");
                    eprintln!("error: run {status}: {reason} ({line})");
                    if summary.status == RunStatus::Cancelled && out.join(checkpoint::FILE).exists()
                    {
                        eprintln!(
                            "the state at t = {:.6} s is saved: `mpsfsi run --resume {}` continues",
                            summary.simulated_time,
                            out.display()
                        );
                    }
                    EXIT_FAILED_RUN
                }
            }
        }
        Err(e) => {
            eprintln!("error: {e}");
            EXIT_ERROR
        }
    }
}

/// The first signal sets `interrupted` (the run stops before its next step); the second
/// exits at once.
fn stop_on_signals(interrupted: Arc<AtomicBool>, say: impl Fn(&str) + Send + 'static) {
    let handler = move || {
        if interrupted.swap(true, Ordering::SeqCst) {
            say("interrupted again: exiting now, without summary.json");
            std::process::exit(EXIT_FAILED_RUN);
        }
        say("interrupted: stopping after the current step and writing summary.json (interrupt again to exit now)");
    };
    if let Err(e) = ctrlc::set_handler(handler) {
        eprintln!("warning: Ctrl-C will kill the run without summary.json: {e}");
    }
}

/// The impulse and peak of every body's vertical and horizontal force with their 95 %
/// half-widths, the ladder's cost and its notes.
fn print_uncertainty(u: &mpsfsi::analysis::uncertainty::UncertaintySummary) {
    for body in &u.bodies {
        for c in body.columns.iter().filter(|c| c.column != "mz") {
            println!(
                "uncertainty: {} {}: impulse {:.4e} ± {:.2e} N s/m, peak {:.4e} ± {:.2e} N/m (observed orders {:.2}, {:.2})",
                body.name,
                c.column,
                c.impulse.value,
                c.impulse.half_width,
                c.peak.value,
                c.peak.half_width,
                c.impulse.order,
                c.peak.order
            );
        }
    }
    println!(
        "uncertainty: {} levels, ratio {}, {:.1} s in all ({:.2} times the run); loads_uncertainty.csv",
        u.levels.len(),
        u.ratio,
        u.wall_time_s,
        u.cost_ratio
    );
    for note in u.notes.iter().chain(&u.advice) {
        eprintln!("uncertainty: {note}");
    }
}
