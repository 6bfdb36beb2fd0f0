//! A progress bar on stderr (simulated time / end time, steps, particles, ETA), shown
//! only when stderr is a terminal; otherwise nothing is drawn.

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use mpsfsi::run::{Observer, Progress};
use std::io::IsTerminal;
use std::time::{Duration, Instant};

/// Resolution of the bar: positions are fractions of the end time in these units.
const TICKS: u64 = 10_000;

pub struct ProgressBarObserver {
    bar: Option<ProgressBar>,
    last_draw: Instant,
}

impl ProgressBarObserver {
    /// A bar when stderr is a terminal, silence otherwise.
    pub fn for_stderr() -> Self {
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
}

impl Drop for ProgressBarObserver {
    fn drop(&mut self) {
        self.finish();
    }
}
