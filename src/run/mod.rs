//! `run_case`: a validated case -> the run directory. Progress and cancellation go
//! through an [`Observer`], so the CLI (progress bar) and the service (job record,
//! DELETE) drive the same loop. A failed run keeps everything it wrote and says why.

use crate::case::{self, Case, Scheme, ValidCase};
use crate::coupling::Coupling;
use crate::engine::{Attempt, SimError, Simulation, StageTimes, StepInfo};
use crate::math::{vec2, Real};
use crate::output::snapshots::SnapshotWriter;
use crate::output::vtk::PvdEntry;
use crate::output::{RunWriter, WriterState};
use crate::state_io::StateError;
use serde::{Deserialize, Serialize};
use std::path::Path;
use std::time::{Duration, Instant};

pub mod checkpoint;
pub mod uncertainty;

pub use checkpoint::Checkpoint;

/// Where a run is, reported after every step.
#[derive(Debug, Clone, Copy, Default, Serialize)]
pub struct Progress {
    pub step: u64,
    pub simulated_time: Real,
    pub end_time: Real,
    pub dt: Real,
    pub particles: usize,
    pub solver_iterations: usize,
}

impl Progress {
    pub fn fraction(&self) -> Real {
        if self.end_time > 0.0 {
            (self.simulated_time / self.end_time).clamp(0.0, 1.0)
        } else {
            1.0
        }
    }
}

/// Receives progress; can ask the run to stop (checked once per step).
pub trait Observer {
    /// Called once the scene is built, before the first step.
    fn started(&mut self, _particles: usize, _estimated_steps: u64) {}
    fn progress(&mut self, _progress: &Progress) {}
    /// Called before each run of a ladder (`--uncertainty`): part `index` of `count`.
    fn part(&mut self, _index: usize, _count: usize, _label: &str) {}
    fn is_cancelled(&self) -> bool {
        false
    }
    /// Called after a checkpoint of `bytes` bytes was saved at `path`, at simulated
    /// time `time` after `steps` steps ([`RunOptions`]).
    fn checkpoint_saved(&mut self, _path: &Path, _time: Real, _steps: u64, _bytes: u64) {}
    /// Status and reason of summary.json when the run stops because `is_cancelled` said
    /// so (at `step`, simulated time `time`). Default: `cancelled`. The service's
    /// observer says `failed` / `interrupted` when its own shutdown stopped the job, so
    /// that summary.json and the job record agree; the CLI's names the signal.
    fn stop_reason(&self, step: u64, time: Real) -> (RunStatus, String) {
        (
            RunStatus::Cancelled,
            SimError::Cancelled { step, time }.to_string(),
        )
    }
}

/// An observer that ignores everything.
pub struct Quiet;
impl Observer for Quiet {}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum RunStatus {
    Succeeded,
    Failed,
    Cancelled,
}

/// summary.json
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Summary {
    pub status: RunStatus,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reason: Option<String>,
    pub case: String,
    pub steps: u64,
    /// Particle updates of the steps taken (the sum over steps of the fluid particles):
    /// the run's cost in a unit that does not depend on the machine.
    #[serde(default)]
    pub particle_steps: u64,
    pub simulated_time: Real,
    pub end_time: Real,
    pub wall_time_s: f64,
    pub particles: usize,
    pub particles_removed: usize,
    /// Of `particles_removed`, those removed for exceeding the speed limit
    /// (`scheme.runaway_allowance`), and the first of them.
    #[serde(default)]
    pub particles_runaway: usize,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub first_runaway: Option<String>,
    pub max_velocity: Real,
    pub min_dt: Real,
    pub max_dt: Real,
    pub mean_solver_iterations: Real,
    /// Steps the step guard turned down and repeated with a shorter dt (a particle would
    /// have moved more than 1.5 cfl spacings).
    #[serde(default)]
    pub steps_repeated: u64,
    /// Width of the zero-phase moving average of loads_filtered.csv (s).
    pub filter_window_s: Real,
    pub stage_seconds: StageTimes,
    /// Wall-clock seconds in the rigid-body coupling (0 without bodies).
    pub coupling_seconds: f64,
    pub n0: Real,
    pub scheme: Scheme,
    pub version: String,
    /// One line for every body that enters the water outside the envelope where the
    /// default scheme's slamming loads are validated (`analysis::envelope`); absent when
    /// there is none.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub advice: Vec<String>,
    /// The 95 % half-widths of the loads' impulses and peaks and the ladder behind them,
    /// when the run was asked for its uncertainty ([`uncertainty`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub uncertainty: Option<crate::analysis::uncertainty::UncertaintySummary>,
}

#[derive(Debug, thiserror::Error)]
pub enum RunError {
    #[error("cannot write the run directory: {0}")]
    Io(#[from] std::io::Error),
    /// The checkpoint to resume from does not fit the case or cannot be read.
    #[error("cannot resume: {0}")]
    Resume(#[from] StateError),
}

/// The step from `time` of at most `dt` that lands on `end` without a sliver: when a
/// full step would leave less than another full one, the last two steps share the rest
/// evenly. A sliver of a step is a load spike: the pressure source goes as 1/dt² (the
/// 30° wedge at 1 cm, its axis l0/4 off the lattice, ended on a step of 2e-8 s that
/// read 9.6 MN/m, 200 times its neighbours).
pub fn step_to_end(time: Real, end: Real, dt: Real) -> Real {
    let rest = end - time;
    // a rest that is one step but for the round-off of the summed times is that step
    if rest <= dt * (1.0 + 1e-9) {
        rest.max(1e-12)
    } else if rest < 2.0 * dt {
        0.5 * rest
    } else {
        dt
    }
}

/// Estimated number of steps (for `check` and progress): end / dt at the larger of the
/// initial speeds and the free-fall speed over the domain height.
pub fn estimate_steps(case: &Case) -> u64 {
    let g = vec2(case.fluid.gravity).norm();
    let h = case.domain.max[1] - case.domain.min[1];
    let mut u = (2.0 * g * h.max(0.0)).sqrt() * 0.5;
    for b in &case.bodies {
        let (case::Motion::Prescribed { velocity, .. } | case::Motion::Free { velocity, .. }) =
            &b.motion;
        u = u.max(vec2(*velocity).norm());
    }
    let mut dt = case.time.max_dt;
    if u > 0.0 {
        dt = dt.min(case.time.cfl * case.particle_spacing / u);
    }
    (case.time.end / dt).ceil() as u64
}

/// One step of at most `dt`, with the bodies' coupling around it: a step the step guard
/// turns down is repeated with dt scaled so that the farthest particle would move cfl
/// spacings (at least a tenth of the last try each time, and at most `MAX_RETRIES` times).
pub fn advance(
    sim: &mut Simulation,
    mut coupling: Option<&mut Coupling>,
    mut dt: Real,
) -> Result<StepInfo, SimError> {
    const MAX_RETRIES: usize = 8;
    let target = sim.config.control.cfl * sim.config.params.l0;
    for retry in 0..=MAX_RETRIES {
        if let Some(c) = coupling.as_deref_mut() {
            c.before_step(sim, dt);
        }
        let attempt = if retry == MAX_RETRIES {
            Attempt::Taken(sim.step(dt)?)
        } else {
            sim.try_step(dt)?
        };
        match attempt {
            Attempt::Taken(info) => {
                if let Some(c) = coupling.as_deref_mut() {
                    c.after_step(sim, dt);
                }
                return Ok(info);
            }
            Attempt::Rejected { moved, .. } => dt *= (target / moved).clamp(0.1, 0.9),
        }
    }
    unreachable!("the last try is taken whatever it moves")
}

/// Build, step to the end time (or failure / cancellation), write the run directory. The
/// case was validated by the caller, against the caller's limits.
pub fn run_case(
    case: &ValidCase,
    out_dir: &Path,
    observer: &mut dyn Observer,
) -> Result<Summary, RunError> {
    run_case_with(case, out_dir, observer, RunOptions::default())
}

/// [`run_case`] with the particle lattice at `phase` of a lattice-offset ensemble's
/// placements ([`Simulation::placed`]).
pub fn run_case_placed(
    case: &ValidCase,
    out_dir: &Path,
    observer: &mut dyn Observer,
    phase: Option<Real>,
) -> Result<Summary, RunError> {
    let options = RunOptions {
        phase,
        ..RunOptions::default()
    };
    run_case_with(case, out_dir, observer, options)
}

/// How a run is carried out, beyond its case.
#[derive(Default)]
pub struct RunOptions {
    /// Lattice placement of a lattice-offset ensemble ([`Simulation::placed`]).
    pub phase: Option<Real>,
    /// Save a checkpoint ([`checkpoint::FILE`] in the run directory) every this much
    /// wall-clock time.
    pub checkpoint_every: Option<Duration>,
    /// Save one when the run stops because the observer asked (Ctrl-C, a worker's
    /// shutdown), so that it can be resumed.
    pub checkpoint_on_stop: bool,
    /// Continue from this checkpoint (of the same case) instead of t = 0.
    pub resume: Option<Checkpoint>,
}

/// What a run holds between steps: the simulation, the coupling, the writers and the
/// extremes summary.json reports.
struct Run {
    sim: Simulation,
    coupling: Option<Coupling>,
    writer: RunWriter,
    snapshots: Option<SnapshotWriter>,
    min_dt: Real,
    max_dt: Real,
    max_velocity: Real,
}

impl Run {
    /// The run at t = 0, or at the checkpoint `resume` (of the same case, checked), with
    /// its files created. The checkpoint is read to its end before any file is touched,
    /// so a checkpoint that cannot be read leaves the run directory as it was.
    fn start(
        case: &Case,
        out_dir: &Path,
        phase: Option<Real>,
        resume: Option<&Checkpoint>,
    ) -> Result<Self, RunError> {
        let mut sim = Simulation::placed(case, phase);
        let mut coupling = Coupling::new(case, &sim);
        let probes = crate::output::probes::points(case, &sim);
        let mut extremes = (Real::INFINITY, 0.0, 0.0);
        let mut files = None;
        if let Some(saved) = resume {
            if saved.header.case_json != checkpoint::case_text(case) {
                return Err(StateError::Mismatch("it was taken of another case".into()).into());
            }
            let h = &saved.header;
            extremes = (h.min_dt, h.max_dt, h.max_velocity);
            let mut r = saved.state();
            sim.restore_state(&mut r)?;
            if let Some(c) = &mut coupling {
                c.restore_state(&mut r)?;
            }
            let writer: WriterState = RunWriter::take_state(&mut r)?;
            let snapshots: Option<(Real, Vec<PvdEntry>)> = r.take()?;
            r.finish()?;
            files = Some((writer, snapshots));
        }
        let mut writer = RunWriter::create(
            out_dir,
            case.output.load_interval.seconds(case.time.end),
            sim.wall_names(),
            coupling.is_some(),
            probes,
            case.output.energy,
        )?;
        let mut snapshots = SnapshotWriter::create(
            out_dir,
            case.output.snapshot_interval.seconds(case.time.end),
        )?;
        match files {
            None => {
                if let Some(s) = &mut snapshots {
                    s.record(&sim)?;
                }
            }
            Some((saved, saved_snapshots)) => {
                writer.apply_state(out_dir, saved)?;
                match (&mut snapshots, saved_snapshots) {
                    (Some(s), Some(state)) => s.apply_state(state)?,
                    (None, None) => {}
                    _ => {
                        let e = StateError::Mismatch("the snapshots are not the case's".into());
                        return Err(e.into());
                    }
                }
            }
        }
        let (min_dt, max_dt, max_velocity) = extremes;
        Ok(Self {
            sim,
            coupling,
            writer,
            snapshots,
            min_dt,
            max_dt,
            max_velocity,
        })
    }

    /// Save the state at the end of the last step to the run directory's checkpoint;
    /// its size in bytes.
    fn save(
        &mut self,
        case: &Case,
        out_dir: &Path,
        phase: Option<Real>,
        wall_time_s: f64,
    ) -> std::io::Result<u64> {
        let header = checkpoint::Header {
            case_json: checkpoint::case_text(case),
            phase,
            time: self.sim.time,
            steps: self.sim.steps,
            wall_time_s,
            min_dt: self.min_dt,
            max_dt: self.max_dt,
            max_velocity: self.max_velocity,
        };
        let Self {
            sim,
            coupling,
            writer,
            snapshots,
            ..
        } = self;
        checkpoint::write(&out_dir.join(checkpoint::FILE), &header, |w| {
            sim.save_state(w)?;
            if let Some(c) = coupling {
                c.save_state(w)?;
            }
            writer.save_state(out_dir, w)?;
            w.put(&snapshots.as_ref().map(|s| s.state()))
        })
    }

    /// [`Run::save`], and tell the observer.
    fn checkpoint(
        &mut self,
        case: &Case,
        out_dir: &Path,
        phase: Option<Real>,
        wall_time_s: f64,
        observer: &mut dyn Observer,
    ) -> std::io::Result<()> {
        let bytes = self.save(case, out_dir, phase, wall_time_s)?;
        let path = out_dir.join(checkpoint::FILE);
        observer.checkpoint_saved(&path, self.sim.time, self.sim.steps, bytes);
        Ok(())
    }
}

/// [`run_case`] with [`RunOptions`]: a lattice placement, checkpoints, a resumed start.
pub fn run_case_with(
    case: &ValidCase,
    out_dir: &Path,
    observer: &mut dyn Observer,
    options: RunOptions,
) -> Result<Summary, RunError> {
    let case: &Case = case;
    let started = Instant::now();
    let phase = options
        .resume
        .as_ref()
        .map_or(options.phase, |c| c.header.phase);
    let mut run = Run::start(case, out_dir, phase, options.resume.as_ref())?;
    let wall_before = options
        .resume
        .as_ref()
        .map_or(0.0, |c| c.header.wall_time_s);
    let wall_time = || wall_before + started.elapsed().as_secs_f64();
    observer.started(run.sim.particle_count(), estimate_steps(case));
    let end = case.time.end;
    let mut failure: Option<(RunStatus, String)> = None;
    let mut last_checkpoint = Instant::now();
    while run.sim.time < end * (1.0 - 1e-12) {
        if observer.is_cancelled() {
            failure = Some(observer.stop_reason(run.sim.steps, run.sim.time));
            if options.checkpoint_on_stop {
                run.checkpoint(case, out_dir, phase, wall_time(), observer)?;
            }
            break;
        }
        let Run {
            sim,
            coupling,
            writer,
            snapshots,
            min_dt,
            max_dt,
            max_velocity,
        } = &mut run;
        let dt = step_to_end(sim.time, end, sim.next_dt());
        match advance(sim, coupling.as_mut(), dt) {
            Ok(info) => {
                let dt = info.dt;
                *min_dt = min_dt.min(dt);
                *max_dt = max_dt.max(dt);
                *max_velocity = max_velocity.max(info.max_speed);
                let bodies = coupling
                    .as_ref()
                    .map(|c| c.samples(sim))
                    .unwrap_or_default();
                writer.record(sim, dt, &bodies)?;
                if let Some(s) = snapshots {
                    s.record(sim)?;
                }
                observer.progress(&Progress {
                    step: sim.steps,
                    simulated_time: sim.time,
                    end_time: end,
                    dt,
                    particles: sim.particle_count(),
                    solver_iterations: info.solver_iterations,
                });
            }
            Err(e) => {
                failure = Some((RunStatus::Failed, e.to_string()));
                break;
            }
        }
        let due = options
            .checkpoint_every
            .is_some_and(|every| last_checkpoint.elapsed() >= every);
        if due && run.sim.time < end * (1.0 - 1e-12) {
            run.checkpoint(case, out_dir, phase, wall_time(), observer)?;
            last_checkpoint = Instant::now();
        }
    }
    let Run {
        sim,
        coupling,
        mut writer,
        mut snapshots,
        min_dt,
        max_dt,
        max_velocity,
    } = run;
    writer.finish()?;
    if let Some(s) = &mut snapshots {
        s.finish()?;
    }
    if failure.is_none() {
        // a finished run has nothing to resume
        match std::fs::remove_file(out_dir.join(checkpoint::FILE)) {
            Err(e) if e.kind() != std::io::ErrorKind::NotFound => return Err(e.into()),
            _ => {}
        }
    }
    // raw loads stay the reference; the filtered copy keeps their impulse exactly
    let filter_window_s = crate::output::filter::filter_window(case);
    crate::output::filter::write_filtered_loads(out_dir, filter_window_s)?;
    let (status, reason) = match failure {
        None => (RunStatus::Succeeded, None),
        Some((s, r)) => (s, Some(r)),
    };
    let summary = Summary {
        status,
        reason,
        case: case.name.clone(),
        steps: sim.steps,
        particle_steps: sim.stats.particle_steps,
        simulated_time: sim.time,
        end_time: end,
        wall_time_s: wall_time(),
        particles: sim.particle_count(),
        particles_removed: sim.stats.removed,
        particles_runaway: sim.stats.runaways,
        first_runaway: sim.stats.first_runaway.clone(),
        max_velocity,
        min_dt: if min_dt.is_finite() { min_dt } else { 0.0 },
        max_dt,
        steps_repeated: sim.stats.rejected_steps,
        mean_solver_iterations: if sim.steps > 0 {
            sim.stats.total_solver_iterations as Real / sim.steps as Real
        } else {
            0.0
        },
        filter_window_s,
        stage_seconds: sim.stats.stage_times,
        coupling_seconds: coupling.as_ref().map_or(0.0, |c| c.seconds),
        n0: sim.config.params.n0,
        scheme: sim.config.scheme.clone(),
        version: env!("CARGO_PKG_VERSION").to_string(),
        advice: crate::analysis::envelope::impact_advice(case),
        uncertainty: None,
    };
    write_summary(out_dir, &summary)?;
    Ok(summary)
}

/// Write `summary.json` into the run directory.
fn write_summary(out_dir: &Path, summary: &Summary) -> std::io::Result<()> {
    let json = serde_json::to_string_pretty(summary).expect("summary serialises");
    std::fs::write(out_dir.join("summary.json"), json + "\n")
}
