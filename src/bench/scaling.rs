//! The scaling study of `mpsfsi bench --scaling` (issue 6): what a step costs as the
//! scene grows, on one and two threads, and how much memory a particle takes.
//!
//! - Sizes: a still hydrostatic tank (aspect 2:1, `cases/hydrostatic.json` scaled in
//!   size at its fixed spacing l0 = 0.01 m, so dt/l0 and the per-particle physics stay
//!   the same) at about 10k, 40k, 160k, 640k and 1.3M fluid particles, up to
//!   `--max-particles`. Each size is built once and stepped a fixed number of steps
//!   from rest at a fixed dt (the default solver stops) on the engine alone (no output
//!   writer). One untimed warm-up step, then the timed steps; stage times come from the
//!   engine's [`StageTimes`]. Memory is measured, not estimated: free heap pages are
//!   handed back (`malloc_trim`), the kernel's peak-RSS mark is reset
//!   (`/proc/self/clear_refs` = 5), then VmRSS before the build, VmRSS after it and
//!   VmHWM after the steps give bytes per particle at rest and at peak.
//! - Threads: the same case run inside a 1-thread and a 2-thread rayon pool.
//!
//! The pure parts (stage arithmetic, tables) are tested in
//! `tests/output/bench_scaling.rs`.

use super::cases::{parse_unlimited, tank_case_value, TANK_DT, TANK_SPACING};
use super::perturb::{perturb_positions, PERTURBATION_SEED};
use super::resources::{cpu_seconds, memory_now, release_free_memory, reset_peak_memory};
use super::stats::{fit_power_law, median, PowerFit};
use super::table::{csv_field, csv_num, md_num};
use super::unwind::catch_panic;
use crate::case::Case;
use crate::engine::{Simulation, StageTimes};
use std::fmt::Write as _;
use std::io;
use std::path::Path;
use std::time::Instant;

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

// ---------------------------------------------------------------- stage times

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

/// Lattice disorder of the scaling tank (ratio of l0, uniform per axis).
pub const SCALING_PERTURBATION: f64 = 0.05;

/// Build `case` and step it `steps` timed steps at fixed `dt` after a warm-up step, on
/// the engine alone, in the current rayon pool. Never panics: a panic or an engine
/// error is the row's status.
pub fn measure_engine(case: &Case, steps: u64, dt: f64, study: &str) -> ScalingPoint {
    let threads = rayon::current_num_threads();
    release_free_memory();
    let peak_reset = reset_peak_memory();
    let before = memory_now();
    let outcome = catch_panic(|| {
        let started = Instant::now();
        let mut sim = Simulation::new(case);
        // The still lattice is an exact discrete equilibrium: after the first step the
        // warm-started solve would need no iteration and the benchmark would time no
        // pressure solve. A small seeded disorder gives every step a real system.
        perturb_positions(
            &mut sim.particles.position,
            SCALING_PERTURBATION * case.particle_spacing,
            PERTURBATION_SEED,
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
    });
    let (cpu, build_s, warmup_ms, n, done, seconds, stages, iterations, built, after, error) =
        match outcome {
            Ok(r) => r,
            Err(panic) => {
                return ScalingPoint::failed(study, threads, format!("panicked: {panic}"))
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
        let row = match parse_unlimited(tank_case_value(target, options.steps)) {
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
    if let Ok(case) = parse_unlimited(tank_case_value(target, options.steps)) {
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
         {} timed steps from rest at fixed dt = {TANK_DT} s after one untimed warm-up step, default scheme \
         (CG to a relative residual of 1e-8 or an energy-norm error of 1e-3), engine only (no output writer). Memory: VmRSS before the build (after `malloc_trim`), \
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
