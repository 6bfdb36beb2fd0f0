//! `mpsfsi bench --scaling` and `--features` (issue 6): what a step costs as the scene
//! grows, on one and two threads, how much memory a particle takes, and what each
//! optional feature adds to a step.
//!
//! - Scaling: a still hydrostatic tank (aspect 2:1, `cases/hydrostatic.json` scaled in
//!   size at its fixed spacing l0 = 0.01 m, so dt/l0 and the per-particle physics stay
//!   the same) at about 10k, 40k, 160k, 640k and 1.3M fluid particles, up to
//!   `--max-particles`. Each size is built once and stepped a fixed number of steps
//!   from rest at a fixed dt (solver tolerance 1e-8) on the engine alone (no output
//!   writer). One untimed warm-up step, then the timed steps; stage times come from the
//!   engine's [`StageTimes`]. Memory is measured, not estimated: free heap pages are
//!   handed back (`malloc_trim`), the kernel's peak-RSS mark is reset
//!   (`/proc/self/clear_refs` = 5), then VmRSS before the build, VmRSS after it and
//!   VmHWM after the steps give bytes per particle at rest and at peak.
//! - Threads: the same case run inside a 1-thread and a 2-thread rayon pool.
//! - Features: the same tank (~20k particles) through the full [`run::run_case`] (output
//!   writer included) bare, with a fixed submerged box, with a fixed box far from the
//!   water, with viscosity, with probes, with snapshots. Each variant is repeated
//!   (round-robin, so that drifting machine load hits all alike); the time per step is
//!   measured from the observer's `started` to the last step.
//!
//! The pure parts (power-law fit, `/proc` parsing, tables) are tested in
//! `tests/output/bench_measures.rs`.

use crate::case::{self, Case, Limits};
use crate::engine::{Simulation, StageTimes};
use crate::run::{self, Observer, Progress, RunStatus};
use serde_json::{json, Value};
use std::fmt::Write as _;
use std::io;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Particle spacing of the scaling tank (that of `cases/hydrostatic.json`).
pub const TANK_SPACING: f64 = 0.01;
/// Fixed time step of the scaling runs (`cases/hydrostatic.json`'s max_dt).
pub const TANK_DT: f64 = 5.0e-4;
/// The sizes of the scaling study (fluid particles, approximate).
pub const SCALING_SIZES: [usize; 5] = [10_000, 40_000, 160_000, 640_000, 1_300_000];
/// Default largest size of `--scaling` (the quick form).
pub const DEFAULT_MAX_PARTICLES: usize = 160_000;

/// What `--scaling` / `--features` run.
#[derive(Debug, Clone)]
pub struct ScalingOptions {
    /// Largest size of the scaling study.
    pub max_particles: usize,
    /// Timed steps per size (after one warm-up step).
    pub steps: u64,
    /// Size of the threads comparison (the largest study size not above it).
    pub threads_particles: usize,
    /// Repeats of each feature variant.
    pub repeats: usize,
}

impl Default for ScalingOptions {
    fn default() -> Self {
        Self {
            max_particles: DEFAULT_MAX_PARTICLES,
            steps: 20,
            threads_particles: 160_000,
            repeats: 3,
        }
    }
}

// ---------------------------------------------------------------- pure measures

/// A least-squares fit of y = prefactor * x^exponent on log-log axes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PowerFit {
    pub exponent: f64,
    pub prefactor: f64,
    /// Coefficient of determination of the log-log fit.
    pub r2: f64,
}

/// Least squares of ln y against ln x over the points with x, y > 0 and finite.
/// None with fewer than two such points or all x equal.
pub fn fit_power_law(points: &[(f64, f64)]) -> Option<PowerFit> {
    let logs: Vec<(f64, f64)> = points
        .iter()
        .filter(|(x, y)| x.is_finite() && y.is_finite() && *x > 0.0 && *y > 0.0)
        .map(|(x, y)| (x.ln(), y.ln()))
        .collect();
    if logs.len() < 2 {
        return None;
    }
    let n = logs.len() as f64;
    let mx = logs.iter().map(|p| p.0).sum::<f64>() / n;
    let my = logs.iter().map(|p| p.1).sum::<f64>() / n;
    let sxx: f64 = logs.iter().map(|p| (p.0 - mx).powi(2)).sum();
    let sxy: f64 = logs.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let syy: f64 = logs.iter().map(|p| (p.1 - my).powi(2)).sum();
    if sxx <= 0.0 {
        return None;
    }
    let exponent = sxy / sxx;
    let intercept = my - exponent * mx;
    let r2 = if syy > 0.0 {
        (sxy * sxy) / (sxx * syy)
    } else {
        1.0
    };
    Some(PowerFit {
        exponent,
        prefactor: intercept.exp(),
        r2,
    })
}

/// A `/proc/self/status` field given in kB (`VmRSS:	  2092 kB`), in bytes.
pub fn parse_status_bytes(status: &str, key: &str) -> Option<u64> {
    status.lines().find_map(|line| {
        let (name, rest) = line.split_once(':')?;
        if name.trim() != key {
            return None;
        }
        let mut parts = rest.split_whitespace();
        let value: u64 = parts.next()?.parse().ok()?;
        let scale = match parts.next().map(|u| u.to_ascii_lowercase()) {
            Some(u) if u == "kb" => 1024,
            Some(u) if u == "mb" => 1024 * 1024,
            Some(u) if u == "gb" => 1024 * 1024 * 1024,
            None => 1,
            Some(_) => return None,
        };
        Some(value * scale)
    })
}

/// Median of the finite values (None when there are none).
pub fn median(values: &[f64]) -> Option<f64> {
    let mut v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    Some(if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    })
}

/// Max - min of the finite values (0 for fewer than two).
pub fn spread(values: &[f64]) -> f64 {
    let v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
    if v.len() < 2 {
        return 0.0;
    }
    v.iter().cloned().fold(f64::NEG_INFINITY, f64::max)
        - v.iter().cloned().fold(f64::INFINITY, f64::min)
}

/// Stage times divided by `steps` and in milliseconds.
pub fn stage_ms_per_step(total: &StageTimes, steps: u64) -> StageTimes {
    let k = if steps > 0 { 1e3 / steps as f64 } else { 0.0 };
    StageTimes {
        explicit_forces: total.explicit_forces * k,
        neighbors: total.neighbors * k,
        walls: total.walls * k,
        number_density: total.number_density * k,
        assemble: total.assemble * k,
        solve: total.solve * k,
        correct: total.correct * k,
        spacing: total.spacing * k,
        bookkeeping: total.bookkeeping * k,
    }
}

/// `after - before`, stage by stage.
pub fn stage_difference(after: &StageTimes, before: &StageTimes) -> StageTimes {
    StageTimes {
        explicit_forces: after.explicit_forces - before.explicit_forces,
        neighbors: after.neighbors - before.neighbors,
        walls: after.walls - before.walls,
        number_density: after.number_density - before.number_density,
        assemble: after.assemble - before.assemble,
        solve: after.solve - before.solve,
        correct: after.correct - before.correct,
        spacing: after.spacing - before.spacing,
        bookkeeping: after.bookkeeping - before.bookkeeping,
    }
}

/// The stage names and values, in the engine's order.
pub fn stage_list(s: &StageTimes) -> [(&'static str, f64); 9] {
    [
        ("explicit_forces", s.explicit_forces),
        ("neighbors", s.neighbors),
        ("walls", s.walls),
        ("number_density", s.number_density),
        ("assemble", s.assemble),
        ("solve", s.solve),
        ("correct", s.correct),
        ("spacing", s.spacing),
        ("bookkeeping", s.bookkeeping),
    ]
}

// ---------------------------------------------------------------- memory

/// (VmRSS, VmHWM) of this process in bytes, None where `/proc` is not there.
pub fn memory_now() -> Option<(u64, u64)> {
    let status = std::fs::read_to_string("/proc/self/status").ok()?;
    Some((
        parse_status_bytes(&status, "VmRSS")?,
        parse_status_bytes(&status, "VmHWM")?,
    ))
}

/// Reset the kernel's peak-RSS mark (VmHWM) to the current RSS. False when not allowed.
pub fn reset_peak_memory() -> bool {
    std::fs::write("/proc/self/clear_refs", "5").is_ok()
}

/// Give free heap pages back to the system so that RSS before a build is not padded
/// with memory freed by the previous size.
pub fn release_free_memory() {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    // SAFETY: malloc_trim only walks glibc's own free lists.
    unsafe {
        libc::malloc_trim(0);
    }
}

/// CPU seconds (user + system, all threads) of this process so far, None where unknown.
pub fn cpu_seconds() -> Option<f64> {
    #[cfg(all(target_os = "linux", target_env = "gnu"))]
    {
        // SAFETY: getrusage writes into the zeroed struct we own.
        let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
        if unsafe { libc::getrusage(libc::RUSAGE_SELF, &mut usage) } == 0 {
            let t = |tv: libc::timeval| tv.tv_sec as f64 + tv.tv_usec as f64 * 1e-6;
            return Some(t(usage.ru_utime) + t(usage.ru_stime));
        }
    }
    None
}

// ---------------------------------------------------------------- the tank

/// Lattice columns and rows of a 2:1 tank of about `target` particles.
pub fn tank_lattice(target: usize) -> (usize, usize) {
    let ny = ((target as f64 / 2.0).sqrt().round() as usize).max(2);
    (2 * ny, ny)
}

/// The still tank of `cases/hydrostatic.json` scaled to about `target` fluid particles
/// at spacing [`TANK_SPACING`], stepped `steps` steps at the fixed dt [`TANK_DT`]
/// (max_dt = dt, end = steps dt), solver tolerance 1e-8, no probes or snapshots.
pub fn tank_case_value(target: usize, steps: u64) -> Value {
    let l0 = TANK_SPACING;
    let (nx, ny) = tank_lattice(target);
    let (w, h) = (nx as f64 * l0, ny as f64 * l0);
    let m = 0.1 * h.max(0.1);
    json!({
        "name": format!("scaling-tank-{}", nx * ny),
        "fluid": { "density": 1000.0, "kinematic_viscosity": 0.0, "gravity": [0.0, -9.81] },
        "particle_spacing": l0,
        "domain": { "min": [-m, -m], "max": [w + m, 1.4 * h + m] },
        "fluid_blocks": [ { "polygon": [[0.0, 0.0], [w, 0.0], [w, h], [0.0, h]] } ],
        "walls": [ { "name": "tank", "polyline": [[0.0, 1.4 * h], [0.0, 0.0], [w, 0.0], [w, 1.4 * h]] } ],
        "time": { "end": steps as f64 * TANK_DT, "cfl": 0.2, "max_dt": TANK_DT },
        "output": { "load_interval": 0.01, "snapshot_interval": null, "probes": [] },
        "scheme": { "solver_tolerance": 1.0e-8 }
    })
}

fn parse(v: Value) -> io::Result<case::ValidCase> {
    let case = case::parse_case_value(v)
        .map_err(|e| io::Error::new(io::ErrorKind::InvalidData, e.to_string()))?;
    case::ValidCase::new(
        case,
        &Limits {
            max_particles: usize::MAX,
        },
    )
    .map_err(|e| io::Error::new(io::ErrorKind::InvalidData, e.to_string()))
}

// ---------------------------------------------------------------- scaling

/// One size (or thread count) of the scaling study: one row of `scaling.csv`.
#[derive(Debug, Clone, PartialEq)]
pub struct ScalingPoint {
    /// `size` rows make the N sweep, `threads` rows the thread comparison.
    pub study: String,
    pub threads: usize,
    pub particles: usize,
    /// Timed steps (after one untimed warm-up step).
    pub steps: u64,
    pub build_s: f64,
    pub warmup_ms: f64,
    pub ms_per_step: f64,
    /// CPU time of the process (all threads) per timed step: ms_per_step × threads when
    /// the threads had the cores to themselves, less when other processes competed.
    pub cpu_ms_per_step: f64,
    /// Engine stage times per timed step (ms).
    pub stage_ms: StageTimes,
    pub solver_iterations_per_step: f64,
    pub particle_steps_per_s: f64,
    /// VmRSS after the build minus VmRSS before, per particle (NaN without /proc).
    pub bytes_per_particle_built: f64,
    /// Peak RSS (VmHWM) over build and steps minus VmRSS before, per particle.
    pub bytes_per_particle_peak: f64,
    pub rss_before_mb: f64,
    pub peak_mb: f64,
    pub status: String,
    pub note: String,
}

impl ScalingPoint {
    fn failed(study: &str, threads: usize, note: String) -> Self {
        Self {
            study: study.into(),
            threads,
            particles: 0,
            steps: 0,
            build_s: f64::NAN,
            warmup_ms: f64::NAN,
            ms_per_step: f64::NAN,
            cpu_ms_per_step: f64::NAN,
            stage_ms: StageTimes::default(),
            solver_iterations_per_step: f64::NAN,
            particle_steps_per_s: f64::NAN,
            bytes_per_particle_built: f64::NAN,
            bytes_per_particle_peak: f64::NAN,
            rss_before_mb: f64::NAN,
            peak_mb: f64::NAN,
            status: "failed".into(),
            note,
        }
    }
}

/// Build `case` and step it `steps` timed steps at fixed `dt` after a warm-up step, on
/// the engine alone, in the current rayon pool. Never panics: a panic or an engine
/// error is the row's status.
/// Lattice disorder of the scaling tank (ratio of l0, uniform per axis).
pub const SCALING_PERTURBATION: f64 = 0.05;

pub fn measure_engine(case: &Case, steps: u64, dt: f64, study: &str) -> ScalingPoint {
    let threads = rayon::current_num_threads();
    release_free_memory();
    let peak_reset = reset_peak_memory();
    let before = memory_now();
    let outcome = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        let started = Instant::now();
        let mut sim = Simulation::new(case);
        // The still lattice is an exact discrete equilibrium: after the first step the
        // warm-started solve would need no iteration and the benchmark would time no
        // pressure solve. A small seeded disorder gives every step a real system.
        super::stress::perturb_positions(
            &mut sim.particles.position,
            SCALING_PERTURBATION * case.particle_spacing,
            super::stress::PERTURBATION_SEED,
        );
        sim.initialize();
        let build_s = started.elapsed().as_secs_f64();
        let built = memory_now();
        let n = sim.particle_count();
        let clock = Instant::now();
        let warm = sim.step(dt);
        let warmup_ms = clock.elapsed().as_secs_f64() * 1e3;
        let stages_before = sim.stats.stage_times;
        let iterations_before = sim.stats.total_solver_iterations;
        let mut error = warm.err().map(|e| e.to_string());
        let clock = Instant::now();
        let cpu0 = cpu_seconds();
        let mut done = 0;
        while error.is_none() && done < steps {
            match sim.step(dt) {
                Ok(_) => done += 1,
                Err(e) => error = Some(e.to_string()),
            }
        }
        let seconds = clock.elapsed().as_secs_f64();
        let cpu = match (cpu0, cpu_seconds()) {
            (Some(a), Some(b)) => b - a,
            _ => f64::NAN,
        };
        let after = memory_now();
        (
            cpu,
            build_s,
            warmup_ms,
            n,
            done,
            seconds,
            stage_difference(&sim.stats.stage_times, &stages_before),
            sim.stats.total_solver_iterations - iterations_before,
            built,
            after,
            error,
        )
    }));
    let (cpu, build_s, warmup_ms, n, done, seconds, stages, iterations, built, after, error) =
        match outcome {
            Ok(r) => r,
            Err(panic) => {
                return ScalingPoint::failed(
                    study,
                    threads,
                    format!("panicked: {}", panic_text(&panic)),
                )
            }
        };
    let per = |bytes: Option<u64>| match (before, bytes) {
        (Some((rss0, _)), Some(b)) if n > 0 => (b as f64 - rss0 as f64) / n as f64,
        _ => f64::NAN,
    };
    let mb = |b: u64| b as f64 / (1024.0 * 1024.0);
    let mut note = String::new();
    if !peak_reset {
        note.push_str("peak RSS mark not reset (clear_refs refused): peak is the process's; ");
    }
    if let Some(e) = &error {
        note.push_str(e);
    }
    ScalingPoint {
        study: study.into(),
        threads,
        particles: n,
        steps: done,
        build_s,
        warmup_ms,
        ms_per_step: if done > 0 {
            seconds * 1e3 / done as f64
        } else {
            f64::NAN
        },
        cpu_ms_per_step: if done > 0 {
            cpu * 1e3 / done as f64
        } else {
            f64::NAN
        },
        stage_ms: stage_ms_per_step(&stages, done),
        solver_iterations_per_step: if done > 0 {
            iterations as f64 / done as f64
        } else {
            f64::NAN
        },
        particle_steps_per_s: if seconds > 0.0 {
            (n as f64) * done as f64 / seconds
        } else {
            f64::NAN
        },
        bytes_per_particle_built: per(built.map(|m| m.0)),
        bytes_per_particle_peak: per(after.map(|m| m.1)),
        rss_before_mb: before.map_or(f64::NAN, |m| mb(m.0)),
        peak_mb: after.map_or(f64::NAN, |m| mb(m.1)),
        status: if error.is_none() {
            "succeeded".into()
        } else {
            "failed".into()
        },
        note: note.trim_end_matches("; ").to_string(),
    }
}

fn panic_text(panic: &Box<dyn std::any::Any + Send>) -> String {
    panic
        .downcast_ref::<String>()
        .cloned()
        .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()))
        .unwrap_or_default()
}

fn in_pool<T: Send>(threads: usize, f: impl FnOnce() -> T + Send) -> Result<T, String> {
    let pool = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| e.to_string())?;
    Ok(pool.install(f))
}

/// The study sizes not above `max_particles` (the first always, so that a tiny limit
/// still measures something).
pub fn scaling_sizes(max_particles: usize) -> Vec<usize> {
    let mut sizes: Vec<usize> = SCALING_SIZES
        .iter()
        .copied()
        .filter(|&s| s <= max_particles)
        .collect();
    if sizes.is_empty() {
        sizes.push(max_particles.max(200));
    }
    sizes
}

/// The size sweep then the 1-vs-2-thread comparison.
pub fn scaling_study(options: &ScalingOptions) -> Vec<ScalingPoint> {
    let mut rows = Vec::new();
    let sizes = scaling_sizes(options.max_particles);
    for &target in &sizes {
        let row = match parse(tank_case_value(target, options.steps)) {
            Ok(case) => measure_engine(&case, options.steps, TANK_DT, "size"),
            Err(e) => ScalingPoint::failed("size", rayon::current_num_threads(), e.to_string()),
        };
        eprintln!(
            "scaling N = {:>8} threads {} {:>9.2} ms/step  {:>6.1} iterations/step  {:>7.0} B/particle peak  {}",
            row.particles,
            row.threads,
            row.ms_per_step,
            row.solver_iterations_per_step,
            row.bytes_per_particle_peak,
            row.note
        );
        rows.push(row);
    }
    let target = sizes
        .iter()
        .copied()
        .filter(|&s| s <= options.threads_particles)
        .max()
        .unwrap_or(sizes[0]);
    if let Ok(case) = parse(tank_case_value(target, options.steps)) {
        // alternate 1, 2, 1, 2: drifting load from other processes hits both alike
        for threads in [1, 2, 1, 2] {
            let row = in_pool(threads, || {
                measure_engine(&case, options.steps, TANK_DT, "threads")
            })
            .unwrap_or_else(|e| ScalingPoint::failed("threads", threads, e));
            eprintln!(
                "scaling threads {} N = {:>8} {:>9.2} ms/step",
                threads, row.particles, row.ms_per_step
            );
            rows.push(row);
        }
    }
    rows
}

fn csv_num(x: f64, decimals: usize) -> String {
    if x.is_finite() {
        format!("{x:.decimals$}")
    } else {
        "NaN".into()
    }
}

fn csv_field(s: &str) -> String {
    if s.contains([',', '"', '\n']) {
        format!("\"{}\"", s.replace('"', "\"\""))
    } else {
        s.to_string()
    }
}

/// The header of `scaling.csv`.
pub fn scaling_csv_header() -> String {
    let mut h = String::from(
        "study,threads,particles,steps,build_s,warmup_ms,ms_per_step,cpu_ms_per_step,solver_iterations_per_step,particle_steps_per_s,bytes_per_particle_built,bytes_per_particle_peak,rss_before_mb,peak_mb",
    );
    for (name, _) in stage_list(&StageTimes::default()) {
        let _ = write!(h, ",{name}_ms");
    }
    h.push_str(",status,note");
    h
}

/// `scaling.csv`: one line per row.
pub fn scaling_csv(rows: &[ScalingPoint]) -> String {
    let mut out = scaling_csv_header();
    out.push('\n');
    for r in rows {
        let _ = write!(
            out,
            "{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
            r.study,
            r.threads,
            r.particles,
            r.steps,
            csv_num(r.build_s, 4),
            csv_num(r.warmup_ms, 3),
            csv_num(r.ms_per_step, 3),
            csv_num(r.cpu_ms_per_step, 3),
            csv_num(r.solver_iterations_per_step, 2),
            csv_num(r.particle_steps_per_s, 0),
            csv_num(r.bytes_per_particle_built, 1),
            csv_num(r.bytes_per_particle_peak, 1),
            csv_num(r.rss_before_mb, 1),
            csv_num(r.peak_mb, 1),
        );
        for (_, v) in stage_list(&r.stage_ms) {
            let _ = write!(out, ",{}", csv_num(v, 4));
        }
        let _ = writeln!(out, ",{},{}", r.status, csv_field(&r.note));
    }
    out
}

fn md_num(x: f64, decimals: usize) -> String {
    if x.is_finite() {
        format!("{x:.decimals$}")
    } else {
        "—".into()
    }
}

/// The fitted exponent of ms/step against particles over the succeeded `size` rows.
pub fn step_cost_fit(rows: &[ScalingPoint]) -> Option<PowerFit> {
    let points: Vec<(f64, f64)> = rows
        .iter()
        .filter(|r| r.study == "size" && r.status == "succeeded")
        .map(|r| (r.particles as f64, r.ms_per_step))
        .collect();
    fit_power_law(&points)
}

/// (whole step, solve stage) speed-up of 2 threads over 1 from the fastest succeeded
/// `threads` row of each count.
pub fn thread_speedup(rows: &[ScalingPoint]) -> Option<(f64, f64)> {
    let best = |t: usize| {
        rows.iter()
            .filter(|r| r.study == "threads" && r.threads == t && r.status == "succeeded")
            .min_by(|a, b| a.ms_per_step.total_cmp(&b.ms_per_step))
    };
    let (a, b) = (best(1)?, best(2)?);
    Some((
        a.ms_per_step / b.ms_per_step,
        a.stage_ms.solve / b.stage_ms.solve,
    ))
}

/// `scaling.md`: the tables and what they say, computed from the rows.
pub fn scaling_markdown(rows: &[ScalingPoint], options: &ScalingOptions) -> String {
    let mut md = String::from("# mpsfsi scaling: step cost, memory and threads\n\n");
    let _ = writeln!(
        md,
        "Still hydrostatic tank, aspect 2:1, l0 = {TANK_SPACING} m (`cases/hydrostatic.json` scaled in size), \
         {} timed steps from rest at fixed dt = {TANK_DT} s after one untimed warm-up step, default scheme with \
         solver tolerance 1e-8, engine only (no output writer). Memory: VmRSS before the build (after `malloc_trim`), \
         VmRSS after the build and the peak VmHWM over build and steps (mark reset through `/proc/self/clear_refs`), \
         per fluid particle. Machine: {} logical CPUs; the default pool has {} threads.\n",
        options.steps,
        std::thread::available_parallelism().map_or(0, |n| n.get()),
        rayon::current_num_threads()
    );
    let size: Vec<&ScalingPoint> = rows.iter().filter(|r| r.study == "size").collect();
    let _ = writeln!(md, "## Step cost against particles\n");
    let _ = writeln!(
        md,
        "| particles | threads | build (s) | warm-up step (ms) | ms/step | CPU ms/step | solver iterations/step | particle-steps/s | bytes/particle built | bytes/particle peak | peak RSS (MB) | status |"
    );
    let _ = writeln!(
        md,
        "| ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: | --- |"
    );
    for r in &size {
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {}{} |",
            r.particles,
            r.threads,
            md_num(r.build_s, 2),
            md_num(r.warmup_ms, 1),
            md_num(r.ms_per_step, 2),
            md_num(r.cpu_ms_per_step, 2),
            md_num(r.solver_iterations_per_step, 1),
            md_num(r.particle_steps_per_s / 1e6, 2) + "M",
            md_num(r.bytes_per_particle_built, 0),
            md_num(r.bytes_per_particle_peak, 0),
            md_num(r.peak_mb, 0),
            r.status,
            if r.note.is_empty() {
                String::new()
            } else {
                format!(": {}", r.note.replace('|', "/"))
            }
        );
    }
    md.push('\n');
    let _ = writeln!(md, "Stage times per step (ms):\n");
    let mut header = String::from("| particles |");
    let mut rule = String::from("| ---: |");
    for (name, _) in stage_list(&StageTimes::default()) {
        let _ = write!(header, " {name} |");
        rule.push_str(" ---: |");
    }
    let _ = writeln!(md, "{header} sum of stages |\n{rule} ---: |");
    for r in &size {
        let mut line = format!("| {} |", r.particles);
        for (_, v) in stage_list(&r.stage_ms) {
            let _ = write!(line, " {} |", md_num(v, 2));
        }
        let _ = writeln!(md, "{line} {} |", md_num(r.stage_ms.total(), 2));
    }
    md.push('\n');
    match step_cost_fit(rows) {
        Some(fit) => {
            let _ = writeln!(
                md,
                "- Step cost grows as N^{:.2} (least squares on log-log over {} sizes, R² = {:.3}; 1 would be linear).",
                fit.exponent,
                size.iter().filter(|r| r.status == "succeeded").count(),
                fit.r2
            );
        }
        None => {
            let _ = writeln!(md, "- Fewer than two sizes succeeded: no exponent.");
        }
    }
    let iter_points: Vec<(f64, f64)> = size
        .iter()
        .filter(|r| r.status == "succeeded")
        .map(|r| (r.particles as f64, r.solver_iterations_per_step))
        .collect();
    if let Some(fit) = fit_power_law(&iter_points) {
        let _ = writeln!(
            md,
            "- Solver iterations per step grow as N^{:.2} (R² = {:.3}).",
            fit.exponent, fit.r2
        );
    }
    let solve_points: Vec<(f64, f64)> = size
        .iter()
        .filter(|r| r.status == "succeeded")
        .map(|r| (r.particles as f64, r.stage_ms.solve))
        .collect();
    if let Some(fit) = fit_power_law(&solve_points) {
        let _ = writeln!(md, "- The solve stage grows as N^{:.2}.", fit.exponent);
    }
    if let Some(r) = size
        .iter()
        .filter(|r| r.status == "succeeded")
        .max_by_key(|r| r.particles)
    {
        let total = r.stage_ms.total();
        if total > 0.0 {
            let mut stages: Vec<(&str, f64)> = stage_list(&r.stage_ms).to_vec();
            stages.sort_by(|a, b| b.1.total_cmp(&a.1));
            let top: Vec<String> = stages
                .iter()
                .take(3)
                .map(|(n, v)| format!("{n} {:.0}%", 100.0 * v / total))
                .collect();
            let _ = writeln!(
                md,
                "- At N = {} the largest stages are {}.",
                r.particles,
                top.join(", ")
            );
        }
    }
    let threads: Vec<&ScalingPoint> = rows.iter().filter(|r| r.study == "threads").collect();
    if !threads.is_empty() {
        let _ = writeln!(md, "\n## Threads\n");
        let _ = writeln!(
            md,
            "Same case in a rayon pool of 1 and of 2 threads, alternated (1, 2, 1, 2); the speed-up uses the fastest run of each. \
             CPU/wall is the share of cores the run had: 1 thread ideally 1.0, 2 threads 2.0; below that, other processes took the rest.\n\n\
             | threads | particles | ms/step | CPU/wall | solve ms/step | particle-steps/s | status |\n| ---: | ---: | ---: | ---: | ---: | ---: | --- |"
        );
        for r in &threads {
            let _ = writeln!(
                md,
                "| {} | {} | {} | {} | {} | {}M | {} |",
                r.threads,
                r.particles,
                md_num(r.ms_per_step, 2),
                md_num(r.cpu_ms_per_step / r.ms_per_step, 2),
                md_num(r.stage_ms.solve, 2),
                md_num(r.particle_steps_per_s / 1e6, 2),
                r.status
            );
        }
        match thread_speedup(rows) {
            Some((total, solve)) => {
                let _ = writeln!(
                    md,
                    "\n- Speed-up 2 threads / 1 thread: {total:.2}× (ideal 2; solve stage {solve:.2}×)."
                );
            }
            None => {
                let _ = writeln!(md, "\n- No speed-up: a thread count has no succeeded run.");
            }
        }
        let cores: Vec<f64> = threads
            .iter()
            .filter(|r| r.threads == 2 && r.status == "succeeded")
            .map(|r| r.cpu_ms_per_step / r.ms_per_step)
            .filter(|x| x.is_finite())
            .collect();
        if let Some(c) = median(&cores) {
            if c < 1.5 {
                let _ = writeln!(
                    md,
                    "- The 2-thread runs had {c:.2} cores on average (CPU/wall): other processes held the rest, \
                     so this speed-up measures the machine's load more than the code. Rerun on an idle machine."
                );
            }
        }
    }
    md
}

/// `--scaling`: run the study and write `scaling.csv` (after each row) and `scaling.md`.
pub fn write_scaling(out_dir: &Path, options: &ScalingOptions) -> io::Result<Vec<ScalingPoint>> {
    let rows = scaling_study(options);
    std::fs::write(out_dir.join("scaling.csv"), scaling_csv(&rows))?;
    std::fs::write(out_dir.join("scaling.md"), scaling_markdown(&rows, options))?;
    Ok(rows)
}

// ---------------------------------------------------------------- feature cost

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
    let case = match parse(value) {
        Ok(c) => c,
        Err(e) => {
            sample.status = format!("rejected: {e}");
            return sample;
        }
    };
    let mut clock = StepClock::default();
    let outcome = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        run::run_case(&case, dir, &mut clock)
    }));
    match outcome {
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
        Err(p) => sample.status = format!("panicked: {}", panic_text(&p)),
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
