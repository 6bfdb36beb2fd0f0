//! Spacing control after the correction: velocity filter, sponge layers, the collision
//! and wall-repulsion safety net, particle shifting.

use crate::case::ViscosityKind;
use crate::engine::config::SpacingControl;
use crate::engine::kernel::Kernel;
use crate::engine::operators::{
    collision_velocity_changes, number_density_gradient, vector_laplacian_sums, Cloud,
};
use crate::engine::simulation::{Simulation, WallLoad};
use crate::engine::walls::{moment_about, PlacedWall};
use crate::math::{Real, Vec2};
use rayon::prelude::*;

/// Safety net: pairwise collision below `collision_distance` l0 and an inelastic
/// wall impulse below `wall_repulsion_distance` l0 (textbook values 0.5 and e = 0.2).
pub(super) fn keep_particles_apart(
    sim: &mut Simulation,
    walls: &[PlacedWall],
    dt: Real,
    loads: &mut [WallLoad],
) {
    let l0 = sim.config.params.l0;
    let e = sim.config.method.restitution;
    let m = sim.config.params.particle_mass;
    let n = sim.particles.len();
    if let SpacingControl::Collision { distance } = sim.config.method.spacing_control {
        // the collision distance is the cloud's radius
        let cloud = Cloud::new(
            &sim.particles.position,
            &sim.workspace.neighbors,
            distance * l0,
        )
        .with_scales(sim.scales());
        let du = collision_velocity_changes(&cloud, &sim.particles.velocity, e);
        let parts = &mut sim.particles;
        parts
            .velocity
            .par_iter_mut()
            .zip(parts.position.par_iter_mut())
            .zip(du.par_iter())
            .for_each(|((u, x), du)| {
                *u += du;
                *x += du * dt;
            });
    }
    let rw = sim.config.method.wall_repulsion_distance * l0;
    if rw > 0.0 {
        // the particles within their safety distance of a wall, found in parallel (a
        // dozen a step on the shipped wedge), then treated in index order
        let (contacts, scales) = (&sim.workspace.contacts, sim.scales());
        let close: Vec<usize> = (0..n)
            .into_par_iter()
            .filter(|&i| {
                let rw = rw * scales.of(i);
                contacts
                    .of(i)
                    .iter()
                    .any(|c| c.distance < rw || c.penetrated)
            })
            .collect();
        for i in close {
            for c in sim.workspace.contacts.of(i) {
                // the particle's own safety distance and mass
                let (rw, m) = {
                    let s = sim.scales();
                    (rw * s.of(i), m * s.volume(i))
                };
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
/// over the fluid neighbours at `x_star` (the pair sum of the classic vector Laplacian at r_e,
/// `operators::vector_laplacian_sums`). The pair weights are symmetric, so the fluid's
/// momentum is unchanged; a smooth field changes by O(eps l0² ∇²u) per step, while the
/// odd-even mode (neighbours moving in opposite directions, invisible to the divergence
/// of the PPE source and to the gradient) loses a share of order eps every step.
pub(super) fn filter_velocity<K: Kernel>(sim: &mut Simulation, x_star: &[Vec2], eps: Real) {
    let (re, n0) = (sim.config.params.re, sim.config.params.n0);
    let x = x_star;
    let nb = &sim.workspace.neighbors;
    // a particle created after the last neighbour search has no list and no change
    let cloud = Cloud::new(&x[..nb.len().min(x.len())], nb, re).with_scales(sim.scales());
    let sums = vector_laplacian_sums::<K>(
        true,
        ViscosityKind::Laplacian,
        &cloud,
        &sim.particles.velocity,
    );
    sim.particles
        .velocity
        .par_iter_mut()
        .zip(sums.par_iter())
        .for_each(|(ui, s)| *ui += s * (eps / n0));
}

/// Fickian particle shifting (Lind et al. 2012, in MPS form): δr_i = -A l0² ∇n_i / n0,
/// with ∇n_i = Σ_j w'(r_ij) (x_i - x_j)/r_ij plus the wall lattice's ∇Z, so particles
/// drift from crowded to sparse places and a wall counts as filled (no shift into it).
/// Next to the free surface (a surface particle within r_e) only the tangential part
/// is kept: the surface deficit of n is physical, not disorder. The shift is capped at
/// 0.1 l0 per step. Velocities are not re-interpolated: shifts are O(A l0) per step.
pub(super) fn shift_particles<K: Kernel>(sim: &mut Simulation, a: Real) {
    let (l0, re, n0) = (
        sim.config.params.l0,
        sim.config.params.re,
        sim.config.params.n0,
    );
    let scales = sim.scales();
    let (contacts, surface) = (&sim.workspace.contacts, &sim.particles.free_surface);
    let cloud =
        Cloud::new(&sim.particles.position, &sim.workspace.neighbors, re).with_scales(scales);
    let shift: Vec<Vec2> = (0..cloud.len())
        .into_par_iter()
        .map(|i| {
            let mut grad = number_density_gradient::<K>(&cloud, i);
            for c in contacts.of(i) {
                grad += c.terms.number_density_gradient;
            }
            let near_surface = surface[i] || cloud.any_within(i, |j| surface[j]);
            let l0 = l0 * scales.of(i);
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
pub(super) fn absorb_waves(sim: &mut Simulation, dt: Real) {
    let layers = &sim.config.control.damping;
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
