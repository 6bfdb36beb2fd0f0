//! The Laplacian of a vector field over the fluid neighbours, in the pair form of the
//! symmetric lattice-normalised rows (`laplacian`): each pair contributes through
//! c_ij = L(r_ij) v_ij, with L = w for the classic Laplacian (Koshizuka & Oka 1996;
//! Sun et al. 2022 eq. 15) and L = w'' - w'/r for HL (Khayyer & Gotoh 2010; Ikari,
//! Khayyer & Gotoh 2015 eq. 9), the pairs [`for_each_lattice_coefficient`] visits:
//!
//! - the Laplacian form, Σ_j c_ij u_ij: the viscous term ν∇²u of the explicit stage
//!   (Sun et al. 2022 eq. 9; `ViscosityKind::Laplacian`) and, with the classic weight,
//!   the velocity filter of the spacing stage;
//! - the strain-rate form, Σ_j (d + 2) (u_ij·r_ij) r_ij c_ij / r², whose pair force lies
//!   along r_ij: on an isotropic neighbourhood it is ∇²u + 2∇(∇·u), and its dissipation
//!   is the physical -2ν ∫ e:e, so a cut kernel at the free surface is stress-free
//!   (Colagrossi et al. 2011; `ViscosityKind::StrainRate`).
//!
//! The sums are returned without the lattice coefficient a (the `classic_coefficient` or
//! `hl_coefficient` of [`LatticeConstants`](super::LatticeConstants)): the caller adds the
//! walls' mirror terms (`WallContacts::viscous_mirror`) before scaling by a ν, or scales
//! by the filter's ε / n0. c_ij = c_ji, so with the particle masses m_i v_ij symmetric
//! (`resolution`) the fluid pairs exchange momentum without creating any.

use super::laplacian::for_each_lattice_coefficient;
use super::Cloud;
use crate::case::ViscosityKind;
use crate::engine::kernel::Kernel;
use crate::math::Vec2;
use rayon::prelude::*;

/// Σ_j c_ij u_ij (Laplacian form) or Σ_j (d + 2) (u_ij·r_ij) r_ij c_ij / r² (strain-rate
/// form, coincident pairs left out) at particle i, c_ij = L(r_ij) v_ij with L = w when
/// `classic`, else the HL weight, each pair at its radius r_e s_ij.
#[inline]
pub fn vector_laplacian_sum<K: Kernel>(
    classic: bool,
    form: ViscosityKind,
    cloud: &Cloud,
    u: &[Vec2],
    i: usize,
) -> Vec2 {
    let mut s = Vec2::zeros();
    let ui = u[i];
    match form {
        ViscosityKind::Laplacian => for_each_lattice_coefficient::<K>(
            classic,
            cloud,
            1.0,
            i,
            |_| 1.0,
            |j, _, c| {
                s += (u[j] - ui) * c;
            },
        ),
        ViscosityKind::StrainRate => {
            let stretch = cloud.dim + 2.0;
            for_each_lattice_coefficient::<K>(
                classic,
                cloud,
                1.0,
                i,
                |_| 1.0,
                |j, r, c| {
                    let d = r.norm();
                    if d > 0.0 {
                        s += r * (stretch * (u[j] - ui).dot(&r) / (d * d) * c);
                    }
                },
            )
        }
    }
    s
}

/// [`vector_laplacian_sum`] of every particle of the cloud.
pub fn vector_laplacian_sums<K: Kernel>(
    classic: bool,
    form: ViscosityKind,
    cloud: &Cloud,
    u: &[Vec2],
) -> Vec<Vec2> {
    (0..cloud.len())
        .into_par_iter()
        .map(|i| vector_laplacian_sum::<K>(classic, form, cloud, u, i))
        .collect()
}
