//! A simulation's state in a checkpoint: everything the next steps read that the case
//! does not give. The configuration is not saved: [`Simulation::placed`] rebuilds it
//! from the case exactly (it depends on the initial particles, which the case fixes).

use super::simulation::Simulation;
use super::walls::WallState;
use crate::state_io::{StateError, StateReader, StateWriter};

impl Simulation {
    /// Particles, wall poses, time, the last loads and accelerations (the time-step
    /// control reads them), statistics, and the workspace the next step reads: the
    /// neighbour lists and wall contacts at the last predicted positions and the
    /// pressure solver's reused AMG hierarchy and counters (both change the iterates).
    pub fn save_state(&self, w: &mut StateWriter) -> std::io::Result<()> {
        let poses: Vec<WallState> = self.walls.iter().map(|o| o.state).collect();
        w.put(&self.particles)?;
        w.put(&poses)?;
        w.put(&(self.time, self.steps, self.acceleration_dt))?;
        w.put(&self.loads)?;
        w.put(&self.stats)?;
        w.put(&self.surface_pressure)?;
        w.put(&self.workspace)
    }

    /// Replace the state of this simulation (built from the same case) with a saved one.
    pub fn restore_state(&mut self, r: &mut StateReader) -> Result<(), StateError> {
        self.particles = r.take()?;
        let poses: Vec<WallState> = r.take()?;
        if poses.len() != self.walls.len() {
            return Err(StateError::Mismatch(format!(
                "{} wall objects saved, the case has {}",
                poses.len(),
                self.walls.len()
            )));
        }
        for (object, pose) in self.walls.iter_mut().zip(poses) {
            object.state = pose;
        }
        (self.time, self.steps, self.acceleration_dt) = r.take()?;
        self.loads = r.take()?;
        self.stats = r.take()?;
        self.surface_pressure = r.take()?;
        self.workspace = r.take()?;
        Ok(())
    }
}
