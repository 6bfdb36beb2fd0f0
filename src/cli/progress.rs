//! A progress bar on stderr (simulated time / end time, steps, particles, ETA), shown
//! only when stderr is a terminal; otherwise nothing is drawn. The observer also stops
//! the run once the signal handler of `mpsfsi run` sets its interrupt flag.

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use mpsfsi::math::Real;
use mpsfsi::run::{Observer, Progress, RunStatus};
use std::io::IsTerminal;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::{Duration, Instant};

/// Resolution of the bar: positions are fractions of the end time in these units.
const TICKS: u64 = 10_000;

pub struct ProgressBarObserver {
    bar: Option<ProgressBar>,
    last_draw: Instant,
    /// Set by a signal (Ctrl-C, SIGTERM, SIGHUP): the run stops before its next step.
    interrupted: Arc<AtomicBool>,
}

impl ProgressBarObserver {
    /// A bar when stderr is a terminal, silence otherwise; the run stops once
    /// `interrupted` is set.
    pub fn for_stderr(interrupted: Arc<AtomicBool>) -> Self {
        let bar = std::io::stderr().is_terminal().then(|| {
            let bar =
                ProgressBar::with_draw_target(Some(TICKS), ProgressDrawTarget::stderr_with_hz(5));
            let style = ProgressStyle::with_template(
                "{spinner} [{elapsed_precise}] {wide_bar} {msg} ETA {eta}",
            )
            .unwrap_or_else(|_| ProgressStyle::default_bar());
            bar.set_style(style);
            bar.enable_steady_tick(Duration::from_millis(200));
            bar.set_message("building the scene");
            bar
        });
        Self {
            bar,
            last_draw: Instant::now(),
            interrupted,
        }
    }

    /// Prints a line on stderr from any thread, above the bar if there is one.
    pub fn line_printer(&self) -> impl Fn(&str) + Send + 'static {
        let bar = self.bar.clone();
        move |line| match &bar {
            Some(bar) => bar.suspend(|| eprintln!("{line}")),
            None => eprintln!("{line}"),
        }
    }

    /// Remove the bar before the result line is printed.
    pub fn finish(&mut self) {
        if let Some(bar) = self.bar.take() {
            bar.finish_and_clear();
        }
    }
}

impl Observer for ProgressBarObserver {
    fn started(&mut self, particles: usize, estimated_steps: u64) {
        if let Some(bar) = &self.bar {
            bar.set_message(format!("{particles} particles, ~{estimated_steps} steps"));
            bar.reset_eta();
        }
    }

    fn progress(&mut self, p: &Progress) {
        let Some(bar) = &self.bar else { return };
        // formatting the message every step costs more than a small step
        if self.last_draw.elapsed() < Duration::from_millis(100) {
            return;
        }
        self.last_draw = Instant::now();
        bar.set_position((p.fraction() * TICKS as f64) as u64);
        bar.set_message(format!(
            "t = {:.4}/{:.4} s  step {}  dt {:.2e} s  {} particles",
            p.simulated_time, p.end_time, p.step, p.dt, p.particles
        ));
    }

    fn part(&mut self, index: usize, count: usize, label: &str) {
        (self.line_printer())(&format!("part {} of {count}: {label}", index + 1));
    }

    fn is_cancelled(&self) -> bool {
        self.interrupted.load(Ordering::SeqCst)
    }

    fn checkpoint_saved(&mut self, path: &std::path::Path, time: Real, steps: u64, bytes: u64) {
        let line = format!(
            "checkpoint: step {steps}, t = {time:.6} s, {:.1} MB in {}",
            bytes as f64 / 1e6,
            path.display()
        );
        (self.line_printer())(&line);
    }

    /// ctrlc runs one handler for SIGINT, SIGTERM and SIGHUP without saying which came.
    fn stop_reason(&self, step: u64, time: Real) -> (RunStatus, String) {
        (
            RunStatus::Cancelled,
            format!("interrupted by a signal (SIGINT, SIGTERM or SIGHUP) at step {step}, t = {time:.6} s"),
        )
    }
}

impl Drop for ProgressBarObserver {
    fn drop(&mut self) {
        self.finish();
    }
}
