//! One projection step of semi-implicit MPS, as a list of named stages.
//!
//! Default scheme (MPS-HS-HL-ECS with an antisymmetric gradient, papers 003 and 004):
//! explicit viscosity and gravity give u*, x*; the pressure Poisson equation with the
//! higher-order source plus error-compensating terms is solved on x* with the
//! (lattice-normalised) higher-order Laplacian; the antisymmetric pair gradient corrects
//! velocity and position. Walls enter through the virtual-lattice sums of `walls`.
//!
//! Walls and the pressure equation (our formulation): virtual wall points take the
//! particle's pressure extrapolated with the Neumann condition of an accelerating wall,
//! p_k = p_i + rho (g - a_w) · (x_k - x_i) (notes §2.2), so the wall adds no unknowns
//! and no matrix entries, only right-hand-side terms; the same extrapolation gives the
//! wall part of the gradient, whose reaction is the load on the wall. The kinematic
//! condition enters the source: virtual points move with the wall, so the HS source
//! gains ∇Z · (u_i^n - u_w), the rate at which the wall lattice's share of n changes
//! with the relative velocity at the start of the step (the body-force part of u* is
//! already carried by the Neumann term; counting it twice over-corrects). With the PND
//! source (classic scheme) virtual points take p_i (Harada et al. 2008) and the wall
//! acts through the number density alone.
//!
//! With `scheme.projection = "exact"` the solved pressure is then corrected so that the
//! rows away from the free surface carry the HS divergence of the corrected velocity
//! itself instead of the Laplacian (`exact`: GMRES, preconditioned by the same AMG).

use super::kernel::Kernel;
use super::math::{vec2, Mat2, Real, Vec2};
use super::neighbors::NeighborList;
use super::operators::{gradient_row, laplacian_row, Cloud, LatticeConstants, Normalisation};
use super::params::DIM;
use super::pressure::{self, CsrMatrix, SolveParams};
use super::simulation::{SimError, Simulation, StepInfo, WallLoad};
use super::walls::pressure_load::pressure_loads;
use super::walls::{moment_about, PlacedWall, WallContact, WallContacts, WallKernels, WallWeights};
use crate::case::{
    GradientKind, LaplacianKind, Projection, SourceKind, SpacingControl, ViscosityKind,
    WallKinematics, WallLoadKind,
};
use crate::with_kernel;
use rayon::prelude::*;
use std::marker::PhantomData;
use std::time::Instant;

mod exact;

/// Buffers reused from step to step.
#[derive(Debug, Default)]
pub(crate) struct Scratch {
    x_star: Vec<Vec2>,
    /// u^n, before the explicit forces.
    u_start: Vec<Vec2>,
    n_star: Vec<Real>,
    unknown_of: Vec<u32>,
    particle_of: Vec<u32>,
    rhs: Vec<Real>,
    solution: Vec<Real>,
    neumann: Vec<Vec2>,
    /// Dirichlet value of each free-surface particle (0 elsewhere).
    surface_pressure: Vec<Real>,
    matrix: CsrMatrix,
    /// The source's terms beyond (rho/dt) ∇·u* (ECS, PND relaxation), per particle, for
    /// the exact projection.
    source_extra: Vec<Real>,
    /// The exact projection's correction to the approximate pressure, per particle
    /// (the next step's initial guess).
    exact_correction: Vec<Real>,
}

struct KernelWeights<K> {
    re: Real,
    re_lap: Real,
    classic_laplacian: bool,
    _k: PhantomData<K>,
}

impl<K: Kernel> KernelWeights<K> {
    fn new(sim: &Simulation) -> Self {
        Self {
            re: sim.params.re,
            re_lap: sim.params.re_lap,
            // Imoto's second-order Laplacian is the classic one (paper 000 Theorem 3.1)
            classic_laplacian: matches!(
                sim.scheme.laplacian,
                LaplacianKind::Classic | LaplacianKind::SecondOrder
            ),
            _k: PhantomData,
        }
    }
    #[inline]
    fn laplacian(&self, r: Real) -> Real {
        if self.classic_laplacian {
            K::w(r, self.re_lap)
        } else {
            K::hl(r, self.re_lap)
        }
    }
}

impl<K: Kernel> WallWeights for KernelWeights<K> {
    fn w(&self, r: Real) -> Real {
        K::w(r, self.re)
    }
    fn dw(&self, r: Real) -> Real {
        K::dw(r, self.re)
    }
    fn lap(&self, r: Real) -> Real {
        self.laplacian(r)
    }
}

fn wall_kernels(sim: &Simulation) -> WallKernels {
    WallKernels {
        l0: sim.params.l0,
        re: sim.params.re,
        re_lap: sim.params.re_lap,
    }
}

fn placed_walls(sim: &Simulation, dt: Real) -> Vec<PlacedWall> {
    sim.walls
        .iter()
        .map(|w| PlacedWall::new(w, w.state.advanced(dt)))
        .collect()
}

fn seconds(t: &mut Instant) -> f64 {
    let now = Instant::now();
    let s = (now - *t).as_secs_f64();
    *t = now;
    s
}

impl Simulation {
    /// Neighbours, wall contacts, number density and divergence of the current state: call
    /// it after moving particles by hand (as the perturbed-lattice stress scene does).
    pub fn initialize(&mut self) {
        with_kernel!(self.scheme.kernel, K => initialize::<K>(self))
    }

    /// Advance by `dt`. Body wall states must hold the pose and velocity at the start of
    /// the step; they are advanced kinematically (the coupling may overwrite them after).
    pub fn step(&mut self, dt: Real) -> Result<StepInfo, SimError> {
        with_kernel!(self.scheme.kernel, K => step::<K>(self, dt))
    }
}

fn initialize<K: Kernel>(sim: &mut Simulation) {
    let reach = sim.params.re.max(sim.params.re_lap);
    sim.neighbors = NeighborList::build(&sim.particles.position, reach);
    let walls = placed_walls(sim, 0.0);
    let weights = KernelWeights::<K>::new(sim);
    sim.contacts = WallContacts::build(
        &sim.particles.position,
        &walls,
        &wall_kernels(sim),
        &weights,
    );
    let n = number_density::<K>(
        &sim.particles.position,
        &sim.neighbors,
        &sim.contacts,
        sim.params.re,
    );
    let div = divergence::<K>(
        &sim.particles.position,
        &sim.particles.velocity,
        &sim.neighbors,
        sim.params.re,
        sim.params.divergence_coefficient,
    );
    sim.particles.number_density = n;
    sim.particles.number_density_rate = div;
}

/// The step, stage by stage.
fn step<K: Kernel>(sim: &mut Simulation, dt: Real) -> Result<StepInfo, SimError> {
    let mut clock = Instant::now();
    let weights = KernelWeights::<K>::new(sim);

    // loads of this step, one per wall object, accumulated by every stage with a wall term
    let mut loads = vec![WallLoad::default(); sim.walls.len()];

    // u* = u + dt (g + nu ∇²u); x* = x + dt u*  (paper 003 eqs. 9-10)
    apply_explicit_forces::<K>(sim, &weights, dt, &mut loads);
    predict_positions(sim, dt);
    sim.stage_times.explicit_forces += seconds(&mut clock);

    // neighbours at x*, walls at their predicted pose
    update_neighbors(sim);
    sim.stage_times.neighbors += seconds(&mut clock);
    let walls = placed_walls(sim, dt);
    sim.contacts = WallContacts::build(&sim.scratch.x_star, &walls, &wall_kernels(sim), &weights);
    sim.stage_times.walls += seconds(&mut clock);

    // n* with the wall lattice (Harada et al. 2008); free surface (PND + distribution)
    compute_number_density::<K>(sim);
    detect_free_surface::<K>(sim);
    sim.stage_times.number_density += seconds(&mut clock);

    // PPE: source (HS + ECS, paper 004 eqs. 3, 10-11), Laplacian (HL, eq. 9), Neumann walls
    compute_neumann_gradients(sim, dt);
    assemble_pressure_equation::<K>(sim, &weights, dt);
    sim.stage_times.assemble += seconds(&mut clock);
    let (mut iterations, residual) = solve_pressure(sim)?;
    if sim.scheme.projection == Projection::Exact {
        iterations += exact::correct_to_exact_projection::<K>(sim, dt)?;
    }
    sim.stage_times.solve += seconds(&mut clock);

    // u^{n+1} = u* - dt/rho ∇p, x^{n+1} = x* + dt (u^{n+1} - u*); wall loads as reactions
    correct_velocity_and_position::<K>(sim, &walls, dt, &mut loads);
    sim.stage_times.correct += seconds(&mut clock);
    // the filter before the safety net, which must have the last word on wall approach
    if sim.scheme.velocity_filter > 0.0 {
        filter_velocity::<K>(sim);
    }
    if !sim.damping.is_empty() {
        absorb_waves(sim, dt);
    }
    keep_particles_apart(sim, &walls, dt, &mut loads);
    if sim.scheme.shifting > 0.0 {
        shift_particles::<K>(sim);
    }
    sim.stage_times.spacing += seconds(&mut clock);

    // n and ∇·u at the end of the step, for the error-compensating source
    update_number_density_and_divergence::<K>(sim);
    // the pressure-integral load leaves the safety net out (its share is reported apart)
    let with_repulsion = sim.scheme.wall_load == WallLoadKind::Reaction;
    for load in &mut loads {
        load.force = load.pressure_force + load.viscous_force;
        if with_repulsion {
            load.force += load.repulsion_force;
            load.moment += load.repulsion_moment;
        }
    }
    sim.loads = loads;
    for wall in &mut sim.walls {
        wall.state = wall.state.advanced(dt);
    }
    sim.time += dt;
    sim.steps += 1;
    sim.total_solver_iterations += iterations as u64;
    let removed = remove_particles_outside_domain(sim) + remove_runaways(sim);
    let max_speed = check_health(sim)?;
    sim.stage_times.bookkeeping += seconds(&mut clock);
    Ok(StepInfo {
        dt,
        solver_iterations: iterations,
        solver_residual: residual,
        unknowns: sim.scratch.matrix.n,
        max_speed,
        removed,
    })
}

/// Gravity and (when nu > 0) viscosity with no-slip (or free-slip) walls.
fn apply_explicit_forces<K: Kernel>(
    sim: &mut Simulation,
    weights: &KernelWeights<K>,
    dt: Real,
    loads: &mut [WallLoad],
) {
    let g = vec2(sim.params.gravity);
    let nu = sim.params.viscosity;
    sim.scratch.u_start.clone_from(&sim.particles.velocity);
    if nu <= 0.0 {
        sim.particles
            .velocity
            .par_iter_mut()
            .for_each(|u| *u += g * dt);
        return;
    }
    let c = sim.params.laplacian_coefficient;
    let (x, u) = (&sim.particles.position, &sim.particles.velocity);
    let (nb, contacts) = (&sim.neighbors, &sim.contacts);
    let free_slip: Vec<bool> = sim.walls.iter().map(|w| w.free_slip).collect();
    let form = sim.scheme.viscosity;
    // a particle created after the last neighbour search has no list yet
    let accel: Vec<(Vec2, Vec2)> = (0..x.len())
        .into_par_iter()
        .map(|i| {
            if i >= nb.len() {
                return (g, Vec2::zeros());
            }
            let mut lap = Vec2::zeros();
            for &j in nb.of(i) {
                let j = j as usize;
                let rij = x[j] - x[i];
                let r = rij.norm();
                let du = u[j] - u[i];
                lap += match form {
                    ViscosityKind::Laplacian => du * weights.laplacian(r),
                    ViscosityKind::StrainRate if r > 0.0 => {
                        rij * ((DIM + 2.0) * du.dot(&rij) / (r * r) * weights.laplacian(r))
                    }
                    ViscosityKind::StrainRate => Vec2::zeros(),
                };
            }
            let mut wall = Vec2::zeros();
            for ct in contacts.of(i) {
                // mirror velocity 2 u_w - u_i (no slip); free slip mirrors the
                // normal component only, so the wall exerts no shear
                let relative = ct.wall_velocity - u[i];
                let mirrored = if free_slip[ct.object as usize] {
                    ct.normal * relative.dot(&ct.normal)
                } else {
                    relative
                };
                wall += mirrored * (2.0 * ct.terms.laplacian_sum);
            }
            (g + (lap + wall) * (nu * c), wall * (nu * c))
        })
        .collect();
    let m = sim.params.particle_mass;
    for (i, (a, _)) in accel.iter().enumerate() {
        sim.particles.velocity[i] += a * dt;
    }
    for (i, (_, aw)) in accel.iter().enumerate() {
        if i < sim.neighbors.len() {
            for ct in sim.contacts.of(i) {
                // split the wall acceleration between contacts by their Laplacian weight
                let total: Real = sim
                    .contacts
                    .of(i)
                    .iter()
                    .map(|c| c.terms.laplacian_sum)
                    .sum();
                if total > 0.0 {
                    let share = aw * (ct.terms.laplacian_sum / total);
                    loads[ct.object as usize].viscous_force -= share * m;
                }
            }
        }
    }
}

fn predict_positions(sim: &mut Simulation, dt: Real) {
    let p = &sim.particles;
    sim.scratch.x_star = p
        .position
        .par_iter()
        .zip(p.velocity.par_iter())
        .map(|(x, u)| x + u * dt)
        .collect();
}

fn update_neighbors(sim: &mut Simulation) {
    let reach = sim.params.re.max(sim.params.re_lap);
    sim.neighbors = NeighborList::build(&sim.scratch.x_star, reach);
}

fn number_density<K: Kernel>(
    x: &[Vec2],
    nb: &NeighborList,
    contacts: &WallContacts,
    re: Real,
) -> Vec<Real> {
    (0..x.len())
        .into_par_iter()
        .map(|i| {
            let mut n = 0.0;
            for &j in nb.of(i) {
                n += K::w((x[j as usize] - x[i]).norm(), re);
            }
            n + contacts
                .of(i)
                .iter()
                .map(|c| c.terms.number_density)
                .sum::<Real>()
        })
        .collect()
}

/// ∇·u ≈ -c Σ w'(r) r̂·(u_j - u_i): the HS form (paper 004 eq. 2), lattice-normalised.
fn divergence<K: Kernel>(
    x: &[Vec2],
    u: &[Vec2],
    nb: &NeighborList,
    re: Real,
    c: Real,
) -> Vec<Real> {
    (0..x.len())
        .into_par_iter()
        .map(|i| {
            let mut s = 0.0;
            for &j in nb.of(i) {
                let j = j as usize;
                let r = x[j] - x[i];
                let d = r.norm();
                if d > 0.0 && d < re {
                    s += K::dw(d, re) * r.dot(&(u[j] - u[i])) / d;
                }
            }
            -c * s
        })
        .collect()
}

fn compute_number_density<K: Kernel>(sim: &mut Simulation) {
    sim.scratch.n_star = number_density::<K>(
        &sim.scratch.x_star,
        &sim.neighbors,
        &sim.contacts,
        sim.params.re,
    );
}

/// Free surface: n* < beta n0, confirmed by a one-sided neighbourhood
/// (|Σ w r/r²| l0 / n above `surface_asymmetry`); below 0.8 n0 always.
fn detect_free_surface<K: Kernel>(sim: &mut Simulation) {
    let (x, nb, contacts) = (&sim.scratch.x_star, &sim.neighbors, &sim.contacts);
    let (n0, re, l0) = (sim.params.n0, sim.params.re, sim.params.l0);
    let beta = sim.scheme.surface_threshold;
    let asym_limit = sim.scheme.surface_asymmetry;
    let n_star = &sim.scratch.n_star;
    let offset = sim.scheme.surface_offset;
    let rho_g = vec2(sim.params.gravity) * sim.params.density;
    // (is surface, Dirichlet value): the surface lies half a spacing beyond the particle,
    // so its hydrostatic pressure is rho g·m̂ l0/2 (m̂ the inward normal). Gravity only:
    // an estimate from the previous pressure gradient feeds back into itself (measured:
    // a still tank drifted 2.5% after 1.3 s).
    let flags: Vec<(bool, Real)> = (0..x.len())
        .into_par_iter()
        .map(|i| {
            let n = n_star[i];
            if n >= beta * n0 {
                return (false, 0.0);
            }
            let mut m = Vec2::zeros();
            for &j in nb.of(i) {
                let r = x[j as usize] - x[i];
                let d2 = r.norm_squared();
                let d = d2.sqrt();
                if d < re {
                    m += r * (K::w(d, re) / d2);
                }
            }
            for c in contacts.of(i) {
                m += c.terms.moment1;
            }
            let one_sided = m.norm() * l0 / n.max(1e-12) > asym_limit;
            let surface = asym_limit <= 0.0 || n < 0.8 * n0 || one_sided;
            if !surface {
                return (false, 0.0);
            }
            let value = if offset && m.norm() > 0.0 {
                surface_value(rho_g, m / m.norm(), l0)
            } else {
                0.0
            };
            (true, value)
        })
        .collect();
    sim.particles.free_surface = flags.iter().map(|f| f.0).collect();
    sim.scratch.surface_pressure = flags.iter().map(|f| f.1).collect();
    release_isolated_clusters(sim);
}

/// Largest group of particles, cut off from every free-surface particle, that is taken
/// for spray and released to the surface pressure. The bulk of any real scene is far
/// larger; a completely filled closed tank is one group and is left alone.
const ISOLATED_CLUSTER_LIMIT: usize = 24;

/// A group of at most this many particles whose other neighbours are all free surface is
/// spray as well, even though the surface pressure reaches it.
const ENCLOSED_PAIR: usize = 2;

/// A few particles pressed into a wall corner, apart from the bulk, have their number
/// density made up by the walls, so they are not free surface; yet no Dirichlet
/// particle reaches them, and with Neumann walls on their sides their block of the
/// pressure equation is singular. Measured on the dam break at a/40: at the impact on the
/// far wall a spray particle hit one such particle, alone in the corner among surface
/// particles: its source took 11.7 MPa and threw it through the corner at 437 m/s. Each
/// group of at most [`ISOLATED_CLUSTER_LIMIT`] particles coupled in the Laplacian and
/// linked to no surface particle, and each group of at most [`ENCLOSED_PAIR`] whatever
/// it touches, becomes free surface (p = 0, as spray is). The search
/// starts only from particles touching a wall with fewer than half the lattice's
/// neighbours, and stops past the limit, so it costs nothing in the bulk.
fn release_isolated_clusters(sim: &mut Simulation) {
    let (x, nb, contacts) = (&sim.scratch.x_star, &sim.neighbors, &sim.contacts);
    let surface = &sim.particles.free_surface;
    let (re, re_lap) = (sim.params.re, sim.params.re_lap);
    let lattice_neighbours = lattice_neighbour_count(re / sim.params.l0);
    let seeds: Vec<usize> = (0..x.len().min(nb.len()))
        .into_par_iter()
        .filter(|&i| {
            !surface[i]
                && !contacts.of(i).is_empty()
                && 2 * nb
                    .of(i)
                    .iter()
                    .filter(|&&j| (x[j as usize] - x[i]).norm() < re)
                    .count()
                    < lattice_neighbours
        })
        .collect();
    let mut released: Vec<usize> = Vec::new();
    let mut seen = std::collections::HashSet::new();
    for seed in seeds {
        if !seen.insert(seed) {
            continue;
        }
        let mut group = vec![seed];
        let mut k = 0;
        let mut anchored = false;
        while k < group.len() && group.len() <= ISOLATED_CLUSTER_LIMIT {
            let i = group[k];
            k += 1;
            for &j in nb.of(i) {
                let j = j as usize;
                if (x[j] - x[i]).norm() >= re_lap {
                    continue;
                }
                if surface[j] {
                    anchored = true;
                } else if seen.insert(j) {
                    group.push(j);
                }
            }
        }
        let size = group.len();
        if size <= ENCLOSED_PAIR || (!anchored && size <= ISOLATED_CLUSTER_LIMIT) {
            released.extend(group);
        }
    }
    for i in released {
        sim.particles.free_surface[i] = true;
        sim.scratch.surface_pressure[i] = 0.0;
    }
}

/// Lattice sites within `radius` (in spacings) of a site, the site excluded.
fn lattice_neighbour_count(radius: Real) -> usize {
    let r = radius.ceil() as i64;
    (-r..=r)
        .flat_map(|a| (-r..=r).map(move |b| (a, b)))
        .filter(|&(a, b)| (a, b) != (0, 0) && (((a * a + b * b) as Real).sqrt() < radius))
        .count()
}

/// Below this tilt of the surface normal from the vertical, a free surface counts as level.
const LEVEL_SURFACE_COS: Real = 0.866_025_403_784_438_6; // cos 30°

/// Dirichlet value of a free-surface particle with inward normal `m_hat`: the hydrostatic
/// pressure half a spacing below the surface, rho |g| (l0/2) cos(tilt), taken as level
/// (cos = 1) up to a 30° tilt and falling linearly in cos beyond. Why flat: the normal of
/// a particle near a wall or a slightly displaced neighbour tilts by a few degrees, and a
/// value that follows it feeds the particle positions back into the surface pressure.
/// Measured on the still tank: with the plain rho g·m̂ l0/2 the top-row particles next to
/// the side walls took 48.9 Pa instead of 49.05, which drove a slow flow up the walls and
/// a particle-scale mode that grew from 2 s on (max speed 19 mm/s at 2.5 s, 0.46 m/s at
/// 4 s); with the level value the tank stays on the lattice.
fn surface_value(rho_g: Vec2, m_hat: Vec2, l0: Real) -> Real {
    let weight = rho_g.norm();
    if weight == 0.0 {
        return 0.0;
    }
    let cos = rho_g.dot(&m_hat) / weight;
    weight * 0.5 * l0 * (cos / LEVEL_SURFACE_COS).clamp(0.0, 1.0)
}

/// The extrapolation gradient c = rho (g - a_w) of every wall contact (module docs);
/// zero for the PND source (virtual points take p_i). With `wall_kinematics =
/// "neumann"` it also carries the particle's approach to the wall left over from the
/// last step, (rho/dt) min(0, (u_i - u_w)·n) n (zero when the fluid followed the wall),
/// so the virtual pressure behind the wall rises to push the particle back.
fn compute_neumann_gradients(sim: &mut Simulation, dt: Real) {
    let rho = sim.params.density;
    let g = vec2(sim.params.gravity);
    let extrapolate = sim.scheme.source != SourceKind::Pnd;
    let contacts = &sim.contacts;
    let base = |c: &WallContact| {
        if extrapolate {
            (g - c.wall_acceleration) * rho
        } else {
            Vec2::zeros()
        }
    };
    if sim.scheme.wall_kinematics == WallKinematics::Source || !extrapolate {
        sim.scratch.neumann = contacts.contacts.par_iter().map(base).collect();
        return;
    }
    let u = &sim.scratch.u_start;
    sim.scratch.neumann = (0..u.len())
        .into_par_iter()
        .flat_map_iter(|i| {
            contacts.of(i).iter().map(move |c| {
                let approach = (u[i] - c.wall_velocity).dot(&c.normal).min(0.0);
                base(c) + c.normal * (rho / dt * approach)
            })
        })
        .collect();
}

/// Wall share of the HS divergence: -c ∇Z · (u_i - u_w) (virtual points move with the wall).
fn add_wall_divergence(div: &mut [Real], u: &[Vec2], contacts: &WallContacts, c: Real) {
    div.par_iter_mut().enumerate().for_each(|(i, d)| {
        for ct in contacts.of(i) {
            *d -= c * ct
                .terms
                .number_density_gradient
                .dot(&(u[i] - ct.wall_velocity));
        }
    });
}

fn assemble_pressure_equation<K: Kernel>(
    sim: &mut Simulation,
    weights: &KernelWeights<K>,
    dt: Real,
) {
    let np = sim.particles.len();
    let p = &sim.params;
    let (rho, n0, c_lap) = (p.density, p.n0, p.laplacian_coefficient);
    let x = &sim.scratch.x_star;
    let nb = &sim.neighbors;
    let surface = &mut sim.particles.free_surface;
    // a particle with no Laplacian neighbour cannot be solved for: Dirichlet
    for i in 0..np {
        if !surface[i]
            && nb
                .of(i)
                .iter()
                .all(|&j| weights.laplacian((x[j as usize] - x[i]).norm()) == 0.0)
        {
            surface[i] = true;
            sim.scratch.surface_pressure[i] = 0.0;
        }
    }
    let dirichlet = &sim.scratch.surface_pressure;
    let surface = &sim.particles.free_surface;
    // the previous step's index maps, refilled (no allocation at a steady size)
    let mut unknown_of = std::mem::take(&mut sim.scratch.unknown_of);
    let mut particle_of = std::mem::take(&mut sim.scratch.particle_of);
    unknown_of.clear();
    unknown_of.resize(np, u32::MAX);
    particle_of.clear();
    for i in 0..np {
        if !surface[i] {
            unknown_of[i] = particle_of.len() as u32;
            particle_of.push(i as u32);
        }
    }
    // source term S of ∇²p - (rho alpha / dt²) p = S
    let mut div_star = divergence::<K>(
        x,
        &sim.particles.velocity,
        nb,
        p.re,
        p.divergence_coefficient,
    );
    if sim.scheme.wall_kinematics == WallKinematics::Source {
        add_wall_divergence(
            &mut div_star,
            &sim.scratch.u_start,
            &sim.contacts,
            p.divergence_coefficient,
        );
    }
    let n_prev = &sim.particles.number_density;
    let div_prev = &sim.particles.number_density_rate;
    let n_star = &sim.scratch.n_star;
    let source = sim.scheme.source;
    let gamma = sim.scheme.mixed_relaxation;
    let source_of = |i: usize| -> Real {
        match source {
            SourceKind::Pnd => -rho / (dt * dt) * (n_star[i] - n0) / n0,
            SourceKind::HigherOrder => rho / dt * div_star[i],
            SourceKind::HigherOrderEcs => {
                let dev = (n_prev[i] - n0) / n0;
                let alpha = dev.abs();
                let beta = (dt * div_prev[i]).abs();
                rho / dt * (div_star[i] + alpha * div_prev[i]) - beta * rho / (dt * dt) * dev
            }
            SourceKind::Mixed => {
                rho / dt * div_star[i] - gamma * rho / (dt * dt) * (n_prev[i] - n0) / n0
            }
        }
    };
    let source_extra: Vec<Real> = if sim.scheme.projection == Projection::Exact {
        (0..np)
            .into_par_iter()
            .map(|i| source_of(i) - rho / dt * div_star[i])
            .collect()
    } else {
        Vec::new()
    };
    let compress = rho * sim.scheme.compressibility / (dt * dt);
    let rho_g = vec2(p.gravity) * rho;
    let well_balanced = sim.scheme.hydrostatic_ghosts;
    let contacts = &sim.contacts;
    // CHL, anisotropic and least-squares rows come from engine::operators for particles
    // away from walls; rows with wall contacts keep the tabulated (HL/classic) form,
    // which carries the Neumann condition, with the same lattice normalisation.
    let kind = sim.scheme.laplacian;
    let operator_rows = !kind.is_symmetric();
    let cloud = Cloud::new(x, nb, p.re_lap);
    let lattice = Normalisation::Reference(LatticeConstants::compute::<K>(p.l0, p.re_lap, 2));
    let neumann = &sim.scratch.neumann;
    let nu = particle_of.len();
    // the fill n*/n0 of each neighbourhood, floored (`Scheme::laplacian_fill_floor`);
    // none when disabled, so the default pays nothing per pair
    let floor = sim.scheme.laplacian_fill_floor;
    let fills: Option<Vec<Real>> = (floor < 1.0).then(|| {
        n_star
            .par_iter()
            .map(|n| (n / n0).clamp(floor, 1.0))
            .collect()
    });
    let fills = fills.as_deref();
    // row `row` appended to cols/vals; returns the right-hand side
    let row_entries = |row: usize, cols: &mut Vec<u32>, vals: &mut Vec<Real>| -> Real {
        let i = particle_of[row] as usize;
        let mut diag = compress;
        let mut b = -source_of(i);
        if operator_rows && contacts.of(i).is_empty() {
            for (j, c) in laplacian_row::<K>(kind, &cloud, lattice, i).off_diagonal {
                diag += c;
                let uj = unknown_of[j];
                if uj != u32::MAX {
                    cols.push(uj);
                    vals.push(-c);
                } else {
                    b += c * dirichlet[j];
                }
            }
            cols.push(row as u32);
            vals.push(diag);
            return b;
        }
        // Σ L r over the neighbours present (fluid and wall lattice): zero on a full
        // lattice, the first-order error of the Laplacian where the free surface or
        // disorder truncates the neighbourhood
        let mut first_moment = Vec2::zeros();
        // a pair's weight over the mean fill of its two particles: symmetric, and 1 in
        // a full neighbourhood
        let pair_scale = |j: usize| fills.map_or(1.0, |f| 2.0 / (f[i] + f[j]));
        for &j in nb.of(i) {
            let r = x[j as usize] - x[i];
            let l = c_lap * weights.laplacian(r.norm()) * pair_scale(j as usize);
            if l == 0.0 {
                continue;
            }
            first_moment += r * l;
            diag += l;
            let uj = unknown_of[j as usize];
            if uj != u32::MAX {
                cols.push(uj);
                vals.push(-l);
            } else {
                b += l * dirichlet[j as usize];
            }
        }
        cols.push(row as u32);
        vals.push(diag);
        let base = contacts.offsets[i] as usize;
        let wall_scale = fills.map_or(1.0, |f| 1.0 / f[i]);
        for (k, c) in contacts.of(i).iter().enumerate() {
            b += c_lap * wall_scale * neumann[base + k].dot(&c.terms.laplacian_moment);
            first_moment += c.terms.laplacian_moment * (c_lap * wall_scale);
        }
        // Hydrostatic consistency: the missing part of the neighbourhood (-Σ L r) is
        // filled with ghosts carrying the hydrostatic pressure p_i + rho g·r, so a
        // hydrostatic field solves the discrete equation whatever the arrangement.
        // Without it the row below the free surface, which misses the point 2 l0
        // above it, sets the whole column 0.14 l0 rho g (14 Pa at 1 cm) too high and lifts the top row.
        if well_balanced {
            b -= rho_g.dot(&first_moment);
        }
        b
    };
    // Rows in parallel chunks written straight into per-chunk arrays (one task per
    // chunk, rows in order: deterministic), then copied into the previous step's
    // matrix buffers: no allocation per row and no second matrix alive at the peak.
    const CHUNK: usize = 2048;
    let parts: Vec<(Vec<u32>, Vec<u32>, Vec<Real>, Vec<Real>)> = (0..nu.div_ceil(CHUNK))
        .into_par_iter()
        .map(|c| {
            let (lo, hi) = (c * CHUNK, ((c + 1) * CHUNK).min(nu));
            let mut lens = Vec::with_capacity(hi - lo);
            let mut rhs = Vec::with_capacity(hi - lo);
            // at most one entry per neighbour plus the diagonal
            let bound: usize = (lo..hi)
                .map(|row| nb.of(particle_of[row] as usize).len() + 1)
                .sum();
            let mut cols = Vec::with_capacity(bound);
            let mut vals = Vec::with_capacity(bound);
            for row in lo..hi {
                let before = cols.len();
                rhs.push(row_entries(row, &mut cols, &mut vals));
                lens.push((cols.len() - before) as u32);
            }
            (lens, cols, vals, rhs)
        })
        .collect();
    let nnz = parts.iter().map(|p| p.1.len()).sum();
    let mut m = std::mem::take(&mut sim.scratch.matrix);
    m.n = nu;
    m.row_ptr.clear();
    m.col.clear();
    m.val.clear();
    m.row_ptr.reserve(nu + 1);
    m.col.reserve(nnz);
    m.val.reserve(nnz);
    m.row_ptr.push(0);
    let mut rhs = std::mem::take(&mut sim.scratch.rhs);
    rhs.clear();
    let mut last = 0;
    for (lens, cols, vals, b) in parts {
        for l in lens {
            last += l as usize;
            m.row_ptr.push(last);
        }
        m.col.extend_from_slice(&cols);
        m.val.extend_from_slice(&vals);
        rhs.extend_from_slice(&b);
    }
    // warm start from the last pressures
    let mut solution = std::mem::take(&mut sim.scratch.solution);
    solution.clear();
    solution.extend(
        particle_of
            .iter()
            .map(|&i| sim.particles.pressure[i as usize]),
    );
    sim.scratch.solution = solution;
    sim.scratch.matrix = m;
    sim.scratch.rhs = rhs;
    sim.scratch.unknown_of = unknown_of;
    sim.scratch.particle_of = particle_of;
    sim.scratch.source_extra = source_extra;
}

fn solve_pressure(sim: &mut Simulation) -> Result<(usize, Real), SimError> {
    let params = SolveParams {
        tolerance: sim.scheme.solver_tolerance,
        max_iterations: sim.scheme.solver_max_iterations,
    };
    let s = &mut sim.scratch;
    let policy = pressure::ReusePolicy {
        rebuild_interval: sim.scheme.amg_rebuild_interval,
        // Keep, not Galerkin: recomputing R A P saved only a quarter of the setup
        // (dam break, 10k particles, interval 10: setup 10.3 vs 13.8 ms/step rebuilding
        // every step, against 2.1 ms/step when keeping) for the same iterations (14.0)
        coarse: pressure::CoarseUpdate::Keep,
    };
    // rows are keyed by particle, so a hierarchy survives changes of the unknown set
    let info = pressure::solve_reusing(
        sim.scheme.solver,
        &s.matrix,
        &s.rhs,
        &mut s.solution,
        params,
        pressure::Reuse {
            cache: &mut sim.solver_cache,
            keys: &s.particle_of,
            key_space: s.unknown_of.len(),
            policy,
        },
    )
    .map_err(|e| SimError::Solver {
        step: sim.steps + 1,
        time: sim.time,
        reason: e.to_string(),
    })?;
    let clip = sim.scheme.clip_negative_pressure;
    let p = &mut sim.particles.pressure;
    p.copy_from_slice(&s.surface_pressure);
    for (row, &i) in s.particle_of.iter().enumerate() {
        let v = s.solution[row];
        p[i as usize] = if clip { v.max(0.0) } else { v };
    }
    Ok((info.iterations, info.relative_residual))
}

fn correct_velocity_and_position<K: Kernel>(
    sim: &mut Simulation,
    walls: &[PlacedWall],
    dt: Real,
    loads: &mut [WallLoad],
) {
    let prm = &sim.params;
    let (re, rho, c_grad, m, n0) = (
        prm.re,
        prm.density,
        prm.gradient_coefficient,
        prm.particle_mass,
        prm.n0,
    );
    let x = &sim.scratch.x_star;
    let p = &sim.particles.pressure;
    let nb = &sim.neighbors;
    let n = x.len();
    // minimum pressure over each neighbourhood (stability of the classic gradient)
    let p_min: Vec<Real> = (0..n)
        .into_par_iter()
        .map(|i| {
            nb.of(i)
                .iter()
                .filter(|&&j| (x[j as usize] - x[i]).norm() < re)
                .map(|&j| p[j as usize])
                .fold(p[i], Real::min)
        })
        .collect();
    let form = sim.scheme.gradient;
    let kappa = sim.scheme.gradient_stabilization;
    let close = sim.scheme.stabilization_distance * sim.params.l0;
    let contacts = &sim.contacts;
    let neumann = &sim.scratch.neumann;
    // Anisotropic and least-squares gradients (engine::operators, paper 000 eq. 28 and
    // LSMPS) away from walls, in the linear form Σ g_ij (p_j - p_i) like GC; particles
    // with wall contacts use GC, whose moment matrix includes the virtual wall points.
    let operator_gradient = matches!(form, GradientKind::Anisotropic | GradientKind::LeastSquares);
    let cloud = Cloud::new(x, nb, re);
    let lattice = Normalisation::Reference(LatticeConstants::compute::<K>(prm.l0, re, 2));
    // The gradient that moves the particles (fluid neighbours + virtual wall points).
    let total: Vec<Vec2> = (0..n)
        .into_par_iter()
        .map(|i| {
            let wall_contacts = contacts.of(i);
            if operator_gradient && wall_contacts.is_empty() {
                return gradient_row::<K>(form, &cloud, lattice, i)
                    .iter()
                    .map(|&(j, g)| g * (p[j] - p[i]))
                    .sum();
            }
            let base = contacts.offsets[i] as usize;
            let (mut s_fluid, mut s_min, mut s_sym) = (Vec2::zeros(), Vec2::zeros(), Vec2::zeros());
            let mut s_close = Vec2::zeros();
            let mut moment = Mat2::zeros();
            for &j in nb.of(i) {
                let j = j as usize;
                let r = x[j] - x[i];
                let d2 = r.norm_squared();
                let d = d2.sqrt();
                if d >= re || d == 0.0 {
                    continue;
                }
                let w = K::w(d, re) / d2;
                s_fluid += r * ((p[j] - p[i]) * w);
                s_min += r * ((p[j] - p_min[i]) * w);
                if d < close {
                    s_close += r * w;
                }
                s_sym += match form {
                    GradientKind::Cmps => r * ((p[i] + p[j] - p_min[i] - p_min[j]) * w),
                    _ => r * ((p[i] + p[j]) * w),
                };
                moment += r * r.transpose() * w;
            }
            // virtual points: p_k - p_i = c · r_ik
            let mut wall_linear = Vec2::zeros();
            let mut wall_m1 = Vec2::zeros();
            for (k, c) in wall_contacts.iter().enumerate() {
                wall_linear += c.terms.moment2_times(neumann[base + k]);
                wall_m1 += c.terms.moment1;
                let [xx, xy, yy] = c.terms.moment2;
                moment += Mat2::new(xx, xy, xy, yy);
            }
            let classic = (s_min + wall_m1 * (p[i] - p_min[i]) + wall_linear) * c_grad;
            match form {
                GradientKind::MinimumPressure => classic,
                GradientKind::Symmetric => (s_sym + wall_m1 * (2.0 * p[i]) + wall_linear) * c_grad,
                GradientKind::Cmps => {
                    (s_sym + wall_m1 * (2.0 * (p[i] - p_min[i])) + wall_linear) * c_grad
                }
                _ => {
                    // plus the repulsive part of the minimum-pressure form, (p_i - p̂_i) Σ r w / r²,
                    // over pairs closer than `stabilization_distance`: silent on the lattice (still
                    // water stays still), pushing particles apart where they cluster
                    let stabilizer = s_close * ((p[i] - p_min[i]) * kappa * c_grad);
                    match corrected_gradient_matrix(&moment, n0) {
                        Some(c) => c * (s_fluid + wall_linear) / n0 + stabilizer,
                        None => classic,
                    }
                }
            }
        })
        .collect();
    if sim.scheme.wall_load == WallLoadKind::PressureIntegral {
        let w = |d: Real| K::w(d, re);
        let integral = pressure_loads(
            x,
            p,
            &nb.grid,
            walls,
            &w,
            rho,
            vec2(prm.gravity),
            prm.l0,
            re,
        );
        for (load, (f, moment)) in loads.iter_mut().zip(integral) {
            load.pressure_force += f;
            load.moment += moment;
        }
    }
    // Loads: the conservative (antisymmetric) wall term, virtual pressure p_k = p_i + c·r:
    // Σ_k (p_i + p_k) r w / r² — a pressure integral over the wall through the MPS wall
    // operator, whose sum over a still tank is the fluid's weight.
    let reaction = sim.scheme.wall_load == WallLoadKind::Reaction;
    for i in (0..n).filter(|_| reaction) {
        let base = contacts.offsets[i] as usize;
        for (k, c) in contacts.of(i).iter().enumerate() {
            let gw = (c.terms.moment1 * (2.0 * p[i]) + c.terms.moment2_times(neumann[base + k]))
                * c_grad;
            let f = gw * (m / rho);
            let load = &mut loads[c.object as usize];
            load.pressure_force += f;
            load.moment += moment_about(walls[c.object as usize].state.center_of_mass, c.point, f);
        }
    }
    let scale = dt / rho;
    let parts = &mut sim.particles;
    parts
        .velocity
        .par_iter_mut()
        .zip(total.par_iter())
        .for_each(|(u, g)| *u -= g * scale);
    parts
        .position
        .par_iter_mut()
        .zip(x.par_iter())
        .zip(total.par_iter())
        .for_each(|((pos, xs), g)| *pos = xs - g * (scale * dt));
}

/// The GC matrix C = [(1/n0) Σ w r rᵀ / r²]⁻¹ from the moments Σ w r rᵀ / r² (fluid
/// and virtual wall points); on the full lattice C = d I. `None` where the moments are
/// too degenerate to invert safely (below 0.3 of the lattice's determinant): the
/// gradient then falls back to the classic normalisation.
fn corrected_gradient_matrix(moment: &Mat2, n0: Real) -> Option<Mat2> {
    let mm = moment / n0;
    let lattice_det = (1.0 / DIM).powi(2);
    if mm.determinant() > 0.3 * lattice_det {
        mm.try_inverse()
    } else {
        None
    }
}

/// Safety net: pairwise collision below `collision_distance` l0 and an inelastic
/// wall impulse below `wall_repulsion_distance` l0 (textbook values 0.5 and e = 0.2).
fn keep_particles_apart(
    sim: &mut Simulation,
    walls: &[PlacedWall],
    dt: Real,
    loads: &mut [WallLoad],
) {
    let l0 = sim.params.l0;
    let e = sim.scheme.collision_restitution;
    let m = sim.params.particle_mass;
    let n = sim.particles.len();
    if sim.scheme.spacing_control == SpacingControl::Collision {
        let rc = sim.scheme.collision_distance * l0;
        let (x, u, nb) = (
            &sim.particles.position,
            &sim.particles.velocity,
            &sim.neighbors,
        );
        let du: Vec<Vec2> = (0..n)
            .into_par_iter()
            .map(|i| {
                let mut d = Vec2::zeros();
                for &j in nb.of(i) {
                    let j = j as usize;
                    let r = x[j] - x[i];
                    let dist = r.norm();
                    if dist < rc && dist > 0.0 {
                        let rh = r / dist;
                        let vn = (u[j] - u[i]).dot(&rh);
                        if vn < 0.0 {
                            d += rh * (0.5 * (1.0 + e) * vn);
                        }
                    }
                }
                d
            })
            .collect();
        let parts = &mut sim.particles;
        for i in 0..n {
            parts.velocity[i] += du[i];
            parts.position[i] += du[i] * dt;
        }
    }
    let rw = sim.scheme.wall_repulsion_distance * l0;
    if rw > 0.0 {
        for i in 0..n {
            for c in sim.contacts.of(i) {
                if c.distance >= rw && !c.penetrated {
                    continue;
                }
                let u = sim.particles.velocity[i];
                let vn = (u - c.wall_velocity).dot(&c.normal);
                let mut du = Vec2::zeros();
                if vn < 0.0 {
                    du = -c.normal * ((1.0 + e) * vn);
                }
                sim.particles.velocity[i] += du;
                let mut pos = sim.particles.position[i] + du * dt;
                if c.penetrated {
                    // back outside, half the safety distance off the surface
                    pos = c.point + c.normal * (0.5 * rw);
                }
                sim.particles.position[i] = pos;
                let f = -du * (m / dt);
                let load = &mut loads[c.object as usize];
                load.repulsion_force += f;
                load.repulsion_moment +=
                    moment_about(walls[c.object as usize].state.center_of_mass, c.point, f);
            }
        }
    }
}

/// The velocity filter (`scheme.velocity_filter`): u_i += eps Σ_j w_ij (u_j - u_i) / n0
/// over the fluid neighbours at x*. The pair weights are symmetric, so the fluid's
/// momentum is unchanged; a smooth field changes by O(eps l0² ∇²u) per step, while the
/// odd-even mode (neighbours moving in opposite directions, invisible to the divergence
/// of the PPE source and to the gradient) loses a share of order eps every step.
fn filter_velocity<K: Kernel>(sim: &mut Simulation) {
    let (re, n0) = (sim.params.re, sim.params.n0);
    let eps = sim.scheme.velocity_filter;
    let (x, u, nb) = (&sim.scratch.x_star, &sim.particles.velocity, &sim.neighbors);
    let du: Vec<Vec2> = (0..u.len())
        .into_par_iter()
        .map(|i| {
            if i >= nb.len() {
                return Vec2::zeros();
            }
            let mut s = Vec2::zeros();
            for &j in nb.of(i) {
                let j = j as usize;
                let d = (x[j] - x[i]).norm();
                if d < re && d > 0.0 {
                    s += (u[j] - u[i]) * K::w(d, re);
                }
            }
            s * (eps / n0)
        })
        .collect();
    for (ui, d) in sim.particles.velocity.iter_mut().zip(du) {
        *ui += d;
    }
}

/// Fickian particle shifting (Lind et al. 2012, in MPS form): δr_i = -A l0² ∇n_i / n0,
/// with ∇n_i = Σ_j w'(r_ij) (x_i - x_j)/r_ij plus the wall lattice's ∇Z, so particles
/// drift from crowded to sparse places and a wall counts as filled (no shift into it).
/// Next to the free surface (a surface particle within r_e) only the tangential part
/// is kept: the surface deficit of n is physical, not disorder. The shift is capped at
/// 0.1 l0 per step. Velocities are not re-interpolated: shifts are O(A l0) per step.
fn shift_particles<K: Kernel>(sim: &mut Simulation) {
    let (l0, re, n0) = (sim.params.l0, sim.params.re, sim.params.n0);
    let a = sim.scheme.shifting;
    let (x, nb, contacts, surface) = (
        &sim.particles.position,
        &sim.neighbors,
        &sim.contacts,
        &sim.particles.free_surface,
    );
    let shift: Vec<Vec2> = (0..x.len())
        .into_par_iter()
        .map(|i| {
            let mut grad = Vec2::zeros();
            let mut near_surface = surface[i];
            for &j in nb.of(i) {
                let j = j as usize;
                let r = x[i] - x[j];
                let d = r.norm();
                if d >= re || d == 0.0 {
                    continue;
                }
                grad += r * (K::dw(d, re) / d);
                near_surface |= surface[j];
            }
            for c in contacts.of(i) {
                grad += c.terms.number_density_gradient;
            }
            let mut dr = grad * (-a * l0 * l0 / n0);
            if near_surface {
                let g = grad.norm();
                if g > 0.0 {
                    let normal = grad / g;
                    dr -= normal * dr.dot(&normal);
                }
            }
            let cap = 0.1 * l0;
            let len = dr.norm();
            if len > cap {
                dr *= cap / len;
            }
            dr
        })
        .collect();
    for (xi, dr) in sim.particles.position.iter_mut().zip(shift) {
        *xi += dr;
    }
}

/// Sponge layers: u <- u / (1 + alpha dt), implicit so any rate is stable. Positions
/// of this step are already set; the damped velocity moves the particle from the next.
fn absorb_waves(sim: &mut Simulation, dt: Real) {
    let layers = &sim.damping;
    let x = &sim.particles.position;
    sim.particles
        .velocity
        .par_iter_mut()
        .enumerate()
        .for_each(|(i, u)| {
            let alpha: Real = layers.iter().map(|l| l.rate(x[i])).sum();
            if alpha > 0.0 {
                *u /= 1.0 + alpha * dt;
            }
        });
}

fn update_number_density_and_divergence<K: Kernel>(sim: &mut Simulation) {
    let re = sim.params.re;
    let (x, xs, nb, contacts) = (
        &sim.particles.position,
        &sim.scratch.x_star,
        &sim.neighbors,
        &sim.contacts,
    );
    let n: Vec<Real> = (0..x.len())
        .into_par_iter()
        .map(|i| {
            let mut s = 0.0;
            for &j in nb.of(i) {
                s += K::w((x[j as usize] - x[i]).norm(), re);
            }
            for c in contacts.of(i) {
                s += (c.terms.number_density
                    + c.terms.number_density_gradient.dot(&(x[i] - xs[i])))
                .max(0.0);
            }
            s
        })
        .collect();
    let mut div = divergence::<K>(
        x,
        &sim.particles.velocity,
        nb,
        re,
        sim.params.divergence_coefficient,
    );
    // the same divergence as the source's (with or without the wall's virtual points)
    if sim.scheme.wall_kinematics == WallKinematics::Source {
        add_wall_divergence(
            &mut div,
            &sim.particles.velocity,
            contacts,
            sim.params.divergence_coefficient,
        );
    }
    sim.particles.number_density = n;
    sim.particles.number_density_rate = div;
}

fn remove_particles_outside_domain(sim: &mut Simulation) -> usize {
    let (lo, hi) = (sim.domain_min, sim.domain_max);
    let keep: Vec<bool> = sim
        .particles
        .position
        .iter()
        .map(|p| p.x >= lo.x && p.y >= lo.y && p.x <= hi.x && p.y <= hi.y)
        .collect();
    remove_particles(sim, &keep)
}

/// Remove the particles faster than the speed limit while the allowance
/// (`scheme.runaway_allowance`) lasts; past it they stay, and `check_health` fails the
/// run on the first. A non-finite velocity is never removed: that is a diverged step.
fn remove_runaways(sim: &mut Simulation) -> usize {
    // no allowance left: nothing to scan for, check_health reports the first runaway
    if sim.runaways >= sim.runaway_budget {
        return 0;
    }
    let limit = sim.speed_limit;
    let fast: Vec<usize> = (0..sim.particles.len())
        .into_par_iter()
        .filter(|&i| sim.particles.velocity[i].norm() > limit)
        .collect();
    if fast.is_empty() || sim.runaways + fast.len() > sim.runaway_budget {
        return 0;
    }
    if sim.first_runaway.is_none() {
        let i = fast[0];
        let (x, u) = (sim.particles.position[i], sim.particles.velocity[i]);
        sim.first_runaway = Some(format!(
            "step {}, t = {:.6} s: particle {i} at ({:.4}, {:.4}) reached {:.3} m/s (limit {limit:.3} m/s)",
            sim.steps,
            sim.time,
            x.x,
            x.y,
            u.norm()
        ));
    }
    sim.runaways += fast.len();
    let mut keep = vec![true; sim.particles.len()];
    for i in fast {
        keep[i] = false;
    }
    remove_particles(sim, &keep)
}

/// Keep the particles flagged in `keep` (counted in `sim.removed`), with their lists.
fn remove_particles(sim: &mut Simulation, keep: &[bool]) -> usize {
    let removed = keep.iter().filter(|k| !**k).count();
    if removed > 0 {
        sim.particles.retain(&keep);
        sim.removed += removed;
        // the particles are renumbered: the AMG hierarchy's row keys mean nothing now
        sim.solver_cache.invalidate();
        // lists index particles: rebuild them for the next step's explicit stage
        let reach = sim.params.re.max(sim.params.re_lap);
        sim.neighbors = NeighborList::build(&sim.particles.position, reach);
        let keep_contacts = {
            let mut offsets = vec![0u32];
            let mut contacts = Vec::new();
            for (i, k) in keep.iter().enumerate() {
                if *k {
                    contacts.extend_from_slice(sim.contacts.of(i));
                    offsets.push(contacts.len() as u32);
                }
            }
            WallContacts { offsets, contacts }
        };
        sim.contacts = keep_contacts;
    }
    removed
}

/// Non-finite values, runaway speed or collapsed number density end the run.
fn check_health(sim: &Simulation) -> Result<Real, SimError> {
    let p = &sim.particles;
    let fail = |i: usize, what: String| SimError::Diverged {
        step: sim.steps,
        time: sim.time,
        particle: i,
        x: p.position[i].x,
        y: p.position[i].y,
        what,
    };
    if p.is_empty() {
        return Err(SimError::NoParticles {
            step: sim.steps,
            time: sim.time,
        });
    }
    let mut max_speed: Real = 0.0;
    for i in 0..p.len() {
        let (x, u) = (p.position[i], p.velocity[i]);
        if !(x.x.is_finite() && x.y.is_finite()) {
            return Err(fail(i, "non-finite position".into()));
        }
        if !(u.x.is_finite() && u.y.is_finite()) {
            return Err(fail(i, "non-finite velocity".into()));
        }
        if !p.pressure[i].is_finite() {
            return Err(fail(i, "non-finite pressure".into()));
        }
        let s = u.norm();
        if s > sim.speed_limit {
            return Err(fail(
                i,
                format!(
                    "runaway velocity {s:.3} m/s (limit {:.3} m/s)",
                    sim.speed_limit
                ),
            ));
        }
        if p.number_density[i] > 4.0 * sim.params.n0 {
            return Err(fail(
                i,
                format!(
                    "particle number density collapsed to {:.2} n0",
                    p.number_density[i] / sim.params.n0
                ),
            ));
        }
        max_speed = max_speed.max(s);
    }
    Ok(max_speed)
}
