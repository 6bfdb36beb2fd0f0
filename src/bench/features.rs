//! The feature-cost study of `mpsfsi bench --features` (issue 6): what each optional
//! feature adds to a step. The still tank of the scaling study (~20k particles) runs
//! through the full [`run::run_case`] (output writer included) bare, with a fixed
//! submerged box, with a fixed box far from the water, with viscosity, with probes,
//! with snapshots. Each variant is repeated round-robin, so that drifting machine load
//! hits all alike; the time per step is measured from the observer's `started` to the
//! last step.

use super::cases::{parse_unlimited, tank_case_value, TANK_DT};
use super::resources::cpu_seconds;
use super::stats::{median, spread};
use super::table::{csv_field, csv_num, md_num};
use super::unwind::catch_panic;
use crate::case;
use crate::run::{self, Observer, Progress, RunStatus};
use serde_json::{json, Value};
use std::fmt::Write as _;
use std::io;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Particles of the feature-cost tank.
pub const FEATURE_PARTICLES: usize = 20_000;
/// Steps of each feature-cost run.
pub const FEATURE_STEPS: u64 = 30;

/// One variant of the feature-cost scene: its name and the overrides on the bare tank.
pub fn feature_variants() -> Vec<(&'static str, &'static str, Vec<String>)> {
    let value = tank_case_value(FEATURE_PARTICLES, FEATURE_STEPS);
    let w = value["fluid_blocks"][0]["polygon"][2][0]
        .as_f64()
        .unwrap_or(2.0);
    let h = value["fluid_blocks"][0]["polygon"][2][1]
        .as_f64()
        .unwrap_or(1.0);
    let b = 0.1 * h;
    let fixed_box = |name: &str, x: f64, y: f64| {
        json!([{
            "name": name,
            "polygon": [[-b, -b], [b, -b], [b, b], [-b, b]],
            "position": [x, y],
            "angle": 0.0,
            "motion": { "type": "prescribed", "velocity": [0.0, 0.0], "angular_velocity": 0.0 }
        }])
        .to_string()
    };
    let probes: Vec<Value> = (0..8)
        .map(|k| {
            json!({ "name": format!("p{k}"), "position": [w * (k as f64 + 0.5) / 8.0, 0.5 * h] })
        })
        .collect();
    vec![
        (
            "bare",
            "no body, no viscosity, no probes, no snapshots",
            vec![],
        ),
        (
            "body_submerged",
            "a fixed (prescribed, zero velocity) box of 0.2 H submerged at mid-depth",
            vec![format!("bodies={}", fixed_box("box", 0.5 * w, 0.5 * h))],
        ),
        (
            "body_far",
            "the same box fixed in the air 0.2 H above the water, out of every particle's reach",
            vec![format!("bodies={}", fixed_box("box", 0.5 * w, 1.3 * h - b))],
        ),
        (
            "viscosity",
            "kinematic viscosity 1e-6 m²/s (water)",
            vec!["fluid.kinematic_viscosity=1.0e-6".into()],
        ),
        (
            "probes",
            "8 pressure probes at mid-depth",
            vec![format!("output.probes={}", Value::Array(probes))],
        ),
        (
            "snapshots",
            "a VTK snapshot every 10 steps",
            vec![format!("output.snapshot_interval={}", 10.0 * TANK_DT)],
        ),
    ]
}

/// Times the steps of a [`run::run_case`]: from `started` (scene built) to the last step.
#[derive(Default)]
struct StepClock {
    started: Option<(Instant, Option<f64>)>,
    last: Option<(Instant, Option<f64>)>,
    steps: u64,
    iterations: u64,
}

impl Observer for StepClock {
    fn started(&mut self, _particles: usize, _estimated_steps: u64) {
        self.started = Some((Instant::now(), cpu_seconds()));
    }
    fn progress(&mut self, p: &Progress) {
        self.last = Some((Instant::now(), cpu_seconds()));
        self.steps = p.step;
        self.iterations += p.solver_iterations as u64;
    }
}

/// One run of a feature variant.
#[derive(Debug, Clone, PartialEq)]
pub struct FeatureSample {
    pub variant: String,
    pub particles: usize,
    pub steps: u64,
    pub ms_per_step: f64,
    /// CPU time of the process per step (all threads).
    pub cpu_ms_per_step: f64,
    pub status: String,
}

fn run_feature(name: &str, value: Value, dir: &Path) -> FeatureSample {
    let mut sample = FeatureSample {
        variant: name.into(),
        particles: 0,
        steps: 0,
        ms_per_step: f64::NAN,
        cpu_ms_per_step: f64::NAN,
        status: "failed".into(),
    };
    let case = match parse_unlimited(value) {
        Ok(c) => c,
        Err(e) => {
            sample.status = format!("rejected: {e}");
            return sample;
        }
    };
    let mut clock = StepClock::default();
    match catch_panic(|| run::run_case(&case, dir, &mut clock)) {
        Ok(Ok(summary)) => {
            sample.particles = summary.particles;
            sample.steps = clock.steps;
            if let (Some(a), Some(b)) = (clock.started, clock.last) {
                if clock.steps > 0 {
                    let k = 1e3 / clock.steps as f64;
                    sample.ms_per_step = (b.0 - a.0).as_secs_f64() * k;
                    if let (Some(c0), Some(c1)) = (a.1, b.1) {
                        sample.cpu_ms_per_step = (c1 - c0) * k;
                    }
                }
            }
            sample.status = match summary.status {
                RunStatus::Succeeded => "succeeded".into(),
                _ => format!("failed: {}", summary.reason.unwrap_or_default()),
            };
        }
        Ok(Err(e)) => sample.status = format!("run error: {e}"),
        Err(panic) => sample.status = format!("panicked: {panic}"),
    }
    sample
}

/// A variant's summary over its repeats, compared with the bare scene.
#[derive(Debug, Clone, PartialEq)]
pub struct FeatureRow {
    pub variant: String,
    pub description: String,
    pub particles: usize,
    pub samples_ms: Vec<f64>,
    pub median_ms: f64,
    /// Median CPU time per step (all threads).
    pub median_cpu_ms: f64,
    pub min_ms: f64,
    /// Max - min over the repeats.
    pub spread_ms: f64,
    /// median - the bare scene's median.
    pub difference_ms: f64,
    /// The larger spread of this variant and the bare scene.
    pub noise_ms: f64,
    /// median CPU time per step - the bare scene's (less sensitive to other processes
    /// than wall time on a shared machine; includes rayon's idle spinning).
    pub cpu_difference_ms: f64,
    /// The larger CPU-time spread of this variant and the bare scene.
    pub cpu_noise_ms: f64,
    pub status: String,
}

impl FeatureRow {
    /// True when the difference to the bare scene is within the repeats' noise.
    pub fn within_noise(&self) -> bool {
        self.difference_ms.abs() <= self.noise_ms
    }

    /// The same on CPU time.
    pub fn cpu_within_noise(&self) -> bool {
        self.cpu_difference_ms.abs() <= self.cpu_noise_ms
    }
}

/// Rows from the samples: per variant median, min, spread and the difference to `bare`.
pub fn feature_rows(
    variants: &[(&str, &str)],
    samples: &[FeatureSample],
    bare: &str,
) -> Vec<FeatureRow> {
    // one measured field (wall or CPU ms/step) of a variant's successful samples
    let field = |name: &str, of: fn(&FeatureSample) -> f64| -> Vec<f64> {
        samples
            .iter()
            .filter(|s| s.variant == name && s.status == "succeeded")
            .map(of)
            .collect()
    };
    let times = |name: &str| field(name, |s| s.ms_per_step);
    let cpu_times = |name: &str| field(name, |s| s.cpu_ms_per_step);
    let bare_times = times(bare);
    let bare_median = median(&bare_times).unwrap_or(f64::NAN);
    let bare_cpu = cpu_times(bare);
    let bare_cpu_median = median(&bare_cpu).unwrap_or(f64::NAN);
    variants
        .iter()
        .map(|(name, description)| {
            let t = times(name);
            let mine: Vec<&FeatureSample> = samples.iter().filter(|s| s.variant == *name).collect();
            let failed: Vec<&str> = mine
                .iter()
                .filter(|s| s.status != "succeeded")
                .map(|s| s.status.as_str())
                .collect();
            let med = median(&t).unwrap_or(f64::NAN);
            let cpu = cpu_times(name);
            let cpu_median = median(&cpu).unwrap_or(f64::NAN);
            FeatureRow {
                variant: name.to_string(),
                description: description.to_string(),
                particles: mine.first().map_or(0, |s| s.particles),
                samples_ms: t.clone(),
                median_ms: med,
                median_cpu_ms: cpu_median,
                min_ms: t.iter().cloned().fold(f64::NAN, f64::min),
                spread_ms: spread(&t),
                difference_ms: med - bare_median,
                noise_ms: spread(&t).max(spread(&bare_times)),
                cpu_difference_ms: cpu_median - bare_cpu_median,
                cpu_noise_ms: spread(&cpu).max(spread(&bare_cpu)),
                status: if failed.is_empty() {
                    "succeeded".into()
                } else {
                    failed.join("; ")
                },
            }
        })
        .collect()
}

/// `features.md`: the table and a verdict per variant.
pub fn features_markdown(rows: &[FeatureRow], repeats: usize) -> String {
    let mut md = String::from("# mpsfsi feature cost\n\n");
    let _ = writeln!(
        md,
        "The still tank of the scaling study at about {FEATURE_PARTICLES} particles, {FEATURE_STEPS} steps at dt = {TANK_DT} s, \
         through the full `run_case` (output writer, loads every 0.01 s). Time per step from the built scene to the last step; \
         each variant {repeats}× round-robin. Difference = median − the bare scene's median; noise = the larger max−min spread \
         of the two.\n"
    );
    let _ = writeln!(
        md,
        "| variant | what | particles | median ms/step | min ms/step | spread | difference vs bare | verdict | median CPU ms/step | CPU difference vs bare | CPU verdict | status |\n| --- | --- | ---: | ---: | ---: | ---: | ---: | --- | ---: | ---: | --- | --- |"
    );
    let bare = rows.first().map_or(f64::NAN, |r| r.median_ms);
    let bare_cpu = rows.first().map_or(f64::NAN, |r| r.median_cpu_ms);
    let verdict = |d: f64, within: bool, reference: f64| {
        if !d.is_finite() {
            "—".to_string()
        } else if within {
            "within noise".to_string()
        } else {
            format!("{:+.1}% (above noise)", 100.0 * d / reference)
        }
    };
    for r in rows {
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} | {} | {} | {} ± {} | {} | {} | {} ± {} | {} | {} |",
            r.variant,
            r.description,
            r.particles,
            md_num(r.median_ms, 3),
            md_num(r.min_ms, 3),
            md_num(r.spread_ms, 3),
            md_num(r.difference_ms, 3),
            md_num(r.noise_ms, 3),
            verdict(r.difference_ms, r.within_noise(), bare),
            md_num(r.median_cpu_ms, 3),
            md_num(r.cpu_difference_ms, 3),
            md_num(r.cpu_noise_ms, 3),
            verdict(r.cpu_difference_ms, r.cpu_within_noise(), bare_cpu),
            r.status.replace('|', "/")
        );
    }
    let _ = writeln!(
        md,
        "\nCPU time is the process's user + system time over the same interval (all threads, rayon's idle spinning included): \
         on a machine shared with other processes it varies less than wall time."
    );
    md
}

/// `--features`: run the variants round-robin and write `features.csv` and `features.md`.
pub fn write_features(out_dir: &Path, repeats: usize) -> io::Result<Vec<FeatureRow>> {
    let variants = feature_variants();
    let runs: PathBuf = out_dir.join("runs").join("features");
    let mut samples = Vec::new();
    // an untimed run first: page faults, thread pool start-up, file cache
    let _ = run_feature(
        "warm-up",
        tank_case_value(FEATURE_PARTICLES, FEATURE_STEPS),
        &runs.join("warm-up"),
    );
    for k in 0..repeats.max(1) {
        for (name, _, overrides) in &variants {
            let mut value = tank_case_value(FEATURE_PARTICLES, FEATURE_STEPS);
            let mut rejected = None;
            for o in overrides {
                if let Err(e) = case::apply_override(&mut value, o) {
                    rejected = Some(e.to_string());
                }
            }
            let sample = match rejected {
                Some(e) => FeatureSample {
                    variant: name.to_string(),
                    particles: 0,
                    steps: 0,
                    ms_per_step: f64::NAN,
                    cpu_ms_per_step: f64::NAN,
                    status: format!("rejected: {e}"),
                },
                None => run_feature(name, value, &runs.join(format!("{name}_{k}"))),
            };
            eprintln!(
                "features {:<15} repeat {k}: {:>8.3} ms/step  {:>8.3} CPU ms/step  {} particles  {}",
                sample.variant, sample.ms_per_step, sample.cpu_ms_per_step, sample.particles, sample.status
            );
            samples.push(sample);
        }
    }
    let names: Vec<(&str, &str)> = variants.iter().map(|(n, d, _)| (*n, *d)).collect();
    let rows = feature_rows(&names, &samples, "bare");
    let mut csv =
        String::from("variant,repeat,particles,steps,ms_per_step,cpu_ms_per_step,status\n");
    for (k, s) in samples.iter().enumerate() {
        let _ = writeln!(
            csv,
            "{},{},{},{},{},{},{}",
            s.variant,
            k / variants.len(),
            s.particles,
            s.steps,
            csv_num(s.ms_per_step, 4),
            csv_num(s.cpu_ms_per_step, 4),
            csv_field(&s.status)
        );
    }
    std::fs::write(out_dir.join("features.csv"), csv)?;
    std::fs::write(
        out_dir.join("features.md"),
        features_markdown(&rows, repeats),
    )?;
    Ok(rows)
}
