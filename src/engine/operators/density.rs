//! The particle number density n_i = Σ_j w(r_ij) (Koshizuka & Oka 1996; Sun et al. 2022
//! eq. 4) and the HS divergence of the velocity (Ikari, Khayyer & Gotoh 2015 eq. 2), fluid neighbours
//! only: a wall adds its own shares (`WallContacts::number_density`,
//! `WallContacts::with_divergence`). The step needs both at the same positions, so they
//! come from one pass over each neighbourhood. Beside them: the gradient of n (particle
//! shifting), the HS divergence in row form (the exact projection) and the neighbour
//! count.

use super::Cloud;
use crate::engine::kernel::Kernel;
use crate::math::{Real, Vec2};
use rayon::prelude::*;

/// n_i over the fluid neighbours (w vanishes at and beyond r_e) and the HS divergence
/// ⟨∇·u⟩_i = -c Σ_j w'(r) r_ij·u_ij / r, with c = d / |Σ w'(r) r| of the reference
/// lattice ([`LatticeConstants::hs_divergence_coefficient`](super::LatticeConstants)), so
/// that the divergence of x is d on the lattice. With multi-resolution each pair takes
/// its radius r_e s_ij and volume factor v_ij (`resolution`).
#[inline]
pub fn number_density_and_divergence<K: Kernel>(
    cloud: &Cloud,
    u: &[Vec2],
    c: Real,
    i: usize,
) -> (Real, Real) {
    let x = cloud.positions;
    let (mut n, mut s) = (0.0, 0.0);
    for &j in cloud.neighbors.of(i) {
        let j = j as usize;
        let r = x[j] - x[i];
        let d = r.norm();
        let (re, v) = cloud.pair(i, j);
        let (w, dw_r) = K::w_and_dw_over_r(d, re);
        n += w * v;
        s += dw_r * r.dot(&(u[j] - u[i])) * v;
    }
    (n, -c * s)
}

/// [`number_density_and_divergence`] of every particle: (n, ∇·u).
pub fn number_density_and_divergence_all<K: Kernel>(
    cloud: &Cloud,
    u: &[Vec2],
    c: Real,
) -> (Vec<Real>, Vec<Real>) {
    number_density_and_divergence_then::<K>(cloud, u, c, |_, n, div| (n, div))
}

/// [`number_density_and_divergence`] of every particle, each passed through `then(i, n,
/// ∇·u)` in the same pass (a stage adds the walls' shares there).
pub fn number_density_and_divergence_then<K: Kernel>(
    cloud: &Cloud,
    u: &[Vec2],
    c: Real,
    then: impl Fn(usize, Real, Real) -> (Real, Real) + Sync,
) -> (Vec<Real>, Vec<Real>) {
    (0..cloud.len())
        .into_par_iter()
        .map(|i| {
            let (n, div) = number_density_and_divergence::<K>(cloud, u, c, i);
            then(i, n, div)
        })
        .unzip()
}

/// ∇n_i = Σ_j ∇_i w(r_ij) = Σ_j w'(r) (x_i - x_j) / r v_ij over the fluid neighbours with
/// 0 < r < r_e s_ij: it points from sparse to crowded places (the walls' share is
/// `WallTerms::number_density_gradient`). Fickian shifting moves particles down it
/// (Lind et al. 2012).
#[inline]
pub fn number_density_gradient<K: Kernel>(cloud: &Cloud, i: usize) -> Vec2 {
    let x = cloud.positions;
    let mut grad = Vec2::zeros();
    for &j in cloud.neighbors.of(i) {
        let j = j as usize;
        let r = x[i] - x[j];
        let d = r.norm();
        let (re, v) = cloud.pair(i, j);
        if d >= re || d == 0.0 {
            continue;
        }
        grad += r * (K::dw(d, re) / d * v);
    }
    grad
}

/// The HS divergence of particle i in row form for repeated application, ⟨∇·u⟩_i =
/// Σ_j e_ij·u_ij with e_ij = -c w'(r) r_ij / r v_ij over the neighbours with
/// 0 < r < r_e s_ij: the divergence of [`number_density_and_divergence`], its arithmetic
/// grouped per pair (the two agree to round-off; the exact projection applies these rows
/// at every GMRES iteration).
pub fn hs_divergence_row<K: Kernel>(cloud: &Cloud, c: Real, i: usize) -> Vec<(usize, Vec2)> {
    let x = cloud.positions;
    cloud
        .neighbors
        .of(i)
        .iter()
        .filter_map(|&j| {
            let j = j as usize;
            let r = x[j] - x[i];
            let d = r.norm();
            let (re, v) = cloud.pair(i, j);
            (d > 0.0 && d < re).then(|| (j, r * (-c * K::dw(d, re) / d * v)))
        })
        .collect()
}

/// The number of fluid neighbours of particle i within r_e s_ij (a coincident one
/// included): Σ_j 1, the number density of a unit weight.
#[inline]
pub fn neighbour_count(cloud: &Cloud, i: usize) -> usize {
    cloud.within(i).count()
}
