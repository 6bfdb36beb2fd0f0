//! The particle number density n_i = Σ_j w(r_ij) (Koshizuka & Oka 1996; paper 003
//! eq. 4), fluid neighbours only: a wall adds its own share
//! (`WallContacts::number_density`).

use super::Cloud;
use crate::engine::kernel::Kernel;
use crate::math::Real;

/// n_i over the fluid neighbours (w vanishes at and beyond r_e); with multi-resolution
/// Σ_j w(r_ij, r_e s_ij) v_ij (`resolution`).
#[inline]
pub fn number_density<K: Kernel>(cloud: &Cloud, i: usize) -> Real {
    let x = cloud.positions;
    let mut n = 0.0;
    for &j in cloud.neighbors.of(i) {
        let j = j as usize;
        let (re, v) = cloud.pair(i, j);
        n += K::w((x[j] - x[i]).norm(), re) * v;
    }
    n
}
