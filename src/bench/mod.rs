//! `mpsfsi bench`: run time against error (DESIGN.md §5, issue 6).
//!
//! Each reference case runs at several spacings for each scheme variant through
//! [`run::run_case`], and the error of each run is measured against an analytic or
//! published reference ([`reference`]) by the pure functions of [`measure`]:
//!
//! - `hydrostatic` (`cases/hydrostatic.json`): relative error of the mean vertical
//!   load on the tank over the second half of the run against the water weight
//!   (particles × rho l0² g); second measure the mid-depth probe against rho g depth.
//! - `dam_break` (`cases/dam_break.json` when it exists, else the Koshizuka & Oka
//!   geometry built here): RMS relative error of the surge front against Martin & Moyce
//!   for 1 <= T <= 3, the front measured on the VTK snapshots of the run.
//! - `wedge_30deg` (when `cases/wedge_30deg_constant_velocity.json` exists): relative
//!   error of C_F = F / (rho V³ t), t from the keel contact, fitted over the middle of
//!   the self-similar window against 14.04.
//! - `standing_wave` (`cases/standing_wave.json`, paper 002 §5.6): relative error of
//!   the decay rate of the kinetic-energy peaks (`energy.csv`) against the exact linear
//!   rate (Lamb §349; Lighthill's 4 nu k² is its small-nu limit and is printed); second
//!   measure the angular frequency from the peak spacing against omega² = g k tanh kH.
//!
//! Outputs in the output folder: `results.csv`, `report.md`, one `<case>.svg` of error
//! against wall time per case (log-log, a line per variant), and `runs/` with every
//! run directory. `--operators` adds the operator convergence study of
//! [`operators`] (paper 000 §5) as `operators.md`.
//!
//! Benchmarks and studies report results; the tests assert them against the papers.

pub mod measure;
pub mod operators;
pub mod reference;
pub mod report;
pub mod scaling;
pub mod stress;

use crate::case::{self, Case, Scheme};
use crate::engine::math::Real;
use crate::output::filter::leading_deadrise;
use crate::output::loads_csv::{parse_loads_csv, LoadRow};
use crate::output::snapshots::{PVD_NAME, SNAPSHOT_DIR};
use crate::output::vtk::{parse_pvd, parse_vtu};
use crate::run::{self, RunStatus, Summary};
use serde_json::{json, Value};
use std::io;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// What `mpsfsi bench` runs.
#[derive(Debug, Clone)]
pub struct BenchOptions {
    /// Coarse spacings and short end times (< 5 min on 2 cores; CI).
    pub quick: bool,
    /// Also the operator convergence study (bench::operators, written separately).
    pub operators: bool,
    /// Also the stability stress runs ([`stress`]: long dam break, fast and heeled
    /// wedges, perturbed lattice, long hydrostatic) and the CFL sweep; `stress.md`.
    pub stress: bool,
    /// The scaling study of [`scaling`] (`scaling.csv`, `scaling.md`).
    pub scaling: bool,
    /// The feature-cost study of [`scaling`] (`features.csv`, `features.md`).
    pub features: bool,
    /// Skip the run-time-against-error study (it is skipped anyway with `scaling` or
    /// `features`).
    pub no_study: bool,
    /// Only the study cases with these names; empty: all.
    pub cases: Vec<String>,
    /// Only the scheme variants with these names (study and CFL sweep); empty: all.
    pub variants: Vec<String>,
    /// Sizes, steps and repeats of `scaling` / `features`.
    pub scaling_options: scaling::ScalingOptions,
    pub out_dir: PathBuf,
}

impl BenchOptions {
    /// The options of the run-time-against-error study alone (`quick` or not).
    pub fn study(quick: bool, out_dir: PathBuf) -> Self {
        Self {
            quick,
            operators: false,
            stress: false,
            scaling: false,
            features: false,
            no_study: false,
            cases: Vec::new(),
            variants: Vec::new(),
            scaling_options: scaling::ScalingOptions::default(),
            out_dir,
        }
    }

    /// Whether the run-time-against-error study runs: not when an instrument
    /// (`scaling`, `features`) was asked for, or `no_study`.
    pub fn runs_study(&self) -> bool {
        !(self.no_study || self.scaling || self.features)
    }
}

/// A scheme variant compared by the benchmark.
#[derive(Debug, Clone)]
pub struct Variant {
    pub name: &'static str,
    pub description: &'static str,
    pub scheme: Scheme,
}

/// The variants of issue 6: classic MPS, the default (HS + ECS + HL with GC), CHL and
/// least-squares operators.
pub fn variants() -> Vec<Variant> {
    use crate::case::{GradientKind, LaplacianKind, SolverKind};
    vec![
        Variant {
            name: "classic",
            description:
                "Koshizuka & Oka 1996: minimum-pressure gradient, classic Laplacian, PND source",
            scheme: Scheme::classic(),
        },
        Variant {
            name: "default",
            description: "the scheme block's defaults (HS + ECS source, HL Laplacian, GC gradient)",
            scheme: Scheme::default(),
        },
        Variant {
            name: "chl",
            description: "default with the corrected higher-order Laplacian CHL (BiCGSTAB)",
            scheme: Scheme {
                laplacian: LaplacianKind::CorrectedHigherOrder,
                solver: SolverKind::Bicgstab,
                ..Scheme::default()
            },
        },
        Variant {
            name: "least_squares",
            description: "least-squares gradient and Laplacian (LSMPS-type, BiCGSTAB)",
            scheme: Scheme {
                gradient: GradientKind::LeastSquares,
                laplacian: LaplacianKind::LeastSquares,
                solver: SolverKind::Bicgstab,
                ..Scheme::default()
            },
        },
    ]
}

/// The items whose names are in `wanted` (all when it is empty); an unknown name is an
/// error listing the known ones.
fn select<T>(
    what: &str,
    mut items: Vec<T>,
    wanted: &[String],
    name: impl Fn(&T) -> &'static str,
) -> io::Result<Vec<T>> {
    if wanted.is_empty() {
        return Ok(items);
    }
    let known: Vec<&str> = items.iter().map(&name).collect();
    if let Some(unknown) = wanted.iter().find(|n| !known.contains(&n.as_str())) {
        return Err(io::Error::new(
            io::ErrorKind::InvalidInput,
            format!("unknown {what} {unknown:?}; the study has {known:?}"),
        ));
    }
    items.retain(|item| wanted.iter().any(|n| n == name(item)));
    Ok(items)
}

/// One benchmark run, one line of `results.csv`.
#[derive(Debug, Clone, PartialEq)]
pub struct BenchResult {
    pub case: String,
    pub variant: String,
    pub spacing: Real,
    pub particles: usize,
    pub steps: u64,
    pub wall_time_s: f64,
    /// The case's primary error measure (NaN when the run failed or could not be measured).
    pub error: Real,
    pub error_measure: String,
    pub error2: Real,
    pub error2_measure: String,
    pub mean_solver_iterations: Real,
    pub status: String,
    pub note: String,
}

/// A reference case of the benchmark: how to build its runs and measure them.
pub struct BenchCase {
    pub name: &'static str,
    pub base: Value,
    pub spacings: Vec<Real>,
    /// Extra overrides (end time, output intervals) as PATH=VALUE.
    pub overrides: Vec<String>,
    pub measure: Measure,
}

/// How a run of a case is scored.
pub enum Measure {
    Hydrostatic,
    DamBreak,
    Wedge,
    StandingWave,
}

fn cases_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("cases")
}

fn read_case_value(path: &Path) -> io::Result<Value> {
    let text = std::fs::read_to_string(path)?;
    serde_json::from_str(&text).map_err(|e| {
        io::Error::new(
            io::ErrorKind::InvalidData,
            format!("{}: {e}", path.display()),
        )
    })
}

/// The Koshizuka & Oka (1996) dam break (column L × 2L in a tank 4L wide, L = 0.146 m),
/// used when `cases/dam_break.json` does not exist.
pub fn dam_break_case(a: Real) -> Value {
    let t3 = 3.05 / (2.0 * 9.81 / a).sqrt();
    json!({
        "name": "dam-break",
        "reference": {
            "source": "references.md, Dam break: Martin & Moyce (1952), Phil. Trans. R. Soc. A 244; Koshizuka & Oka (1996) geometry",
            "quantity": "surge front x/a against T = t sqrt(2 g / a), RMS relative error for 1 <= T <= 3"
        },
        "fluid": { "density": 1000.0, "kinematic_viscosity": 1.0e-6, "gravity": [0.0, -9.81] },
        "particle_spacing": a / 20.0,
        "domain": { "min": [-0.2 * a, -0.2 * a], "max": [4.2 * a, 8.6 * a] },
        "fluid_blocks": [ { "polygon": [[0.0, 0.0], [a, 0.0], [a, 2.0 * a], [0.0, 2.0 * a]] } ],
        // walls tall enough for the run-up on the far wall (as the shipped case)
        "walls": [ { "name": "tank", "polyline": [[0.0, 8.2 * a], [0.0, 0.0], [4.0 * a, 0.0], [4.0 * a, 8.2 * a]] } ],
        "time": { "end": t3, "cfl": 0.15, "max_dt": 1.0e-3 },
        "output": { "load_interval": 0.005, "snapshot_interval": 0.05 / (2.0 * 9.81 / a).sqrt() },
        "scheme": { "laplacian_fill_floor": 0.3 }
    })
}

/// The reference cases with their spacings (coarse ones for `quick`).
pub fn bench_cases(quick: bool) -> io::Result<Vec<BenchCase>> {
    let mut cases = Vec::new();
    let hydrostatic = cases_dir().join("hydrostatic.json");
    if hydrostatic.exists() {
        cases.push(BenchCase {
            name: "hydrostatic",
            base: read_case_value(&hydrostatic)?,
            spacings: if quick {
                vec![0.05, 0.0333, 0.025]
            } else {
                vec![0.05, 0.025, 0.0125, 0.00625]
            },
            overrides: if quick {
                vec!["time.end=0.3".into()]
            } else {
                vec!["time.end=2.0".into()]
            },
            measure: Measure::Hydrostatic,
        });
    }
    let dam = cases_dir().join("dam_break.json");
    let (base, a) = if dam.exists() {
        let v = read_case_value(&dam)?;
        let case = case::parse_case_value(v.clone())
            .map_err(|e| io::Error::new(io::ErrorKind::InvalidData, e.to_string()))?;
        let a = column_geometry(&case)
            .map(|g| g.width)
            .unwrap_or(reference::KOSHIZUKA_OKA_COLUMN_WIDTH);
        (v, a)
    } else {
        let a = reference::KOSHIZUKA_OKA_COLUMN_WIDTH;
        (dam_break_case(a), a)
    };
    let to_time = |t_scaled: Real| t_scaled / (2.0 * 9.81 / a).sqrt();
    cases.push(BenchCase {
        name: "dam_break",
        base,
        spacings: if quick {
            vec![a / 8.0, a / 12.0, a / 16.0]
        } else {
            vec![a / 10.0, a / 20.0, a / 30.0, a / 40.0]
        },
        overrides: vec![
            format!("time.end={}", to_time(3.05)),
            format!("output.snapshot_interval={}", to_time(0.05)),
        ],
        measure: Measure::DamBreak,
    });
    let wedge = cases_dir().join("wedge_30deg_constant_velocity.json");
    if wedge.exists() {
        cases.push(BenchCase {
            name: "wedge_30deg",
            base: read_case_value(&wedge)?,
            spacings: if quick {
                vec![0.04, 0.03, 0.02]
            } else {
                // 4 m and 1.2 m / l0 whole numbers of columns and rows (7.5 mm is not)
                vec![0.02, 0.01, 0.008, 0.005]
            },
            overrides: vec![],
            measure: Measure::Wedge,
        });
    }
    let wave = cases_dir().join("standing_wave.json");
    if wave.exists() {
        cases.push(BenchCase {
            name: "standing_wave",
            base: read_case_value(&wave)?,
            spacings: if quick {
                vec![0.025, 0.02, 0.0125]
            } else {
                vec![0.025, 0.0125, 0.01, 0.00625]
            },
            // quick: three periods (six kinetic-energy peaks), else five
            overrides: if quick {
                vec!["time.end=2.5".into()]
            } else {
                vec![]
            },
            measure: Measure::StandingWave,
        });
    }
    Ok(cases)
}

/// Width, left edge and floor of a dam-break column (the first fluid block's bounding box).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ColumnGeometry {
    pub width: Real,
    pub left: Real,
    pub floor: Real,
}

pub fn column_geometry(case: &Case) -> Option<ColumnGeometry> {
    let block = case.fluid_blocks.first()?;
    let xs = block.polygon.iter().map(|p| p[0]);
    let ys = block.polygon.iter().map(|p| p[1]);
    let left = xs.clone().fold(Real::INFINITY, Real::min);
    let right = xs.fold(Real::NEG_INFINITY, Real::max);
    let floor = ys.fold(Real::INFINITY, Real::min);
    (right > left).then_some(ColumnGeometry {
        width: right - left,
        left,
        floor,
    })
}

/// Build the case of one run: base + overrides + spacing + variant scheme. The variant
/// sets the fields in which it differs from the default scheme; the case's own scheme
/// settings stay otherwise (the wedge's `max_speed`, for one).
pub fn run_case_value(
    bench: &BenchCase,
    spacing: Real,
    scheme: &Scheme,
) -> Result<Case, case::CaseError> {
    let mut v = bench.base.clone();
    for o in &bench.overrides {
        case::apply_override(&mut v, o)?;
    }
    case::apply_override(&mut v, &format!("particle_spacing={spacing}"))?;
    let variant = serde_json::to_value(scheme).expect("a scheme serialises");
    let default = serde_json::to_value(Scheme::default()).expect("a scheme serialises");
    if !v["scheme"].is_object() {
        v["scheme"] = json!({});
    }
    if let (Some(fields), Some(defaults)) = (variant.as_object(), default.as_object()) {
        for (key, value) in fields {
            if defaults.get(key) != Some(value) {
                v["scheme"][key] = value.clone();
            }
        }
    }
    case::parse_case_value(v)
}

fn load_series(rows: &[LoadRow], body: &str) -> (Vec<Real>, Vec<LoadRow>) {
    let picked: Vec<LoadRow> = rows.iter().filter(|r| r.body == body).cloned().collect();
    (picked.iter().map(|r| r.time).collect(), picked)
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

/// The errors of a finished run in `dir`: (error, measure, error2, measure2, note).
pub fn score(
    measure: &Measure,
    case: &Case,
    dir: &Path,
    summary: &RunOutcome,
) -> io::Result<(Real, String, Real, String, String)> {
    match measure {
        Measure::Hydrostatic if !summary.succeeded => Ok((
            Real::NAN,
            "tank load vs water weight".into(),
            Real::NAN,
            "mid-depth probe vs rho g d".into(),
            String::new(),
        )),
        Measure::Hydrostatic => {
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
            // probe: rho |g| (top of the fluid - probe height)
            let mut probe_error = Real::NAN;
            let mut note = String::new();
            if let (Some(probe), Some(block)) =
                (case.output.probes.first(), case.fluid_blocks.first())
            {
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
            Ok((
                load_error,
                "tank load vs water weight".into(),
                probe_error,
                "mid-depth probe vs rho g d".into(),
                note,
            ))
        }
        Measure::DamBreak => {
            let geometry = column_geometry(case)
                .ok_or_else(|| io::Error::other("dam break without a fluid block"))?;
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
            Ok((
                error,
                "surge front RMS vs Martin & Moyce, 1<=T<=3".into(),
                Real::NAN,
                String::new(),
                last,
            ))
        }
        Measure::StandingWave => score_standing_wave(case, dir, summary),
        Measure::Wedge => {
            let body = case
                .bodies
                .first()
                .ok_or_else(|| io::Error::other("wedge case without a body"))?;
            let crate::case::Motion::Prescribed { velocity, .. } = &body.motion else {
                return Err(io::Error::other(
                    "the wedge benchmark needs a prescribed motion",
                ));
            };
            let speed = vec_norm(*velocity);
            let d = [velocity[0] / speed, velocity[1] / speed];
            let beta = leading_deadrise(&body.polygon, body.angle, *velocity)
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
            let contact = ((-surface) - keel) / speed;
            let t_chine = breadth * beta.tan() / (std::f64::consts::PI * speed);
            let window = (contact + 0.25 * t_chine, contact + 0.85 * t_chine);
            let rows = parse_loads_csv(&std::fs::read_to_string(dir.join("loads.csv"))?)?;
            let (times, picked) = load_series(&rows, &body.name);
            let force: Vec<Real> = picked
                .iter()
                .map(|r| -(r.fx * d[0] + r.fy * d[1]))
                .collect();
            let covered = times.last().is_some_and(|t| *t >= window.1);
            let (rho, start) = (case.fluid.density, 0.0);
            let fit = measure::force_coefficient_from_contact(
                contact, start, &times, &force, window, rho, speed,
            )
            .filter(|_| covered);
            let slope = measure::fit_force_coefficient(start, &times, &force, window, rho, speed);
            let (error, note) = match fit {
                Some((cf, se)) => (
                    measure::relative_error(cf, reference::WEDGE_30_FORCE_COEFFICIENT),
                    format!(
                        "C_F = {cf:.2} ± {se:.2} from the keel contact (two-parameter slope {}; Wagner {:.2})",
                        slope.map_or("none".into(), |(c, t0)| format!(
                            "{c:.2}, t0 = {:.2} ms",
                            t0 * 1e3
                        )),
                        reference::wagner_force_coefficient(beta)
                    ),
                ),
                None => (
                    Real::NAN,
                    format!(
                        "the loads do not cover the self-similar window {:.2}-{:.2} ms",
                        window.0 * 1e3,
                        window.1 * 1e3
                    ),
                ),
            };
            Ok((
                error,
                "C_F vs similarity solution 14.04".into(),
                Real::NAN,
                String::new(),
                note,
            ))
        }
    }
}

/// The standing wave's scores: the mode is one wavelength across the first fluid
/// block (antinodes at its free-slip ends), the depth its area over its width (the
/// cosine top integrates to zero).
fn score_standing_wave(
    case: &Case,
    dir: &Path,
    summary: &RunOutcome,
) -> io::Result<(Real, String, Real, String, String)> {
    let block = case
        .fluid_blocks
        .first()
        .ok_or_else(|| io::Error::other("standing wave without a fluid block"))?;
    let xs = block.polygon.iter().map(|p| p[0]);
    let width = xs.clone().fold(Real::NEG_INFINITY, Real::max) - xs.fold(Real::INFINITY, Real::min);
    let points: Vec<_> = block
        .polygon
        .iter()
        .map(|p| crate::engine::math::vec2(*p))
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
    Ok((
        rate.map_or(Real::NAN, |r| measure::relative_error(r, exact)),
        "kinetic-energy decay rate vs exact linear (Lamb)".into(),
        measured_omega.map_or(Real::NAN, |w| measure::relative_error(w, omega)),
        "angular frequency vs omega² = g k tanh kH".into(),
        note,
    ))
}

fn vec_norm(v: [Real; 2]) -> Real {
    (v[0] * v[0] + v[1] * v[1]).sqrt()
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

/// (T, Z) of the surge front read from the run's VTK snapshots.
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
    for e in entries {
        let grid = parse_vtu(&std::fs::read_to_string(snapshots.join(&e.file))?)?;
        let points: Vec<(Real, Real)> = grid.points.iter().map(|p| (p[0], p[1])).collect();
        if let Some(x) = measure::surge_front(&points, geometry.floor, band, l0) {
            out.push((e.time * scale, (x - geometry.left) / geometry.width));
        }
    }
    Ok(out)
}

/// Run one case at one spacing with one variant and score it. Never panics: a panic in
/// the engine is caught and reported as a failed run.
pub fn run_one(
    bench: &BenchCase,
    variant: &Variant,
    spacing: Real,
    runs_dir: &Path,
) -> BenchResult {
    let mut result = BenchResult {
        case: bench.name.to_string(),
        variant: variant.name.to_string(),
        spacing,
        particles: 0,
        steps: 0,
        wall_time_s: Real::NAN,
        error: Real::NAN,
        error_measure: String::new(),
        error2: Real::NAN,
        error2_measure: String::new(),
        mean_solver_iterations: Real::NAN,
        status: "failed".into(),
        note: String::new(),
    };
    let case = match run_case_value(bench, spacing, &variant.scheme)
        .and_then(|c| case::ValidCase::new(c, &case::Limits::default()))
    {
        Ok(c) => c,
        Err(e) => {
            result.note = format!("case rejected: {e}");
            return result;
        }
    };
    let dir = runs_dir
        .join(bench.name)
        .join(variant.name)
        .join(format!("l0_{spacing:.6}"));
    let started = Instant::now();
    let outcome = std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        run::run_case(&case, &dir, &mut run::Quiet)
    }));
    let summary = match outcome {
        Ok(Ok(s)) => s,
        Ok(Err(e)) => {
            result.note = format!("run error: {e}");
            return result;
        }
        Err(panic) => {
            let what = panic
                .downcast_ref::<String>()
                .cloned()
                .or_else(|| panic.downcast_ref::<&str>().map(|s| s.to_string()));
            result.note = format!("panicked: {}", what.unwrap_or_default());
            result.wall_time_s = started.elapsed().as_secs_f64();
            return result;
        }
    };
    result.particles = summary.particles;
    result.steps = summary.steps;
    result.wall_time_s = summary.wall_time_s;
    result.mean_solver_iterations = summary.mean_solver_iterations;
    result.status = match summary.status {
        RunStatus::Succeeded => "succeeded",
        RunStatus::Failed => "failed",
        RunStatus::Cancelled => "cancelled",
    }
    .into();
    // a run that failed is still scored on what it wrote: the measures return NaN when
    // the outputs do not cover the comparison window (the status column says it failed)
    let reason = summary
        .reason
        .clone()
        .map(|r| format!("{r}; "))
        .unwrap_or_default();
    match score(&bench.measure, &case, &dir, &RunOutcome::from(&summary)) {
        Ok((e1, m1, e2, m2, note)) => {
            result.error = e1;
            result.error_measure = m1;
            result.error2 = e2;
            result.error2_measure = m2;
            result.note = format!("{reason}{note}").trim_end_matches("; ").to_string();
        }
        Err(e) => result.note = format!("{reason}cannot measure: {e}"),
    }
    result
}

/// Run the benchmark and write its report into `options.out_dir`.
pub fn run(options: BenchOptions) -> io::Result<()> {
    let started = Instant::now();
    std::fs::create_dir_all(&options.out_dir)?;
    let runs_dir = options.out_dir.join("runs");
    if options.scaling {
        scaling::write_scaling(&options.out_dir, &options.scaling_options)?;
    }
    if options.features {
        scaling::write_features(&options.out_dir, options.scaling_options.repeats)?;
    }
    let mut results = Vec::new();
    let cases = select("case", bench_cases(options.quick)?, &options.cases, |c| {
        c.name
    })?;
    let variants = select("variant", variants(), &options.variants, |v| v.name)?;
    if options.runs_study() {
        for bench in &cases {
            for variant in &variants {
                for &spacing in &bench.spacings {
                    let r = run_one(bench, variant, spacing, &runs_dir);
                    eprintln!(
                        "bench {:<12} {:<14} l0 = {:<9.5} {:>7} particles {:>6} steps {:>8.2} s  error {:.4e}  {}",
                        r.case, r.variant, r.spacing, r.particles, r.steps, r.wall_time_s, r.error, r.note
                    );
                    results.push(r);
                    report::write_results_csv(&options.out_dir.join("results.csv"), &results)?;
                }
            }
        }
    }
    let mut cfl = Vec::new();
    let mut stress_rows = Vec::new();
    if options.stress {
        stress_rows = stress::run_all(options.quick, &runs_dir.join("stress"))?;
        std::fs::write(
            options.out_dir.join("stress.md"),
            stress::stress_markdown(&stress_rows, &[], options.quick),
        )?;
        cfl = report::cfl_sweep(&cases, &variants, &runs_dir.join("stress"));
        std::fs::write(
            options.out_dir.join("stress.md"),
            stress::stress_markdown(&stress_rows, &cfl, options.quick),
        )?;
    }
    let total = started.elapsed().as_secs_f64();
    if options.runs_study() {
        report::write_report(
            &options.out_dir,
            &cases,
            &results,
            &cfl,
            &stress_rows,
            options.quick,
            total,
        )?;
    }
    if options.operators {
        report::write_operators(&options.out_dir)?;
    }
    Ok(())
}
