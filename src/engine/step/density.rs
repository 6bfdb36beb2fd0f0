//! Neighbours, particle number density (with the wall lattice, Harada et al. 2008) and
//! the HS divergence of the velocity (paper 004 eq. 2).

use crate::case::WallKinematics;
use crate::engine::kernel::Kernel;
use crate::engine::math::{Real, Vec2};
use crate::engine::neighbors::NeighborList;
use crate::engine::params::MpsParameters;
use crate::engine::simulation::Simulation;
use crate::engine::walls::WallContacts;
use rayon::prelude::*;

/// The neighbour list at `x`, out to the larger of the two radii.
pub(super) fn neighbor_list(params: &MpsParameters, x: &[Vec2]) -> NeighborList {
    NeighborList::build(x, params.re.max(params.re_lap))
}

/// n and ∇·u of the current state (before the first step).
pub(super) fn initial_number_density_and_divergence<K: Kernel>(sim: &mut Simulation) {
    let (x, nb, re) = (&sim.particles.position, &sim.neighbors, sim.params.re);
    let n = number_density::<K>(x, nb, &sim.contacts, re);
    let div = divergence::<K>(
        x,
        &sim.particles.velocity,
        nb,
        re,
        sim.params.divergence_coefficient,
    );
    sim.particles.number_density = n;
    sim.particles.number_density_rate = div;
}

pub(super) fn number_density<K: Kernel>(
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
pub(super) fn divergence<K: Kernel>(
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

pub(super) fn compute_number_density<K: Kernel>(sim: &mut Simulation) {
    sim.scratch.n_star = number_density::<K>(
        &sim.scratch.x_star,
        &sim.neighbors,
        &sim.contacts,
        sim.params.re,
    );
}

pub(super) fn update_number_density_and_divergence<K: Kernel>(sim: &mut Simulation) {
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

/// Wall share of the HS divergence: -c ∇Z · (u_i - u_w) (virtual points move with the wall).
pub(super) fn add_wall_divergence(div: &mut [Real], u: &[Vec2], contacts: &WallContacts, c: Real) {
    div.par_iter_mut().enumerate().for_each(|(i, d)| {
        for ct in contacts.of(i) {
            *d -= c * ct
                .terms
                .number_density_gradient
                .dot(&(u[i] - ct.wall_velocity));
        }
    });
}
