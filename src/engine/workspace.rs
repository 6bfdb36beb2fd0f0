//! Buffers the step reuses from one step to the next (no allocation at a steady size).

use super::neighbors::NeighborList;
use super::pressure::{CsrMatrix, SolverCache};
use super::walls::WallContacts;
use crate::math::{Real, Vec2};

/// What the step derives from the state and keeps for the next step, and its buffers.
#[derive(Debug, Default, serde::Serialize, serde::Deserialize)]
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

/// Buffers reused from step to step. Every one but `exact_correction` is written by a
/// step before that step reads it, so a checkpoint skips them (they were half of the
/// state of the 30° wedge: 6 of 12 MB at 20 000 particles).
#[derive(Debug, Default, serde::Serialize, serde::Deserialize)]
pub(crate) struct Scratch {
    #[serde(skip)]
    pub(crate) x_star: Vec<Vec2>,
    /// u^n, before the explicit forces.
    #[serde(skip)]
    pub(crate) u_start: Vec<Vec2>,
    #[serde(skip)]
    pub(crate) n_star: Vec<Real>,
    /// The source's ∇·u* at x* (walls' share with u^n).
    #[serde(skip)]
    pub(crate) div_star: Vec<Real>,
    #[serde(skip)]
    pub(crate) unknown_of: Vec<u32>,
    #[serde(skip)]
    pub(crate) particle_of: Vec<u32>,
    #[serde(skip)]
    pub(crate) rhs: Vec<Real>,
    #[serde(skip)]
    pub(crate) solution: Vec<Real>,
    #[serde(skip)]
    pub(crate) neumann: Vec<Vec2>,
    /// Dirichlet value of each free-surface particle, and the penalty's target of each
    /// graded one (0 elsewhere).
    #[serde(skip)]
    pub(crate) surface_pressure: Vec<Real>,
    /// Surface share s in (0, 1) of a particle at the edge of the graded surface test,
    /// 0 elsewhere (`Scheme::soft_surface`).
    #[serde(skip)]
    pub(crate) surface_softness: Vec<Real>,
    #[serde(skip)]
    pub(crate) matrix: CsrMatrix,
    /// The source's terms beyond (rho/dt) ∇·u* (ECS, PND relaxation), per particle, for
    /// the exact projection.
    #[serde(skip)]
    pub(crate) source_extra: Vec<Real>,
    /// The exact projection's correction to the approximate pressure, per particle
    /// (the next step's initial guess).
    pub(crate) exact_correction: Vec<Real>,
}
