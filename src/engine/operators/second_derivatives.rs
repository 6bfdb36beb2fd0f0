//! Imoto's second-order partial derivative operators (Imoto 2022 §5), two-dimensional:
//!
//! - regular (eq. 26): ⟨∂_k² f⟩ = 2d/(nλ - d²θ) Σ f_ij x_k² w / r² - 2d²θ/(nλ(nλ - d²θ)) Σ f_ij w;
//! - mixed (eq. 27): ⟨∂_x∂_y f⟩ = (1/θ) Σ f_ij x y w / r²;
//! - anisotropic regular (eq. 29): (⟨∂_x² f⟩, ⟨∂_y² f⟩) = 2 Θ⁻¹ Σ f_ij q_ij w / r²,
//!   q_ij = (x², y²);
//! - anisotropic mixed (eq. 30): (1/θ_{x,y}) Σ f_ij x y w / r², equal to eq. 27 in 2D.
//!
//! n, λ, θ are the particle's own (Imoto 2022 §3.1 "non-fixed values").

use super::moments::moments;
use super::Cloud;
use crate::engine::kernel::Kernel;
use crate::math::{Real, Vec2};
use rayon::prelude::*;

/// ∂xx, ∂yy and ∂xy of a field at one particle.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SecondDerivatives {
    pub xx: Real,
    pub yy: Real,
    pub xy: Real,
}

/// Σ f_ij (x², y², xy, 1) w / r² and Σ f_ij w.
fn sums<K: Kernel>(cloud: &Cloud, i: usize, f: &[Real]) -> (Vec2, Real, Real) {
    let mut q = Vec2::zeros();
    let (mut mixed, mut plain) = (0.0, 0.0);
    for (j, r, d) in cloud.pairs(i) {
        let w = K::w(d, cloud.re);
        let fw = (f[j] - f[i]) * w;
        q += Vec2::new(r.x * r.x, r.y * r.y) * (fw / (d * d));
        mixed += fw * r.x * r.y / (d * d);
        plain += fw;
    }
    (q, mixed, plain)
}

/// Paper 000 eqs. 26-27 at every particle.
pub fn second_derivatives<K: Kernel>(cloud: &Cloud, f: &[Real]) -> Vec<SecondDerivatives> {
    (0..cloud.len())
        .into_par_iter()
        .map(|i| {
            let m = moments::<K>(cloud, i);
            let (q, mixed, plain) = sums::<K>(cloud, i, f);
            let (nl, theta, d) = (m.wr2, m.theta[(0, 1)], 2.0);
            let den = nl - d * d * theta;
            if nl <= 0.0 || den <= 0.0 || theta <= 0.0 {
                return SecondDerivatives::default();
            }
            let a = 2.0 * d / den;
            let b = 2.0 * d * d * theta / (nl * den);
            SecondDerivatives {
                xx: a * q.x - b * plain,
                yy: a * q.y - b * plain,
                xy: mixed / theta,
            }
        })
        .collect()
}

/// Paper 000 eqs. 29-30 at every particle.
pub fn anisotropic_second_derivatives<K: Kernel>(
    cloud: &Cloud,
    f: &[Real],
) -> Vec<SecondDerivatives> {
    (0..cloud.len())
        .into_par_iter()
        .map(|i| {
            let theta = moments::<K>(cloud, i).theta;
            let (q, mixed, _) = sums::<K>(cloud, i, f);
            match theta.try_inverse() {
                Some(inv) if theta[(0, 1)] > 0.0 => {
                    let v = inv * q * 2.0;
                    SecondDerivatives {
                        xx: v.x,
                        yy: v.y,
                        xy: mixed / theta[(0, 1)],
                    }
                }
                _ => SecondDerivatives::default(),
            }
        })
        .collect()
}
