//! The pairwise collision of the textbook MPS code (Koshizuka et al. 2018): a pair closer
//! than the collision distance and approaching loses the share (1 + e)/2 of its normal
//! relative velocity at each end, e the restitution; a separating pair is left alone.
//! Between two equal particles that is an inelastic collision: the pair's normal
//! relative velocity becomes -e times what it was, and its momentum is kept.
//!
//! The cloud's r_e is the collision distance; with multi-resolution each pair takes it
//! times s_ij (`resolution`).

use super::Cloud;
use crate::math::{Real, Vec2};
use rayon::prelude::*;

/// The collision's velocity change of particle i, Σ_j (1 + e)/2 (u_ij·n̂) n̂ over the
/// neighbours j with 0 < r_ij < r_c s_ij and u_ij·n̂ < 0, n̂ = r_ij / r.
#[inline]
pub fn collision_velocity_change(cloud: &Cloud, u: &[Vec2], restitution: Real, i: usize) -> Vec2 {
    let x = cloud.positions;
    let mut d = Vec2::zeros();
    for &j in cloud.neighbors.of(i) {
        let j = j as usize;
        let r = x[j] - x[i];
        let rc = cloud.pair(i, j).0;
        // most pairs are well apart: skip them without the square root (the margin keeps
        // the test below the one that decides)
        if r.norm_squared() > rc * rc * (1.0 + 1e-9) {
            continue;
        }
        let dist = r.norm();
        if dist < rc && dist > 0.0 {
            let rh = r / dist;
            let vn = (u[j] - u[i]).dot(&rh);
            if vn < 0.0 {
                d += rh * (0.5 * (1.0 + restitution) * vn);
            }
        }
    }
    d
}

/// [`collision_velocity_change`] of every particle, from the same velocities `u` (a
/// Jacobi pass: the changes are applied together).
pub fn collision_velocity_changes(cloud: &Cloud, u: &[Vec2], restitution: Real) -> Vec<Vec2> {
    (0..cloud.len())
        .into_par_iter()
        .map(|i| collision_velocity_change(cloud, u, restitution, i))
        .collect()
}
