//! The step guard's rollback: what the stages before the correction overwrite, kept
//! until the guard has accepted the step, and put back when it turns the step down
//! (`Simulation::try_step`).

use crate::engine::neighbors::NeighborList;
use crate::engine::simulation::Simulation;
use crate::engine::walls::WallContacts;
use crate::math::{Real, Vec2};

/// The state at the start of a step that its stages overwrite before the guard's test.
pub(super) struct Rollback {
    pressure: Vec<Real>,
    free_surface: Vec<bool>,
    /// The neighbours and wall contacts of the last step (the explicit stage of a
    /// repeated step reads them), once the new ones have replaced them.
    lists: Option<(NeighborList, WallContacts)>,
}

impl Rollback {
    /// Saves what the stages overwrite besides the velocity (which the explicit stage
    /// returns as u^n) and the lists (`keep_lists`).
    pub(super) fn save(sim: &Simulation) -> Self {
        Self {
            pressure: sim.particles.pressure.clone(),
            free_surface: sim.particles.free_surface.clone(),
            lists: None,
        }
    }

    /// Keeps the last step's lists once the step has replaced them.
    pub(super) fn keep_lists(&mut self, lists: (NeighborList, WallContacts)) {
        self.lists = Some(lists);
    }

    /// Puts the state back as the step found it, velocity `u_start`.
    pub(super) fn restore(self, sim: &mut Simulation, u_start: &[Vec2]) {
        sim.particles.velocity.clear();
        sim.particles.velocity.extend_from_slice(u_start);
        sim.particles.pressure = self.pressure;
        sim.particles.free_surface = self.free_surface;
        if let Some((neighbors, contacts)) = self.lists {
            sim.workspace.neighbors = neighbors;
            sim.workspace.contacts = contacts;
        }
    }
}
