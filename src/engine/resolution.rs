//! Multi-resolution particles: each particle carries its spacing as a multiple s_i of
//! l0, the finest spacing (1 in the fine region, 2 one level coarser, …), and keeps it
//! for the run (a static graded layout, built by `scene`).
//!
//! Every pair operator sees a pair (i, j) through two factors:
//! - the pair radius r_e s_ij with s_ij = (s_i + s_j)/2, symmetric, so j is a
//!   neighbour of i exactly when i is one of j;
//! - the volume factor v_ij = (s_j / s_ij)^d, the neighbour's volume over the pair's
//!   lattice cell: in a uniform region of any level both are exact (w and n0 are
//!   functions of r/r_e, so a lattice of spacing s l0 with radius s r_e has the same
//!   n0, and the lattice-normalised coefficients carry over), and across a jump
//!   m_i v_ij = ρ l0^d s_i^d s_j^d / s_ij^d is symmetric, so a pair sum weighted by the
//!   particle's mass (the viscous and filter exchanges, the pressure equation's row
//!   scaled by the particle's volume) stays symmetric: momentum is exchanged pairwise and
//!   the pressure matrix stays symmetric for the conjugate-gradient solver.
//!
//! A uniform run has no scales at all ([`Scales::UNIFORM`]): every factor is exactly 1,
//! so its arithmetic is the single-resolution arithmetic, bit for bit.

use crate::math::Real;

/// The particles' spacing multiples, or none for a uniform run.
#[derive(Debug, Clone, Copy, Default)]
pub struct Scales<'a>(Option<&'a [Real]>);

impl<'a> Scales<'a> {
    pub const UNIFORM: Self = Self(None);

    /// The scales `s` when the run has more than one level, else [`Self::UNIFORM`].
    pub fn new(s: &'a [Real], multi_resolution: bool) -> Self {
        if multi_resolution {
            Self(Some(s))
        } else {
            Self::UNIFORM
        }
    }

    pub fn is_uniform(&self) -> bool {
        self.0.is_none()
    }

    /// s_i.
    #[inline]
    pub fn of(&self, i: usize) -> Real {
        self.0.map_or(1.0, |s| s[i])
    }

    /// s_i^d with d = 2: the particle's volume (and mass) over that of a fine particle.
    #[inline]
    pub fn volume(&self, i: usize) -> Real {
        let s = self.of(i);
        s * s
    }

    /// (s_ij, v_ij) of the pair (i, j) (module docs).
    #[inline]
    pub fn pair(&self, i: usize, j: usize) -> (Real, Real) {
        match self.0 {
            None => (1.0, 1.0),
            // most pairs share a level (about 97 % of the shipped wedge's): (s, 1) is
            // what the general formula gives them bit for bit, without its division
            Some(s) if s[i] == s[j] => (s[i], 1.0),
            Some(s) => {
                let sij = 0.5 * (s[i] + s[j]);
                let v = s[j] / sij;
                (sij, v * v)
            }
        }
    }

    /// The largest and smallest s.
    pub fn range(&self) -> (Real, Real) {
        match self.0 {
            None => (1.0, 1.0),
            Some(s) => s
                .iter()
                .fold((Real::INFINITY, 0.0 as Real), |(lo, hi), &v| {
                    (lo.min(v), hi.max(v))
                }),
        }
    }
}
