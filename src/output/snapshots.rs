//! VTK snapshots: `snapshots/step_NNNNNN.vtu` (the particles; NNNNNN the step number)
//! and `snapshots/walls_NNNNNN.vtu` (every wall and body surface at its pose, cut into the
//! pieces the load integral reads, each with its pressure) every
//! snapshot interval of simulated time, the first at t = 0, and `snapshots/run.pvd`, the
//! ParaView collection indexing both by time, so that opening it shows the bodies moving
//! with the water.
//!
//! The collection is rewritten (to a temporary file, then renamed over the old one)
//! after every snapshot, so a running or failed job always leaves a valid `run.pvd`
//! naming only complete `.vtu` files.

use super::vtk::{
    pvd_string, vtu_string, walls_vtu_string, Outline, PvdEntry, VtuFields, PARTICLES_PART,
    WALLS_PART,
};
use crate::engine::walls::pressure_load::{pieces, SurfacePressure};
use crate::engine::walls::WallObject;
use crate::engine::Simulation;
use crate::math::Real;
use std::path::{Path, PathBuf};

/// Folder of the snapshots inside the run directory.
pub const SNAPSHOT_DIR: &str = "snapshots";
/// Name of the collection file.
pub const PVD_NAME: &str = "run.pvd";

pub struct SnapshotWriter {
    dir: PathBuf,
    interval: Real,
    next_time: Real,
    entries: Vec<PvdEntry>,
}

/// File name of the particles' snapshot of step `step`.
pub fn snapshot_file_name(step: u64) -> String {
    format!("step_{step:06}.vtu")
}

/// File name of the walls' and bodies' snapshot of step `step`.
pub fn walls_file_name(step: u64) -> String {
    format!("walls_{step:06}.vtu")
}

/// Write `contents` to `path` through a temporary file and a rename, so readers never
/// see a half-written file.
fn write_atomically(path: &Path, contents: &str) -> std::io::Result<()> {
    let tmp = path.with_extension("tmp");
    std::fs::write(&tmp, contents)?;
    std::fs::rename(&tmp, path)
}

/// The surface of wall object `w` at its pose as line cells carrying the pressure the
/// load integral read: each segment cut into as many equal pieces as it has points in
/// `points` (the object's [`SurfacePressure`] list, in segment order), cell k carrying
/// point k's pressure. A segment without points (before the first step) is cut into
/// [`pieces`] with pressure 0, a segment of zero length is one cell with pressure 0.
fn outline(w: &WallObject, points: &[SurfacePressure], l0: Real) -> Outline {
    let surface = w.shape.transformed(w.state.position, w.state.angle).surface;
    let mut out = Outline {
        cells: Vec::new(),
        velocities: Vec::new(),
        segment: Vec::new(),
        pressure: Vec::new(),
        moving: w.body.is_some(),
        speed: w.state.velocity.norm(),
    };
    let mut next = 0;
    for (index, [a, b]) in surface.iter().enumerate() {
        let start = next;
        while next < points.len() && points[next].segment as usize == index {
            next += 1;
        }
        let own = &points[start..next];
        let len = (b - a).norm();
        let count = match (len > 0.0, own.len()) {
            (false, _) => 1,
            (true, 0) => pieces(len, l0),
            (true, n) => n,
        };
        for m in 0..count {
            let t = |m: usize| m as Real / count as Real;
            let ends = [a + (b - a) * t(m), a + (b - a) * t(m + 1)];
            out.cells.push(ends);
            out.velocities.push(ends.map(|x| w.state.point_velocity(x)));
            out.segment.push(index as u32);
            out.pressure.push(own.get(m).map_or(0.0, |s| s.pressure));
        }
    }
    out
}

impl SnapshotWriter {
    /// None when no snapshot interval is set: no writer exists. Creates
    /// `dir/snapshots/` with an empty (valid) collection.
    pub fn create(dir: &Path, interval: Option<f64>) -> std::io::Result<Option<Self>> {
        let Some(interval) = interval.filter(|i| *i > 0.0 && i.is_finite()) else {
            return Ok(None);
        };
        let dir = dir.join(SNAPSHOT_DIR);
        std::fs::create_dir_all(&dir)?;
        let writer = Self {
            dir,
            interval,
            next_time: 0.0,
            entries: Vec::new(),
        };
        writer.write_collection()?;
        Ok(Some(writer))
    }

    /// Write a snapshot if the simulation has reached the next snapshot time.
    pub fn record(&mut self, sim: &Simulation) -> std::io::Result<()> {
        if sim.time < self.next_time - 1e-9 * self.interval {
            return Ok(());
        }
        // the same step twice (e.g. a final record after the loop) writes nothing new
        if self.entries.last().is_some_and(|e| e.time == sim.time) {
            return Ok(());
        }
        let p = &sim.particles;
        let fields = VtuFields {
            position: &p.position,
            velocity: &p.velocity,
            pressure: &p.pressure,
            number_density: &p.number_density,
            n0: Some(sim.config.params.n0),
            free_surface: &p.free_surface,
            density: Some(sim.config.params.density),
            spacing: Some(sim.config.params.l0),
            particle_spacing: sim
                .config
                .multi_resolution
                .then(|| p.scale.iter().map(|s| s * sim.config.params.l0).collect()),
        };
        let file = snapshot_file_name(sim.steps);
        write_atomically(&self.dir.join(&file), &vtu_string(&fields, sim.time))?;
        let l0 = sim.config.params.l0;
        let outlines: Vec<Outline> = sim
            .walls
            .iter()
            .enumerate()
            .map(|(k, w)| {
                let points = sim.surface_pressure.get(k).map_or(&[][..], Vec::as_slice);
                outline(w, points, l0)
            })
            .collect();
        let walls = walls_file_name(sim.steps);
        write_atomically(
            &self.dir.join(&walls),
            &walls_vtu_string(&outlines, sim.time),
        )?;
        self.entries.push(PvdEntry {
            time: sim.time,
            file,
            part: PARTICLES_PART,
        });
        self.entries.push(PvdEntry {
            time: sim.time,
            file: walls,
            part: WALLS_PART,
        });
        self.write_collection()?;
        while self.next_time <= sim.time + 1e-9 * self.interval {
            self.next_time += self.interval;
        }
        Ok(())
    }

    /// The next snapshot time and the collection so far, for a checkpoint (the `.vtu`
    /// files stay where they were written).
    pub fn state(&self) -> (Real, &[PvdEntry]) {
        (self.next_time, &self.entries)
    }

    /// Continue from a checkpoint's [`SnapshotWriter::state`].
    pub fn apply_state(
        &mut self,
        (next_time, entries): (Real, Vec<PvdEntry>),
    ) -> std::io::Result<()> {
        (self.next_time, self.entries) = (next_time, entries);
        self.write_collection()
    }

    /// The collection is complete after every `record`; nothing is pending.
    pub fn finish(&mut self) -> std::io::Result<()> {
        self.write_collection()
    }

    /// Files written so far (time, file relative to `snapshots/`, part), two per snapshot.
    pub fn entries(&self) -> &[PvdEntry] {
        &self.entries
    }

    fn write_collection(&self) -> std::io::Result<()> {
        write_atomically(&self.dir.join(PVD_NAME), &pvd_string(&self.entries))
    }
}
