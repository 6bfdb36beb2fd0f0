//! Free-surface detection and the Dirichlet value of surface particles.

use crate::engine::kernel::Kernel;
use crate::engine::operators::{first_moment, neighbour_count, Cloud};
use crate::engine::simulation::Simulation;
use crate::math::{vec2, Real, Vec2};
use rayon::prelude::*;

/// What the free-surface stage gives the pressure equation, per particle.
pub(super) struct SurfaceValues {
    /// Dirichlet value of each free-surface particle, and the penalty's target of each
    /// graded one (0 elsewhere).
    pub(super) dirichlet: Vec<Real>,
    /// Surface share s in (0, 1) of a particle at the edge of the graded surface test,
    /// 0 elsewhere (`Scheme::soft_surface`).
    pub(super) softness: Vec<Real>,
}

/// Free surface: n* < beta n0, confirmed by a one-sided neighbourhood
/// (|Σ w r/r²| l0 / n above `surface_asymmetry`); below 0.8 n0 always. With the graded
/// test a particle near the edge of both is neither: it gets a surface share
/// (`surface_share`) that the pressure equation turns into a penalty. Writes the
/// particles' `free_surface` flags.
pub(super) fn detect_free_surface<K: Kernel>(
    sim: &mut Simulation,
    x_star: &[Vec2],
    n_star: &[Real],
) -> SurfaceValues {
    let contacts = &sim.workspace.contacts;
    let (n0, re, l0) = (
        sim.config.params.n0,
        sim.config.params.re,
        sim.config.params.l0,
    );
    let scales = sim.scales();
    let cloud = Cloud::new(x_star, &sim.workspace.neighbors, re).with_scales(scales);
    let beta = sim.config.method.free_surface.threshold;
    let asym_limit = sim.config.method.free_surface.asymmetry;
    let offset = sim.config.method.free_surface.offset;
    let rho_g = vec2(sim.config.params.gravity) * sim.config.params.density;
    // (is surface, Dirichlet value): the surface lies half a spacing beyond the particle,
    // so its hydrostatic pressure is rho g·m̂ l0/2 (m̂ the inward normal). Gravity only:
    // an estimate from the previous pressure gradient feeds back into itself (measured:
    // a still tank drifted 2.5% after 1.3 s).
    let soft = sim.config.method.free_surface.soft;
    let flags: Vec<(bool, Real, Real)> = (0..cloud.len())
        .into_par_iter()
        .map(|i| {
            let n = n_star[i];
            if n >= beta * n0 {
                return (false, 0.0, 0.0);
            }
            let mut m = first_moment::<K>(&cloud, i);
            for c in contacts.of(i) {
                m += c.terms.moment1;
            }
            // the particle's own spacing
            let l0 = l0 * scales.of(i);
            let asym = m.norm() * l0 / n.max(1e-12);
            let value = if offset && m.norm() > 0.0 {
                surface_value(rho_g, m / m.norm(), l0)
            } else {
                0.0
            };
            if soft && asym_limit > 0.0 && n >= 0.8 * n0 {
                let s = surface_share(n / n0, beta, asym / asym_limit);
                return match s {
                    s if s >= SOFT_DIRICHLET => (true, value, 0.0),
                    s if s > 0.0 => (false, value, s),
                    _ => (false, 0.0, 0.0),
                };
            }
            let one_sided = asym > asym_limit;
            let surface = asym_limit <= 0.0 || n < 0.8 * n0 || one_sided;
            if !surface {
                return (false, 0.0, 0.0);
            }
            (true, value, 0.0)
        })
        .collect();
    sim.particles.free_surface = flags.iter().map(|f| f.0).collect();
    let mut values = SurfaceValues {
        dirichlet: flags.iter().map(|f| f.1).collect(),
        softness: flags.iter().map(|f| f.2).collect(),
    };
    release_isolated_clusters(sim, x_star, &mut values.dirichlet);
    values
}

/// The graded test's ramps: the surface share falls from 1 at n* = `SOFT_DENSITY_LOW`
/// n0 to 0 at the threshold, and from 1 at `1 + SOFT_ASYMMETRY_BAND` times the
/// asymmetry limit to 0 at `1 - SOFT_ASYMMETRY_BAND` times it; the particle's share is
/// the product. Bands this wide let a jet-root particle, which moves about 0.2 l0 a
/// step, take three or four steps to submerge.
const SOFT_DENSITY_LOW: Real = 0.90;
const SOFT_ASYMMETRY_BAND: Real = 0.5;
/// A share at least this high is a Dirichlet particle (the penalty would be 1000 times
/// the row's diagonal).
const SOFT_DIRICHLET: Real = 0.999;

/// Surface share s in [0, 1] of a particle with fill `fill` = n*/n0 and asymmetry
/// `asymmetry` (a ratio of the limit), `beta` the threshold.
fn surface_share(fill: Real, beta: Real, asymmetry: Real) -> Real {
    let by_density = ((beta - fill) / (beta - SOFT_DENSITY_LOW)).clamp(0.0, 1.0);
    let by_asymmetry =
        ((asymmetry - 1.0 + SOFT_ASYMMETRY_BAND) / (2.0 * SOFT_ASYMMETRY_BAND)).clamp(0.0, 1.0);
    by_density * by_asymmetry
}

/// Largest group of particles, cut off from every free-surface particle, that is taken
/// for spray and released to the surface pressure. The bulk of any real scene is far
/// larger; a completely filled closed tank is one group and is left alone.
pub(super) const ISOLATED_CLUSTER_LIMIT: usize = 24;

/// A group of at most this many particles whose other neighbours are all free surface is
/// spray as well, even though the surface pressure reaches it.
pub(super) const ENCLOSED_PAIR: usize = 2;

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
fn release_isolated_clusters(sim: &mut Simulation, x: &[Vec2], dirichlet: &mut [Real]) {
    let (nb, contacts) = (&sim.workspace.neighbors, &sim.workspace.contacts);
    let surface = &sim.particles.free_surface;
    let (re, re_lap) = (sim.config.params.re, sim.config.params.re_lap);
    let lattice_neighbours = sim.config.params.lattice.neighbours;
    let scales = sim.scales();
    let cloud = Cloud::new(x, nb, re).with_scales(scales);
    let seeds: Vec<usize> = (0..x.len().min(nb.len()))
        .into_par_iter()
        .filter(|&i| {
            !surface[i]
                && !contacts.of(i).is_empty()
                && 2 * neighbour_count(&cloud, i) < lattice_neighbours
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
                if (x[j] - x[i]).norm() >= re_lap * scales.pair(i, j).0 {
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
        dirichlet[i] = 0.0;
    }
}

/// Below this tilt of the surface normal from the vertical, a free surface counts as level.
pub(super) const LEVEL_SURFACE_COS: Real = 0.866_025_403_784_438_6; // cos 30°

/// Dirichlet value of a free-surface particle with inward normal `m_hat`: the hydrostatic
/// pressure half a spacing below the surface, rho |g| (l0/2) cos(tilt), taken as level
/// (cos = 1) up to a 30° tilt and falling linearly in cos beyond. Why flat: the normal of
/// a particle near a wall or a slightly displaced neighbour tilts by a few degrees, and a
/// value that follows it feeds the particle positions back into the surface pressure.
/// Measured on the still tank: with the plain rho g·m̂ l0/2 the top-row particles next to
/// the side walls took 48.9 Pa instead of 49.05, which drove a slow flow up the walls and
/// a particle-scale mode that grew from 2 s on (max speed 19 mm/s at 2.5 s, 0.46 m/s at
/// 4 s); with the level value the tank stays on the lattice.
pub(super) fn surface_value(rho_g: Vec2, m_hat: Vec2, l0: Real) -> Real {
    let weight = rho_g.norm();
    if weight == 0.0 {
        return 0.0;
    }
    let cos = rho_g.dot(&m_hat) / weight;
    weight * 0.5 * l0 * (cos / LEVEL_SURFACE_COS).clamp(0.0, 1.0)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The graded test's share: 1 (Dirichlet) deep in both ramps, 0 (interior) at the
    /// threshold or at half the asymmetry limit, the product in between, and never
    /// rising as a particle fills up or its neighbourhood evens out.
    #[test]
    fn surface_share_ramps_between_interior_and_dirichlet() {
        let beta = 0.97;
        assert_eq!(surface_share(0.90, beta, 1.5), 1.0);
        assert_eq!(surface_share(0.85, beta, 3.0), 1.0);
        assert_eq!(surface_share(beta, beta, 3.0), 0.0);
        assert_eq!(surface_share(0.85, beta, 0.5), 0.0);
        assert!((surface_share(0.935, beta, 1.0) - 0.25).abs() < 1e-12);
        let mut last = 1.0;
        for k in 0..=70 {
            let s = surface_share(0.90 + 0.001 * k as Real, beta, 1.2);
            assert!(s <= last);
            last = s;
        }
    }
}
