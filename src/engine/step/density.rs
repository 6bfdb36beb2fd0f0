//! Neighbours, particle number density (with the wall lattice, Harada et al. 2008) and
//! the HS divergence of the velocity (paper 004 eq. 2), from `engine::operators` and the
//! wall model.

use crate::case::WallKinematics;
use crate::engine::kernel::Kernel;
use crate::engine::neighbors::NeighborList;
use crate::engine::operators::{self, hs_divergence, Cloud};
use crate::engine::resolution::Scales;
use crate::engine::simulation::Simulation;
use crate::engine::walls::WallContacts;
use crate::math::{Real, Vec2};
use rayon::prelude::*;

/// The neighbour list at `x`, out to the larger of the two radii (of each pair, with
/// multi-resolution).
pub(super) fn neighbor_list(sim: &Simulation, x: &[Vec2]) -> NeighborList {
    let params = &sim.config.params;
    NeighborList::build_scaled(x, params.re.max(params.re_lap), sim.scales())
}

/// n and ∇·u of the current state (before the first step).
pub(super) fn initial_number_density_and_divergence<K: Kernel>(sim: &mut Simulation) {
    let cloud = Cloud::new(
        &sim.particles.position,
        &sim.workspace.neighbors,
        sim.config.params.re,
    )
    .with_scales(sim.scales());
    let n = number_density::<K>(&cloud, &sim.workspace.contacts);
    let div = hs_divergence::<K>(
        &cloud,
        &sim.particles.velocity,
        sim.config.params.divergence_coefficient,
    );
    sim.particles.number_density = n;
    sim.particles.number_density_rate = div;
}

/// n_i of every particle, fluid neighbours and walls.
fn number_density<K: Kernel>(cloud: &Cloud, contacts: &WallContacts) -> Vec<Real> {
    (0..cloud.len())
        .into_par_iter()
        .map(|i| contacts.number_density(i, operators::number_density::<K>(cloud, i)))
        .collect()
}

/// n* at the predicted positions.
pub(super) fn compute_number_density<K: Kernel>(sim: &mut Simulation) {
    let scales = Scales::new(&sim.particles.scale, sim.config.multi_resolution);
    let cloud = Cloud::new(
        &sim.workspace.scratch.x_star,
        &sim.workspace.neighbors,
        sim.config.params.re,
    )
    .with_scales(scales);
    sim.workspace.scratch.n_star = number_density::<K>(&cloud, &sim.workspace.contacts);
}

/// The HS divergence of `u` at the positions of `cloud`, plus, when
/// `scheme.wall_kinematics` is `source`, the walls' share -c ∇Z·(u_i - u_w) taken with
/// the particle velocities `u_at_walls` (the source uses u^n there, the end of the step u).
pub(super) fn divergence<K: Kernel>(
    sim: &Simulation,
    cloud: &Cloud,
    u: &[Vec2],
    u_at_walls: &[Vec2],
) -> Vec<Real> {
    let c = sim.config.params.divergence_coefficient;
    let mut div = hs_divergence::<K>(cloud, u, c);
    if sim.config.method.wall_kinematics == WallKinematics::Source {
        sim.workspace
            .contacts
            .add_divergence(&mut div, u_at_walls, c);
    }
    div
}

/// n and ∇·u at the end of the step, for the error-compensating source: the walls' share
/// of n carried from x* to the corrected positions to first order.
pub(super) fn update_number_density_and_divergence<K: Kernel>(sim: &mut Simulation) {
    let (x, xs) = (&sim.particles.position, &sim.workspace.scratch.x_star);
    let cloud =
        Cloud::new(x, &sim.workspace.neighbors, sim.config.params.re).with_scales(sim.scales());
    let contacts = &sim.workspace.contacts;
    let n: Vec<Real> = (0..x.len())
        .into_par_iter()
        .map(|i| {
            let fluid = operators::number_density::<K>(&cloud, i);
            contacts.number_density_moved(i, fluid, x[i] - xs[i])
        })
        .collect();
    // the same divergence as the source's (with or without the wall's virtual points)
    let u = &sim.particles.velocity;
    let div = divergence::<K>(sim, &cloud, u, u);
    sim.particles.number_density = n;
    sim.particles.number_density_rate = div;
}
