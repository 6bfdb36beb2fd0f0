//! Divergence of a vector field matching each gradient: ⟨∇·u⟩_i = Σ_j g_ij · u_ij with
//! the gradient's own coefficients g_ij (see `gradient`). For the minimum-pressure,
//! CMPS and symmetric kinds this is the classic MPS divergence (d/n) Σ u_ij · r_ij w / r²
//! (Koshizuka & Oka 1996; paper 003 eq. 14); for GC the corrected one (paper 003
//! eq. 22 applied componentwise); for the anisotropic and least-squares kinds the trace
//! of their gradient of u.

use super::gradient::gradient_row;
use super::{Cloud, Normalisation};
use crate::case::GradientKind;
use crate::engine::kernel::Kernel;
use crate::math::{Real, Vec2};
use rayon::prelude::*;

/// ⟨∇·u⟩ at every particle.
pub fn divergence<K: Kernel>(
    kind: GradientKind,
    cloud: &Cloud,
    norm: Normalisation,
    u: &[Vec2],
) -> Vec<Real> {
    (0..cloud.len())
        .into_par_iter()
        .map(|i| {
            gradient_row::<K>(kind, cloud, norm, i)
                .iter()
                .map(|&(j, g)| g.dot(&(u[j] - u[i])))
                .sum()
        })
        .collect()
}

/// The HS divergence of the step (paper 004 eq. 2), lattice-normalised:
/// ⟨∇·u⟩_i = -c Σ_j w'(r) r_ij·u_ij / r, with c = d / |Σ w'(r) r| of the reference
/// lattice ([`LatticeConstants::hs_divergence_coefficient`](super::LatticeConstants)), so
/// the divergence of x is d on the lattice. The fluid part only: a wall adds its own
/// (`WallContacts::add_divergence`).
pub fn hs_divergence<K: Kernel>(cloud: &Cloud, u: &[Vec2], c: Real) -> Vec<Real> {
    let (x, nb) = (cloud.positions, cloud.neighbors);
    (0..x.len())
        .into_par_iter()
        .map(|i| {
            let mut s = 0.0;
            for &j in nb.of(i) {
                let j = j as usize;
                let r = x[j] - x[i];
                let d = r.norm();
                let (re, v) = cloud.pair(i, j);
                if d > 0.0 && d < re {
                    s += K::dw(d, re) * r.dot(&(u[j] - u[i])) / d * v;
                }
            }
            -c * s
        })
        .collect()
}
