//! Neighbours, particle number density (with the wall lattice, Harada et al. 2008) and
//! the HS divergence of the velocity (Ikari, Khayyer & Gotoh 2015 eq. 2), from `engine::operators` and the
//! wall model. Number density and divergence are taken together, in one pass over the
//! neighbours: at x* (n* and the source's ∇·u*) and at the end of the step (n and ∇·u
//! for the error-compensating source).

use crate::case::WallKinematics;
use crate::engine::kernel::Kernel;
use crate::engine::neighbors::NeighborList;
use crate::engine::operators::{number_density_and_divergence_then, Cloud};
use crate::engine::simulation::Simulation;
use crate::math::{Real, Vec2};

/// The neighbour list at `x`, out to the larger of the two radii (of each pair, with
/// multi-resolution), written into `pairs` (a buffer to reuse).
pub(super) fn neighbor_list(sim: &Simulation, x: &[Vec2], mut pairs: Vec<u32>) -> NeighborList {
    let params = &sim.config.params;
    let radius = params.neighbour_radius();
    // room for the last list's pairs and a twentieth more: particles move a fraction of
    // a spacing a step
    let last = sim.workspace.neighbors.pair_count();
    pairs.clear();
    pairs.reserve(last + last / 20);
    NeighborList::build_scaled_into(x, radius, sim.scales(), pairs)
}

/// n and ∇·u of the current state (before the first step).
pub(super) fn initial_number_density_and_divergence<K: Kernel>(sim: &mut Simulation) {
    let x = &sim.particles.position;
    let u = &sim.particles.velocity;
    let contacts = &sim.workspace.contacts;
    let (n, div) =
        density_and_divergence::<K>(sim, x, u, |i, n, div| (contacts.number_density(i, n), div));
    sim.particles.number_density = n;
    sim.particles.number_density_rate = div;
}

/// n and the HS divergence of `u` at the positions `x` over the fluid neighbours, each
/// particle's (n, ∇·u) passed through `walls(i, n, ∇·u)` in the same pass to add the
/// walls' shares.
fn density_and_divergence<K: Kernel>(
    sim: &Simulation,
    x: &[Vec2],
    u: &[Vec2],
    walls: impl Fn(usize, Real, Real) -> (Real, Real) + Sync,
) -> (Vec<Real>, Vec<Real>) {
    let params = &sim.config.params;
    let cloud = Cloud::new(x, &sim.workspace.neighbors, params.re).with_scales(sim.scales());
    number_density_and_divergence_then::<K>(&cloud, u, params.divergence_coefficient, walls)
}

/// Particle i's divergence `div` with the walls' share, -c ∇Z·(u_i - u_w), for the
/// particle velocity `u_i`, when `scheme.wall_kinematics` is `source` (the source uses
/// u^n there, the end of the step u).
fn wall_divergence(sim: &Simulation) -> impl Fn(usize, Real, Vec2) -> Real + Sync + '_ {
    let source = sim.config.method.wall_kinematics == WallKinematics::Source;
    let c = sim.config.params.divergence_coefficient;
    let contacts = &sim.workspace.contacts;
    move |i, div, u_i| {
        if source {
            contacts.with_divergence(i, div, u_i, c)
        } else {
            div
        }
    }
}

/// n* with the wall lattice and the source's ∇·u* at the predicted positions.
pub(super) struct AtPrediction {
    pub(super) n: Vec<Real>,
    /// ∇·u* (the walls' share with u^n).
    pub(super) div: Vec<Real>,
}

/// n* and ∇·u* at `x_star`, with the velocities u* of the particles and the walls'
/// share of the divergence with `u_start` (u^n).
pub(super) fn at_prediction<K: Kernel>(
    sim: &Simulation,
    x_star: &[Vec2],
    u_start: &[Vec2],
) -> AtPrediction {
    let (contacts, wall_div) = (&sim.workspace.contacts, wall_divergence(sim));
    let (n, div) =
        density_and_divergence::<K>(sim, x_star, &sim.particles.velocity, |i, n, div| {
            (contacts.number_density(i, n), wall_div(i, div, u_start[i]))
        });
    AtPrediction { n, div }
}

/// n and ∇·u at the end of the step, for the error-compensating source: the walls' share
/// of n carried from `x_star` to the corrected positions to first order.
pub(super) fn update_number_density_and_divergence<K: Kernel>(
    sim: &mut Simulation,
    x_star: &[Vec2],
) {
    let (n, div) = {
        let x = &sim.particles.position;
        let u = &sim.particles.velocity;
        let (contacts, wall_div) = (&sim.workspace.contacts, wall_divergence(sim));
        // the same divergence as the source's (with or without the wall's virtual points)
        density_and_divergence::<K>(sim, x, u, |i, n, div| {
            let n = contacts.number_density_moved(i, n, x[i] - x_star[i]);
            (n, wall_div(i, div, u[i]))
        })
    };
    sim.particles.number_density = n;
    sim.particles.number_density_rate = div;
}
