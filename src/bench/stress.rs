//! The stress study of `mpsfsi bench --stress` (issue 6): scenes that push the scheme,
//! each reported as completed or failed with the engine's own diagnosis, and the CFL
//! sweep of the error study's dam break ([`cfl_sweep`]). A failed run is a result,
//! never a panic.
//!
//! - `dam_break_long`: the Koshizuka & Oka dam break to t = 5 s at l0 = a/40 (impact on
//!   the far wall, overturning wave, sloshing) at CFL 0.1 (the case's 0.15 is on the
//!   edge of stability over 5 s); quick: 2 s at a/10.
//! - `wedge_20ms`, `wedge_30ms`: the 30° wedge of
//!   `cases/wedge_30deg_constant_velocity.json` at constant 20 and 30 m/s, spacing
//!   10 mm (quick: 20 mm), to the chine time (the first chine reaching the undisturbed surface level
//!   under Wagner's 2/π rise-up: t = 2 h_chine / (π V), = B tanβ / (π V) for a
//!   symmetric wedge). The case's absolute speed limit (150 m/s for 6.15 m/s) is scaled
//!   with V: the jet tip of a 30° wedge runs at about 5 V.
//! - `wedge_heel_10deg`: the same wedge at its case speed rotated 10° (deadrise 20° on
//!   one side and 40° on the other), to its first chine time.
//! - `perturbed_lattice`: the still tank of `cases/hydrostatic.json` with every fluid
//!   particle moved by a seeded uniform random offset in ±0.2 l0 per axis after the
//!   scene is built (bench side: the case format has no such option), stepped by the
//!   engine directly, to 2 s (quick: 0.5 s).
//! - `hydrostatic_long`: `cases/hydrostatic.json` to 20 s (2 s in the quick form).
//!
//! For the still tanks the report adds the load drift: the relative error of the mean
//! vertical tank load against the water weight early (10-20% of the run) and late
//! (last 10%), and the largest particle speed.

use super::cases::{cases_dir, dam_break_value, parse_case, read_case_value, set_override};
use super::error_study::{run_one, BenchCase, Variant};
use super::perturb::{perturb_positions, PERTURBATION_SEED};
use super::score::Measure;
use super::stats::window_mean;
use super::table::{md_percent, md_text};
use super::unwind::catch_panic;
use crate::analysis::measure::relative_error;
use crate::analysis::reference::KOSHIZUKA_OKA_COLUMN_WIDTH;
use crate::case::{self, Case, Motion};
use crate::engine::Simulation;
use crate::math::Real;
use crate::output::loads_csv::parse_loads_csv;
use crate::run::{self, RunStatus};
use serde_json::Value;
use std::fmt::Write as _;
use std::io;
use std::path::Path;
use std::time::Instant;

/// Amplitude of the lattice perturbation (ratio of l0).
pub const PERTURBATION: Real = 0.2;
/// CFL of the dam break to 5 s: the case's 0.15 is on the edge of stability over that
/// long (it completed, then failed at 2.96 s after a round-off change); 0.1 and 0.12
/// complete. The ignored test of the same run uses it too.
pub const DAM_BREAK_LONG_CFL: Real = 0.1;

/// How a stress run is driven and measured.
#[derive(Debug, Clone, PartialEq)]
pub enum StressKind {
    /// Through `run::run_case` (outputs written); no extra measure.
    Plain,
    /// Through `run::run_case`; the load drift of the first wall is measured.
    StillTank,
    /// The engine directly, after perturbing the lattice by ± amplitude l0 (seeded).
    PerturbedTank { amplitude: Real, seed: u64 },
}

/// One stress scene.
#[derive(Debug, Clone)]
pub struct StressRun {
    pub name: String,
    pub description: String,
    pub case: Value,
    pub kind: StressKind,
}

/// What a stress run did (one row of `stress.md`).
#[derive(Debug, Clone, PartialEq)]
pub struct StressOutcome {
    pub name: String,
    pub description: String,
    pub status: String,
    /// The engine's diagnosis of a failure (empty when completed).
    pub reason: String,
    pub end_time: Real,
    pub final_time: Real,
    pub steps: u64,
    pub particles: usize,
    pub wall_time_s: f64,
    pub max_speed: Real,
    /// Relative error of the mean tank load against the water weight over 10-20% of the run.
    pub load_error_early: Real,
    /// The same over the last 10% of the run.
    pub load_error_late: Real,
}

// ---------------------------------------------------------------- pure parts

/// Relative errors of the mean load against `expected` over 10-20% and the last 10% of
/// `[0, end]` (NaN where a window holds no interval).
pub fn load_drift(times: &[Real], loads: &[Real], end: Real, expected: Real) -> (Real, Real) {
    let err = |from: Real, to: Real| {
        window_mean(0.0, times, loads, from, to).map_or(Real::NAN, |m| relative_error(m, expected))
    };
    (err(0.1 * end, 0.2 * end), err(0.9 * end, end))
}

/// First chine time of a body moving at constant velocity into a free surface at
/// `surface` (the level across the motion; the keel starts `gap` above it): the time at
/// which the water, rising at 2/π of the entry depth (Wagner), reaches the nearer of the
/// two vertices next to the leading one. Returns (contact time, chine time after contact).
pub fn chine_time(
    polygon: &[[Real; 2]],
    position: [Real; 2],
    angle: Real,
    velocity: [Real; 2],
    surface: Real,
) -> Option<(Real, Real)> {
    let speed = (velocity[0].powi(2) + velocity[1].powi(2)).sqrt();
    if polygon.len() < 3 || !(speed > 0.0) {
        return None;
    }
    let d = [velocity[0] / speed, velocity[1] / speed];
    let (s, c) = angle.sin_cos();
    let along: Vec<Real> = polygon
        .iter()
        .map(|p| {
            let x = position[0] + c * p[0] - s * p[1];
            let y = position[1] + s * p[0] + c * p[1];
            x * d[0] + y * d[1]
        })
        .collect();
    let n = along.len();
    let lead = (0..n).max_by(|&a, &b| along[a].total_cmp(&along[b]))?;
    let h = [(lead + 1) % n, (lead + n - 1) % n]
        .iter()
        .map(|&k| along[lead] - along[k])
        .fold(Real::INFINITY, Real::min);
    // `surface` is the water level along -d (distance of the surface ahead of the keel)
    let contact = ((surface - along[lead]) / speed).max(0.0);
    (h > 0.0).then(|| (contact, 2.0 * h / (std::f64::consts::PI * speed)))
}

// ---------------------------------------------------------------- the runs

/// The wedge case at `speed` (m/s, downwards), heel `angle` (rad), spacing `l0`, ending
/// at its first chine time. A `scheme.max_speed` of the base case is scaled with the
/// speed (the jet tip of a 30° wedge runs at about 5 V, physically: an absolute limit
/// set for the base speed would stop a faster entry for a physical jet).
pub fn wedge_case(base: &Value, speed: Real, angle: Real, l0: Real) -> io::Result<Value> {
    let mut v = base.clone();
    let base_case = parse_case(base.clone())?;
    let base_speed = base_case.bodies.first().and_then(|b| match &b.motion {
        Motion::Prescribed { velocity, .. } => {
            Some((velocity[0].powi(2) + velocity[1].powi(2)).sqrt())
        }
        _ => None,
    });
    if let (Some(limit), Some(v0)) = (base_case.scheme.max_speed, base_speed) {
        if v0 > 0.0 {
            set_override(&mut v, &format!("scheme.max_speed={}", limit * speed / v0))?;
        }
    }
    set_override(
        &mut v,
        &format!("bodies.0.motion.velocity=[0.0,{}]", -speed),
    )?;
    set_override(&mut v, &format!("bodies.0.angle={angle}"))?;
    set_override(&mut v, &format!("particle_spacing={l0}"))?;
    let case = parse_case(v.clone())?;
    let body = case
        .bodies
        .first()
        .ok_or_else(|| io::Error::other("the wedge case has no body"))?;
    let Motion::Prescribed { velocity, .. } = &body.motion else {
        return Err(io::Error::other("the wedge case needs a prescribed motion"));
    };
    let d = {
        let s = (velocity[0].powi(2) + velocity[1].powi(2)).sqrt();
        [velocity[0] / s, velocity[1] / s]
    };
    // the free surface: the fluid furthest against the motion
    let surface = case
        .fluid_blocks
        .iter()
        .flat_map(|b| b.polygon.iter().map(|p| p[0] * d[0] + p[1] * d[1]))
        .fold(Real::INFINITY, Real::min);
    let (contact, t_chine) =
        chine_time(&body.polygon, body.position, body.angle, *velocity, surface)
            .ok_or_else(|| io::Error::other("no chine time"))?;
    set_override(&mut v, &format!("time.end={}", contact + t_chine))?;
    // loads at 50 rows over the run, no snapshots
    set_override(
        &mut v,
        &format!("output.load_interval={}", (contact + t_chine) / 50.0),
    )?;
    set_override(&mut v, "output.snapshot_interval=null")?;
    Ok(v)
}

/// The stress scenes (shorter or coarser in the quick form).
pub fn stress_runs(quick: bool) -> io::Result<Vec<StressRun>> {
    let mut runs = Vec::new();
    // dam break to 5 s
    let mut dam = dam_break_value()?;
    let a = KOSHIZUKA_OKA_COLUMN_WIDTH;
    let dam_end = if quick { 2.0 } else { 5.0 };
    let per_width = if quick { 10 } else { 40 };
    set_override(
        &mut dam,
        &format!("particle_spacing={}", a / per_width as Real),
    )?;
    set_override(&mut dam, &format!("time.end={dam_end}"))?;
    set_override(&mut dam, &format!("time.cfl={DAM_BREAK_LONG_CFL}"))?;
    set_override(&mut dam, "output.load_interval=0.01")?;
    set_override(&mut dam, "output.snapshot_interval=null")?;
    runs.push(StressRun {
        name: "dam_break_long".into(),
        description: format!(
            "Koshizuka & Oka dam break to {dam_end} s at l0 = a/{per_width}, CFL {DAM_BREAK_LONG_CFL} (far-wall impact, overturning wave)"
        ),
        case: dam,
        kind: StressKind::Plain,
    });
    // wedges
    let wedge_path = cases_dir().join("wedge_30deg_constant_velocity.json");
    if wedge_path.exists() {
        let base = read_case_value(&wedge_path)?;
        let l0 = if quick { 0.02 } else { 0.01 };
        for speed in [20.0, 30.0] {
            runs.push(StressRun {
                name: format!("wedge_{speed:.0}ms"),
                description: format!(
                    "30° wedge at constant {speed} m/s, l0 = {} mm, to the chine time (the case's speed limit scaled with V)",
                    l0 * 1e3
                ),
                case: wedge_case(&base, speed, 0.0, l0)?,
                kind: StressKind::Plain,
            });
        }
        let base_speed = parse_case(base.clone())?
            .bodies
            .first()
            .and_then(|b| match &b.motion {
                Motion::Prescribed { velocity, .. } => {
                    Some((velocity[0].powi(2) + velocity[1].powi(2)).sqrt())
                }
                _ => None,
            })
            .unwrap_or(6.15);
        runs.push(StressRun {
            name: "wedge_heel_10deg".into(),
            description: format!(
                "30° wedge heeled 10° (deadrise 20°/40°) at {base_speed} m/s, l0 = {} mm, to the first chine time",
                l0 * 1e3
            ),
            case: wedge_case(&base, base_speed, 10f64.to_radians(), l0)?,
            kind: StressKind::Plain,
        });
    }
    // still tanks
    let tank_path = cases_dir().join("hydrostatic.json");
    if tank_path.exists() {
        let base = read_case_value(&tank_path)?;
        let mut perturbed = base.clone();
        let end = if quick { 0.5 } else { 2.0 };
        set_override(&mut perturbed, &format!("time.end={end}"))?;
        runs.push(StressRun {
            name: "perturbed_lattice".into(),
            description: format!(
                "hydrostatic tank, fluid lattice perturbed by uniform ±{PERTURBATION} l0 per axis (seed {PERTURBATION_SEED}), to {end} s"
            ),
            case: perturbed,
            kind: StressKind::PerturbedTank {
                amplitude: PERTURBATION,
                seed: PERTURBATION_SEED,
            },
        });
        let mut long = base;
        let end = if quick { 2.0 } else { 20.0 };
        set_override(&mut long, &format!("time.end={end}"))?;
        set_override(&mut long, "output.snapshot_interval=null")?;
        runs.push(StressRun {
            name: "hydrostatic_long".into(),
            description: format!("hydrostatic tank to {end} s"),
            case: long,
            kind: StressKind::StillTank,
        });
    }
    Ok(runs)
}

fn status_text(s: RunStatus) -> String {
    match s {
        RunStatus::Succeeded => "completed",
        RunStatus::Failed => "failed",
        RunStatus::Cancelled => "cancelled",
    }
    .into()
}

fn water_weight(case: &Case, particles: usize) -> Real {
    particles as Real * case.fluid.density * case.particle_spacing.powi(2) * case.fluid.gravity[1]
}

/// Run one stress scene into `dir`. Never panics.
pub fn run_stress(run: &StressRun, dir: &Path) -> StressOutcome {
    let mut out = StressOutcome {
        name: run.name.clone(),
        description: run.description.clone(),
        status: "failed".into(),
        reason: String::new(),
        end_time: Real::NAN,
        final_time: 0.0,
        steps: 0,
        particles: 0,
        wall_time_s: f64::NAN,
        max_speed: Real::NAN,
        load_error_early: Real::NAN,
        load_error_late: Real::NAN,
    };
    let case = match parse_case(run.case.clone()) {
        Ok(c) => c,
        Err(e) => {
            out.reason = format!("case rejected: {e}");
            return out;
        }
    };
    out.end_time = case.time.end;
    let started = Instant::now();
    let outcome = catch_panic(|| match &run.kind {
        StressKind::Plain | StressKind::StillTank => {
            let case = case::ValidCase::new(case.clone(), &case::Limits::default())
                .map_err(|e| format!("invalid case: {e}"))?;
            let summary = run::run_case(&case, dir, &mut run::Quiet).map_err(|e| e.to_string())?;
            let mut o = out.clone();
            o.status = status_text(summary.status);
            o.reason = summary.reason.clone().unwrap_or_default();
            o.final_time = summary.simulated_time;
            o.steps = summary.steps;
            o.particles = summary.particles;
            o.wall_time_s = summary.wall_time_s;
            o.max_speed = summary.max_velocity;
            if run.kind == StressKind::StillTank {
                let wall = case
                    .walls
                    .first()
                    .map(|w| w.name.clone())
                    .unwrap_or_default();
                let text =
                    std::fs::read_to_string(dir.join("loads.csv")).map_err(|e| e.to_string())?;
                let rows = parse_loads_csv(&text).map_err(|e| e.to_string())?;
                let (t, fy): (Vec<Real>, Vec<Real>) = rows
                    .iter()
                    .filter(|r| r.body == wall)
                    .map(|r| (r.time, r.fy))
                    .unzip();
                let (early, late) = load_drift(
                    &t,
                    &fy,
                    summary.simulated_time,
                    water_weight(&case, summary.particles),
                );
                o.load_error_early = early;
                o.load_error_late = late;
            }
            Ok::<StressOutcome, String>(o)
        }
        StressKind::PerturbedTank { amplitude, seed } => {
            Ok(perturbed_tank(&case, *amplitude, *seed, out.clone()))
        }
    });
    match outcome {
        Ok(Ok(mut o)) => {
            if !o.wall_time_s.is_finite() {
                o.wall_time_s = started.elapsed().as_secs_f64();
            }
            o
        }
        Ok(Err(e)) => {
            out.reason = format!("run error: {e}");
            out.wall_time_s = started.elapsed().as_secs_f64();
            out
        }
        Err(panic) => {
            out.reason = format!("panicked: {panic}");
            out.wall_time_s = started.elapsed().as_secs_f64();
            out
        }
    }
}

/// The engine's own loop (as in `run::run_case`, without bodies or writer) on a
/// perturbed lattice; the tank load is recorded every step.
fn perturbed_tank(
    case: &Case,
    amplitude: Real,
    seed: u64,
    mut out: StressOutcome,
) -> StressOutcome {
    if let Err(e) = case::validate(case, &case::Limits::default()) {
        out.reason = format!("case rejected: {e}");
        return out;
    }
    let started = Instant::now();
    let mut sim = Simulation::new(case);
    perturb_positions(
        &mut sim.particles.position,
        amplitude * case.particle_spacing,
        seed,
    );
    // neighbours, wall contacts and number densities of the moved particles
    sim.initialize();
    let tank = 0;
    let end = case.time.end;
    let (mut times, mut loads) = (Vec::new(), Vec::new());
    let mut max_speed: Real = 0.0;
    let mut failure = None;
    while sim.time < end * (1.0 - 1e-12) {
        let mut dt = sim.next_dt();
        if sim.time + dt > end {
            dt = (end - sim.time).max(1e-12);
        }
        match sim.step(dt) {
            Ok(info) => {
                max_speed = max_speed.max(info.max_speed);
                if let Some(l) = sim.loads.get(tank) {
                    times.push(sim.time);
                    loads.push(l.force.y);
                }
            }
            Err(e) => {
                failure = Some(e.to_string());
                break;
            }
        }
    }
    out.status = if failure.is_some() {
        "failed"
    } else {
        "completed"
    }
    .into();
    out.reason = failure.unwrap_or_default();
    out.final_time = sim.time;
    out.steps = sim.steps;
    out.particles = sim.particle_count();
    out.wall_time_s = started.elapsed().as_secs_f64();
    out.max_speed = max_speed;
    let (early, late) = load_drift(
        &times,
        &loads,
        sim.time,
        water_weight(case, sim.particle_count()),
    );
    out.load_error_early = early;
    out.load_error_late = late;
    out
}

// ---------------------------------------------------------------- the CFL sweep

/// One row of the CFL sweep.
#[derive(Debug, Clone)]
pub struct CflRow {
    pub variant: String,
    pub cfl: Real,
    pub completed: bool,
    pub error: Real,
    pub note: String,
}

/// For each variant, the dam break at the coarsest spacing with CFL 0.1, 0.2, 0.4, 0.8:
/// which complete (with a measurable front).
pub fn cfl_sweep(cases: &[BenchCase], variants: &[Variant], dir: &Path) -> Vec<CflRow> {
    let mut rows = Vec::new();
    let Some(dam) = cases
        .iter()
        .find(|c| matches!(c.measure, Measure::DamBreak))
    else {
        return rows;
    };
    let spacing = dam.spacings[0];
    for variant in variants {
        for cfl in [0.1, 0.2, 0.4, 0.8] {
            let mut case = BenchCase {
                name: dam.name,
                base: dam.base.clone(),
                spacings: vec![spacing],
                overrides: dam.overrides.clone(),
                measure: Measure::DamBreak,
            };
            case.overrides.push(format!("time.cfl={cfl}"));
            case.overrides.push("time.max_dt=0.01".into());
            let r = run_one(&case, variant, spacing, &dir.join(format!("cfl_{cfl}")));
            eprintln!(
                "stress dam_break {:<14} cfl {cfl:<4} {} error {:.3e} {}",
                variant.name, r.status, r.error, r.note
            );
            rows.push(CflRow {
                variant: variant.name.into(),
                cfl,
                completed: r.status == "succeeded" && r.error.is_finite(),
                error: r.error,
                note: r.note,
            });
        }
    }
    rows
}

/// The CFL sweep as a markdown table (error study report and stress report).
pub fn cfl_sweep_table(md: &mut String, rows: &[CflRow]) {
    let _ = writeln!(
        md,
        "| variant | CFL | completed | error | note |\n| --- | ---: | --- | ---: | --- |"
    );
    for s in rows {
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} | {} |",
            s.variant,
            s.cfl,
            s.completed,
            md_percent(s.error),
            md_text(&s.note)
        );
    }
}

// ---------------------------------------------------------------- the tables

/// The table of stress outcomes (markdown, with a header line).
pub fn stress_table(rows: &[StressOutcome]) -> String {
    let mut md = String::from(
        "| run | status | t reached / end (s) | steps | particles | wall (s) | max speed (m/s) | load error 10-20% | load error last 10% | diagnosis |\n\
         | --- | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | --- |\n",
    );
    for r in rows {
        let _ = writeln!(
            md,
            "| {} | {} | {:.4} / {:.4} | {} | {} | {:.1} | {} | {} | {} | {} |",
            r.name,
            r.status,
            r.final_time,
            r.end_time,
            r.steps,
            r.particles,
            r.wall_time_s,
            if r.max_speed.is_finite() {
                format!("{:.3}", r.max_speed)
            } else {
                "—".into()
            },
            md_percent(r.load_error_early),
            md_percent(r.load_error_late),
            md_text(&r.reason)
        );
    }
    md
}

/// `stress.md`: the scenes, the table, the CFL sweep table when given.
pub fn stress_markdown(rows: &[StressOutcome], cfl: &[CflRow], quick: bool) -> String {
    let mut md = String::from("# mpsfsi stress runs\n\n");
    let _ = writeln!(
        md,
        "Mode: {}. Default scheme. A failed run is a result: its row gives the time reached and the engine's diagnosis. \
         Load error: mean vertical tank load against the water weight (particles × rho l0² g) over the window; \
         max speed: the largest particle speed over the run.\n",
        if quick { "quick (shorter, coarser)" } else { "full" }
    );
    for r in rows {
        let _ = writeln!(md, "- `{}`: {}", r.name, r.description);
    }
    md.push('\n');
    md.push_str(&stress_table(rows));
    let failed: Vec<&str> = rows
        .iter()
        .filter(|r| r.status != "completed")
        .map(|r| r.name.as_str())
        .collect();
    let _ = writeln!(
        md,
        "\n- {} of {} runs completed{}.",
        rows.len() - failed.len(),
        rows.len(),
        if failed.is_empty() {
            String::new()
        } else {
            format!("; not completed: {}", failed.join(", "))
        }
    );
    if !cfl.is_empty() {
        let _ = writeln!(md, "\n## CFL sweep of the dam break\n");
        cfl_sweep_table(&mut md, cfl);
    }
    md
}

/// Run every stress scene into `dir/<name>` and return the outcomes.
pub fn run_all(quick: bool, dir: &Path) -> io::Result<Vec<StressOutcome>> {
    let mut rows = Vec::new();
    for run in stress_runs(quick)? {
        let o = run_stress(&run, &dir.join(&run.name));
        eprintln!(
            "stress {:<18} {:<9} t = {:.4}/{:.4} s  {} steps  {:.1} s  max speed {:.3}  load error {} -> {}  {}",
            o.name,
            o.status,
            o.final_time,
            o.end_time,
            o.steps,
            o.wall_time_s,
            o.max_speed,
            md_percent(o.load_error_early),
            md_percent(o.load_error_late),
            o.reason
        );
        rows.push(o);
    }
    Ok(rows)
}
