//! Gradient operators ⟨∇f⟩_i, each as vector row coefficients g_ij with
//! ⟨∇f⟩_i = Σ_j g_ij f_ij for the linear ones:
//!
//! - classic (Koshizuka & Oka 1996; Imoto 2022 eq. 13, Sun et al. 2022 eq. 13):
//!   g_ij = (d / n) r_ij w / r², n = n0 or n_i by [`Normalisation`]. Used by
//!   [`GradientKind::MinimumPressure`] with f_ij replaced by f_j - f̂_i, f̂_i the minimum
//!   of f over i and its neighbours (stability), and by [`GradientKind::Cmps`] with the
//!   antisymmetric (f_i + f_j) - (f̂_i + f̂_j) (Khayyer & Gotoh 2008; Sun et al. 2022 eq. 19),
//!   and by [`GradientKind::Symmetric`] with f_i + f_j (the SPH-like pair form).
//! - corrected GC (Ikari, Khayyer & Gotoh 2015 eqs. 12-13, Sun et al. 2022 eqs. 21-22):
//!   g_ij = A_i⁻¹ r_ij w / r² with A_i = Σ w r rᵀ / r²: exact for linear fields on any cloud. Where A_i is
//!   ill-conditioned (splash, few neighbours, a one-sided line of neighbours) the
//!   reciprocal condition number falls below [`CORRECTED_GRADIENT_MIN_RCOND`] and the
//!   classic coefficient is used instead.
//! - anisotropic (Imoto 2022 eq. 28): g_ij,k = r_ij,k w / (r² n_{i,k}).
//! - least squares (LSMPS type, Tamai & Koshizuka 2014; Sun et al. 2022 §3.3): the first
//!   components of the weighted least-squares fit of f_ij on the second-order basis
//!   (x, y, x², xy, y²) scaled by r_e; second-order accurate on any non-degenerate cloud.

use super::laplacian::least_squares_fit;
use super::moments::moments;
use super::{Cloud, Normalisation};
use crate::case::GradientKind;
use crate::engine::kernel::Kernel;
use crate::math::{Mat2, Real, Vec2};
use rayon::prelude::*;

/// The GC matrix C = [(1/n0) A]⁻¹ from the moments A = Σ w r rᵀ / r² (fluid and virtual
/// wall points); on the full lattice C = d I. `None` where the moments are too degenerate
/// to invert safely, det(A/n0) at most 0.3 of the lattice's (1/d)^d: the gradient then
/// falls back to the classic normalisation. The one criterion of every corrected
/// gradient (a splash particle at the dam break's plunge took 0.1-3 MPa within two
/// steps with a looser one).
pub fn corrected_gradient_matrix(moment: &Mat2, n0: Real, dim: Real) -> Option<Mat2> {
    let mm = moment / n0;
    let lattice_det = (1.0 / dim).powi(2);
    if mm.determinant() > 0.3 * lattice_det {
        mm.try_inverse()
    } else {
        None
    }
}

/// f̂_i: the minimum of f over i and its neighbours within r_e (the classic gradient's
/// reference value, Koshizuka & Oka 1996).
#[inline]
pub fn minimum_over_neighbourhood(cloud: &Cloud, f: &[Real], i: usize) -> Real {
    cloud.within(i).map(|j| f[j]).fold(f[i], Real::min)
}

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
            let m = moments::<K>(cloud, i);
            let n0 = match norm {
                Normalisation::Local => m.n,
                Normalisation::Reference(c) => c.n0,
            };
            let mut a = m.gc;
            if cloud.dim < 2.0 {
                // the unused direction as on the lattice
                a[(1, 1)] = n0 / cloud.dim;
            }
            match corrected_gradient_matrix(&a, n0, cloud.dim) {
                Some(c) => cloud
                    .pairs(i)
                    .map(|(j, r, d)| (j, c * r * (K::w(d, cloud.re) / (d * d)) / n0))
                    .collect(),
                None => classic_row::<K>(cloud, norm, i),
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
            .map(|i| minimum_over_neighbourhood(cloud, f, i))
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

/// The virtual wall points' share of one particle's pressure gradient, from one wall
/// contact (supplied by the wall model, `WallContacts::virtual_points`): with the
/// extrapolated virtual pressures p_k = p_i + c·r_ik, Σ_k (p_k - p_i) r w / r² = M2 c.
#[derive(Debug, Clone, Copy, Default)]
pub struct VirtualPoints {
    /// M2 c: the Neumann part.
    pub linear: Vec2,
    /// Σ r w / r² (M1).
    pub moment1: Vec2,
    /// Σ r rᵀ w / r² (M2).
    pub moment2: Mat2,
}

/// The constants of the step's pressure gradient.
#[derive(Debug, Clone, Copy)]
pub struct PressureGradient {
    pub kind: GradientKind,
    /// d / n0: the classic normalisation.
    pub classic: Real,
    pub n0: Real,
    pub dim: Real,
    /// κ of the corrected gradient's repulsive term and the pair distance below which it
    /// acts (`scheme.gradient_stabilization`, `scheme.stabilization_distance`; times s_ij
    /// with multi-resolution).
    pub stabilization: Real,
    pub close: Real,
}

/// The pressure gradient that moves particle i, fluid neighbours plus virtual wall points:
/// - minimum pressure (Sun et al. 2022 eq. 13): (d/n0) [Σ r (p_j - p̂_i) w/r² + M1 (p_i - p̂_i) + M2 c];
/// - symmetric: (d/n0) [Σ r (p_i + p_j) w/r² + 2 p_i M1 + M2 c];
/// - CMPS (Sun et al. 2022 eq. 19): (d/n0) [Σ r (p_i + p_j - p̂_i - p̂_j) w/r² + 2 (p_i - p̂_i) M1 + M2 c];
/// - corrected (Ikari, Khayyer & Gotoh 2015 eqs. 12-13, the others away from walls):
///   C [Σ r (p_j - p_i) w/r² + M2 c] / n0 with C over the fluid and wall moments, plus
///   the repulsive part of the minimum-pressure form, κ (d/n0) (p_i - p̂_i) Σ r w / r²
///   over pairs closer than `close` (silent on the lattice, so still water stays still;
///   it pushes clustered particles apart); the minimum-pressure form where C is
///   degenerate.
///
/// p̂ is the minimum over each neighbourhood ([`minimum_over_neighbourhood`]): `p_min`
/// gives it for every particle, which CMPS needs (it reads p̂_j); without it p̂_i is
/// found when the form needs it, which for the corrected form is only where a pair is
/// closer than `close` or C is degenerate (a 160k-particle tank skips a pass over the
/// neighbours, 4 of its 155 ms a step).
#[inline]
pub fn pressure_gradient<K: Kernel>(
    g: &PressureGradient,
    cloud: &Cloud,
    p: &[Real],
    p_min: Option<&[Real]>,
    i: usize,
    walls: impl Iterator<Item = VirtualPoints>,
) -> Vec2 {
    let p_hat = || p_min.map_or_else(|| minimum_over_neighbourhood(cloud, p, i), |m| m[i]);
    let minimum_pressure = |p_hat: Real, wall: &WallSums| {
        let s_min = weighted_sum::<K>(cloud, i, |j| p[j] - p_hat);
        (s_min + wall.m1 * (p[i] - p_hat) + wall.linear) * g.classic
    };
    match g.kind {
        GradientKind::MinimumPressure => {
            minimum_pressure(p_hat(), &WallSums::of(walls, &mut Mat2::zeros()))
        }
        GradientKind::Symmetric => {
            let wall = WallSums::of(walls, &mut Mat2::zeros());
            let s_sym = weighted_sum::<K>(cloud, i, |j| p[i] + p[j]);
            (s_sym + wall.m1 * (2.0 * p[i]) + wall.linear) * g.classic
        }
        GradientKind::Cmps => {
            let wall = WallSums::of(walls, &mut Mat2::zeros());
            let m = p_min.expect("CMPS reads the neighbours' minimum pressures");
            let s_sym = weighted_sum::<K>(cloud, i, |j| p[i] + p[j] - m[i] - m[j]);
            (s_sym + wall.m1 * (2.0 * (p[i] - m[i])) + wall.linear) * g.classic
        }
        _ => {
            let (mut s_fluid, mut s_close) = (Vec2::zeros(), Vec2::zeros());
            let mut moment = Mat2::zeros();
            for_each_pair::<K>(cloud, i, |j, r, w, d, s| {
                s_fluid += r * ((p[j] - p[i]) * w);
                if d < g.close * s {
                    s_close += r * w;
                }
                moment += r * r.transpose() * w;
            });
            let wall = WallSums::of(walls, &mut moment);
            match corrected_gradient_matrix(&moment, g.n0, g.dim) {
                Some(c) => {
                    // zero without a close pair, whatever p̂_i: not looked for then
                    let stabilizer = if s_close == Vec2::zeros() {
                        Vec2::zeros()
                    } else {
                        s_close * ((p[i] - p_hat()) * g.stabilization * g.classic)
                    };
                    c * (s_fluid + wall.linear) / g.n0 + stabilizer
                }
                None => minimum_pressure(p_hat(), &wall),
            }
        }
    }
}

/// The corrected gradient of particle i in row form, ⟨∇p⟩_i = Σ_j g_ij (p_j - p_i) + b_i
/// (Ikari, Khayyer & Gotoh 2015 eqs. 12-13): g_ij = C r_ij w / r² v_ij / n0 with C over
/// the fluid and the virtual wall points' moments (`walls`, as in [`pressure_gradient`]),
/// and b_i = C Σ M2 c / n0 the virtual points' Neumann part; where C is degenerate
/// ([`corrected_gradient_matrix`]) the classic normalisation `classic` (d/n0) replaces
/// C / n0. Returns ((j, g_ij) for the neighbours within r_e s_ij, b_i). The exact
/// projection applies these rows at every GMRES iteration.
pub fn corrected_gradient_row<K: Kernel>(
    cloud: &Cloud,
    n0: Real,
    classic: Real,
    i: usize,
    walls: impl Iterator<Item = VirtualPoints>,
) -> (GradientRow, Vec2) {
    let mut moment = Mat2::zeros();
    let mut raw = Vec::with_capacity(cloud.neighbors.of(i).len());
    for_each_pair::<K>(cloud, i, |j, r, w, _, _| {
        moment += r * r.transpose() * w;
        raw.push((j, r * w));
    });
    let wall = WallSums::of(walls, &mut moment);
    let scale = corrected_gradient_matrix(&moment, n0, cloud.dim)
        .map_or(Mat2::identity() * classic, |c| c / n0);
    let row = raw.into_iter().map(|(j, g)| (j, scale * g)).collect();
    (row, scale * wall.linear)
}

/// The first moment of particle i's fluid neighbourhood, M1 = Σ_j r_ij w / r² v_ij over
/// 0 < r < r_e s_ij: zero inside a full lattice, pointing into the fluid where the
/// neighbourhood is one-sided (the free-surface test's asymmetry, Sun et al. 2022 §2.3;
/// the walls' share is `WallTerms::moment1`).
#[inline]
pub fn first_moment<K: Kernel>(cloud: &Cloud, i: usize) -> Vec2 {
    weighted_sum::<K>(cloud, i, |_| 1.0)
}

/// The virtual wall points' sums of one particle: Σ M2 c and Σ M1 (M2 goes into the
/// caller's moment matrix, after the fluid pairs).
struct WallSums {
    linear: Vec2,
    m1: Vec2,
}

impl WallSums {
    #[inline]
    fn of(walls: impl Iterator<Item = VirtualPoints>, moment: &mut Mat2) -> Self {
        let mut sums = Self {
            linear: Vec2::zeros(),
            m1: Vec2::zeros(),
        };
        for v in walls {
            sums.linear += v.linear;
            sums.m1 += v.moment1;
            *moment += v.moment2;
        }
        sums
    }
}

/// Σ r_ij f(j) w(r)/r² v_ij over the pairs of i inside r_e.
#[inline]
fn weighted_sum<K: Kernel>(cloud: &Cloud, i: usize, f: impl Fn(usize) -> Real) -> Vec2 {
    let mut s = Vec2::zeros();
    for_each_pair::<K>(cloud, i, |j, r, w, _, _| s += r * (f(j) * w));
    s
}

/// `f(j, r_ij, w(r)/r² v_ij, r, s_ij)` for the neighbours j of i strictly inside the
/// pair's radius r_e s_ij, in list order.
#[inline]
fn for_each_pair<K: Kernel>(
    cloud: &Cloud,
    i: usize,
    mut f: impl FnMut(usize, Vec2, Real, Real, Real),
) {
    let x = cloud.positions;
    for &j in cloud.neighbors.of(i) {
        let j = j as usize;
        let r = x[j] - x[i];
        let d2 = r.norm_squared();
        let d = d2.sqrt();
        let (s, v) = cloud.scales.pair(i, j);
        let re = cloud.re * s;
        if d >= re || d == 0.0 {
            continue;
        }
        f(j, r, K::w(d, re) / d2 * v, d, s);
    }
}
