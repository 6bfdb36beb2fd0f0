//! Laplacian operators ⟨∇²f⟩_i = Σ_j c_ij f_ij, each defined by its row coefficients
//! c_ij (the pressure equation's row of particle i is c_ij off the diagonal and
//! -Σ_j c_ij on it):
//!
//! - classic (Koshizuka & Oka 1996; Sun et al. 2022 eqs. 15-16, Imoto 2022 eq. 14):
//!   c_ij = 2d / (λ n) w, with n λ = n0 λ0 ([`Normalisation::Reference`]) or the
//!   particle's own Σ w r² ([`Normalisation::Local`]). Symmetric with the reference.
//! - higher order HL (Khayyer & Gotoh 2010; Ikari, Khayyer & Gotoh 2015 eq. 9): c_ij = α (w'' - w'/r).
//!   The paper's α = 1/n0 gives about twice the Laplacian of |x|² on the lattice (the
//!   ∂f_ij/∂r ≈ -2 f_ij / r step of its eq. 7), so α is normalised like λ: α = 2d /
//!   Σ (w'' - w'/r) r² on the reference lattice (or per particle with `Local`).
//!   Symmetric with the reference.
//! - corrected higher order CHL (Ikari, Khayyer & Gotoh 2015, eqs. 18-25):
//!   c_ij = α [(w''/r² - 4 w'/r³) r_ijᵀ C_i r_ij + (w'/r) tr C_i], C_i = (Σ -w' r rᵀ / r)⁻¹
//!   the corrective matrix of eq. 19 (without its 1/n0, absorbed in α), eq. 23 for
//!   ∇f_ij · C∇w, eq. 24 for ∇·(C∇w) with the ∂C/∂x_ij of eq. 25; α normalised on the
//!   lattice as for HL. Non-symmetric (C_i is per row). Falls back to HL where C_i is
//!   ill-conditioned.
//! - second order (Imoto 2022, eq. 26 summed over k, eq. 31's isotropic
//!   form): c_ij = 2d/(nλ - d²θ) w Σ_k x_k²/r² - 2d³θ/(nλ(nλ - d²θ)) w, which the paper's
//!   Theorem 3.1 shows equals the classic coefficient with the same n, λ (so it is kept
//!   as a separate name, computed through eq. 26, for the case files).
//! - anisotropic (Imoto 2022 eqs. 29, 31): c_ij = 2 [1 … 1] Θ_i⁻¹ q_ij w / r²,
//!   q_ij = (x_1², …, x_d²); always with the particle's own Θ_i. Non-symmetric.
//! - least squares (LSMPS type, Tamai & Koshizuka 2014; Sun et al. 2022 §3.3): ∂xx + ∂yy of the
//!   weighted least-squares fit of f_ij on (x, y, x²/2, xy, y²/2) scaled by r_e, weight w.
//!   Exact for quadratics on any cloud where the moment matrix is regular (second-order
//!   consistent: error O(h) on disordered clouds, O(h²) on symmetric ones).
//!   Non-symmetric. Falls back to the classic local row where the fit is singular.

use super::moments::{chl_moment, chl_weight, moments, rcond};
use super::{Cloud, Normalisation};
use crate::case::LaplacianKind;
use crate::engine::kernel::Kernel;
use crate::math::{Mat2, Real, Vec2};
use nalgebra::{SMatrix, SVector};
use rayon::prelude::*;

/// Row of particle i: `off_diagonal` holds (j, c_ij); `diagonal` = -Σ_j c_ij.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct LaplacianRow {
    pub diagonal: Real,
    pub off_diagonal: Vec<(usize, Real)>,
}

impl LaplacianRow {
    fn from_coefficients(off_diagonal: Vec<(usize, Real)>) -> Self {
        let diagonal = -off_diagonal.iter().map(|&(_, c)| c).sum::<Real>();
        Self {
            diagonal,
            off_diagonal,
        }
    }

    /// Σ_j c_ij (f_j - f_i), in neighbour order.
    pub fn apply(&self, i: usize, f: &[Real]) -> Real {
        self.off_diagonal
            .iter()
            .map(|&(j, c)| c * (f[j] - f[i]))
            .sum::<Real>()
    }
}

/// Below this reciprocal condition number the CHL corrective matrix is not used.
const CHL_MIN_RCOND: Real = 0.05;

/// The symmetric rows with the lattice normalisation, pair by pair and without
/// allocating: calls `visit(j, r_ij, c_ij)` for every neighbour with c_ij ≠ 0, where
/// c_ij = a L(r_ij) scale(j), L = w for the classic Laplacian and w'' - w'/r for HL,
/// a the lattice coefficient ([`LatticeConstants`](super::LatticeConstants)'
/// `classic_coefficient` or `hl_coefficient`) and `scale` a symmetric pair factor (1 in
/// a full neighbourhood). The step's pressure rows and [`laplacian_row`] with
/// [`Normalisation::Reference`] both come from here.
#[inline]
pub fn for_each_lattice_coefficient<K: Kernel>(
    classic: bool,
    cloud: &Cloud,
    a: Real,
    i: usize,
    scale: impl Fn(usize) -> Real,
    visit: impl FnMut(usize, Vec2, Real),
) {
    if classic {
        lattice_row(cloud, i, K::w, a, scale, visit)
    } else {
        lattice_row(cloud, i, K::hl, a, scale, visit)
    }
}

/// Whether particle i has a neighbour with a non-zero weight in the symmetric rows of
/// [`for_each_lattice_coefficient`] (L = w when `classic`, else the HL weight, at the
/// pair's radius r_e s_ij): a particle without one has an empty Laplacian row. Stops at
/// the first such neighbour.
#[inline]
pub fn has_laplacian_neighbour<K: Kernel>(classic: bool, cloud: &Cloud, i: usize) -> bool {
    let x = cloud.positions;
    let weight = if classic { K::w } else { K::hl };
    cloud.neighbors.of(i).iter().any(|&j| {
        let j = j as usize;
        weight((x[j] - x[i]).norm(), cloud.pair(i, j).0) != 0.0
    })
}

#[inline(always)]
fn lattice_row(
    cloud: &Cloud,
    i: usize,
    weight: impl Fn(Real, Real) -> Real,
    a: Real,
    scale: impl Fn(usize) -> Real,
    mut visit: impl FnMut(usize, Vec2, Real),
) {
    let x = cloud.positions;
    for &j in cloud.neighbors.of(i) {
        let j = j as usize;
        let r = x[j] - x[i];
        // with multi-resolution the pair's radius and volume factor (`resolution`)
        let (re, v) = cloud.pair(i, j);
        let c = a * weight(r.norm(), re) * scale(j) * v;
        if c != 0.0 {
            visit(j, r, c);
        }
    }
}

fn reference_row<K: Kernel>(classic: bool, cloud: &Cloud, a: Real, i: usize) -> Vec<(usize, Real)> {
    let mut row = Vec::with_capacity(cloud.neighbors.of(i).len());
    for_each_lattice_coefficient::<K>(classic, cloud, a, i, |_| 1.0, |j, _, c| row.push((j, c)));
    row
}

fn classic<K: Kernel>(cloud: &Cloud, norm: Normalisation, i: usize) -> Vec<(usize, Real)> {
    let nl = match norm {
        Normalisation::Local => moments::<K>(cloud, i).wr2,
        Normalisation::Reference(c) => {
            return reference_row::<K>(true, cloud, c.classic_coefficient, i)
        }
    };
    if nl <= 0.0 {
        return Vec::new();
    }
    let a = 2.0 * cloud.dim / nl;
    cloud
        .pairs(i)
        .map(|(j, _, d)| (j, a * K::w(d, cloud.re)))
        .collect()
}

fn normalised(
    cloud: &Cloud,
    reference: Option<Real>,
    pairs: Vec<(usize, Vec2, Real, Real)>,
) -> Vec<(usize, Real)> {
    // pairs: (j, r, d, L(r)); α from the reference or from Σ L r² of this row
    let a = reference.unwrap_or_else(|| {
        let s: Real = pairs.iter().map(|&(_, _, d, l)| l * d * d).sum();
        if s != 0.0 {
            2.0 * cloud.dim / s
        } else {
            0.0
        }
    });
    pairs.into_iter().map(|(j, _, _, l)| (j, a * l)).collect()
}

fn higher_order<K: Kernel>(cloud: &Cloud, norm: Normalisation, i: usize) -> Vec<(usize, Real)> {
    if let Normalisation::Reference(c) = norm {
        return reference_row::<K>(false, cloud, c.hl_coefficient, i);
    }
    let pairs = cloud
        .pairs(i)
        .map(|(j, r, d)| (j, r, d, K::hl(d, cloud.re)))
        .collect();
    normalised(cloud, None, pairs)
}

fn corrected_higher_order<K: Kernel>(
    cloud: &Cloud,
    norm: Normalisation,
    i: usize,
) -> Vec<(usize, Real)> {
    let a = chl_moment::<K>(cloud, i);
    let c = match a.try_inverse() {
        Some(c) if rcond(&a) >= CHL_MIN_RCOND => c,
        _ => return higher_order::<K>(cloud, norm, i),
    };
    let reference = match norm {
        Normalisation::Local => None,
        Normalisation::Reference(k) => Some(k.chl_coefficient),
    };
    let pairs = cloud
        .pairs(i)
        .map(|(j, r, d)| (j, r, d, chl_weight::<K>(r, d, cloud.re, &c)))
        .collect();
    normalised(cloud, reference, pairs)
}

fn second_order<K: Kernel>(cloud: &Cloud, norm: Normalisation, i: usize) -> Vec<(usize, Real)> {
    if cloud.dim < 2.0 {
        return classic::<K>(cloud, norm, i);
    }
    let (nl, theta) = match norm {
        Normalisation::Local => {
            let m = moments::<K>(cloud, i);
            (m.wr2, m.theta[(0, 1)])
        }
        Normalisation::Reference(c) => (c.n0 * c.lambda, c.theta),
    };
    let d = cloud.dim;
    let den = nl - d * d * theta;
    if nl <= 0.0 || den <= 0.0 {
        return classic::<K>(cloud, norm, i);
    }
    let (a, b) = (2.0 * d / den, 2.0 * d * d * theta / (nl * den));
    // Σ_k of eq. 26: Σ_k x_k² / r² = 1, and the correction term appears d times
    cloud
        .pairs(i)
        .map(|(j, r, dist)| {
            (
                j,
                K::w(dist, cloud.re) * (a * (r.x * r.x + r.y * r.y) / (dist * dist) - d * b),
            )
        })
        .collect()
}

fn anisotropic<K: Kernel>(cloud: &Cloud, norm: Normalisation, i: usize) -> Vec<(usize, Real)> {
    if cloud.dim < 2.0 {
        return classic::<K>(cloud, Normalisation::Local, i);
    }
    let theta: Mat2 = moments::<K>(cloud, i).theta;
    let Some(inv) = theta.try_inverse().filter(|_| rcond(&theta) > 1e-8) else {
        return classic::<K>(cloud, norm, i);
    };
    let s = inv.row_sum().transpose() * 2.0; // 2 [1 1] Θ⁻¹ as a column
    cloud
        .pairs(i)
        .map(|(j, r, d)| {
            (
                j,
                s.dot(&Vec2::new(r.x * r.x, r.y * r.y)) * K::w(d, cloud.re) / (d * d),
            )
        })
        .collect()
}

/// The weighted least-squares fit of particle i: for each neighbour the coefficients of
/// f_ij in (∂x, ∂y, ∂xx, ∂xy, ∂yy).
pub(crate) struct LeastSquaresFit {
    pub rows: Vec<(usize, [Real; 5])>,
}

/// The LSMPS fit (see the module doc), None where the moment matrix is singular.
pub(crate) fn least_squares_fit<K: Kernel>(cloud: &Cloud, i: usize) -> Option<LeastSquaresFit> {
    let s = cloud.re;
    if cloud.dim < 2.0 {
        let basis = |r: Vec2| SVector::<Real, 2>::new(r.x / s, r.x * r.x / (2.0 * s * s));
        let mut m = SMatrix::<Real, 2, 2>::zeros();
        let mut count = 0;
        for (_, r, d) in cloud.pairs(i) {
            let p = basis(r);
            m += p * p.transpose() * K::w(d, s);
            count += 1;
        }
        if count < 2 {
            return None;
        }
        let inv = m.cholesky()?.inverse();
        let rows = cloud
            .pairs(i)
            .map(|(j, r, d)| {
                let a = inv * basis(r) * K::w(d, s);
                (j, [a[0] / s, 0.0, a[1] / (s * s), 0.0, 0.0])
            })
            .collect();
        return Some(LeastSquaresFit { rows });
    }
    let basis = |r: Vec2| {
        SVector::<Real, 5>::new(
            r.x / s,
            r.y / s,
            r.x * r.x / (2.0 * s * s),
            r.x * r.y / (s * s),
            r.y * r.y / (2.0 * s * s),
        )
    };
    let mut m = SMatrix::<Real, 5, 5>::zeros();
    let mut count = 0;
    for (_, r, d) in cloud.pairs(i) {
        let p = basis(r);
        m += p * p.transpose() * K::w(d, s);
        count += 1;
    }
    if count < 6 {
        return None;
    }
    let chol = m.cholesky()?;
    // reject nearly singular fits (a line of neighbours, a corner with few particles)
    let diag = chol.l_dirty().diagonal();
    let (lo, hi) = diag.iter().fold((Real::MAX, 0.0 as Real), |(lo, hi), &v| {
        (lo.min(v.abs()), hi.max(v.abs()))
    });
    if hi <= 0.0 || (lo / hi).powi(2) < 1e-10 {
        return None;
    }
    let inv = chol.inverse();
    let rows = cloud
        .pairs(i)
        .map(|(j, r, d)| {
            let a = inv * basis(r) * K::w(d, s);
            (
                j,
                [
                    a[0] / s,
                    a[1] / s,
                    a[2] / (s * s),
                    a[3] / (s * s),
                    a[4] / (s * s),
                ],
            )
        })
        .collect();
    Some(LeastSquaresFit { rows })
}

fn least_squares<K: Kernel>(cloud: &Cloud, i: usize) -> Vec<(usize, Real)> {
    match least_squares_fit::<K>(cloud, i) {
        Some(fit) => fit
            .rows
            .into_iter()
            .map(|(j, c)| (j, c[2] + c[4]))
            .collect(),
        None => classic::<K>(cloud, Normalisation::Local, i),
    }
}

/// The row of particle i for the Laplacian `kind`.
pub fn laplacian_row<K: Kernel>(
    kind: LaplacianKind,
    cloud: &Cloud,
    norm: Normalisation,
    i: usize,
) -> LaplacianRow {
    let c = match kind {
        LaplacianKind::Classic => classic::<K>(cloud, norm, i),
        LaplacianKind::HigherOrder => higher_order::<K>(cloud, norm, i),
        LaplacianKind::CorrectedHigherOrder => corrected_higher_order::<K>(cloud, norm, i),
        LaplacianKind::SecondOrder => second_order::<K>(cloud, norm, i),
        LaplacianKind::Anisotropic => anisotropic::<K>(cloud, norm, i),
        LaplacianKind::LeastSquares => least_squares::<K>(cloud, i),
    };
    LaplacianRow::from_coefficients(c)
}

/// ⟨∇²f⟩ at every particle.
pub fn laplacian<K: Kernel>(
    kind: LaplacianKind,
    cloud: &Cloud,
    norm: Normalisation,
    f: &[Real],
) -> Vec<Real> {
    (0..cloud.len())
        .into_par_iter()
        .map(|i| laplacian_row::<K>(kind, cloud, norm, i).apply(i, f))
        .collect()
}
