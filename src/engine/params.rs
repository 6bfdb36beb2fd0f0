//! MpsParameters: the constants of one simulation, derived once from the case.
//!
//! Symbols (used throughout the engine): l0 initial spacing; r_e influence radius of
//! number density, gradient and source; r_e,lap of the Laplacian; n0 the number
//! density of a particle in the full initial lattice; d = 2 the dimension.
//!
//! The Laplacian and divergence coefficients are normalised on the initial lattice,
//! as lambda normalises the classic Laplacian (Koshizuka & Oka 1996): the Laplacian of
//! |x|² is 2d and the divergence of x is d exactly on the lattice, for every kernel.
//! With the 1/n0 prefactor of Ikari, Khayyer & Gotoh (2015) eqs. 3 and 9 the HL Laplacian of |x|² is 8.5
//! instead of 4 at r_e = 2.1 l0 (Koshizuka kernel), which scales pressures down.

use super::operators::LatticeConstants;
use crate::case::{Case, LaplacianKind, Scheme};
use crate::math::Real;
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
    /// The full lattice at r_e (number density, gradient, source) and at r_e,lap.
    pub lattice: LatticeConstants,
    pub lattice_lap: LatticeConstants,
}

impl MpsParameters {
    /// Radius of the neighbour list: the larger of r_e and the Laplacian's.
    pub fn neighbour_radius(&self) -> Real {
        self.re.max(self.re_lap)
    }

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
        // the full lattice seen from one of its points, once for the run
        let (lattice, lattice_lap) = with_kernel!(scheme.kernel, K => (
            LatticeConstants::compute::<K>(l0, re, 2),
            LatticeConstants::compute::<K>(l0, re_lap, 2),
        ));
        let laplacian_coefficient = match scheme.laplacian {
            // Imoto's second-order Laplacian is the classic one (Imoto 2022 Theorem 3.1)
            LaplacianKind::Classic | LaplacianKind::SecondOrder => lattice_lap.classic_coefficient,
            _ => lattice_lap.hl_coefficient,
        };
        Self {
            l0,
            re,
            re_lap,
            n0: lattice.n0,
            lambda: lattice_lap.lambda,
            laplacian_coefficient,
            divergence_coefficient: lattice.hs_divergence_coefficient,
            gradient_coefficient: DIM / lattice.n0,
            lattice,
            lattice_lap,
            density,
            viscosity,
            gravity,
            particle_mass: density * l0 * l0,
        }
    }
}
