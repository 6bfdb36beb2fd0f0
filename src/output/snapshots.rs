//! VTK snapshots (.vtu per snapshot + .pvd index). PLACEHOLDER: writes nothing yet.

use crate::engine::Simulation;
use std::path::Path;

pub struct SnapshotWriter;

impl SnapshotWriter {
    /// None when no snapshot interval is set: no writer exists.
    pub fn create(_dir: &Path, interval: Option<f64>) -> std::io::Result<Option<Self>> {
        Ok(interval.filter(|i| *i > 0.0).map(|_| Self))
    }
    pub fn record(&mut self, _sim: &Simulation) -> std::io::Result<()> {
        Ok(())
    }
    pub fn finish(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}
