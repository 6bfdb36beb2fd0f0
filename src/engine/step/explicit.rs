//! Explicit stage: gravity and viscosity give u*, and x* = x + dt u* (Sun et al. 2022
//! eqs. 9-10).

use super::walls::KernelWeights;
use crate::engine::kernel::Kernel;
use crate::engine::operators::{vector_laplacian_sums, Cloud};
use crate::engine::particles::Particles;
use crate::engine::resolution::Scales;
use crate::engine::simulation::{Simulation, WallLoad};
use crate::math::{vec2, Real, Vec2};
use rayon::prelude::*;

/// Gravity and (when nu > 0) viscosity: the fluid pairs' viscous Laplacian
/// (`operators::vector_laplacian_sums`, the case's form and Laplacian weight) plus the
/// walls' mirror terms (`WallContacts::viscous_mirror`, no slip or free slip), times
/// nu and the lattice coefficient. The particles' velocity becomes u*; returns u^n.
pub(super) fn apply_explicit_forces<K: Kernel>(
    sim: &mut Simulation,
    weights: &KernelWeights<K>,
    dt: Real,
    loads: &mut [WallLoad],
) -> Vec<Vec2> {
    let g = vec2(sim.config.params.gravity);
    let nu = sim.config.params.viscosity;
    let u_start = sim.particles.velocity.clone();
    if nu <= 0.0 {
        sim.particles
            .velocity
            .par_iter_mut()
            .for_each(|u| *u += g * dt);
        return u_start;
    }
    let c = sim.config.params.laplacian_coefficient;
    let (x, u) = (&sim.particles.position, &sim.particles.velocity);
    let (nb, contacts) = (&sim.workspace.neighbors, &sim.workspace.contacts);
    let free_slip: Vec<bool> = sim.walls.iter().map(|w| w.free_slip).collect();
    // a particle created after the last neighbour search has no list yet: the cloud is
    // the particles that have one
    let listed = nb.len().min(x.len());
    let cloud = Cloud::new(&x[..listed], nb, sim.config.params.re_lap).with_scales(sim.scales());
    let lap = vector_laplacian_sums::<K>(
        weights.classic_laplacian(),
        sim.config.method.viscosity,
        &cloud,
        u,
    );
    let accel: Vec<(Vec2, Vec2)> = (0..x.len())
        .into_par_iter()
        .map(|i| {
            if i >= listed {
                return (g, Vec2::zeros());
            }
            let wall = contacts.viscous_mirror(i, u[i], &free_slip);
            (g + (lap[i] + wall) * (nu * c), wall * (nu * c))
        })
        .collect();
    let m = sim.config.params.particle_mass;
    for (i, (a, _)) in accel.iter().enumerate() {
        sim.particles.velocity[i] += a * dt;
    }
    let scales = Scales::new(&sim.particles.scale, sim.config.multi_resolution);
    for (i, (_, aw)) in accel.iter().enumerate() {
        if i < sim.workspace.neighbors.len() {
            for ct in sim.workspace.contacts.of(i) {
                // split the wall acceleration between contacts by their Laplacian weight
                let total: Real = sim
                    .workspace
                    .contacts
                    .of(i)
                    .iter()
                    .map(|c| c.terms.laplacian_sum)
                    .sum();
                if total > 0.0 {
                    let share = aw * (ct.terms.laplacian_sum / total);
                    loads[ct.object as usize].viscous_force -= share * (m * scales.volume(i));
                }
            }
        }
    }
    u_start
}

/// x* = x + dt u*.
pub(super) fn predicted_positions(p: &Particles, dt: Real) -> Vec<Vec2> {
    p.position
        .par_iter()
        .zip(p.velocity.par_iter())
        .map(|(x, u)| x + u * dt)
        .collect()
}
