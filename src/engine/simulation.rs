//! The state of one simulation and what it reports each step. No globals: a job
//! server runs many of these side by side.

use super::config::Config;
use super::params::MpsParameters;
use super::particles::Particles;
use super::resolution::Scales;
use super::scene::{build_scene_placed, Scene};
use super::walls::pressure_load::SurfacePressure;
use super::walls::WallObject;
use super::workspace::Workspace;
use crate::case::Case;
use crate::math::{vec2, Real, Vec2};

/// Why a run stopped early.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SimError {
    #[error("step {step}, t = {time:.6} s: {what} at particle {particle} ({x:.4}, {y:.4})")]
    Diverged {
        step: u64,
        time: Real,
        particle: usize,
        x: Real,
        y: Real,
        what: String,
    },
    #[error("step {step}, t = {time:.6} s: pressure solve failed: {reason}")]
    Solver {
        step: u64,
        time: Real,
        reason: String,
    },
    #[error("step {step}, t = {time:.6} s: all fluid particles left the domain")]
    NoParticles { step: u64, time: Real },
    #[error("cancelled at step {step}, t = {time:.6} s")]
    Cancelled { step: u64, time: Real },
}

/// Force and moment the fluid exerted on one wall object during the last step.
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct WallLoad {
    /// N/m
    pub force: Vec2,
    /// N·m/m about the object's centre of mass (fixed walls: about the origin).
    pub moment: Real,
    /// Pressure share of `force`: the integral of p n over the surface, or the reaction
    /// of the wall gradient terms (`scheme.wall_load`).
    pub pressure_force: Vec2,
    /// What the repulsion safety net gave the fluid; part of `force` (and
    /// `repulsion_moment` of `moment`) only with the reaction estimator.
    pub repulsion_force: Vec2,
    pub repulsion_moment: Real,
    /// Share from wall viscosity.
    pub viscous_force: Vec2,
}

/// Wall-clock seconds spent in each stage (accumulated over the run).
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct StageTimes {
    pub explicit_forces: f64,
    pub neighbors: f64,
    pub walls: f64,
    pub number_density: f64,
    pub assemble: f64,
    pub solve: f64,
    pub correct: f64,
    pub spacing: f64,
    pub bookkeeping: f64,
}

impl std::ops::AddAssign for StageTimes {
    fn add_assign(&mut self, o: Self) {
        self.explicit_forces += o.explicit_forces;
        self.neighbors += o.neighbors;
        self.walls += o.walls;
        self.number_density += o.number_density;
        self.assemble += o.assemble;
        self.solve += o.solve;
        self.correct += o.correct;
        self.spacing += o.spacing;
        self.bookkeeping += o.bookkeeping;
    }
}

impl StageTimes {
    pub fn total(&self) -> f64 {
        self.explicit_forces
            + self.neighbors
            + self.walls
            + self.number_density
            + self.assemble
            + self.solve
            + self.correct
            + self.spacing
            + self.bookkeeping
    }
}

/// What one step did.
#[derive(Debug, Clone, Copy, Default)]
pub struct StepInfo {
    pub dt: Real,
    pub solver_iterations: usize,
    pub solver_residual: Real,
    pub unknowns: usize,
    pub max_speed: Real,
    pub removed: usize,
}

/// What an attempted step did (`Simulation::try_step`).
#[derive(Debug, Clone, Copy)]
pub enum Attempt {
    Taken(StepInfo),
    /// A particle would have moved `moved` (m) in the step of `dt`, beyond the step
    /// guard; nothing changed.
    Rejected {
        dt: Real,
        moved: Real,
    },
}

/// Counts and timings of the run so far.
#[derive(Debug, Clone, Default, serde::Serialize, serde::Deserialize)]
pub struct RunStatistics {
    /// Particles removed (left the domain or ran away).
    pub removed: usize,
    /// Of `removed`, those that exceeded the speed limit, and the first of them (step,
    /// time, particle and speed).
    pub runaways: usize,
    pub first_runaway: Option<String>,
    pub stage_times: StageTimes,
    pub total_solver_iterations: u64,
    /// Attempted steps the step guard turned down (each repeated with a shorter dt).
    pub rejected_steps: u64,
    /// Particle updates of the steps taken: the sum over steps of the fluid particles
    /// at the start of each (a step turned down and repeated counts once).
    pub particle_steps: u64,
}

/// One simulation: its configuration (fixed for the run), its state (particles, walls,
/// time, the loads of the last step), its statistics and the workspace the step reuses
/// (the split of rapier's pipeline and world). No globals: a job server runs many of
/// these side by side.
pub struct Simulation {
    pub config: Config,
    pub particles: Particles,
    pub walls: Vec<WallObject>,
    pub time: Real,
    pub steps: u64,
    /// Loads of the last step, one per wall object.
    pub loads: Vec<WallLoad>,
    pub stats: RunStatistics,
    /// The pressure along every wall object's surface at the last step, as the load
    /// integral reads it (one list per wall object, in the order of `walls`).
    pub surface_pressure: Vec<Vec<SurfacePressure>>,
    /// The Courant limit of the next step with the last step's accelerations
    /// (bookkeeping::acceleration_limited_dt); infinite before the first step.
    pub(crate) acceleration_dt: Real,
    pub(crate) workspace: Workspace,
}

impl Simulation {
    /// Build the initial state of a (validated) case.
    pub fn new(case: &Case) -> Self {
        Self::placed(case, None)
    }

    /// [`Simulation::new`] with the particle lattice at `phase` of the placements a
    /// lattice-offset ensemble samples ([`build_scene_placed`]); None places it as `new` does.
    pub fn placed(case: &Case, phase: Option<Real>) -> Self {
        let params = MpsParameters::new(case);
        let Scene {
            particles,
            walls,
            domain_min,
            domain_max,
        } = build_scene_placed(case, &params, phase);
        let mut fastest: Real = particles
            .velocity
            .iter()
            .map(|v| v.norm())
            .fold(0.0, Real::max);
        for w in &walls {
            fastest = fastest.max(w.state.velocity.norm());
        }
        let config = Config::new(
            case,
            params,
            (domain_min, domain_max),
            particles.len(),
            fastest,
        );
        let mut config = config;
        config.multi_resolution = particles.scale.iter().any(|&s| s != 1.0);
        let n_walls = walls.len();
        let mut sim = Self {
            config,
            particles,
            walls,
            time: 0.0,
            steps: 0,
            loads: vec![WallLoad::default(); n_walls],
            stats: RunStatistics::default(),
            surface_pressure: vec![Vec::new(); n_walls],
            acceleration_dt: Real::INFINITY,
            workspace: Workspace::default(),
        };
        sim.initialize();
        sim
    }

    /// The particles' spacing multiples, uniform unless the layout has several levels.
    pub fn scales(&self) -> Scales<'_> {
        Scales::new(&self.particles.scale, self.config.multi_resolution)
    }

    /// Number of fluid particles now.
    pub fn particle_count(&self) -> usize {
        self.particles.len()
    }

    /// How the pressure preconditioners of the steps so far were obtained (built or
    /// reused AMG hierarchies).
    pub fn solver_reuse_counts(&self) -> super::pressure::ReuseCounts {
        self.workspace.solver_cache.counts()
    }

    /// Kinetic and potential energy of the fluid per unit depth (J/m): sum of m |u|²/2
    /// and of -m g·x (zero potential at the origin).
    pub fn fluid_energy(&self) -> (Real, Real) {
        let m = self.config.params.particle_mass;
        let g = vec2(self.config.params.gravity);
        let p = &self.particles;
        let s = self.scales();
        let kinetic: Real = (0..p.len())
            .map(|i| p.velocity[i].norm_squared() * s.volume(i))
            .sum::<Real>()
            * 0.5
            * m;
        let potential: Real = -(0..p.len())
            .map(|i| g.dot(&p.position[i]) * s.volume(i))
            .sum::<Real>()
            * m;
        (kinetic, potential)
    }

    /// Largest particle speed now.
    pub fn max_particle_speed(&self) -> Real {
        self.particles
            .velocity
            .iter()
            .map(|v| v.norm())
            .fold(0.0, Real::max)
    }

    /// The next time step: dt = min(cfl l0 / u_max, the same with the last step's
    /// accelerations, viscous limit, max_dt).
    pub fn next_dt(&self) -> Real {
        let mut u = self.max_particle_speed();
        for w in &self.walls {
            u = u.max(w.state.velocity.norm());
        }
        let l0 = self.config.params.l0;
        let mut dt = self.config.control.max_dt;
        if u > 0.0 {
            dt = dt.min(self.config.control.cfl * l0 / u);
        }
        dt = dt.min(self.acceleration_dt);
        if self.config.params.viscosity > 0.0 {
            // explicit diffusion: the strain-rate form's largest eigenvalue is (d + 2)/d
            // times the Laplacian's (it weights r̂ r̂ by d + 2 where the Laplacian has 1)
            let form = match self.config.method.viscosity {
                crate::case::ViscosityKind::Laplacian => 1.0,
                crate::case::ViscosityKind::StrainRate => {
                    super::params::DIM / (super::params::DIM + 2.0)
                }
            };
            dt = dt.min(0.2 * form * l0 * l0 / self.config.params.viscosity);
        }
        let g = vec2(self.config.params.gravity).norm();
        if g > 0.0 {
            // a particle starting from rest should not fall more than cfl * l0 in a step
            dt = dt.min((2.0 * self.config.control.cfl * l0 / g).sqrt());
        }
        dt
    }

    /// Names of the wall objects (fixed walls first, then bodies), as in `loads`.
    pub fn wall_names(&self) -> Vec<String> {
        self.walls.iter().map(|w| w.name.clone()).collect()
    }

    /// Each particle's wall contacts of the last step (diagnostics).
    pub fn wall_contacts(&self) -> &crate::engine::walls::WallContacts {
        &self.workspace.contacts
    }
}
