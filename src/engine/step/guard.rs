//! The step guard's rollback: what the stages before the correction overwrite, kept
//! until the guard has accepted the step, and put back when it turns the step down
//! (`Simulation::try_step`).

use crate::engine::neighbors::NeighborList;
use crate::engine::simulation::Simulation;
use crate::engine::walls::WallContacts;
use crate::math::{Real, Vec2};

/// The state at the start of a step that its stages overwrite before the guard's test,
/// besides the velocity (the explicit stage returns u^n) and the neighbour and contact
/// lists (the step keeps the last ones).
pub(super) struct Rollback {
    pressure: Vec<Real>,
    free_surface: Vec<bool>,
}

impl Rollback {
    pub(super) fn save(sim: &Simulation) -> Self {
        Self {
            pressure: sim.particles.pressure.clone(),
            free_surface: sim.particles.free_surface.clone(),
        }
    }

    /// Puts the state back as the step found it: velocity `u_start` and the last step's
    /// `lists` (the explicit stage of the repeated step reads them).
    pub(super) fn restore(
        self,
        sim: &mut Simulation,
        u_start: &[Vec2],
        lists: (NeighborList, WallContacts),
    ) {
        sim.particles.velocity.clear();
        sim.particles.velocity.extend_from_slice(u_start);
        sim.particles.pressure = self.pressure;
        sim.particles.free_surface = self.free_surface;
        (sim.workspace.neighbors, sim.workspace.contacts) = lists;
    }
}
