//! Explicit stage: gravity and viscosity give u*, and x* = x + dt u* (Sun et al. 2022
//! eqs. 9-10).

use super::walls::KernelWeights;
use crate::case::ViscosityKind;
use crate::engine::kernel::Kernel;
use crate::engine::params::DIM;
use crate::engine::resolution::Scales;
use crate::engine::simulation::{Simulation, WallLoad};
use crate::math::{vec2, Real, Vec2};
use rayon::prelude::*;

/// Gravity and (when nu > 0) viscosity with no-slip (or free-slip) walls.
pub(super) fn apply_explicit_forces<K: Kernel>(
    sim: &mut Simulation,
    weights: &KernelWeights<K>,
    dt: Real,
    loads: &mut [WallLoad],
) {
    let g = vec2(sim.config.params.gravity);
    let nu = sim.config.params.viscosity;
    sim.workspace
        .scratch
        .u_start
        .clone_from(&sim.particles.velocity);
    if nu <= 0.0 {
        sim.particles
            .velocity
            .par_iter_mut()
            .for_each(|u| *u += g * dt);
        return;
    }
    let c = sim.config.params.laplacian_coefficient;
    let (x, u) = (&sim.particles.position, &sim.particles.velocity);
    let (nb, contacts) = (&sim.workspace.neighbors, &sim.workspace.contacts);
    let free_slip: Vec<bool> = sim.walls.iter().map(|w| w.free_slip).collect();
    let form = sim.config.method.viscosity;
    let scales = Scales::new(&sim.particles.scale, sim.config.multi_resolution);
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
                // the pair's radius and volume factor (`resolution`)
                let (s, v) = scales.pair(i, j);
                let l = weights.laplacian_scaled(r, s) * v;
                lap += match form {
                    ViscosityKind::Laplacian => du * l,
                    ViscosityKind::StrainRate if r > 0.0 => {
                        rij * ((DIM + 2.0) * du.dot(&rij) / (r * r) * l)
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
}

pub(super) fn predict_positions(sim: &mut Simulation, dt: Real) {
    let p = &sim.particles;
    sim.workspace.scratch.x_star = p
        .position
        .par_iter()
        .zip(p.velocity.par_iter())
        .map(|(x, u)| x + u * dt)
        .collect();
}
