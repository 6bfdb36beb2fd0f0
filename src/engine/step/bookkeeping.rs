//! End of step: particles that left the domain or ran away are removed, and the state
//! is checked for divergence.

use super::density::neighbor_list;
use crate::engine::simulation::{SimError, Simulation};
use crate::engine::walls::WallContacts;
use crate::math::{Real, Vec2};
use rayon::prelude::*;

/// How far, in cfl spacings, a particle keeping its acceleration may move in the next
/// step: 1.2 (the dam break takes 1 262 steps against 1 266 without the bound; 1.0 gave
/// 1 594), below the step guard's 1.5 so that the guard acts only where an acceleration
/// starts.
const ACCELERATION_REACH: Real = 1.2;

/// The longest next step over which no particle that keeps this step's acceleration a
/// moves more than `ACCELERATION_REACH` cfl spacings: the root of dt (|u| + |a| dt) =
/// reach, smallest over the particles (a = (u - `u_start`) / dt).
pub(super) fn acceleration_limited_dt(sim: &Simulation, u_start: &[Vec2], dt: Real) -> Real {
    let reach = ACCELERATION_REACH * sim.config.control.cfl * sim.config.params.l0;
    let u = &sim.particles.velocity;
    u.par_iter()
        .zip(u_start.par_iter())
        .map(|(u, u0)| {
            let (speed, accel) = (u.norm(), (u - u0).norm() / dt);
            2.0 * reach / (speed + (speed * speed + 4.0 * accel * reach).sqrt())
        })
        .reduce(|| Real::INFINITY, Real::min)
}

pub(super) fn remove_particles_outside_domain(sim: &mut Simulation) -> usize {
    let (lo, hi) = (sim.config.control.domain_min, sim.config.control.domain_max);
    let keep: Vec<bool> = sim
        .particles
        .position
        .par_iter()
        .map(|p| p.x >= lo.x && p.y >= lo.y && p.x <= hi.x && p.y <= hi.y)
        .collect();
    remove_particles(sim, &keep)
}

/// Remove the particles faster than the speed limit while the allowance
/// (`scheme.runaway_allowance`) lasts; past it they stay, and `check_health` fails the
/// run on the first. A non-finite velocity is never removed: that is a diverged step.
pub(super) fn remove_runaways(sim: &mut Simulation) -> usize {
    // no allowance left: nothing to scan for, check_health reports the first runaway
    if sim.stats.runaways >= sim.config.control.runaway_budget {
        return 0;
    }
    let limit = sim.config.control.speed_limit;
    let fast: Vec<usize> = (0..sim.particles.len())
        .into_par_iter()
        .filter(|&i| sim.particles.velocity[i].norm() > limit)
        .collect();
    if fast.is_empty() || sim.stats.runaways + fast.len() > sim.config.control.runaway_budget {
        return 0;
    }
    if sim.stats.first_runaway.is_none() {
        let i = fast[0];
        let (x, u) = (sim.particles.position[i], sim.particles.velocity[i]);
        sim.stats.first_runaway = Some(format!(
            "step {}, t = {:.6} s: particle {i} at ({:.4}, {:.4}) reached {:.3} m/s (limit {limit:.3} m/s)",
            sim.steps,
            sim.time,
            x.x,
            x.y,
            u.norm()
        ));
    }
    sim.stats.runaways += fast.len();
    let mut keep = vec![true; sim.particles.len()];
    for i in fast {
        keep[i] = false;
    }
    remove_particles(sim, &keep)
}

/// Keep the particles flagged in `keep` (counted in `sim.stats.removed`), with their lists.
pub(super) fn remove_particles(sim: &mut Simulation, keep: &[bool]) -> usize {
    let removed = keep.iter().filter(|k| !**k).count();
    if removed > 0 {
        sim.particles.retain(keep);
        sim.stats.removed += removed;
        // the particles are renumbered: the AMG hierarchy's row keys mean nothing now
        sim.workspace.solver_cache.invalidate();
        // lists index particles: rebuild them for the next step's explicit stage
        sim.workspace.neighbors = neighbor_list(sim, &sim.particles.position, Vec::new());
        let keep_contacts = {
            let mut offsets = vec![0u32];
            let mut contacts = Vec::new();
            for (i, k) in keep.iter().enumerate() {
                if *k {
                    contacts.extend_from_slice(sim.workspace.contacts.of(i));
                    offsets.push(contacts.len() as u32);
                }
            }
            WallContacts { offsets, contacts }
        };
        sim.workspace.contacts = keep_contacts;
    }
    removed
}

/// Non-finite values, runaway speed or collapsed number density end the run.
pub(super) fn check_health(sim: &Simulation) -> Result<Real, SimError> {
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
    let limit = sim.config.control.speed_limit;
    let n_max = 4.0 * sim.config.params.n0;
    // what is wrong with particle i, checked in this order
    let problem = |i: usize| -> Option<String> {
        let (x, u) = (p.position[i], p.velocity[i]);
        if !(x.x.is_finite() && x.y.is_finite()) {
            return Some("non-finite position".into());
        }
        if !(u.x.is_finite() && u.y.is_finite()) {
            return Some("non-finite velocity".into());
        }
        if !p.pressure[i].is_finite() {
            return Some("non-finite pressure".into());
        }
        let s = u.norm();
        if s > limit {
            return Some(format!(
                "runaway velocity {s:.3} m/s (limit {limit:.3} m/s)"
            ));
        }
        if p.number_density[i] > n_max {
            return Some(format!(
                "particle number density collapsed to {:.2} n0",
                p.number_density[i] / sim.config.params.n0
            ));
        }
        None
    };
    // the first particle in index order with a problem, whatever the number of threads
    if let Some(i) = (0..p.len())
        .into_par_iter()
        .find_first(|&i| problem(i).is_some())
    {
        return Err(fail(i, problem(i).expect("found above")));
    }
    let max_speed = p
        .velocity
        .par_iter()
        .map(|u| u.norm())
        .reduce(|| 0.0, Real::max);
    Ok(max_speed)
}
