//! The MPS operator family as pure functions over a particle cloud: positions, the
//! neighbour list, the influence radius r_e and the dimension d. Each operator returns
//! one value per particle (computed in parallel, written by index: deterministic).
//!
//! Symbols (used in every submodule): r_ij = x_j - x_i, r = |r_ij|, f_ij = f_j - f_i,
//! w = w(r) the weight of [`Kernel`](super::kernel::Kernel), n_i = Σ_j w (the particle
//! number density), n0 its value in the full reference lattice, λ the classic
//! Laplacian's Σ w r² / Σ w.
//!
//! Every Laplacian here is linear with the form ⟨∇²f⟩_i = Σ_j c_ij f_ij, so each
//! variant is defined once by its row coefficients ([`laplacian_row`]), from which
//! both the value ([`laplacian`]) and the pressure-equation row follow. Likewise every
//! linear gradient is ⟨∇f⟩_i = Σ_j g_ij f_ij with vector coefficients
//! ([`gradient_row`]); the divergence matching a gradient is Σ_j g_ij · u_ij.
//!
//! Which formula each variant is, with the paper and equation, is in the doc comment of
//! the submodule that defines it.

mod collision;
mod density;
mod divergence;
mod gradient;
mod laplacian;
mod moments;
mod second_derivatives;
mod vector_laplacian;

pub use collision::{collision_velocity_change, collision_velocity_changes};
pub use density::{
    hs_divergence_row, neighbour_count, number_density_and_divergence,
    number_density_and_divergence_all, number_density_and_divergence_then, number_density_gradient,
};
pub use divergence::divergence;
pub use gradient::{
    corrected_gradient_matrix, corrected_gradient_row, first_moment, gradient, gradient_row,
    minimum_over_neighbourhood, pressure_gradient, GradientRow, PressureGradient, VirtualPoints,
};
pub use laplacian::{
    for_each_lattice_coefficient, has_laplacian_neighbour, laplacian, laplacian_row, LaplacianRow,
};
pub use moments::LatticeConstants;
pub use second_derivatives::{
    anisotropic_second_derivatives, second_derivatives, SecondDerivatives,
};
pub use vector_laplacian::{vector_laplacian_sum, vector_laplacian_sums};

use super::neighbors::NeighborList;
use super::resolution::Scales;
use crate::math::{Real, Vec2};

/// The particle cloud an operator acts on. The neighbour list may have been built with a
/// radius larger than `re`: every weight vanishes at and beyond `re`.
#[derive(Debug, Clone, Copy)]
pub struct Cloud<'a> {
    pub positions: &'a [Vec2],
    pub neighbors: &'a NeighborList,
    /// Influence radius r_e of the operator.
    pub re: Real,
    /// Dimension d: 2 for the engine, 1 for the one-dimensional paper tests (points on
    /// the x axis).
    pub dim: Real,
    /// Multi-resolution spacings: the operators the step calls (number density and its
    /// gradient, HS divergence, the lattice Laplacian rows and the vector Laplacian, the
    /// pressure gradient and the corrected gradient's rows, the first moment, the
    /// collision pass, the neighbourhood queries) take each pair's radius and volume
    /// factor from them; the other operators are single-resolution.
    pub scales: Scales<'a>,
}

impl<'a> Cloud<'a> {
    pub fn new(positions: &'a [Vec2], neighbors: &'a NeighborList, re: Real) -> Self {
        Self {
            positions,
            neighbors,
            re,
            dim: 2.0,
            scales: Scales::UNIFORM,
        }
    }

    /// The same cloud with multi-resolution spacings.
    pub fn with_scales(self, scales: Scales<'a>) -> Self {
        Self { scales, ..self }
    }

    pub fn one_dimensional(positions: &'a [Vec2], neighbors: &'a NeighborList, re: Real) -> Self {
        Self {
            positions,
            neighbors,
            re,
            dim: 1.0,
            scales: Scales::UNIFORM,
        }
    }

    pub fn len(&self) -> usize {
        self.positions.len()
    }

    pub fn is_empty(&self) -> bool {
        self.positions.is_empty()
    }

    /// (r_e of the pair, volume factor v_ij): see `resolution`.
    #[inline]
    pub(crate) fn pair(&self, i: usize, j: usize) -> (Real, Real) {
        let (s, v) = self.scales.pair(i, j);
        (self.re * s, v)
    }

    /// The neighbours j of i with r_ij < r_e s_ij (a coincident one included), in list
    /// order.
    #[inline]
    pub fn within(&self, i: usize) -> impl Iterator<Item = usize> + '_ {
        let xi = self.positions[i];
        self.neighbors
            .of(i)
            .iter()
            .map(|&j| j as usize)
            .filter(move |&j| (self.positions[j] - xi).norm() < self.pair(i, j).0)
    }

    /// Whether `pred(j)` holds for a neighbour j of i with 0 < r_ij < r_e s_ij (a query of
    /// the neighbourhood, not a sum: it stops at the first such neighbour).
    #[inline]
    pub fn any_within(&self, i: usize, pred: impl Fn(usize) -> bool) -> bool {
        let xi = self.positions[i];
        self.neighbors.of(i).iter().any(|&j| {
            let j = j as usize;
            pred(j) && {
                let d = (self.positions[j] - xi).norm();
                d < self.pair(i, j).0 && d != 0.0
            }
        })
    }

    /// (j, r_ij, r) for the neighbours of i strictly inside r_e, in list order.
    #[inline]
    pub(crate) fn pairs(&self, i: usize) -> impl Iterator<Item = (usize, Vec2, Real)> + '_ {
        let xi = self.positions[i];
        let re = self.re;
        self.neighbors.of(i).iter().filter_map(move |&j| {
            let j = j as usize;
            let r = self.positions[j] - xi;
            let d = r.norm();
            (d > 0.0 && d < re).then_some((j, r, d))
        })
    }
}

/// How the number density and λ in the classic formulas are taken.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Normalisation {
    /// Per particle: n_i and λ_i of the particle's own neighbourhood, as in Imoto (2022)
    /// §3.1 ("non-fixed values"); the HL/CHL coefficients likewise from the particle's own
    /// Σ L(r) r² (exact for |x|² wherever the sum is not degenerate).
    Local,
    /// Fixed constants of the full reference lattice of spacing l0 (the classic choice:
    /// n0 and λ of Koshizuka & Oka 1996, and the HL/CHL coefficients that make the
    /// Laplacian of |x|² equal 2d on the lattice, as lambda does for the classic one).
    Reference(LatticeConstants),
}
