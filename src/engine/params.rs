//! MpsParameters: the constants of one simulation, derived once from the case.
//!
//! Symbols (used throughout the engine): l0 initial spacing; r_e influence radius of
//! number density, gradient and source; r_e,lap of the Laplacian; n0 the number
//! density of a particle in the full initial lattice; d = 2 the dimension.
//!
//! The Laplacian and divergence coefficients are normalised on the initial lattice,
//! as lambda normalises the classic Laplacian (Koshizuka & Oka 1996): the Laplacian of
//! |x|² is 2d and the divergence of x is d exactly on the lattice, for every kernel.
//! With the 1/n0 prefactor of paper 004 eqs. 3 and 9 the HL Laplacian of |x|² is 8.5
//! instead of 4 at r_e = 2.1 l0 (Koshizuka kernel), which scales pressures down.

use super::kernel::Kernel;
use super::math::Real;
use crate::case::{Case, LaplacianKind, Scheme};
use crate::with_kernel;

pub const DIM: Real = 2.0;

#[derive(Debug, Clone, PartialEq)]
pub struct MpsParameters {
    pub l0: Real,
    pub re: Real,
    pub re_lap: Real,
    /// Σ w over the full lattice at r_e.
    pub n0: Real,
    /// Classic lambda = Σ w r² / Σ w at r_e,lap.
    pub lambda: Real,
    /// Coefficient of Σ L(r)(φ_j - φ_i) for the Laplacian in use.
    pub laplacian_coefficient: Real,
    /// Coefficient c with ∇·u ≈ -c Σ w'(r) r̂·u_ij (HS form).
    pub divergence_coefficient: Real,
    /// d / n0: coefficient of the classic gradient.
    pub gradient_coefficient: Real,
    pub density: Real,
    pub viscosity: Real,
    pub gravity: [Real; 2],
    /// Mass per particle per metre of span: rho l0².
    pub particle_mass: Real,
}

/// Points (a, b) of the unit lattice within `reach` (excluding the origin), scaled by l0.
pub fn lattice_offsets(reach: Real, l0: Real) -> Vec<(Real, Real)> {
    let m = (reach / l0).ceil() as i64 + 1;
    let mut v = Vec::new();
    for a in -m..=m {
        for b in -m..=m {
            if (a, b) != (0, 0) {
                v.push((a as Real * l0, b as Real * l0));
            }
        }
    }
    v
}

impl MpsParameters {
    pub fn new(case: &Case) -> Self {
        Self::from_scheme(
            case.particle_spacing,
            &case.scheme,
            case.fluid.density,
            case.fluid.kinematic_viscosity,
            case.fluid.gravity,
        )
    }

    pub fn from_scheme(
        l0: Real,
        scheme: &Scheme,
        density: Real,
        viscosity: Real,
        gravity: [Real; 2],
    ) -> Self {
        let re = scheme.radius * l0;
        let re_lap = scheme.laplacian_radius() * l0;
        let offsets = lattice_offsets(re.max(re_lap), l0);
        let r_of = |(x, y): &(Real, Real)| (x * x + y * y).sqrt();
        let (n0, lambda, lap_sum, div_sum) = with_kernel!(scheme.kernel, K => {
            let n0: Real = offsets.iter().map(|o| K::w(r_of(o), re)).sum();
            let wl: Real = offsets.iter().map(|o| K::w(r_of(o), re_lap)).sum();
            let wl_r2: Real = offsets.iter().map(|o| K::w(r_of(o), re_lap) * r_of(o).powi(2)).sum();
            let lap_kernel_r2: Real = match scheme.laplacian {
                // Imoto's second-order Laplacian is the classic one (paper 000 Theorem 3.1)
                LaplacianKind::Classic | LaplacianKind::SecondOrder => wl_r2,
                _ => offsets.iter().map(|o| K::hl(r_of(o), re_lap) * r_of(o).powi(2)).sum(),
            };
            let div: Real = offsets.iter().map(|o| K::dw(r_of(o), re) * r_of(o)).sum();
            (n0, wl_r2 / wl, lap_kernel_r2, div)
        });
        Self {
            l0,
            re,
            re_lap,
            n0,
            lambda,
            laplacian_coefficient: 2.0 * DIM / lap_sum,
            divergence_coefficient: DIM / div_sum.abs(),
            gradient_coefficient: DIM / n0,
            density,
            viscosity,
            gravity,
            particle_mass: density * l0 * l0,
        }
    }
}
