//! Buffers the step reuses from one step to the next (no allocation at a steady size).

use super::neighbors::NeighborList;
use super::pressure::{CsrMatrix, SolverCache};
use super::walls::WallContacts;
use crate::math::{Real, Vec2};

/// What the step derives from the state and keeps for the next step, and its buffers.
#[derive(Debug, Default)]
pub(crate) struct Workspace {
    /// Neighbours and wall contacts at the last predicted positions (the next step's
    /// explicit stage reads them).
    pub(crate) neighbors: NeighborList,
    pub(crate) contacts: WallContacts,
    pub(crate) scratch: Scratch,
    /// The pressure preconditioner carried from step to step (the AMG hierarchy, see
    /// engine::pressure::reuse). It changes the iterates of later solves (within the
    /// solver tolerance), so it lives with the simulation it serves.
    pub(crate) solver_cache: SolverCache,
}

/// Buffers reused from step to step.
#[derive(Debug, Default)]
pub(crate) struct Scratch {
    pub(crate) x_star: Vec<Vec2>,
    /// u^n, before the explicit forces.
    pub(crate) u_start: Vec<Vec2>,
    pub(crate) n_star: Vec<Real>,
    /// The source's ∇·u* at x* (walls' share with u^n).
    pub(crate) div_star: Vec<Real>,
    pub(crate) unknown_of: Vec<u32>,
    pub(crate) particle_of: Vec<u32>,
    pub(crate) rhs: Vec<Real>,
    pub(crate) solution: Vec<Real>,
    pub(crate) neumann: Vec<Vec2>,
    /// Dirichlet value of each free-surface particle, and the penalty's target of each
    /// graded one (0 elsewhere).
    pub(crate) surface_pressure: Vec<Real>,
    /// Surface share s in (0, 1) of a particle at the edge of the graded surface test,
    /// 0 elsewhere (`Scheme::soft_surface`).
    pub(crate) surface_softness: Vec<Real>,
    pub(crate) matrix: CsrMatrix,
    /// The source's terms beyond (rho/dt) ∇·u* (ECS, PND relaxation), per particle, for
    /// the exact projection.
    pub(crate) source_extra: Vec<Real>,
    /// The exact projection's correction to the approximate pressure, per particle
    /// (the next step's initial guess).
    pub(crate) exact_correction: Vec<Real>,
}
