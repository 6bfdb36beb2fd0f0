//! `mpsfsi run --uncertainty`: the user's run, coarser levels and a lattice-offset
//! ensemble at the coarsest, and the 95 % half-width of every load and probe reading
//! (`analysis::uncertainty`, the least-squares GCI of Eça & Hoekstra 2014).
//!
//! Layout: the run directory holds the user's run exactly as without the option, plus
//! `levels/<part>/` for every coarser part, `loads_uncertainty.csv`,
//! `probes_uncertainty.csv` (when there are probes), `bodies_uncertainty.csv` (when
//! there are bodies) and `summary.json`'s `uncertainty`.

use super::{run_case_placed, write_summary, Observer, RunError, RunStatus, Summary};
use crate::analysis::measure::interpolate;
use crate::analysis::uncertainty::{
    half_width, mean_and_std, student_t95, ComponentUncertainty, Estimate, LevelSummary,
    SeriesUncertainty, UncertaintySummary,
};
use crate::case::{CaseError, Limits, ValidCase};
use crate::math::Real;
use crate::output::filter::{impulse, moving_average};
use crate::output::series::csv_to_columns;
use serde_json::{Map, Value};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Spacing ratio between consecutive levels.
pub const RATIO: Real = 1.25;
/// Levels in all, the user's spacing included: four, so that the three-parameter fit
/// keeps a residual.
pub const LEVELS: usize = 4;
/// Members of the lattice-offset ensemble at the coarsest level.
pub const MEMBERS: usize = 4;

/// One run of the ladder.
#[derive(Debug, Clone, PartialEq)]
pub struct Part {
    /// 0 for the user's spacing, up to LEVELS - 1.
    pub level: usize,
    pub spacing: Real,
    /// The ensemble member's lattice placement (`engine::scene::build_scene_placed`).
    pub phase: Option<Real>,
    /// Directory name under `levels/` (empty for the user's run).
    pub name: String,
}

/// The parts of a ladder over `levels` spacings from the case's up by about `ratio`,
/// with `members` lattice offsets at the coarsest (part 0 is the user's run).
///
/// Each coarser spacing is rounded so that the depth of the user's fluid (the rows of
/// its highest block, bottom to top) is a whole number of its rows: every level then
/// has its free surface where the user's run has it. Without the rounding, a level
/// whose spacing leaves part of a row starts with its surface up to a spacing low: the
/// 30° wedge's impulse at 15.6 mm read 20 % under its neighbours, its surface 12.5 mm
/// (2 ms of entry) down.
pub fn plan(
    case: &crate::case::Case,
    ratio: Real,
    levels: usize,
    members: usize,
) -> Result<Vec<Part>, CaseError> {
    let h0 = case.particle_spacing;
    let depth = case
        .fluid_blocks
        .iter()
        .map(|b| {
            b.polygon
                .iter()
                .fold((Real::NEG_INFINITY, Real::INFINITY), |(hi, lo), p| {
                    (hi.max(p[1]), lo.min(p[1]))
                })
        })
        .max_by(|a, b| a.0.total_cmp(&b.0))
        .map(|(hi, lo)| ((hi - lo) / h0 + 1e-9).floor())
        .unwrap_or(0.0);
    let mut parts = Vec::new();
    let mut rows = depth;
    for level in 0..levels {
        let h = if level == 0 {
            h0
        } else {
            // fewer rows than the level before, however the rounding falls
            rows = (depth / ratio.powi(level as i32)).round().min(rows - 1.0);
            if rows < 1.0 {
                return Err(CaseError::new(
                    "particle_spacing",
                    format!(
                        "--uncertainty needs {levels} levels with fewer and fewer rows of fluid, and {depth} rows at {h0} m leave too few"
                    ),
                ));
            }
            depth * h0 / rows
        };
        let name = match level {
            0 => String::new(),
            _ => format!("level_{level}"),
        };
        if level + 1 < levels {
            parts.push(Part {
                level,
                spacing: h,
                phase: None,
                name,
            });
        } else {
            for m in 0..members {
                parts.push(Part {
                    level,
                    spacing: h,
                    phase: Some((m as Real + 0.5) / members as Real),
                    name: format!("{name}_member_{m}"),
                });
            }
        }
    }
    Ok(parts)
}

/// The case of each part, validated before any work: a level the case cannot be laid
/// out at is an error on `particle_spacing`.
pub fn part_cases(case: &ValidCase, parts: &[Part]) -> Result<Vec<ValidCase>, CaseError> {
    parts
        .iter()
        .map(|p| {
            let mut c = (**case).clone();
            c.particle_spacing = p.spacing;
            // coarser than a case that passed its limits: fewer particles
            ValidCase::new(c, &Limits { max_particles: usize::MAX }).map_err(|e| {
                CaseError::new(
                    "particle_spacing",
                    format!(
                        "--uncertainty needs the case at {:.4e} m (level {} of the ladder, ratio {RATIO}): {}: {}",
                        p.spacing, p.level, e.path, e.message
                    ),
                )
            })
        })
        .collect()
}

/// The ladder of `case`: its parts ([`plan`] at [`RATIO`], [`LEVELS`] and [`MEMBERS`])
/// and each part's case, validated ([`part_cases`]).
pub fn ladder(case: &ValidCase) -> Result<(Vec<Part>, Vec<ValidCase>), CaseError> {
    let parts = plan(case, RATIO, LEVELS, MEMBERS)?;
    let cases = part_cases(case, &parts)?;
    Ok((parts, cases))
}

/// A ladder the case cannot be laid out at, as a run error.
fn invalid(e: CaseError) -> RunError {
    RunError::Io(std::io::Error::new(
        std::io::ErrorKind::InvalidInput,
        e.to_string(),
    ))
}

/// Run the ladder of `case` into `out_dir` (the user's run in `out_dir` itself) and
/// write the uncertainty outputs. The summary returned (and in summary.json) is the
/// user's run's with `uncertainty` filled in; a part that fails or is cancelled ends
/// the whole with that status and reason, keeping what was written.
pub fn run_with_uncertainty(
    case: &ValidCase,
    out_dir: &Path,
    observer: &mut dyn Observer,
) -> Result<Summary, RunError> {
    let (parts, cases) = ladder(case).map_err(invalid)?;
    let mut summaries: Vec<Summary> = Vec::new();
    let mut dirs: Vec<PathBuf> = Vec::new();
    for (k, (part, part_case)) in parts.iter().zip(&cases).enumerate() {
        let dir = part_dir(out_dir, part);
        std::fs::create_dir_all(&dir)?;
        observer.part(k, parts.len(), &describe(part));
        let s = run_case_placed(part_case, &dir, observer, part.phase)?;
        if s.status != RunStatus::Succeeded {
            return match k {
                0 => Ok(s),
                _ => {
                    let user = summaries.swap_remove(0);
                    Ok(part_stopped(
                        out_dir,
                        &parts,
                        user,
                        k,
                        s.status,
                        s.reason.as_deref(),
                    )?)
                }
            };
        }
        summaries.push(s);
        dirs.push(dir);
    }
    conclude(case, out_dir, &parts, &dirs, summaries)
}

/// Where part `part` runs: `out_dir` itself for the user's level, `levels/<name>`
/// under it for the others.
pub fn part_dir(out_dir: &Path, part: &Part) -> PathBuf {
    if part.name.is_empty() {
        out_dir.to_path_buf()
    } else {
        out_dir.join("levels").join(&part.name)
    }
}

/// The end of a ladder whose part `k` stopped with `status` and `reason`: the user's
/// run's summary (`user`) with them, also written to `out_dir`'s summary.json.
pub fn part_stopped(
    out_dir: &Path,
    parts: &[Part],
    mut user: Summary,
    k: usize,
    status: RunStatus,
    reason: Option<&str>,
) -> std::io::Result<Summary> {
    user.status = status;
    user.reason = Some(format!(
        "uncertainty part {} of {} ({}) stopped: {}; the user's level completed",
        k + 1,
        parts.len(),
        describe(&parts[k]),
        reason.unwrap_or("no reason given")
    ));
    write_summary(out_dir, &user)?;
    Ok(user)
}

/// The end of a ladder whose parts all succeeded: the uncertainty outputs from the
/// parts' run directories (`dirs[k]` holds part k's loads, probes and bodies), and the
/// user's run's summary (`summaries[0]`) with `uncertainty` filled in, also written to
/// `out_dir`'s summary.json.
pub fn conclude(
    case: &ValidCase,
    out_dir: &Path,
    parts: &[Part],
    dirs: &[PathBuf],
    mut summaries: Vec<Summary>,
) -> Result<Summary, RunError> {
    let window = summaries[0].filter_window_s;
    let mut uncertainty = combine(out_dir, parts, dirs, window)?;
    uncertainty.levels = level_summaries(parts, &summaries);
    uncertainty.wall_time_s = summaries.iter().map(|s| s.wall_time_s).sum();
    uncertainty.cost_ratio = uncertainty.wall_time_s / summaries[0].wall_time_s.max(1e-9);
    uncertainty.particle_steps_ratio = summaries.iter().map(|s| s.particle_steps).sum::<u64>()
        as Real
        / summaries[0].particle_steps.max(1) as Real;
    let coarsest = part_cases(case, &parts[parts.len() - 1..]).map_err(invalid)?;
    let coarsest = &coarsest[0];
    uncertainty.advice = crate::analysis::envelope::impact_advice(coarsest)
        .into_iter()
        .filter(|a| !summaries[0].advice.contains(a))
        .map(|a| format!("coarsest level ({:.4e} m): {a}", coarsest.particle_spacing))
        .collect();
    let mut main = summaries.swap_remove(0);
    main.uncertainty = Some(uncertainty);
    write_summary(out_dir, &main)?;
    Ok(main)
}

fn describe(p: &Part) -> String {
    match p.phase {
        None if p.level == 0 => format!("the user's spacing {:.4e} m", p.spacing),
        None => format!("level {}, spacing {:.4e} m", p.level, p.spacing),
        Some(phase) => format!(
            "level {}, spacing {:.4e} m, lattice offset {phase:.3}",
            p.level, p.spacing
        ),
    }
}

fn level_summaries(parts: &[Part], summaries: &[Summary]) -> Vec<LevelSummary> {
    let mut levels: Vec<LevelSummary> = Vec::new();
    for (p, s) in parts.iter().zip(summaries) {
        match levels.iter_mut().find(|l| l.level == p.level) {
            Some(l) => {
                l.members += 1;
                l.wall_time_s += s.wall_time_s;
                l.particle_steps += s.particle_steps;
            }
            None => levels.push(LevelSummary {
                level: p.level,
                spacing: p.spacing,
                members: 1,
                particles: s.particles,
                wall_time_s: s.wall_time_s,
                particle_steps: s.particle_steps,
            }),
        }
    }
    levels
}

/// The series of one CSV file of a part: per name (body or probe), the row times and
/// the columns' values.
type Series = Vec<(String, Vec<Real>, Vec<Vec<Real>>)>;

fn read_series(path: &Path, columns: &[&str]) -> std::io::Result<Series> {
    let text = std::fs::read(path)?;
    let map = csv_to_columns(&text).map_err(|e| {
        std::io::Error::new(
            std::io::ErrorKind::InvalidData,
            format!("{}: {e}", path.display()),
        )
    })?;
    let numbers = |m: &Map<String, Value>, c: &str| -> Vec<Real> {
        m.get(c)
            .and_then(Value::as_array)
            .map(|a| a.iter().map(|v| v.as_f64().unwrap_or(Real::NAN)).collect())
            .unwrap_or_default()
    };
    Ok(map
        .into_iter()
        .filter_map(|(name, v)| {
            let Value::Object(m) = v else { return None };
            let times = numbers(&m, "time");
            let cols = columns.iter().map(|c| numbers(&m, c)).collect();
            Some((name, times, cols))
        })
        .collect())
}

/// The estimate of one reading from each part's value (parts in `plan` order).
fn estimate(parts: &[Part], values: &[Real]) -> Estimate {
    let coarsest = parts.last().map_or(0, |p| p.level);
    let mut h = Vec::new();
    let mut phi = Vec::new();
    for level in 0..=coarsest {
        let of_level: Vec<Real> = parts
            .iter()
            .zip(values)
            .filter(|(p, _)| p.level == level)
            .map(|(_, v)| *v)
            .collect();
        let (mean, _) = mean_and_std(&of_level);
        h.push(
            parts
                .iter()
                .find(|p| p.level == level)
                .map_or(1.0, |p| p.spacing),
        );
        phi.push(if level == 0 { of_level[0] } else { mean });
    }
    let members: Vec<Real> = parts
        .iter()
        .zip(values)
        .filter(|(p, _)| p.phase.is_some())
        .map(|(_, v)| *v)
        .collect();
    let random = if members.len() > 1 {
        let (_, std) = mean_and_std(&members);
        let m = members.len() as Real;
        // a 95 % prediction interval for one more draw (the user's run)
        student_t95(members.len() - 1) * std * (1.0 + 1.0 / m).sqrt()
    } else {
        0.0
    };
    half_width(&h, &phi, random)
}

/// Filtered series of every part onto the user's rows, their half-widths written to
/// `<stem>_uncertainty.csv`, and per name and column the impulse and peak estimates.
fn combine_file(
    out_dir: &Path,
    parts: &[Part],
    dirs: &[PathBuf],
    window: Real,
    file: &str,
    key: &str,
    columns: &[&str],
) -> std::io::Result<Vec<SeriesUncertainty>> {
    let path0 = dirs[0].join(format!("{file}.csv"));
    if !path0.exists() {
        return Ok(Vec::new());
    }
    let all: Vec<Series> = dirs
        .iter()
        .map(|d| read_series(&d.join(format!("{file}.csv")), columns))
        .collect::<Result<_, _>>()?;
    let mut rows: Vec<(Real, String, Vec<Real>, Vec<Real>)> = Vec::new();
    let mut out = Vec::new();
    for (name, times0, _) in &all[0] {
        let mut per_column = Vec::new();
        let mut filtered_cols: Vec<Vec<Vec<Real>>> = Vec::new(); // [column][part][row]
        for c in 0..columns.len() {
            let mut per_part = Vec::new();
            let mut impulses = Vec::new();
            let mut peaks = Vec::new();
            for series in &all {
                let Some((_, t, cols)) = series.iter().find(|(n, _, _)| n == name) else {
                    return Err(std::io::Error::new(
                        std::io::ErrorKind::InvalidData,
                        format!("{file}.csv of a coarser level has no series {name}"),
                    ));
                };
                let f = moving_average(0.0, t, &cols[c], window);
                impulses.push(impulse(0.0, t, &cols[c]));
                peaks.push(
                    f.iter()
                        .copied()
                        .fold(0.0, |a: Real, x| if x.abs() > a.abs() { x } else { a }),
                );
                let series: Vec<(Real, Real)> = t.iter().copied().zip(f).collect();
                // held at the end values beyond the level's rows
                let end = |t0: Real| match series.first() {
                    Some(&(first, v)) if t0 < first => v,
                    _ => series.last().map_or(Real::NAN, |p| p.1),
                };
                per_part.push(
                    times0
                        .iter()
                        .map(|&t0| interpolate(&series, t0).unwrap_or_else(|| end(t0)))
                        .collect(),
                );
            }
            per_column.push(ComponentUncertainty {
                column: columns[c].to_string(),
                impulse: estimate(parts, &impulses),
                peak: estimate(parts, &peaks),
                rows_well_behaved: 0.0,
            });
            filtered_cols.push(per_part);
        }
        for (r, &t) in times0.iter().enumerate() {
            let mut values = Vec::new();
            let mut widths = Vec::new();
            for (c, col) in filtered_cols.iter().enumerate() {
                let at: Vec<Real> = col.iter().map(|part| part[r]).collect();
                let e = estimate(parts, &at);
                if e.well_behaved() {
                    per_column[c].rows_well_behaved += 1.0;
                }
                values.push(e.value);
                widths.push(e.half_width);
            }
            rows.push((t, name.clone(), values, widths));
        }
        for c in &mut per_column {
            c.rows_well_behaved /= times0.len().max(1) as Real;
        }
        out.push(SeriesUncertainty {
            name: name.clone(),
            columns: per_column,
        });
    }
    rows.sort_by(|a, b| a.0.total_cmp(&b.0));
    let mut text = format!("time,{key},{}", columns.join(","));
    for c in columns {
        let _ = write!(text, ",u_{c}");
    }
    text.push('\n');
    for (t, name, values, widths) in rows {
        let _ = write!(text, "{t:.9e},{name}");
        for v in values.iter().chain(&widths) {
            let _ = write!(text, ",{v:.9e}");
        }
        text.push('\n');
    }
    let tmp = out_dir.join(format!("{file}_uncertainty.csv.tmp"));
    std::fs::write(&tmp, text)?;
    std::fs::rename(tmp, out_dir.join(format!("{file}_uncertainty.csv")))?;
    Ok(out)
}

/// Write `loads_uncertainty.csv`, `probes_uncertainty.csv` and `bodies_uncertainty.csv` from the parts' run
/// directories (`dirs[0]` the user's) and return the summary block (levels and times
/// are filled in by the caller).
pub fn combine(
    out_dir: &Path,
    parts: &[Part],
    dirs: &[PathBuf],
    window: Real,
) -> std::io::Result<UncertaintySummary> {
    let bodies = combine_file(
        out_dir,
        parts,
        dirs,
        window,
        "loads",
        "body",
        &["fx", "fy", "mz"],
    )?;
    let probes = combine_file(
        out_dir,
        parts,
        dirs,
        window,
        "probes",
        "probe",
        &["pressure"],
    )?;
    // the bodies' motion, for drop tests: bodies.csv holds states, not interval means,
    // so its columns are compared as they are (no filter) and have no impulse or peak
    combine_file(
        out_dir,
        parts,
        dirs,
        0.0,
        "bodies",
        "body",
        &["x", "y", "angle", "vx", "vy", "omega"],
    )?;
    // one line per body or probe naming the readings outside the expected behaviour
    let notes = bodies
        .iter()
        .chain(&probes)
        .filter_map(|s| {
            let odd: Vec<String> = s
                .columns
                .iter()
                .flat_map(|c| [("impulse", &c.impulse), ("peak", &c.peak)].map(|w| (c, w)))
                .filter(|(_, (_, e))| !e.well_behaved())
                .map(|(c, (what, e))| {
                    format!("{} {what} (order {:.2}, factor {:.2})", c.column, e.order, e.safety_factor)
                })
                .collect();
            (!odd.is_empty()).then(|| {
                format!(
                    "{}: {}: observed order outside [0.5, 2.1) or a fit that scatters more than the levels differ, so the half-width carries the safety factor 3 or the scatter factor 3 U_s/Delta",
                    s.name,
                    odd.join(", ")
                )
            })
        })
        .collect();
    Ok(UncertaintySummary {
        ratio: RATIO,
        filter_window_s: window,
        bodies,
        probes,
        notes,
        ..Default::default()
    })
}
