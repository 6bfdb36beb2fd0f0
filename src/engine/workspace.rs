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
    /// The buffer of the list before `neighbors`, which the next list is written into.
    #[serde(skip)]
    pub(crate) spare_pairs: Vec<u32>,
    /// The pressure equation of the last step: its buffers, reused, and the exact
    /// projection's correction, carried.
    pub(crate) system: PressureSystem,
    /// The pressure preconditioner carried from step to step (the AMG hierarchy, see
    /// engine::pressure::reuse). It changes the iterates of later solves (within the
    /// solver tolerance), so it lives with the simulation it serves.
    pub(crate) solver_cache: SolverCache,
}

/// The pressure equation A p = b over the unknown (not free-surface) particles, written
/// by the assembly stage and solved by the solve stage; the correction stage reads its
/// wall gradients. Every buffer but `exact_correction` is written by a step before that
/// step reads it, so a checkpoint skips them (they were half of the state of the 30°
/// wedge: 6 of 12 MB at 20 000 particles); they are kept only to be refilled without
/// allocation.
#[derive(Debug, Default, serde::Serialize, serde::Deserialize)]
pub(crate) struct PressureSystem {
    /// The Neumann extrapolation gradient c = rho (g - a_w) of every wall contact.
    #[serde(skip)]
    pub(crate) neumann: Vec<Vec2>,
    /// Row of each particle (u32::MAX for a Dirichlet particle), and particle of each row.
    #[serde(skip)]
    pub(crate) unknown_of: Vec<u32>,
    #[serde(skip)]
    pub(crate) particle_of: Vec<u32>,
    #[serde(skip)]
    pub(crate) matrix: CsrMatrix,
    #[serde(skip)]
    pub(crate) rhs: Vec<Real>,
    /// The initial guess (the last pressures), then the solution.
    #[serde(skip)]
    pub(crate) solution: Vec<Real>,
    /// The source's terms beyond (rho/dt) ∇·u* (ECS, PND relaxation), per particle, for
    /// the exact projection.
    #[serde(skip)]
    pub(crate) source_extra: Vec<Real>,
    /// The exact projection's correction to the approximate pressure, per particle
    /// (the next step's initial guess).
    pub(crate) exact_correction: Vec<Real>,
}
