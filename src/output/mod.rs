//! The run directory (README.md, "Run directory"; docs/contracts.md): loads.csv,
//! bodies.csv, probes.csv and
//! summary.json, plus energy.csv (fluid kinetic and potential energy) when asked for. Rows are flushed as they are written so a running job can be read.
//!
//! Sampling: a row of loads.csv at time t is the mean force over the sample interval
//! that ends at t (impulse / interval), so the integral of the sampled force equals
//! the impulse the fluid actually transmitted, whatever the step size.

pub mod filter;
pub mod flow;
pub mod loads_csv;
pub mod plot;
pub mod probes;
pub mod series;
pub mod snapshots;
pub mod surface;
pub mod vtk;

use crate::engine::Simulation;
use crate::math::Real;
use crate::state_io::{StateError, StateReader, StateWriter};
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

pub const LOADS_HEADER: &str = "time,body,fx,fy,mz";
pub const BODIES_HEADER: &str = "time,body,x,y,angle,vx,vy,omega";
pub const PROBES_HEADER: &str = "time,probe,pressure,pressure_max";
pub const ENERGY_HEADER: &str = "time,kinetic_energy,potential_energy,particles";
pub const LOADS_FILE: &str = "loads.csv";
pub const BODIES_FILE: &str = "bodies.csv";
pub const PROBES_FILE: &str = "probes.csv";
pub const ENERGY_FILE: &str = "energy.csv";

/// Kinematics of one body at a sample time (x, y: centre of mass).
#[derive(Debug, Clone, PartialEq)]
pub struct BodySample {
    pub name: String,
    pub x: Real,
    pub y: Real,
    pub angle: Real,
    pub vx: Real,
    pub vy: Real,
    pub omega: Real,
}

/// A run writer's part of a checkpoint, read back ([`RunWriter::take_state`]).
pub struct WriterState {
    /// Next and last sample times.
    samples: (Real, Real),
    impulse: Vec<[Real; 3]>,
    /// Each probe's reading and largest reading of the interval under way.
    peaks: Option<(Vec<Real>, Vec<Real>)>,
    /// loads, bodies, probes and energy rows so far (None: not written by the run).
    rows: [Option<Vec<u8>>; 4],
}

/// Accumulates per-step loads into interval means and writes the CSV files.
pub struct RunWriter {
    interval: Option<Real>,
    next_sample: Real,
    last_sample: Real,
    names: Vec<String>,
    impulse: Vec<[Real; 3]>,
    loads: BufWriter<File>,
    bodies: Option<BufWriter<File>>,
    probes: Option<Probes>,
    energy: Option<BufWriter<File>>,
}

/// probes.csv and what its next rows need: a row holds each probe's pressure at its time
/// and the largest of the per-step readings since the previous row (a gauge is read for
/// its peak, which a row interval longer than the peak would miss).
struct Probes {
    file: BufWriter<File>,
    points: Vec<probes::ProbePoint>,
    now: Vec<Real>,
    max: Vec<Real>,
}

/// A CSV file that starts with `rows` (its header, or what a checkpoint saved), open
/// for appending.
fn csv_file(path: &Path, rows: &[u8]) -> std::io::Result<BufWriter<File>> {
    let mut w = BufWriter::new(File::create(path)?);
    w.write_all(rows)?;
    w.flush()?;
    Ok(w)
}

impl RunWriter {
    pub fn create(
        dir: &Path,
        interval: Option<Real>,
        wall_names: Vec<String>,
        has_bodies: bool,
        probes: Vec<probes::ProbePoint>,
        energy: bool,
    ) -> std::io::Result<Self> {
        std::fs::create_dir_all(dir)?;
        let n = wall_names.len();
        let n_probes = probes.len();
        let fresh = |header: &str| format!("{header}\n").into_bytes();
        Ok(Self {
            interval: interval.filter(|v| *v > 0.0),
            next_sample: interval.unwrap_or(0.0),
            last_sample: 0.0,
            names: wall_names,
            impulse: vec![[0.0; 3]; n],
            loads: csv_file(&dir.join(LOADS_FILE), &fresh(LOADS_HEADER))?,
            bodies: if has_bodies {
                Some(csv_file(&dir.join(BODIES_FILE), &fresh(BODIES_HEADER))?)
            } else {
                None
            },
            probes: if probes.is_empty() {
                None
            } else {
                Some(Probes {
                    file: csv_file(&dir.join(PROBES_FILE), &fresh(PROBES_HEADER))?,
                    now: vec![0.0; n_probes],
                    max: vec![Real::NEG_INFINITY; n_probes],
                    points: probes,
                })
            },
            energy: if energy {
                Some(csv_file(&dir.join(ENERGY_FILE), &fresh(ENERGY_HEADER))?)
            } else {
                None
            },
        })
    }

    /// The sampling state (next and last sample times, the impulses and probe peaks of
    /// the interval under way) and every file's rows so far, for a checkpoint: a run
    /// resumed from it on another machine writes the same files.
    pub fn save_state(&mut self, dir: &Path, w: &mut StateWriter) -> std::io::Result<()> {
        self.finish()?;
        w.put(&(self.next_sample, self.last_sample))?;
        w.put(&self.impulse)?;
        w.put(&self.probes.as_ref().map(|p| (&p.now, &p.max)))?;
        for (name, present) in self.files() {
            let rows = if present {
                Some(std::fs::read(dir.join(name))?)
            } else {
                None
            };
            w.put(&rows)?;
        }
        Ok(())
    }

    /// Read back what [`RunWriter::save_state`] wrote, touching no file.
    pub fn take_state(r: &mut StateReader) -> Result<WriterState, StateError> {
        Ok(WriterState {
            samples: r.take()?,
            impulse: r.take()?,
            peaks: r.take()?,
            rows: [r.take()?, r.take()?, r.take()?, r.take()?],
        })
    }

    /// Rewrite the files of `dir` as a checkpoint saved them and continue from its
    /// sampling state (this writer was created for the same case).
    pub fn apply_state(&mut self, dir: &Path, saved: WriterState) -> Result<(), StateError> {
        let mismatch =
            |what: &str| StateError::Mismatch(format!("the saved {what} are not the case's"));
        if saved.impulse.len() != self.impulse.len() {
            return Err(mismatch("walls"));
        }
        (self.next_sample, self.last_sample) = saved.samples;
        self.impulse = saved.impulse;
        match (&mut self.probes, saved.peaks) {
            (Some(p), Some((now, max))) if now.len() == p.points.len() => {
                (p.now, p.max) = (now, max)
            }
            (None, None) => {}
            _ => return Err(mismatch("probes")),
        }
        for ((name, present), rows) in self.files().into_iter().zip(saved.rows) {
            match (present, rows) {
                (true, Some(rows)) => *self.file_mut(name) = csv_file(&dir.join(name), &rows)?,
                (false, None) => {}
                _ => return Err(mismatch(name)),
            }
        }
        Ok(())
    }

    /// The run's CSV files and whether this run writes each.
    fn files(&self) -> [(&'static str, bool); 4] {
        [
            (LOADS_FILE, true),
            (BODIES_FILE, self.bodies.is_some()),
            (PROBES_FILE, self.probes.is_some()),
            (ENERGY_FILE, self.energy.is_some()),
        ]
    }

    fn file_mut(&mut self, name: &str) -> &mut BufWriter<File> {
        match name {
            BODIES_FILE => self.bodies.as_mut(),
            PROBES_FILE => self.probes.as_mut().map(|p| &mut p.file),
            ENERGY_FILE => self.energy.as_mut(),
            _ => Some(&mut self.loads),
        }
        .expect("only the files this run writes")
    }

    /// Record the step that just ended (`dt` long, ending at `sim.time`); write rows when a
    /// sample time is reached.
    pub fn record(
        &mut self,
        sim: &Simulation,
        dt: Real,
        bodies: &[BodySample],
    ) -> std::io::Result<()> {
        for (k, l) in sim.loads.iter().enumerate() {
            self.impulse[k][0] += l.force.x * dt;
            self.impulse[k][1] += l.force.y * dt;
            self.impulse[k][2] += l.moment * dt;
        }
        if let Some(pr) = &mut self.probes {
            pr.now = probes::sample(sim, &pr.points);
            for (m, v) in pr.max.iter_mut().zip(&pr.now) {
                *m = m.max(*v);
            }
        }
        let due = match self.interval {
            None => true,
            Some(_) => sim.time >= self.next_sample * (1.0 - 1e-12),
        };
        if due {
            self.write_sample(sim, bodies)?;
        }
        Ok(())
    }

    fn write_sample(&mut self, sim: &Simulation, bodies: &[BodySample]) -> std::io::Result<()> {
        let t = sim.time;
        let span = (t - self.last_sample).max(Real::MIN_POSITIVE);
        for (k, name) in self.names.iter().enumerate() {
            let [fx, fy, mz] = self.impulse[k];
            writeln!(
                self.loads,
                "{t:.9e},{name},{:.9e},{:.9e},{:.9e}",
                fx / span,
                fy / span,
                mz / span
            )?;
            self.impulse[k] = [0.0; 3];
        }
        self.loads.flush()?;
        if let Some(w) = &mut self.bodies {
            for b in bodies {
                writeln!(
                    w,
                    "{t:.9e},{},{:.9e},{:.9e},{:.9e},{:.9e},{:.9e},{:.9e}",
                    b.name, b.x, b.y, b.angle, b.vx, b.vy, b.omega
                )?;
            }
            w.flush()?;
        }
        if let Some(pr) = &mut self.probes {
            for ((point, p), max) in pr.points.iter().zip(&pr.now).zip(&mut pr.max) {
                writeln!(
                    pr.file,
                    "{t:.9e},{},{p:.9e},{:.9e}",
                    point.name,
                    max.max(*p)
                )?;
                *max = Real::NEG_INFINITY;
            }
            pr.file.flush()?;
        }
        if let Some(w) = &mut self.energy {
            // the state at the sample time, not an interval mean
            let (kinetic, potential) = sim.fluid_energy();
            writeln!(
                w,
                "{t:.9e},{kinetic:.9e},{potential:.9e},{}",
                sim.particle_count()
            )?;
            w.flush()?;
        }
        self.last_sample = t;
        if let Some(iv) = self.interval {
            while self.next_sample <= t * (1.0 + 1e-12) {
                self.next_sample += iv;
            }
        }
        Ok(())
    }

    pub fn finish(&mut self) -> std::io::Result<()> {
        self.loads.flush()?;
        if let Some(w) = &mut self.bodies {
            w.flush()?;
        }
        if let Some(pr) = &mut self.probes {
            pr.file.flush()?;
        }
        if let Some(w) = &mut self.energy {
            w.flush()?;
        }
        Ok(())
    }
}
