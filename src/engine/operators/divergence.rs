//! Divergence of a vector field matching each gradient: ⟨∇·u⟩_i = Σ_j g_ij · u_ij with
//! the gradient's own coefficients g_ij (see `gradient`). For the minimum-pressure,
//! CMPS and symmetric kinds this is the classic MPS divergence (d/n) Σ u_ij · r_ij w / r²
//! (Koshizuka & Oka 1996; Sun et al. 2022 eq. 14); for GC the corrected one (Sun et al. 2022
//! eq. 22 applied componentwise); for the anisotropic and least-squares kinds the trace
//! of their gradient of u. The step's HS divergence is in `density`, beside the number
//! density it shares its pass with.

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
