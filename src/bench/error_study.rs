//! The error study of `mpsfsi bench`: run time against error. Each reference case runs
//! at several spacings for each scheme variant through [`run::run_case`], and each run
//! is scored against an analytic or published reference ([`super::score`]):
//!
//! - `hydrostatic` (`cases/hydrostatic.json`): relative error of the mean vertical
//!   load on the tank over the second half of the run against the water weight
//!   (particles × rho l0² g); second measure the mid-depth probe against rho g depth.
//! - `dam_break` (`cases/dam_break.json` when it exists, else the Koshizuka & Oka
//!   geometry of [`super::cases::dam_break_case`]): RMS relative error of the surge
//!   front against Martin & Moyce for 1 <= T <= 3, the front measured on the VTK
//!   snapshots of the run.
//! - `wedge_30deg` (when `cases/wedge_30deg_constant_velocity.json` exists): relative
//!   error against 14.04 of C_F = F / (rho V³ (t - t0)), t0 the first load above 1 % of
//!   the peak, fitted over 20-85 % of the time to the chine after it.
//! - `wedge_free_fall` (when `cases/wedge_free_fall.json` exists): mean relative error
//!   of the body's velocity loss over 0.6-0.9 t_chine against the momentum model of
//!   the similarity solution (the reading of the free-fall tests), and the worst sample.
//! - `standing_wave` (`cases/standing_wave.json`, Souto-Iglesias et al. 2013 §5.6): relative error of
//!   the decay rate of the kinetic-energy peaks (`energy.csv`) against the exact linear
//!   rate (Lamb §349; Lighthill's 4 nu k² is its small-nu limit and is printed); second
//!   measure the angular frequency from the peak spacing against omega² = g k tanh kH.
//!
//! Its outputs (`results.csv`, `report.md`, the SVGs) are written by `error_report`.

use super::cases::{cases_dir, column_geometry, dam_break_case, parse_case, read_case_value};
use super::score::{score, Measure, RunOutcome};
use super::unwind::catch_panic;
use crate::analysis::reference;
use crate::case::{self, Case, Refinement, Scheme};
use crate::math::Real;
use crate::run::{self, RunStatus};
use serde_json::{json, Value};
use std::io;
use std::path::Path;
use std::time::Instant;

/// A scheme variant compared by the benchmark.
#[derive(Debug, Clone)]
pub struct Variant {
    pub name: &'static str,
    pub description: &'static str,
    pub scheme: Scheme,
    /// The layout every run of the variant gets (`case.refinement`).
    pub refinement: Refinement,
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
            refinement: Refinement::Auto,
        },
        Variant {
            name: "default",
            description: "the scheme block's defaults (HS + ECS source, HL Laplacian, GC gradient) and the automatic multi-resolution layout",
            scheme: Scheme::default(),
            refinement: Refinement::Auto,
        },
        Variant {
            name: "uniform",
            description: "the default scheme on one spacing everywhere (`\"refinement\": \"none\"`)",
            scheme: Scheme::default(),
            refinement: Refinement::None,
        },
        Variant {
            name: "chl",
            description: "default with the corrected higher-order Laplacian CHL (BiCGSTAB)",
            scheme: Scheme {
                laplacian: LaplacianKind::CorrectedHigherOrder,
                solver: SolverKind::Bicgstab,
                ..Scheme::default()
            },
            refinement: Refinement::Auto,
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
            refinement: Refinement::Auto,
        },
    ]
}

/// One benchmark run, one line of `results.csv`.
#[derive(Debug, Clone, PartialEq)]
pub struct BenchResult {
    pub case: String,
    pub variant: String,
    pub spacing: Real,
    pub particles: usize,
    pub steps: u64,
    /// Particle updates of the run (`summary.json`'s `particle_steps`).
    pub particle_steps: u64,
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
        let case = parse_case(v.clone())?;
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
            // a row every step: the score reports the per-step scatter of the load
            overrides: vec!["output.load_interval=null".into()],
            measure: Measure::Wedge,
        });
    }
    let free_fall = cases_dir().join("wedge_free_fall.json");
    if free_fall.exists() {
        cases.push(BenchCase {
            name: "wedge_free_fall",
            base: read_case_value(&free_fall)?,
            spacings: if quick {
                vec![0.04, 0.03, 0.02]
            } else {
                // 2 m and 1 m / l0 whole numbers of columns and rows
                vec![0.02, 0.01, 0.008, 0.005]
            },
            // the velocity-loss window ends at 0.9 t_chine = 13.4 ms
            overrides: vec!["time.end=0.0135".into(), "output.load_interval=null".into()],
            measure: Measure::FreeFall,
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
        particle_steps: 0,
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
        .map(|mut case| {
            case.refinement = variant.refinement.clone();
            case
        })
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
    let summary = match catch_panic(|| run::run_case(&case, &dir, &mut run::Quiet)) {
        Ok(Ok(s)) => s,
        Ok(Err(e)) => {
            result.note = format!("run error: {e}");
            return result;
        }
        Err(panic) => {
            result.note = format!("panicked: {panic}");
            result.wall_time_s = started.elapsed().as_secs_f64();
            return result;
        }
    };
    result.particles = summary.particles;
    result.steps = summary.steps;
    result.particle_steps = summary.particle_steps;
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
        Ok(s) => {
            result.error = s.error;
            result.error_measure = s.error_measure;
            result.error2 = s.error2;
            result.error2_measure = s.error2_measure;
            result.note = format!("{reason}{}", s.note)
                .trim_end_matches("; ")
                .to_string();
        }
        Err(e) => result.note = format!("{reason}cannot measure: {e}"),
    }
    result
}
