//! Gradient operators ⟨∇f⟩_i, each as vector row coefficients g_ij with
//! ⟨∇f⟩_i = Σ_j g_ij f_ij for the linear ones:
//!
//! - classic (Koshizuka & Oka 1996; paper 000 eq. 13, paper 003 eq. 13):
//!   g_ij = (d / n) r_ij w / r², n = n0 or n_i by [`Normalisation`]. Used by
//!   [`GradientKind::MinimumPressure`] with f_ij replaced by f_j - f̂_i, f̂_i the minimum
//!   of f over i and its neighbours (stability), and by [`GradientKind::Cmps`] with the
//!   antisymmetric (f_i + f_j) - (f̂_i + f̂_j) (Khayyer & Gotoh 2008; paper 003 eq. 19),
//!   and by [`GradientKind::Symmetric`] with f_i + f_j (the SPH-like pair form).
//! - corrected GC (paper 004 eqs. 12-13, paper 003 eqs. 21-22): g_ij = A_i⁻¹ r_ij w / r²
//!   with A_i = Σ w r rᵀ / r²: exact for linear fields on any cloud. Where A_i is
//!   ill-conditioned (splash, few neighbours, a one-sided line of neighbours) the
//!   reciprocal condition number falls below [`CORRECTED_GRADIENT_MIN_RCOND`] and the
//!   classic coefficient is used instead.
//! - anisotropic (paper 000 eq. 28): g_ij,k = r_ij,k w / (r² n_{i,k}).
//! - least squares (LSMPS type, Tamai & Koshizuka 2014; paper 003 §3.3): the first
//!   components of the weighted least-squares fit of f_ij on the second-order basis
//!   (x, y, x², xy, y²) scaled by r_e; second-order accurate on any non-degenerate cloud.

use super::laplacian::least_squares_fit;
use super::moments::{moments, rcond};
use super::{Cloud, Normalisation};
use crate::case::GradientKind;
use crate::engine::kernel::Kernel;
use crate::engine::math::{Real, Vec2};
use rayon::prelude::*;

/// Below this reciprocal condition number of A_i the corrected gradient falls back to
/// the classic one.
pub const CORRECTED_GRADIENT_MIN_RCOND: Real = 0.05;

/// (j, g_ij) of particle i.
pub type GradientRow = Vec<(usize, Vec2)>;

fn classic_row<K: Kernel>(cloud: &Cloud, norm: Normalisation, i: usize) -> GradientRow {
    let n = match norm {
        Normalisation::Local => moments::<K>(cloud, i).n,
        Normalisation::Reference(c) => c.n0,
    };
    if n <= 0.0 {
        return Vec::new();
    }
    cloud
        .pairs(i)
        .map(|(j, r, d)| (j, r * (cloud.dim * K::w(d, cloud.re) / (d * d * n))))
        .collect()
}

/// The vector coefficients g_ij of particle i's gradient (the classic one for the
/// minimum-pressure, CMPS and symmetric kinds, whose pressure shift [`gradient`] applies).
pub fn gradient_row<K: Kernel>(
    kind: GradientKind,
    cloud: &Cloud,
    norm: Normalisation,
    i: usize,
) -> GradientRow {
    match kind {
        GradientKind::MinimumPressure | GradientKind::Cmps | GradientKind::Symmetric => {
            classic_row::<K>(cloud, norm, i)
        }
        GradientKind::Corrected => {
            let mut a = moments::<K>(cloud, i).gc;
            if cloud.dim < 2.0 {
                a[(1, 1)] = 1.0;
            }
            match a.try_inverse() {
                Some(b) if rcond(&a) >= CORRECTED_GRADIENT_MIN_RCOND => cloud
                    .pairs(i)
                    .map(|(j, r, d)| (j, b * r * (K::w(d, cloud.re) / (d * d))))
                    .collect(),
                _ => classic_row::<K>(cloud, norm, i),
            }
        }
        GradientKind::Anisotropic => {
            let m = moments::<K>(cloud, i);
            let (nx, ny) = (m.gc[(0, 0)], m.gc[(1, 1)]);
            cloud
                .pairs(i)
                .map(|(j, r, d)| {
                    let w = K::w(d, cloud.re) / (d * d);
                    let gx = if nx > 0.0 { r.x * w / nx } else { 0.0 };
                    let gy = if ny > 0.0 { r.y * w / ny } else { 0.0 };
                    (j, Vec2::new(gx, gy))
                })
                .collect()
        }
        GradientKind::LeastSquares => match least_squares_fit::<K>(cloud, i) {
            Some(fit) => fit
                .rows
                .iter()
                .map(|&(j, c)| (j, Vec2::new(c[0], c[1])))
                .collect(),
            None => classic_row::<K>(cloud, norm, i),
        },
    }
}

/// ⟨∇f⟩ at every particle.
pub fn gradient<K: Kernel>(
    kind: GradientKind,
    cloud: &Cloud,
    norm: Normalisation,
    f: &[Real],
) -> Vec<Vec2> {
    let shifted = matches!(kind, GradientKind::MinimumPressure | GradientKind::Cmps);
    let f_min: Vec<Real> = if shifted {
        (0..cloud.len())
            .into_par_iter()
            .map(|i| cloud.pairs(i).map(|(j, _, _)| f[j]).fold(f[i], Real::min))
            .collect()
    } else {
        Vec::new()
    };
    (0..cloud.len())
        .into_par_iter()
        .map(|i| {
            let mut g = Vec2::zeros();
            for (j, gij) in gradient_row::<K>(kind, cloud, norm, i) {
                let df = match kind {
                    GradientKind::MinimumPressure => f[j] - f_min[i],
                    GradientKind::Cmps => f[i] + f[j] - f_min[i] - f_min[j],
                    GradientKind::Symmetric => f[i] + f[j],
                    _ => f[j] - f[i],
                };
                g += gij * df;
            }
            g
        })
        .collect()
}
