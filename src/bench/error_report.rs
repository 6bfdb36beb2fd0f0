//! The error study's outputs: `results.csv`, `report.md` (tables and an interpretation
//! computed from the results, with the CFL sweep and the stress runs of `--stress`
//! when they ran), one SVG per case (error against wall time).

use super::error_study::{variants, BenchCase, BenchResult};
use super::stress::{cfl_sweep_table, stress_table, CflRow, StressOutcome};
use super::table::{csv_field, md_percent, md_text};
use crate::math::Real;
use crate::output::plot::{log_log_svg, Series};
use std::fmt::Write as _;
use std::io;
use std::path::Path;

pub const RESULTS_HEADER: &str =
    "case,variant,spacing,particles,steps,particle_steps,wall_time_s,error,error_measure,error2,error2_measure,mean_solver_iterations,status,note";

/// Write `results.csv` (rewritten after every run, so a long benchmark can be read while it runs).
pub fn write_results_csv(path: &Path, results: &[BenchResult]) -> io::Result<()> {
    let mut out = String::from(RESULTS_HEADER);
    out.push('\n');
    for r in results {
        let _ = writeln!(
            out,
            "{},{},{},{},{},{},{:.4},{:.6e},{},{:.6e},{},{:.2},{},{}",
            csv_field(&r.case),
            csv_field(&r.variant),
            r.spacing,
            r.particles,
            r.steps,
            r.particle_steps,
            r.wall_time_s,
            r.error,
            csv_field(&r.error_measure),
            r.error2,
            csv_field(&r.error2_measure),
            r.mean_solver_iterations,
            r.status,
            csv_field(&r.note)
        );
    }
    std::fs::write(path, out)
}

/// Runs not dominated in (wall time, error): no other run is both faster and more accurate.
pub fn pareto_front(results: &[&BenchResult]) -> Vec<usize> {
    let ok = |r: &BenchResult| r.error.is_finite() && r.wall_time_s.is_finite();
    let mut front: Vec<usize> = (0..results.len())
        .filter(|&i| ok(results[i]))
        .filter(|&i| {
            let a = results[i];
            !results.iter().any(|b| {
                ok(b)
                    && b.wall_time_s <= a.wall_time_s
                    && b.error <= a.error
                    && (b.wall_time_s < a.wall_time_s || b.error < a.error)
            })
        })
        .collect();
    front.sort_by(|&a, &b| results[a].wall_time_s.total_cmp(&results[b].wall_time_s));
    front
}

/// The shortest wall time of a run with error at most `threshold`, and its variant.
pub fn time_to_reach<'a>(results: &[&'a BenchResult], threshold: Real) -> Option<&'a BenchResult> {
    results
        .iter()
        .copied()
        .filter(|r| r.error.is_finite() && r.error <= threshold)
        .min_by(|a, b| a.wall_time_s.total_cmp(&b.wall_time_s))
}

/// Write `report.md` and the SVGs.
pub fn write_report(
    out_dir: &Path,
    cases: &[BenchCase],
    results: &[BenchResult],
    stress: &[CflRow],
    stress_runs: &[StressOutcome],
    quick: bool,
    total_seconds: f64,
) -> io::Result<()> {
    let mut md = String::new();
    let _ = writeln!(md, "# mpsfsi benchmark: run time against error\n");
    let _ = writeln!(
        md,
        "Mode: {}. Total wall time {:.1} s on {} threads. Errors are relative (see `results.csv` for every column); \
         wall time is the run's own (`summary.json`), without the scoring.\n",
        if quick { "quick (coarse spacings, short end times)" } else { "full" },
        total_seconds,
        rayon::current_num_threads()
    );
    let _ = writeln!(md, "Variants:\n");
    // those the study ran (`--variant` may have picked some)
    let ran: Vec<_> = variants()
        .into_iter()
        .filter(|v| results.iter().any(|r| r.variant == v.name))
        .collect();
    for v in &ran {
        let _ = writeln!(md, "- `{}`: {}", v.name, v.description);
    }
    md.push('\n');
    for case in cases {
        let rows: Vec<&BenchResult> = results.iter().filter(|r| r.case == case.name).collect();
        if rows.is_empty() {
            continue;
        }
        let measure = rows
            .iter()
            .find(|r| !r.error_measure.is_empty())
            .map(|r| r.error_measure.clone())
            .unwrap_or_default();
        let measure2 = rows
            .iter()
            .find(|r| !r.error2_measure.is_empty())
            .map(|r| r.error2_measure.clone());
        let _ = writeln!(md, "## {}\n", case.name);
        let _ = writeln!(
            md,
            "Error: {measure}.{}\n",
            measure2
                .as_ref()
                .map(|m| format!(" Second error: {m}."))
                .unwrap_or_default()
        );
        let _ = writeln!(md, "| variant | spacing (m) | particles | steps | particle-steps | wall time (s) | error | {}status | note |", if measure2.is_some() { "error 2 | " } else { "" });
        let _ = writeln!(
            md,
            "| --- | ---: | ---: | ---: | ---: | ---: | ---: | {}--- | --- |",
            if measure2.is_some() { "---: | " } else { "" }
        );
        for r in &rows {
            let _ = writeln!(
                md,
                "| {} | {:.5} | {} | {} | {:.1} M | {:.2} | {} | {}{} | {} |",
                r.variant,
                r.spacing,
                r.particles,
                r.steps,
                r.particle_steps as Real / 1e6,
                r.wall_time_s,
                md_percent(r.error),
                if measure2.is_some() {
                    format!("{} | ", md_percent(r.error2))
                } else {
                    String::new()
                },
                r.status,
                md_text(&r.note)
            );
        }
        md.push('\n');
        md.push_str(&interpretation(&rows));
        md.push('\n');
        // the plot
        let series: Vec<Series> = ran
            .iter()
            .map(|v| Series {
                name: v.name.to_string(),
                points: {
                    let mut mine: Vec<&&BenchResult> =
                        rows.iter().filter(|r| r.variant == v.name).collect();
                    mine.sort_by(|a, b| b.spacing.total_cmp(&a.spacing));
                    mine.iter().map(|r| (r.wall_time_s, r.error)).collect()
                },
            })
            .collect();
        match log_log_svg(
            &format!("{}: error against wall time", case.name),
            "wall time (s)",
            "relative error",
            &series,
        ) {
            Ok(svg) => {
                std::fs::write(out_dir.join(format!("{}.svg", case.name)), svg)?;
                let _ = writeln!(md, "![{0}]({0}.svg)\n", case.name);
            }
            Err(e) => {
                let _ = writeln!(md, "(plot failed: {e})\n");
            }
        }
    }
    if !stress.is_empty() {
        let _ = writeln!(md, "## Stability: CFL sweep of the dam break\n");
        cfl_sweep_table(&mut md, stress);
        md.push('\n');
        // the variants the sweep ran (`--variant` may have picked some)
        for v in variants()
            .iter()
            .filter(|v| stress.iter().any(|s| s.variant == v.name))
        {
            let stable = stress
                .iter()
                .filter(|s| s.variant == v.name && s.completed)
                .map(|s| s.cfl)
                .fold(None, |a: Option<Real>, c| Some(a.map_or(c, |a| a.max(c))));
            let _ = writeln!(
                md,
                "- `{}`: largest completing CFL {}",
                v.name,
                stable.map_or("none".to_string(), |c| c.to_string())
            );
        }
        md.push('\n');
    }
    if !stress_runs.is_empty() {
        let _ = writeln!(md, "## Stress runs\n");
        md.push_str(&stress_table(stress_runs));
        let _ = writeln!(md, "\nScenes and notes in `stress.md`.\n");
    }
    std::fs::write(out_dir.join("report.md"), md)
}

/// What the rows of one case say, computed from them.
pub fn interpretation(rows: &[&BenchResult]) -> String {
    let mut md = String::new();
    let failed = rows.iter().filter(|r| r.status != "succeeded").count();
    if failed > 0 {
        let _ = writeln!(
            md,
            "- {failed} of {} runs did not complete (see the notes).",
            rows.len()
        );
    }
    let mut names: Vec<&str> = rows.iter().map(|r| r.variant.as_str()).collect();
    names.dedup();
    for name in &names {
        let mut mine: Vec<&&BenchResult> = rows
            .iter()
            .filter(|r| r.variant == *name && r.error.is_finite())
            .collect();
        mine.sort_by(|a, b| b.spacing.total_cmp(&a.spacing));
        if mine.len() >= 2 {
            let trend = if mine.windows(2).all(|w| w[1].error <= w[0].error) {
                "decreasing with refinement"
            } else if mine.windows(2).all(|w| w[1].error >= w[0].error) {
                "growing with refinement: a bias the spacing does not remove, or a model error"
            } else {
                "not monotone in the spacing"
            };
            let (first, last) = (mine[0], mine[mine.len() - 1]);
            let order = (last.error / first.error).ln() / (last.spacing / first.spacing).ln();
            let _ = writeln!(
                md,
                "- `{name}`: error {} at l0 = {:.4} to {} at l0 = {:.4} ({}; observed order {:.2}).",
                md_percent(first.error),
                first.spacing,
                md_percent(last.error),
                last.spacing,
                trend,
                order
            );
        }
    }
    // variants that the engine does not tell apart (same errors at every spacing)
    for (k, a) in names.iter().enumerate() {
        for b in &names[..k] {
            let pairs: Vec<(&&BenchResult, &&BenchResult)> = rows
                .iter()
                .filter(|r| r.variant == *a)
                .filter_map(|r| {
                    rows.iter()
                        .find(|q| q.variant == *b && q.spacing == r.spacing)
                        .map(|q| (r, q))
                })
                .collect();
            let same = !pairs.is_empty()
                && pairs.iter().all(|(r, q)| {
                    r.error.is_finite()
                        && q.error.is_finite()
                        && (r.error - q.error).abs() <= 1e-6 * q.error.abs()
                });
            if same {
                let ratio = pairs
                    .iter()
                    .map(|(r, q)| r.wall_time_s / q.wall_time_s)
                    .sum::<f64>()
                    / pairs.len() as f64;
                let _ = writeln!(
                    md,
                    "- `{a}` gives the errors of `{b}` to 1e-6 at every spacing: the engine does not distinguish them here; it costs {ratio:.1}× the wall time."
                );
                break;
            }
        }
    }
    let front = pareto_front(rows);
    if !front.is_empty() {
        let list: Vec<String> = front
            .iter()
            .map(|&i| {
                format!(
                    "`{}` l0 = {:.4} ({:.2} s, {})",
                    rows[i].variant,
                    rows[i].spacing,
                    rows[i].wall_time_s,
                    md_percent(rows[i].error)
                )
            })
            .collect();
        let _ = writeln!(
            md,
            "- Pareto front (fastest to most accurate): {}.",
            list.join("; ")
        );
    }
    for threshold in [0.05, 0.02] {
        match time_to_reach(rows, threshold) {
            Some(r) => {
                let _ = writeln!(
                    md,
                    "- Cheapest run within {:.0}%: `{}` at l0 = {:.4}, {:.2} s.",
                    threshold * 100.0,
                    r.variant,
                    r.spacing,
                    r.wall_time_s
                );
            }
            None => {
                let _ = writeln!(md, "- No run reached {:.0}%.", threshold * 100.0);
            }
        }
    }
    md
}
