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
//! `exact` (the optional exact projection), `correction`, `spacing`, `bookkeeping`.

mod bookkeeping;
mod correction;
mod density;
mod exact;
mod explicit;
mod free_surface;
mod pressure_equation;
mod spacing;
mod walls;

use super::config::Projection;
use super::kernel::Kernel;
use super::simulation::{Attempt, SimError, Simulation, StageTimes, StepInfo, WallLoad};
use super::walls::WallContacts;
use crate::case::WallLoadKind;
use crate::math::Real;
use crate::with_kernel;
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
    sim.workspace.neighbors = density::neighbor_list(sim, &sim.particles.position);
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
/// particle would move farther than `limit` and leaves the state as it found it.
fn step<K: Kernel>(
    sim: &mut Simulation,
    dt: Real,
    limit: Option<Real>,
) -> Result<Attempt, SimError> {
    let mut times = StageTimes::default();
    let weights = KernelWeights::<K>::new(sim);
    // loads of this step, one per wall object, accumulated by every stage with a wall term
    let mut loads = vec![WallLoad::default(); sim.walls.len()];
    // what the stages before the correction overwrite, for a step the guard turns down
    let restore = limit.map(|_| {
        (
            sim.particles.pressure.clone(),
            sim.particles.free_surface.clone(),
        )
    });

    timed(&mut times.explicit_forces, || {
        // u* = u + dt (g + nu ∇²u), Sun et al. (2022) eq. 9; x* = x + dt u*, eq. 10
        explicit::apply_explicit_forces::<K>(sim, &weights, dt, &mut loads);
        explicit::predict_positions(sim, dt);
    });
    // neighbours at x* (cell grid, counting sort)
    // (the lists of the last step are kept until the step is accepted: the explicit
    // stage of a repeated step reads them)
    let last_neighbors = timed(&mut times.neighbors, || {
        let list = density::neighbor_list(sim, &sim.workspace.scratch.x_star);
        std::mem::replace(&mut sim.workspace.neighbors, list)
    });
    // the walls at their predicted pose and each particle's contacts with them
    let (walls, last_contacts) = timed(&mut times.walls, || {
        let walls = placed_walls(sim, dt);
        let kernels = wall_kernels(sim);
        let contacts = WallContacts::build(
            &sim.workspace.scratch.x_star,
            &walls,
            &kernels,
            &weights,
            sim.scales(),
        );
        (
            walls,
            std::mem::replace(&mut sim.workspace.contacts, contacts),
        )
    });
    timed(&mut times.number_density, || {
        // n* with the wall lattice (Harada et al. 2008) and the source's ∇·u*
        density::compute_number_density_and_divergence::<K>(sim);
        // n* < beta n0 confirmed by a one-sided neighbourhood (Sun et al. 2022 §2.3)
        free_surface::detect_free_surface::<K>(sim);
    });
    timed(&mut times.assemble, || {
        // the Neumann extrapolation gradient of every wall contact (docs/method.md, walls)
        pressure_equation::compute_neumann_gradients(sim, dt);
        // source HS + ECS (Ikari, Khayyer & Gotoh 2015 eqs. 3, 10-11) and HL rows (eq. 9)
        pressure_equation::assemble_pressure_equation::<K>(sim, &weights, dt);
    });
    let (iterations, residual) = timed(&mut times.solve, || -> Result<_, SimError> {
        let (mut iterations, residual) = pressure_equation::solve_pressure(sim)?;
        if let Projection::Exact { blend } = sim.config.method.projection {
            iterations += exact::correct_to_exact_projection::<K>(sim, blend, dt)?;
        }
        Ok((iterations, residual))
    })?;
    // ∇p of every particle (fluid neighbours and virtual wall points)
    let gradient = timed(&mut times.correct, || {
        correction::pressure_gradients::<K>(sim)
    });
    if let Some(limit) = limit {
        // the step guard: dt was set from the speeds at the start of the step, and a
        // jet-root particle the correction accelerates several-fold would move more
        // than a spacing; x^{n+1} - x^n = dt u^{n+1}
        let moved = correction::largest_displacement(sim, &gradient, dt);
        if moved > limit {
            let u_start = &sim.workspace.scratch.u_start;
            sim.particles.velocity.clone_from(u_start);
            if let Some((pressure, free_surface)) = restore {
                sim.particles.pressure = pressure;
                sim.particles.free_surface = free_surface;
            }
            sim.workspace.neighbors = last_neighbors;
            sim.workspace.contacts = last_contacts;
            sim.stats.rejected_steps += 1;
            sim.stats.stage_times += times;
            return Ok(Attempt::Rejected { dt, moved });
        }
    }
    timed(&mut times.correct, || {
        // u^{n+1} = u* - dt/rho ∇p, x^{n+1} = x* + dt (u^{n+1} - u*) (Sun et al. 2022 eqs. 11-12);
        // the wall loads
        correction::correct_velocity_and_position::<K>(sim, &walls, &gradient, dt, &mut loads);
    });
    timed(&mut times.spacing, || {
        // the filter before the safety net, which must have the last word on wall approach
        if let Some(eps) = sim.config.method.velocity_filter {
            spacing::filter_velocity::<K>(sim, eps);
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
        density::update_number_density_and_divergence::<K>(sim);
        sim.loads = total_loads(loads, sim.config.method.wall_load);
        for wall in &mut sim.walls {
            wall.state = wall.state.advanced(dt);
        }
        sim.time += dt;
        sim.steps += 1;
        sim.stats.particle_steps += sim.particles.len() as u64;
        sim.acceleration_dt = bookkeeping::acceleration_limited_dt(sim, dt);
        sim.stats.total_solver_iterations += iterations as u64;
        let removed =
            bookkeeping::remove_particles_outside_domain(sim) + bookkeeping::remove_runaways(sim);
        bookkeeping::check_health(sim).map(|max_speed| (removed, max_speed))
    })?;
    sim.stats.stage_times += times;
    Ok(Attempt::Taken(StepInfo {
        dt,
        solver_iterations: iterations,
        solver_residual: residual,
        unknowns: sim.workspace.scratch.matrix.n,
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
