//! Shared helpers: load a shipped case with overrides, run it with the coupling, and
//! keep the per-step loads and body samples.

use mpsfsi::analysis::reference::{
    FreeFall, FreeFallModel, LogvinovichFreeFall, PotentialFlowFreeFall, WEDGE_30_FORCE_COEFFICIENT,
};
use mpsfsi::analysis::similarity;
use mpsfsi::case::{load_case_file, Case, Limits, ValidCase};
use mpsfsi::coupling::{BodySample, Coupling, CouplingOptions};
use mpsfsi::engine::{SimError, Simulation};
use mpsfsi::math::{Real, Vec2};
use mpsfsi::run::{run_case, Quiet, Summary};
use std::path::PathBuf;
use std::time::Instant;

pub const RHO: Real = 1000.0;

pub fn case_path(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("cases")
        .join(name)
}

/// A shipped case with `--set`-style overrides.
pub fn shipped(name: &str, overrides: &[String]) -> Case {
    load_case_file(&case_path(name), overrides).unwrap_or_else(|e| panic!("{name}: {e}"))
}

/// Overrides giving a rectangular tank of fluid [-w, w] x [-depth, 0] with walls up to `top`.
pub fn tank(w: Real, depth: Real, top: Real) -> Vec<String> {
    vec![
        format!("fluid_blocks=[{{\"polygon\": [[{a}, {d}], [{w}, {d}], [{w}, 0.0], [{a}, 0.0]]}}]", a = -w, d = -depth),
        format!(
            "walls=[{{\"name\": \"tank\", \"polyline\": [[{a}, {top}], [{a}, {d}], [{w}, {d}], [{w}, {top}]]}}]",
            a = -w,
            d = -depth
        ),
        format!("domain={{\"min\": [{}, {}], \"max\": [{}, {}]}}", -w - 0.05, -depth - 0.05, w + 0.05, top + 0.3),
    ]
}

/// One step's record.
#[derive(Debug, Clone)]
pub struct StepRecord {
    /// Time at the end of the step.
    pub time: Real,
    pub dt: Real,
    /// Fluid force on each wall object during the step (N/m).
    pub force: Vec<Vec2>,
    /// Bodies at the end of the step.
    pub bodies: Vec<BodySample>,
}

pub struct Trace {
    pub initial: Vec<BodySample>,
    pub steps: Vec<StepRecord>,
    pub wall_names: Vec<String>,
    pub particles: usize,
    /// summary.json's `particle_steps`: the particle updates of the run.
    pub particle_steps: u64,
    pub wall_seconds: f64,
    pub coupling_seconds: f64,
    pub error: Option<SimError>,
}

impl Trace {
    pub fn wall(&self, name: &str) -> usize {
        self.wall_names
            .iter()
            .position(|n| n == name)
            .unwrap_or_else(|| panic!("no wall {name}"))
    }
}

/// Run `case` to `end` (or its own end time), stepping the coupling around every step.
pub fn run(
    case: &Case,
    options: CouplingOptions,
    end: Option<Real>,
    mut each: impl FnMut(&Simulation),
) -> Trace {
    let clock = Instant::now();
    let mut sim = Simulation::new(case);
    let mut coupling = Coupling::with_options(case, &sim, options).expect("case has bodies");
    let end = end.unwrap_or(case.time.end);
    let initial = coupling.samples(&sim);
    let mut steps = Vec::new();
    let mut error = None;
    while sim.time < end - 1e-12 {
        // as `mpsfsi run` steps: no sliver of a step at the end (a load spike)
        let proposed = mpsfsi::run::step_to_end(sim.time, end, sim.next_dt());
        let dt = match mpsfsi::run::advance(&mut sim, Some(&mut coupling), proposed) {
            Ok(info) => info.dt,
            Err(e) => {
                error = Some(e);
                break;
            }
        };
        steps.push(StepRecord {
            time: sim.time,
            dt,
            force: sim.loads.iter().map(|l| l.force).collect(),
            bodies: coupling.samples(&sim),
        });
        each(&sim);
    }
    Trace {
        initial,
        steps,
        wall_names: sim.wall_names(),
        particles: sim.particle_count(),
        particle_steps: sim.stats.particle_steps,
        wall_seconds: clock.elapsed().as_secs_f64(),
        coupling_seconds: coupling.seconds,
        error,
    }
}

/// Least-squares line y = a + b x.
pub fn fit_line(x: &[Real], y: &[Real]) -> (Real, Real) {
    let n = x.len() as Real;
    let mx = x.iter().sum::<Real>() / n;
    let my = y.iter().sum::<Real>() / n;
    let sxy: Real = x.iter().zip(y).map(|(a, b)| (a - mx) * (b - my)).sum();
    let sxx: Real = x.iter().map(|a| (a - mx) * (a - mx)).sum();
    let b = sxy / sxx;
    (my - b * mx, b)
}

/// The rows of a run directory's csv file (loads.csv, bodies.csv) for the object `name`:
/// time, then the numeric columns after the name.
/// Run `case` through the CLI's run loop into a scratch directory named by `tag`, and
/// return `body`'s rows of loads.csv (time, fx, fy, mz) and bodies.csv (time, x, y,
/// angle, vx, vy, omega) with the summary; the directory is removed.
pub fn run_case_rows(case: Case, tag: &str, body: &str) -> (Vec<Vec<f64>>, Vec<Vec<f64>>, Summary) {
    let valid = ValidCase::new(case, &Limits::default()).expect("the case is valid");
    let dir = std::env::temp_dir().join(format!("mpsfsi-bodies-{tag}-{}", std::process::id()));
    let summary = run_case(&valid, &dir, &mut Quiet).expect("the run directory is written");
    let loads = csv_rows(&dir.join("loads.csv"), body);
    let bodies = csv_rows(&dir.join("bodies.csv"), body);
    let _ = std::fs::remove_dir_all(&dir);
    (loads, bodies, summary)
}

pub fn csv_rows(path: &std::path::Path, name: &str) -> Vec<Vec<f64>> {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    text.lines()
        .skip(1)
        .filter_map(|l| {
            let mut f = l.split(',');
            let t: f64 = f.next()?.parse().ok()?;
            (f.next()? == name).then(|| {
                std::iter::once(t)
                    .chain(f.map(|v| v.parse::<f64>().unwrap()))
                    .collect()
            })
        })
        .collect()
}

/// The free-falling 30° wedge's velocity loss against the momentum balance of the
/// similarity solution, at every bodies.csv row (time, x, y, angle, vx, vy, omega) of
/// 0.6-0.9 t_chine: (time, relative error of V0 - V). Wagner's model writes the entry
/// force as F = d(m_a V)/dt with an added mass of the penetration h only; calibrated to
/// the similarity solution (docs/references.md), m_a(h) = C_F rho h² / 2 so that F = C_F rho
/// V³ t at constant speed, and with M dV/dt = M g - F (downward positive) the body obeys
/// (M + m_a(h)) V = M (V0 + g t), dh/dt = V, integrated here with a step far below the
/// run's.
pub fn momentum_model_errors(case: &Case, mass: Real, bodies: &[Vec<f64>]) -> Vec<(Real, Real)> {
    velocity_loss_against(&momentum_model(case, mass), bodies)
}

/// The same against the quasi-steady potential-flow model (`PotentialFlowFreeFall`): the
/// similarity solution's force at the body's depth and speed plus its acceleration
/// reaction, the potential-flow added mass of its wetted geometry (8.31 rho h² at 30°,
/// 1.19 times the momentum model's C_F/2), which the engine's own acceleration reaction
/// matches (tests/bodies/acceleration_reaction.rs). The free-fall tests hold to it.
pub fn potential_flow_errors(case: &Case, mass: Real, bodies: &[Vec<f64>]) -> Vec<(Real, Real)> {
    let model = PotentialFlowFreeFall {
        v0: -case.bodies[0].motion_velocity_y(),
        g: -case.fluid.gravity[1],
        mass,
        density: RHO,
        force_coefficient: WEDGE_30_FORCE_COEFFICIENT,
        acceleration_added_mass: similarity::acceleration_added_mass(30.0).unwrap(),
    };
    velocity_loss_against(&model, bodies)
}

/// The same against the modified Logvinovich model (the closure of a free fall in
/// docs/references.md) with its force scaled onto the similarity solution's at constant
/// speed: the two models part in the added mass of the deceleration (`LogvinovichFreeFall`).
pub fn logvinovich_errors(case: &Case, mass: Real, bodies: &[Vec<f64>]) -> Vec<(Real, Real)> {
    let model = LogvinovichFreeFall::matching(&momentum_model(case, mass), 30f64.to_radians());
    velocity_loss_against(&model, bodies)
}

/// The momentum model of the shipped 30° free fall's `case` with `mass` kg/m.
pub fn momentum_model(case: &Case, mass: Real) -> FreeFallModel {
    FreeFallModel {
        v0: -case.bodies[0].motion_velocity_y(),
        g: -case.fluid.gravity[1],
        mass,
        force_coefficient: WEDGE_30_FORCE_COEFFICIENT,
        density: RHO,
    }
}

fn velocity_loss_against(model: &impl FreeFall, bodies: &[Vec<f64>]) -> Vec<(Real, Real)> {
    let t_chine = 0.0149;
    let samples: Vec<(Real, Real)> = bodies.iter().map(|b| (b[0], -b[5])).collect();
    mpsfsi::analysis::measure::velocity_loss_errors(model, &samples, 0.6 * t_chine, 0.9 * t_chine)
}

/// The vertical velocity a body's motion starts with.
pub trait MotionVelocity {
    fn motion_velocity_y(&self) -> f64;
}

impl MotionVelocity for mpsfsi::case::Body {
    fn motion_velocity_y(&self) -> f64 {
        match &self.motion {
            mpsfsi::case::Motion::Free { velocity, .. }
            | mpsfsi::case::Motion::Prescribed { velocity, .. } => velocity[1],
        }
    }
}
