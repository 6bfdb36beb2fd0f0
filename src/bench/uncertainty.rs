//! `mpsfsi bench --uncertainty`: for each study case, the band that `mpsfsi run
//! --uncertainty` gives beside the error the study measures against the reference.
//! The band comes from the default scheme at the case's finest study spacing.
//! Results go to `uncertainty.csv` and `uncertainty.md`.
//!
//! The band is the relative 95 % half-width of the leading series' fy: its impulse, its
//! peak, and the mean over the rows between 30 % and 95 % of the run (u_fy over |fy|).
//! The leading series is the first moving body, else the first wall. The measured error
//! is the study's own measure (`score`), which is not always a load. So the table puts
//! the two side by side, and `inside` says only whether the error's magnitude is within
//! the impulse band.

use super::error_study::{run_case_value, BenchCase};
use super::score::{score, RunOutcome};
use crate::case::{Limits, Scheme, ValidCase};
use crate::math::Real;
use crate::run::uncertainty::run_with_uncertainty;
use crate::run::Quiet;
use std::fmt::Write as _;
use std::io;
use std::path::Path;

/// One case's band beside its measured error.
#[derive(Debug, Clone, PartialEq)]
pub struct BandRow {
    pub case: String,
    pub spacing: Real,
    pub series: String,
    pub error: Real,
    pub error_measure: String,
    pub impulse_band: Real,
    pub peak_band: Real,
    pub row_band: Real,
    pub cost_ratio: Real,
    pub wall_time_s: Real,
    pub note: String,
}

impl BandRow {
    /// |error| within the impulse band (false when either is unknown).
    pub fn inside(&self) -> bool {
        self.error.abs() <= self.impulse_band
    }
}

fn relative(e: &crate::analysis::uncertainty::Estimate) -> Real {
    e.half_width / e.value.abs()
}

/// Mean u_fy over mean |fy| of `series` between 30 % and 95 % of the last row's time.
fn row_band(path: &Path, series: &str) -> io::Result<Real> {
    let text = std::fs::read_to_string(path)?;
    let rows: Vec<(Real, Real, Real)> = text
        .lines()
        .skip(1)
        .filter_map(|l| {
            let f: Vec<&str> = l.split(',').collect();
            (f.len() == 8 && f[1] == series)
                .then(|| Some((f[0].parse().ok()?, f[3].parse().ok()?, f[6].parse().ok()?)))
                .flatten()
        })
        .collect();
    let end = rows.last().map_or(0.0, |r| r.0);
    let window = rows
        .iter()
        .filter(|r| r.0 >= 0.3 * end && r.0 <= 0.95 * end);
    let (u, f) = window.fold((0.0, 0.0), |(u, f), r| (u + r.2, f + r.1.abs()));
    Ok(u / f)
}

fn band_of(bench: &BenchCase, runs_dir: &Path) -> BandRow {
    let spacing = bench
        .spacings
        .iter()
        .copied()
        .fold(Real::INFINITY, Real::min);
    let mut row = BandRow {
        case: bench.name.to_string(),
        spacing,
        series: String::new(),
        error: Real::NAN,
        error_measure: String::new(),
        impulse_band: Real::NAN,
        peak_band: Real::NAN,
        row_band: Real::NAN,
        cost_ratio: Real::NAN,
        wall_time_s: Real::NAN,
        note: String::new(),
    };
    let case = match run_case_value(bench, spacing, &Scheme::default())
        .and_then(|c| ValidCase::new(c, &Limits::default()))
    {
        Ok(c) => c,
        Err(e) => {
            row.note = format!("case rejected: {e}");
            return row;
        }
    };
    let dir = runs_dir.join(bench.name);
    let summary = match std::fs::create_dir_all(&dir)
        .map_err(crate::run::RunError::from)
        .and_then(|_| run_with_uncertainty(&case, &dir, &mut Quiet))
    {
        Ok(s) => s,
        Err(e) => {
            row.note = format!("run error: {e}");
            return row;
        }
    };
    if let Some(reason) = &summary.reason {
        row.note = reason.clone();
    }
    match score(&bench.measure, &case, &dir, &RunOutcome::from(&summary)) {
        Ok(s) => {
            row.error = s.error;
            row.error_measure = s.error_measure;
        }
        Err(e) => row.note = format!("cannot measure: {e}"),
    }
    let Some(u) = &summary.uncertainty else {
        return row;
    };
    row.cost_ratio = u.cost_ratio;
    row.wall_time_s = u.wall_time_s;
    let moving: Vec<&str> = case
        .bodies
        .iter()
        .filter(|b| crate::case::layout::moves(b))
        .map(|b| b.name.as_str())
        .collect();
    let lead = u
        .bodies
        .iter()
        .find(|s| moving.contains(&s.name.as_str()))
        .or(u.bodies.first());
    if let Some(series) = lead {
        row.series = series.name.clone();
        if let Some(fy) = series.columns.iter().find(|c| c.column == "fy") {
            row.impulse_band = relative(&fy.impulse);
            row.peak_band = relative(&fy.peak);
        }
        row.row_band =
            row_band(&dir.join("loads_uncertainty.csv"), &series.name).unwrap_or(Real::NAN);
    }
    row
}

/// A relative number for the table: three decimals, or three digits when it is small.
fn cell(x: Real) -> String {
    if x.abs() >= 1e-3 || x == 0.0 {
        format!("{x:.3}")
    } else {
        format!("{x:.2e}")
    }
}

/// Run the ladder of every case and write `uncertainty.csv` and `uncertainty.md`.
pub fn run_all(cases: &[BenchCase], runs_dir: &Path, out_dir: &Path) -> io::Result<Vec<BandRow>> {
    let mut rows = Vec::new();
    for bench in cases {
        let r = band_of(bench, runs_dir);
        eprintln!(
            "bench uncertainty {:<12} l0 = {:<9.5} error {:.4e}, impulse band {:.4e}, rows {:.4e}  {}",
            r.case, r.spacing, r.error, r.impulse_band, r.row_band, r.note
        );
        rows.push(r);
    }
    let mut csv = String::from(
        "case,spacing,series,error,error_measure,impulse_band,peak_band,row_band,inside,cost_ratio,wall_time_s,note\n",
    );
    let mut md = String::from(
        "# The band of `--uncertainty` beside the measured error\n\n\
         Default scheme at each case's finest study spacing. Bands are relative 95 % half-widths of the leading series' fy (`src/bench/uncertainty.rs`); the error is the study's own measure.\n\n\
         | case | l0 (m) | series | measured error | impulse band | peak band | row band | error within the impulse band | cost (runs) |\n\
         | --- | --- | --- | --- | --- | --- | --- | --- | --- |\n",
    );
    for r in &rows {
        let quote = |s: &str| s.replace(',', ";");
        let _ = writeln!(
            csv,
            "{},{},{},{:.6e},{},{:.6e},{:.6e},{:.6e},{},{:.3},{:.3},{}",
            r.case,
            r.spacing,
            r.series,
            r.error,
            quote(&r.error_measure),
            r.impulse_band,
            r.peak_band,
            r.row_band,
            r.inside(),
            r.cost_ratio,
            r.wall_time_s,
            quote(&r.note)
        );
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} ({}) | {} | {} | {} | {} | {:.2} |",
            r.case,
            r.spacing,
            r.series,
            cell(r.error),
            r.error_measure,
            cell(r.impulse_band),
            cell(r.peak_band),
            cell(r.row_band),
            if r.inside() { "yes" } else { "no" },
            r.cost_ratio
        );
    }
    std::fs::write(out_dir.join("uncertainty.csv"), csv)?;
    std::fs::write(out_dir.join("uncertainty.md"), md)?;
    Ok(rows)
}
