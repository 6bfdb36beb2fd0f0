//! Scoring a finished run of the error study: the errors of the run's outputs
//! (`loads.csv`, `probes.csv`, `energy.csv`, the VTK snapshots) against the case's
//! reference, one function per [`Measure`], through the estimators of
//! [`crate::analysis::measure`].

use super::cases::{column_geometry, ColumnGeometry};
use crate::analysis::{measure, reference};
use crate::case::Case;
use crate::math::Real;
use crate::output::filter::vertex_deadrise;
use crate::output::loads_csv::{parse_loads_csv, LoadRow};
use crate::output::series::csv_to_columns;
use crate::output::snapshots::{PVD_NAME, SNAPSHOT_DIR};
use crate::output::vtk::{parse_pvd, parse_vtu, PARTICLES_PART};
use crate::run::{RunStatus, Summary};
use std::io;
use std::path::Path;

/// How a run of a case is scored.
pub enum Measure {
    Hydrostatic,
    DamBreak,
    Wedge,
    /// The free-falling 30° wedge's velocity loss.
    FreeFall,
    StandingWave,
}

/// What the scoring needs of a run's summary.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RunOutcome {
    pub succeeded: bool,
    pub simulated_time: Real,
    /// Fluid particles at the end.
    pub particles: usize,
}

impl From<&Summary> for RunOutcome {
    fn from(s: &Summary) -> Self {
        Self {
            succeeded: s.status == RunStatus::Succeeded,
            simulated_time: s.simulated_time,
            particles: s.particles,
        }
    }
}

/// The errors of one run against its case's reference (the columns of `results.csv`).
#[derive(Debug, Clone, PartialEq)]
pub struct Score {
    /// The case's primary error (NaN when the outputs do not cover the comparison).
    pub error: Real,
    /// What `error` compares.
    pub error_measure: String,
    /// A second error (NaN when the case has none or it could not be measured).
    pub error2: Real,
    /// What `error2` compares (empty when the case has none).
    pub error2_measure: String,
    pub note: String,
}

impl Score {
    /// A score with a primary error only.
    fn single(error: Real, error_measure: &str, note: String) -> Self {
        Self {
            error,
            error_measure: error_measure.into(),
            error2: Real::NAN,
            error2_measure: String::new(),
            note,
        }
    }
}

/// The errors of a finished run in `dir`.
pub fn score(
    measure: &Measure,
    case: &Case,
    dir: &Path,
    summary: &RunOutcome,
) -> io::Result<Score> {
    match measure {
        Measure::Hydrostatic => score_hydrostatic(case, dir, summary),
        Measure::DamBreak => score_dam_break(case, dir),
        Measure::Wedge => score_wedge(case, dir),
        Measure::FreeFall => score_free_fall(case, dir),
        Measure::StandingWave => score_standing_wave(case, dir, summary),
    }
}

const TANK_LOAD: &str = "tank load vs water weight";
const MID_DEPTH_PROBE: &str = "mid-depth probe vs rho g d";

/// The still tank: the mean vertical load on the first wall over the second half of
/// the run against the water weight (particles × rho l0² g), and the first probe
/// against rho |g| (top of the fluid - probe height). A failed run is not scored.
fn score_hydrostatic(case: &Case, dir: &Path, summary: &RunOutcome) -> io::Result<Score> {
    if !summary.succeeded {
        return Ok(Score {
            error: Real::NAN,
            error_measure: TANK_LOAD.into(),
            error2: Real::NAN,
            error2_measure: MID_DEPTH_PROBE.into(),
            note: String::new(),
        });
    }
    let rows = parse_loads_csv(&std::fs::read_to_string(dir.join("loads.csv"))?)?;
    let wall = case
        .walls
        .first()
        .map(|w| w.name.clone())
        .unwrap_or_default();
    let (times, picked) = load_series(&rows, &wall);
    let fy: Vec<Real> = picked.iter().map(|r| r.fy).collect();
    let half = 0.5 * summary.simulated_time;
    let expected = summary.particles as Real
        * case.fluid.density
        * case.particle_spacing.powi(2)
        * case.fluid.gravity[1];
    let load_error = measure::interval_mean_after(0.0, &times, &fy, half)
        .map_or(Real::NAN, |m| measure::relative_error(m, expected));
    let mut probe_error = Real::NAN;
    let mut note = String::new();
    if let (Some(probe), Some(block)) = (case.output.probes.first(), case.fluid_blocks.first()) {
        let top = block
            .polygon
            .iter()
            .map(|p| p[1])
            .fold(Real::NEG_INFINITY, Real::max);
        let g = (case.fluid.gravity[0].powi(2) + case.fluid.gravity[1].powi(2)).sqrt();
        let expected_p = case.fluid.density * g * (top - probe.position[1]);
        if let Ok(text) = std::fs::read_to_string(dir.join("probes.csv")) {
            let (t, p) = probe_series(&text, &probe.name);
            if let Some((mean, std)) = measure::sample_stats_after(&t, &p, half) {
                probe_error = measure::relative_error(mean, expected_p);
                note = format!("probe noise std/p = {:.3e}", std / expected_p);
            }
        }
    }
    Ok(Score {
        error: load_error,
        error_measure: TANK_LOAD.into(),
        error2: probe_error,
        error2_measure: MID_DEPTH_PROBE.into(),
        note,
    })
}

/// The dam break: RMS relative error of the surge front (from the VTK snapshots)
/// against Martin & Moyce for 1 <= T <= 3.
fn score_dam_break(case: &Case, dir: &Path) -> io::Result<Score> {
    let geometry =
        column_geometry(case).ok_or_else(|| io::Error::other("dam break without a fluid block"))?;
    let front = surge_front_history(
        dir,
        &geometry,
        case.particle_spacing,
        vec_norm(case.fluid.gravity),
    )?;
    let error = measure::surge_front_rms_error(&front).unwrap_or(Real::NAN);
    let last = front
        .last()
        .map(|(t, z)| format!("front Z = {z:.2} at T = {t:.2}"))
        .unwrap_or_default();
    Ok(Score::single(
        error,
        "surge front RMS vs Martin & Moyce, 1<=T<=3",
        last,
    ))
}

/// The wedge at constant velocity: C_F as a user reads it from loads.csv
/// (`measure::force_coefficient_from_onset`) against the similarity solution; the fit
/// with t from the keel contact over 25-85 % of the time to the chine is in the note.
fn score_wedge(case: &Case, dir: &Path) -> io::Result<Score> {
    let body = case
        .bodies
        .first()
        .ok_or_else(|| io::Error::other("wedge case without a body"))?;
    let crate::case::Motion::Prescribed { velocity, .. } = &body.motion else {
        return Err(io::Error::other(
            "the wedge benchmark needs a prescribed motion",
        ));
    };
    let Entry {
        speed,
        direction: d,
        beta,
        contact,
        t_chine,
    } = entry(case, body, *velocity)?;
    let window = (contact + 0.25 * t_chine, contact + 0.85 * t_chine);
    let rows = parse_loads_csv(&std::fs::read_to_string(dir.join("loads.csv"))?)?;
    let (times, picked) = load_series(&rows, &body.name);
    let force: Vec<Real> = picked
        .iter()
        .map(|r| -(r.fx * d[0] + r.fy * d[1]))
        .collect();
    let (rho, start) = (case.fluid.density, 0.0);
    let last = times.last().copied().unwrap_or(Real::NEG_INFINITY);
    // the product's reading (README, docs/validation.md): from the first load above 1 %
    // of the peak, over 20-85 % of t_chine after it
    let onset = measure::force_coefficient_from_onset(&times, &force, t_chine, rho, speed)
        .filter(|(_, t0)| last >= t0 + measure::ONSET_FIT_WINDOW.1 * t_chine);
    let from_contact =
        measure::force_coefficient_from_contact(contact, start, &times, &force, window, rho, speed)
            .filter(|_| last >= window.1);
    let (error, note) = match onset {
        Some((cf, t0)) => (
            measure::relative_error(cf, reference::WEDGE_30_FORCE_COEFFICIENT),
            format!(
                "C_F = {cf:.2} from the onset t0 = {:.2} ms, per-step scatter {} (from the keel contact {}; Wagner {:.2})",
                t0 * 1e3,
                measure::step_scatter(&times, &force, t0, t_chine)
                    .map_or("none".into(), |s| format!("{s:.2}")),
                from_contact.map_or("none".into(), |(c, se)| format!("{c:.2} ± {se:.2}")),
                reference::wagner_force_coefficient(beta)
            ),
        ),
        None => (
            Real::NAN,
            format!(
                "the loads do not cover 85 % of t_chine = {:.2} ms after their onset",
                t_chine * 1e3
            ),
        ),
    };
    let (error2, peak_note) = peak_cp_error(case, dir, &body.name, beta, speed);
    Ok(Score {
        error,
        error_measure: "C_F vs similarity solution 14.04".into(),
        error2,
        error2_measure: PEAK_CP.into(),
        note: format!("{note}; {peak_note}"),
    })
}

/// What the wedge's `error2` compares: the largest `pressure_max` of the body's gauges
/// against the similarity solution's Cp_max of its deadrise.
pub const PEAK_CP: &str = "peak_cp";

/// The relative error of the largest gauge reading on `body` (probes.csv's
/// `pressure_max` over ½ ρ V²) against the similarity solution's Cp_max, and a note; NaN
/// without a gauge on the body or a tabulated deadrise.
fn peak_cp_error(case: &Case, dir: &Path, body: &str, beta: Real, speed: Real) -> (Real, String) {
    let gauges: Vec<&str> = case
        .output
        .probes
        .iter()
        .filter(|p| p.body.as_deref() == Some(body))
        .map(|p| p.name.as_str())
        .collect();
    let Some((cp_max, _)) = reference::similarity_peak(beta) else {
        return (
            Real::NAN,
            format!("no similarity peak tabulated at {:.1}°", beta.to_degrees()),
        );
    };
    if gauges.is_empty() {
        return (Real::NAN, "no gauge on the body".into());
    }
    let Ok(text) = std::fs::read_to_string(dir.join("probes.csv")) else {
        return (Real::NAN, "no probes.csv".into());
    };
    let q = 0.5 * case.fluid.density * speed * speed;
    let peak = text
        .lines()
        .skip(1)
        .filter_map(|line| {
            let f: Vec<&str> = line.split(',').collect();
            (f.len() >= 4 && gauges.contains(&f[1])).then(|| f[3].parse::<Real>().ok())?
        })
        .fold(Real::NEG_INFINITY, Real::max);
    if !peak.is_finite() {
        return (Real::NAN, "no gauge rows".into());
    }
    (
        measure::relative_error(peak / q, cp_max),
        format!(
            "peak Cp {:.2} of {} gauges vs {cp_max}",
            peak / q,
            gauges.len()
        ),
    )
}

/// A wedge's entry: speed, direction of motion, deadrise, the time its keel meets the
/// free surface and Wagner's chine-wetting time B tan β / (π V).
struct Entry {
    speed: Real,
    direction: [Real; 2],
    beta: Real,
    contact: Real,
    t_chine: Real,
}

fn entry(case: &Case, body: &crate::case::Body, velocity: [Real; 2]) -> io::Result<Entry> {
    let speed = vec_norm(velocity);
    let d = [velocity[0] / speed, velocity[1] / speed];
    let beta = vertex_deadrise(&body.polygon, body.angle, velocity)
        .ok_or_else(|| io::Error::other("no deadrise"))?;
    // breadth across the motion, keel and free surface along it
    let (s, c) = body.angle.sin_cos();
    let world: Vec<[Real; 2]> = body
        .polygon
        .iter()
        .map(|p| {
            [
                body.position[0] + c * p[0] - s * p[1],
                body.position[1] + s * p[0] + c * p[1],
            ]
        })
        .collect();
    let across: Vec<Real> = world.iter().map(|p| p[0] * d[1] - p[1] * d[0]).collect();
    let breadth = across.iter().cloned().fold(Real::NEG_INFINITY, Real::max)
        - across.iter().cloned().fold(Real::INFINITY, Real::min);
    let keel = world
        .iter()
        .map(|p| p[0] * d[0] + p[1] * d[1])
        .fold(Real::NEG_INFINITY, Real::max);
    let surface = case
        .fluid_blocks
        .iter()
        .flat_map(|b| b.polygon.iter().map(|p| -(p[0] * d[0] + p[1] * d[1])))
        .fold(Real::NEG_INFINITY, Real::max);
    Ok(Entry {
        speed,
        direction: d,
        beta,
        contact: ((-surface) - keel) / speed,
        t_chine: breadth * beta.tan() / (std::f64::consts::PI * speed),
    })
}

/// The window of the free fall's velocity loss, in t_chine after contact.
pub const FREE_FALL_WINDOW: (Real, Real) = (0.6, 0.9);

/// The free-falling 30° wedge: the size of the mean relative error of its velocity loss
/// over 0.6-0.9 t_chine against the momentum model ([`reference::FreeFallModel`], the
/// reading of tests/bodies/impact.rs), and of the worst sample (signed in the note).
fn score_free_fall(case: &Case, dir: &Path) -> io::Result<Score> {
    let body = case
        .bodies
        .first()
        .ok_or_else(|| io::Error::other("free-fall case without a body"))?;
    let crate::case::Motion::Free { velocity, mass, .. } = &body.motion else {
        return Err(io::Error::other(
            "the free-fall benchmark needs a free body",
        ));
    };
    let Entry {
        speed,
        direction: d,
        beta,
        contact,
        t_chine,
    } = entry(case, body, *velocity)?;
    if (beta.to_degrees() - 30.0).abs() > 0.5 {
        return Err(io::Error::other(format!(
            "the free-fall reference is the 30° wedge's (deadrise {:.1}°)",
            beta.to_degrees()
        )));
    }
    let g = case.fluid.gravity[0] * d[0] + case.fluid.gravity[1] * d[1];
    let model = reference::FreeFallModel {
        // the body falls freely until its keel meets the surface
        v0: speed + g * contact.max(0.0),
        g,
        mass: *mass,
        force_coefficient: reference::WEDGE_30_FORCE_COEFFICIENT,
        density: case.fluid.density,
    };
    let samples = body_speeds(
        &std::fs::read_to_string(dir.join("bodies.csv"))?,
        &body.name,
        d,
        contact,
    )?;
    let (from, to) = (FREE_FALL_WINDOW.0 * t_chine, FREE_FALL_WINDOW.1 * t_chine);
    let errors = measure::velocity_loss_errors(&model, &samples, from, to);
    let covered = samples.last().is_some_and(|s| s.0 >= to);
    if errors.is_empty() || !covered {
        return Ok(Score::single(
            Real::NAN,
            FREE_FALL_MEASURE,
            format!(
                "bodies.csv does not cover 0.9 t_chine = {:.2} ms after contact",
                to * 1e3
            ),
        ));
    }
    let mean = measure::mean_error(&errors);
    let worst = errors
        .iter()
        .map(|e| e.1)
        .fold(0.0, |w: Real, e| if e.abs() > w.abs() { e } else { w });
    // the closure of a free fall in docs/references.md, on the same constant-speed force: the
    // two models part in the deceleration's added mass (by 4 % for a body a quarter of
    // the shipped mass), so the note gives both
    let logvinovich = reference::LogvinovichFreeFall::matching(&model, beta);
    let other_mean = measure::mean_error(&measure::velocity_loss_errors(
        &logvinovich,
        &samples,
        from,
        to,
    ));
    // the report ranks runs by the size of their error; the note keeps the sign
    Ok(Score {
        error: mean.abs(),
        error_measure: FREE_FALL_MEASURE.into(),
        error2: worst.abs(),
        error2_measure: "worst velocity-loss sample".into(),
        note: format!(
            "velocity loss {:+.1} % on average, worst {:+.1} %, over {} samples of 0.6-0.9 t_chine = {:.2} ms; against the modified Logvinovich model scaled to the similarity force {:+.1} %",
            100.0 * mean,
            100.0 * worst,
            errors.len(),
            t_chine * 1e3,
            100.0 * other_mean
        ),
    })
}

const FREE_FALL_MEASURE: &str = "mean velocity loss vs momentum model";

/// (time after contact, speed along `d`) of `body` from bodies.csv, read by the
/// service's CSV-to-columns reader.
fn body_speeds(
    text: &str,
    body: &str,
    d: [Real; 2],
    contact: Real,
) -> io::Result<Vec<(Real, Real)>> {
    let columns = csv_to_columns(text.as_bytes()).map_err(io::Error::other)?;
    let series = columns
        .get(body)
        .ok_or_else(|| io::Error::other(format!("bodies.csv has no rows of {body}")))?;
    let column = |name: &str| -> io::Result<Vec<Real>> {
        series[name]
            .as_array()
            .ok_or_else(|| io::Error::other(format!("bodies.csv has no column {name}")))?
            .iter()
            .map(|v| {
                v.as_f64().ok_or_else(|| {
                    io::Error::other(format!("bodies.csv: {name} {v} is not a number"))
                })
            })
            .collect()
    };
    let (t, vx, vy) = (column("time")?, column("vx")?, column("vy")?);
    Ok(t.iter()
        .zip(vx.iter().zip(&vy))
        .map(|(t, (vx, vy))| (t - contact, vx * d[0] + vy * d[1]))
        .collect())
}

/// The standing wave's scores: the mode is one wavelength across the first fluid
/// block (antinodes at its free-slip ends), the depth its area over its width (the
/// cosine top integrates to zero).
fn score_standing_wave(case: &Case, dir: &Path, summary: &RunOutcome) -> io::Result<Score> {
    let block = case
        .fluid_blocks
        .first()
        .ok_or_else(|| io::Error::other("standing wave without a fluid block"))?;
    let xs = block.polygon.iter().map(|p| p[0]);
    let width = xs.clone().fold(Real::NEG_INFINITY, Real::max) - xs.fold(Real::INFINITY, Real::min);
    let points: Vec<_> = block
        .polygon
        .iter()
        .map(|p| crate::math::vec2(*p))
        .collect();
    let depth = crate::geometry::signed_area(&points).abs() / width;
    let k = 2.0 * std::f64::consts::PI / width;
    let (g, nu) = (vec_norm(case.fluid.gravity), case.fluid.kinematic_viscosity);
    let omega = reference::wave_frequency(g, k, depth);
    let exact = reference::exact_energy_decay(g, nu, k)
        .ok_or_else(|| io::Error::other("the exact decay rate did not converge"))?;
    let text = std::fs::read_to_string(dir.join("energy.csv"))?;
    // columns time, kinetic_energy
    let (times, kinetic) = csv_columns(&text, (0, 1), |_| true);
    // the kinetic energy peaks twice a period, pi / omega apart
    let peaks = measure::oscillation_peaks(&times, &kinetic, 0.5 * std::f64::consts::PI / omega);
    let rate = measure::exponential_decay_rate(&peaks);
    let measured_omega = (peaks.len() >= 2).then(|| {
        let span = peaks[peaks.len() - 1].0 - peaks[0].0;
        std::f64::consts::PI * (peaks.len() - 1) as Real / span
    });
    // a rate fitted to the first peaks of a run that failed says nothing of the decay
    let complete = summary.simulated_time >= case.time.end * (1.0 - 1e-9);
    let (rate, measured_omega) = if complete {
        (rate, measured_omega)
    } else {
        (None, None)
    };
    let note = format!(
        "{} kinetic-energy peaks; decay rate {} 1/s (exact linear {exact:.4}, Lighthill {:.4}); omega {} rad/s (theory {omega:.4})",
        peaks.len(),
        rate.map_or("none".into(), |r| format!("{r:.4}")),
        reference::lighthill_energy_decay(nu, k),
        measured_omega.map_or("none".into(), |w| format!("{w:.4}")),
    );
    Ok(Score {
        error: rate.map_or(Real::NAN, |r| measure::relative_error(r, exact)),
        error_measure: "kinetic-energy decay rate vs exact linear (Lamb)".into(),
        error2: measured_omega.map_or(Real::NAN, |w| measure::relative_error(w, omega)),
        error2_measure: "angular frequency vs omega² = g k tanh kH".into(),
        note,
    })
}

fn vec_norm(v: [Real; 2]) -> Real {
    (v[0] * v[0] + v[1] * v[1]).sqrt()
}

/// The times and rows of one body's loads.
fn load_series(rows: &[LoadRow], body: &str) -> (Vec<Real>, Vec<LoadRow>) {
    let picked: Vec<LoadRow> = rows.iter().filter(|r| r.body == body).cloned().collect();
    (picked.iter().map(|r| r.time).collect(), picked)
}

fn probe_series(text: &str, name: &str) -> (Vec<Real>, Vec<Real>) {
    // columns time, probe, pressure
    csv_columns(text, (0, 2), |record| record.get(1) == Some(name))
}

/// Two numeric columns of a CSV text (header skipped), for the records `keep` accepts;
/// records whose fields do not parse are skipped.
fn csv_columns(
    text: &str,
    (x, y): (usize, usize),
    keep: impl Fn(&csv::StringRecord) -> bool,
) -> (Vec<Real>, Vec<Real>) {
    let mut reader = csv::Reader::from_reader(text.as_bytes());
    let (mut xs, mut ys) = (Vec::new(), Vec::new());
    for record in reader.records().flatten().filter(|r| keep(r)) {
        if let (Some(Ok(a)), Some(Ok(b))) = (
            record.get(x).map(str::parse::<Real>),
            record.get(y).map(str::parse::<Real>),
        ) {
            xs.push(a);
            ys.push(b);
        }
    }
    (xs, ys)
}

/// (T, Z) of the surge front read from the run's VTK snapshots (their particles part: the
/// walls part's vertices would read as a front at the tank's far wall).
pub fn surge_front_history(
    dir: &Path,
    geometry: &ColumnGeometry,
    l0: Real,
    g: Real,
) -> io::Result<Vec<(Real, Real)>> {
    let snapshots = dir.join(SNAPSHOT_DIR);
    let entries = parse_pvd(&std::fs::read_to_string(snapshots.join(PVD_NAME))?)?;
    let band = (2.0 * l0).max(0.05 * geometry.width);
    let scale = (2.0 * g / geometry.width).sqrt();
    let mut out = Vec::with_capacity(entries.len());
    for e in entries.into_iter().filter(|e| e.part == PARTICLES_PART) {
        let grid = parse_vtu(&std::fs::read_to_string(snapshots.join(&e.file))?)?;
        let points: Vec<(Real, Real)> = grid.points.iter().map(|p| (p[0], p[1])).collect();
        if let Some(x) = measure::surge_front(&points, geometry.floor, band, l0) {
            out.push((e.time * scale, (x - geometry.left) / geometry.width));
        }
    }
    Ok(out)
}
