//! One projection step of semi-implicit MPS, as a list of named stages.
//!
//! Default scheme (MPS-HS-HL-ECS with the corrected gradient; Sun et al. 2022,
//! Ikari, Khayyer & Gotoh 2015):
//! explicit viscosity and gravity give u*, x*; the pressure Poisson equation with the
//! higher-order source plus error-compensating terms is solved on x* with the
//! (lattice-normalised) higher-order Laplacian; the corrected gradient corrects
//! velocity and position. Walls enter through the virtual-lattice sums of `walls`.
//!
//! Walls and the pressure equation (our formulation): virtual wall points take the
//! particle's pressure extrapolated with the Neumann condition of an accelerating wall,
//! p_k = p_i + rho (g - a_w) · (x_k - x_i) (docs/method.md, walls), so the wall adds no unknowns
//! and no matrix entries, only right-hand-side terms; the same extrapolation gives the
//! wall part of the gradient, whose reaction is the load on the wall. The kinematic
//! condition enters the source: virtual points move with the wall, so the HS source
//! gains ∇Z · (u_i^n - u_w), the rate at which the wall lattice's share of n changes
//! with the relative velocity at the start of the step (the body-force part of u* is
//! already carried by the Neumann term; counting it twice over-corrects). With the PND
//! source (classic scheme) virtual points take p_i (Harada et al. 2008) and the wall
//! acts through the number density alone.
//!
//! The stages live in the sibling files, one per stage group: `explicit`, `density`
//! (neighbours, number density, divergence), `free_surface`, `pressure_equation`,
//! `exact` (the optional exact projection), `correction`, `spacing`, `bookkeeping`;
//! the step guard's rollback in `guard`.

mod bookkeeping;
mod correction;
mod density;
mod exact;
mod explicit;
mod free_surface;
mod guard;
mod pressure_equation;
mod spacing;
mod walls;

use super::config::Projection;
use super::kernel::Kernel;
use super::simulation::{Attempt, SimError, Simulation, StageTimes, StepInfo, WallLoad};
use super::walls::WallContacts;
use super::workspace::PressureSystem;
use crate::case::WallLoadKind;
use crate::math::Real;
use crate::with_kernel;
use guard::Rollback;
use std::time::Instant;
use walls::{placed_walls, wall_kernels, KernelWeights};

impl Simulation {
    /// Neighbours, wall contacts, number density and divergence of the current state: call
    /// it after moving particles by hand (as the perturbed-lattice stress scene does).
    pub fn initialize(&mut self) {
        with_kernel!(self.config.method.kernel, K => initialize::<K>(self))
    }

    /// Advance by `dt`, whatever the particles' displacement. Body wall states must hold
    /// the pose and velocity at the start of the step; they are advanced kinematically
    /// (the coupling may overwrite them after).
    pub fn step(&mut self, dt: Real) -> Result<StepInfo, SimError> {
        match with_kernel!(self.config.method.kernel, K => step::<K>(self, dt, None))? {
            Attempt::Taken(info) => Ok(info),
            Attempt::Rejected { .. } => unreachable!("a step without a displacement limit"),
        }
    }

    /// Advance by `dt` unless a particle would move farther than the step guard allows
    /// (`StepControl::displacement_limit`): then the state is left as it was and the
    /// attempt says which shorter step to try (`run::advance` does so).
    pub fn try_step(&mut self, dt: Real) -> Result<Attempt, SimError> {
        let limit = self.config.control.displacement_limit * self.config.params.l0;
        with_kernel!(self.config.method.kernel, K => step::<K>(self, dt, Some(limit)))
    }
}

/// Runs `stage` and adds its wall-clock seconds to `total`.
fn timed<T>(total: &mut f64, stage: impl FnOnce() -> T) -> T {
    let start = Instant::now();
    let out = stage();
    *total += start.elapsed().as_secs_f64();
    out
}

fn initialize<K: Kernel>(sim: &mut Simulation) {
    sim.workspace.neighbors = density::neighbor_list(sim, &sim.particles.position, Vec::new());
    let walls = placed_walls(sim, 0.0);
    let weights = KernelWeights::<K>::new(sim);
    let kernels = wall_kernels(sim);
    sim.workspace.contacts = WallContacts::build(
        &sim.particles.position,
        &walls,
        &kernels,
        &weights,
        sim.scales(),
    );
    density::initial_number_density_and_divergence::<K>(sim);
}

/// The step, stage by stage. With `limit`, the step stops before the correction when a
/// particle would move farther than `limit` and leaves the state as it found it. The
/// pressure system's buffers are lent to the stages and returned whatever the outcome.
fn step<K: Kernel>(
    sim: &mut Simulation,
    dt: Real,
    limit: Option<Real>,
) -> Result<Attempt, SimError> {
    let mut system = std::mem::take(&mut sim.workspace.system);
    let mut times = StageTimes::default();
    let attempt = stages::<K>(sim, &mut system, &mut times, dt, limit);
    sim.workspace.system = system;
    sim.stats.stage_times += times;
    attempt
}

/// The stages in order. Each takes what it reads and returns what it produces, besides
/// the particles and the lists in `sim`: u^n and x* (explicit), n* and ∇·u*
/// (density), the surface values (free surface), the pressure system (assembly,
/// solve), ∇p (correction).
fn stages<K: Kernel>(
    sim: &mut Simulation,
    system: &mut PressureSystem,
    times: &mut StageTimes,
    dt: Real,
    limit: Option<Real>,
) -> Result<Attempt, SimError> {
    let weights = KernelWeights::<K>::new(sim);
    // loads of this step, one per wall object, accumulated by every stage with a wall term
    let mut loads = vec![WallLoad::default(); sim.walls.len()];
    let rollback = limit.map(|_| Rollback::save(sim));

    let (u_start, x_star) = timed(&mut times.explicit_forces, || {
        // u* = u + dt (g + nu ∇²u), Sun et al. (2022) eq. 9; x* = x + dt u*, eq. 10
        let u_start = explicit::apply_explicit_forces::<K>(sim, &weights, dt, &mut loads);
        (u_start, explicit::predicted_positions(&sim.particles, dt))
    });
    // neighbours at x* (cell grid, counting sort), and the walls at their predicted pose
    // with each particle's contacts; the last step's lists are kept to the end of the
    // step: a repeated step's explicit stage reads them, and freed at once they changed
    // where the later stages' buffers went (the step at 160k took 77.0 against 74.9 ms,
    // bench --scaling, medians of 12)
    let last_neighbors = timed(&mut times.neighbors, || {
        let spare = std::mem::take(&mut sim.workspace.spare_pairs);
        let list = density::neighbor_list(sim, &x_star, spare);
        std::mem::replace(&mut sim.workspace.neighbors, list)
    });
    let (walls, last_contacts) = timed(&mut times.walls, || {
        let walls = placed_walls(sim, dt);
        let kernels = wall_kernels(sim);
        let contacts = WallContacts::build(&x_star, &walls, &kernels, &weights, sim.scales());
        (
            walls,
            std::mem::replace(&mut sim.workspace.contacts, contacts),
        )
    });
    let (at_star, mut surface) = timed(&mut times.number_density, || {
        // n* with the wall lattice (Harada et al. 2008) and the source's ∇·u*
        let at_star = density::at_prediction::<K>(sim, &x_star, &u_start);
        // n* < beta n0 confirmed by a one-sided neighbourhood (Sun et al. 2022 §2.3)
        let surface = free_surface::detect_free_surface::<K>(sim, &x_star, &at_star.n);
        (at_star, surface)
    });
    timed(&mut times.assemble, || {
        // the Neumann extrapolation gradient of every wall contact (docs/method.md, walls)
        system.neumann = pressure_equation::neumann_gradients(sim, &u_start, dt);
        // source HS + ECS (Ikari, Khayyer & Gotoh 2015 eqs. 3, 10-11) and HL rows (eq. 9)
        pressure_equation::assemble_pressure_equation::<K>(
            sim,
            &weights,
            &x_star,
            &at_star,
            &mut surface,
            system,
            dt,
        );
    });
    drop(at_star);
    let (iterations, residual) = timed(&mut times.solve, || -> Result<_, SimError> {
        let (mut iterations, residual) = pressure_equation::solve_pressure(sim, system, &surface)?;
        if let Projection::Exact { blend } = sim.config.method.projection {
            let at = (&x_star[..], &surface.dirichlet[..]);
            iterations += exact::correct_to_exact_projection::<K>(sim, at, system, blend, dt)?;
        }
        Ok((iterations, residual))
    })?;
    // ∇p of every particle (fluid neighbours and virtual wall points)
    let gradient = timed(&mut times.correct, || {
        correction::pressure_gradients::<K>(sim, &x_star, &system.neumann)
    });
    if let Some(limit) = limit {
        // the step guard: dt was set from the speeds at the start of the step, and a
        // jet-root particle the correction accelerates several-fold would move more
        // than a spacing; x^{n+1} - x^n = dt u^{n+1}
        let moved = correction::largest_displacement(sim, &gradient, dt);
        if moved > limit {
            if let Some(rollback) = rollback {
                rollback.restore(sim, &u_start, (last_neighbors, last_contacts));
            }
            sim.stats.rejected_steps += 1;
            return Ok(Attempt::Rejected { dt, moved });
        }
    }
    timed(&mut times.correct, || {
        // u^{n+1} = u* - dt/rho ∇p, x^{n+1} = x* + dt (u^{n+1} - u*) (Sun et al. 2022 eqs. 11-12);
        // the wall loads
        let at = (&x_star[..], &system.neumann[..]);
        correction::correct_velocity_and_position::<K>(sim, &walls, at, &gradient, dt, &mut loads);
    });
    timed(&mut times.spacing, || {
        // the filter before the safety net, which must have the last word on wall approach
        if let Some(eps) = sim.config.method.velocity_filter {
            spacing::filter_velocity::<K>(sim, &x_star, eps);
        }
        if !sim.config.control.damping.is_empty() {
            spacing::absorb_waves(sim, dt);
        }
        spacing::keep_particles_apart(sim, &walls, dt, &mut loads);
        if let Some(a) = sim.config.method.shifting {
            spacing::shift_particles::<K>(sim, a);
        }
    });
    let (removed, max_speed) = timed(&mut times.bookkeeping, || {
        // n and ∇·u at the end of the step, for the error-compensating source
        density::update_number_density_and_divergence::<K>(sim, &x_star);
        sim.loads = total_loads(loads, sim.config.method.wall_load);
        for wall in &mut sim.walls {
            wall.state = wall.state.advanced(dt);
        }
        sim.time += dt;
        sim.steps += 1;
        sim.stats.particle_steps += sim.particles.len() as u64;
        sim.acceleration_dt = bookkeeping::acceleration_limited_dt(sim, &u_start, dt);
        sim.stats.total_solver_iterations += iterations as u64;
        let removed =
            bookkeeping::remove_particles_outside_domain(sim) + bookkeeping::remove_runaways(sim);
        bookkeeping::check_health(sim).map(|max_speed| (removed, max_speed))
    })?;
    // the last list's buffer is the next one's: the lists alternate between two buffers
    sim.workspace.spare_pairs = last_neighbors.into_pairs();
    Ok(Attempt::Taken(StepInfo {
        dt,
        solver_iterations: iterations,
        solver_residual: residual,
        unknowns: system.matrix.n,
        max_speed,
        removed,
    }))
}

/// Each wall object's load: pressure and viscosity; the repulsion safety net only with
/// the reaction estimator (the pressure integral reports its share apart).
fn total_loads(mut loads: Vec<WallLoad>, estimator: WallLoadKind) -> Vec<WallLoad> {
    for load in &mut loads {
        load.force = load.pressure_force + load.viscous_force;
        if estimator == WallLoadKind::Reaction {
            load.force += load.repulsion_force;
            load.moment += load.repulsion_moment;
        }
    }
    loads
}
