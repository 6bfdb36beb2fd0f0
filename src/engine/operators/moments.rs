//! Moment sums of a neighbourhood that the operators normalise by, and their values on
//! the full reference lattice.
//!
//! Per particle i (Imoto 2022 §3, eqs. 15 and 21; Ikari, Khayyer & Gotoh 2015 eqs. 13 and 19):
//! - n_i = Σ w, and Σ w r² = n_i λ_i;
//! - n_{i,k} = Σ w x_k² / r² (eq. 21 of Imoto 2022), the diagonal of the GC matrix
//!   A_i = Σ w r rᵀ / r² (Ikari, Khayyer & Gotoh 2015 eq. 13 without its 1/n0, which cancels);
//! - Θ_i = (θ_{i,k,l}) with θ_{i,k,l} = Σ w x_k² x_l² / r² (Imoto 2022 eq. 15);
//! - the CHL matrix Σ -w' r rᵀ / r (inverse of Ikari, Khayyer & Gotoh 2015 eq. 19 without its 1/n0).

use super::Cloud;
use crate::engine::kernel::Kernel;
use crate::math::{Mat2, Real, Vec2};

/// Reciprocal condition number (smallest over largest eigenvalue modulus) of a symmetric 2×2 matrix.
pub(crate) fn rcond(m: &Mat2) -> Real {
    let tr = m[(0, 0)] + m[(1, 1)];
    let det = m.determinant();
    let disc = ((tr * tr / 4.0) - det).max(0.0).sqrt();
    let (a, b) = ((tr / 2.0 + disc).abs(), (tr / 2.0 - disc).abs());
    let (lo, hi) = if a < b { (a, b) } else { (b, a) };
    if hi > 0.0 {
        lo / hi
    } else {
        0.0
    }
}

/// The moment sums of one neighbourhood.
#[derive(Debug, Clone, Copy, Default)]
pub(crate) struct Moments {
    pub n: Real,
    /// Σ w r² (= n λ).
    pub wr2: Real,
    /// Σ w r rᵀ / r²: diagonal n_{i,k}, the GC matrix.
    pub gc: Mat2,
    /// Θ_i of Imoto (2022).
    pub theta: Mat2,
}

pub(crate) fn moments<K: Kernel>(cloud: &Cloud, i: usize) -> Moments {
    let mut m = Moments::default();
    for (_, r, d) in cloud.pairs(i) {
        let w = K::w(d, cloud.re);
        let d2 = d * d;
        m.n += w;
        m.wr2 += w * d2;
        m.gc += r * r.transpose() * (w / d2);
        let q = Vec2::new(r.x * r.x, r.y * r.y);
        m.theta += q * q.transpose() * (w / d2);
    }
    m
}

/// Σ -w'(r) r rᵀ / r, the inverse of the CHL corrective matrix C_i up to 1/n0.
pub(crate) fn chl_moment<K: Kernel>(cloud: &Cloud, i: usize) -> Mat2 {
    let mut a = Mat2::zeros();
    for (_, r, d) in cloud.pairs(i) {
        a -= r * r.transpose() * (K::dw(d, cloud.re) / d);
    }
    a
}

/// The CHL row weight of one pair for a corrective matrix C (Ikari, Khayyer & Gotoh 2015 eqs. 20, 23-25):
/// (w''/r² - 4 w'/r³) rᵀ C r + (w'/r) tr C. With C = I this is w'' - 2w'/r.
#[inline]
pub(crate) fn chl_weight<K: Kernel>(r: Vec2, d: Real, re: Real, c: &Mat2) -> Real {
    let (dw, d2w) = (K::dw(d, re), K::d2w(d, re));
    let q = r.dot(&(c * r));
    (d2w / (d * d) - 4.0 * dw / (d * d * d)) * q + dw / d * c.trace()
}

/// Constants of the full lattice of spacing l0 (square in 2D, a line in 1D) seen from
/// one of its points: the fixed normalisation of the classic MPS operators.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LatticeConstants {
    pub l0: Real,
    pub re: Real,
    pub dim: Real,
    /// n0 = Σ w.
    pub n0: Real,
    /// λ = Σ w r² / Σ w.
    pub lambda: Real,
    /// θ = Σ w x² y² / r² (Imoto 2022 eq. 15; 0 in 1D).
    pub theta: Real,
    /// 2d / Σ w r²: the classic Laplacian's 2d / (λ n0) (Sun et al. 2022 eq. 15), so the
    /// Laplacian of |x|² is 2d on the lattice.
    pub classic_coefficient: Real,
    /// 2d / Σ L_HL(r) r² with L_HL = w'' - w'/r: the HL coefficient that replaces 1/n0
    /// of Ikari, Khayyer & Gotoh (2015) eq. 9 so the Laplacian of |x|² is 2d on the lattice.
    pub hl_coefficient: Real,
    /// d / |Σ w'(r) r|: the HS divergence's coefficient that replaces 1/n0 of Ikari, Khayyer & Gotoh (2015)
    /// eq. 2 so the divergence of x is d on the lattice.
    pub hs_divergence_coefficient: Real,
    /// Lattice points within r_e, the point itself excluded.
    pub neighbours: usize,
    /// 2d / Σ L_CHL(r) r² with the lattice's own corrective matrix (see [`chl_weight`]).
    pub chl_coefficient: Real,
}

impl LatticeConstants {
    pub fn compute<K: Kernel>(l0: Real, re: Real, dim: usize) -> Self {
        let m = (re / l0).ceil() as i64 + 1;
        let mut offsets = Vec::new();
        for a in -m..=m {
            if dim == 1 {
                if a != 0 {
                    offsets.push(Vec2::new(a as Real * l0, 0.0));
                }
                continue;
            }
            for b in -m..=m {
                if (a, b) != (0, 0) {
                    offsets.push(Vec2::new(a as Real * l0, b as Real * l0));
                }
            }
        }
        let inside: Vec<(Vec2, Real)> = offsets
            .into_iter()
            .map(|r| (r, r.norm()))
            .filter(|&(_, d)| d < re)
            .collect();
        let n0: Real = inside.iter().map(|&(_, d)| K::w(d, re)).sum();
        let wr2: Real = inside.iter().map(|&(_, d)| K::w(d, re) * (d * d)).sum();
        let theta: Real = inside
            .iter()
            .map(|&(r, d)| K::w(d, re) * r.x * r.x * r.y * r.y / (d * d))
            .sum();
        let hl: Real = inside.iter().map(|&(_, d)| K::hl(d, re) * (d * d)).sum();
        let dw_r: Real = inside.iter().map(|&(_, d)| K::dw(d, re) * d).sum();
        let mut a = Mat2::zeros();
        for &(r, d) in &inside {
            a -= r * r.transpose() * (K::dw(d, re) / d);
        }
        if dim == 1 {
            a[(1, 1)] = 1.0;
        }
        let c = a.try_inverse().unwrap_or_else(Mat2::identity);
        let chl: Real = inside
            .iter()
            .map(|&(r, d)| chl_weight::<K>(r, d, re, &c) * d * d)
            .sum();
        let d = dim as Real;
        Self {
            l0,
            re,
            dim: d,
            n0,
            lambda: wr2 / n0,
            theta,
            classic_coefficient: 2.0 * d / wr2,
            hl_coefficient: 2.0 * d / hl,
            hs_divergence_coefficient: d / dw_r.abs(),
            neighbours: inside.len(),
            chl_coefficient: 2.0 * d / chl,
        }
    }
}
