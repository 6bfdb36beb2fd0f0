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
use std::fs::File;
use std::io::{BufWriter, Write};
use std::path::Path;

pub const LOADS_HEADER: &str = "time,body,fx,fy,mz";
pub const BODIES_HEADER: &str = "time,body,x,y,angle,vx,vy,omega";
pub const PROBES_HEADER: &str = "time,probe,pressure,pressure_max";
pub const ENERGY_HEADER: &str = "time,kinetic_energy,potential_energy,particles";

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

fn csv_file(path: &Path, header: &str) -> std::io::Result<BufWriter<File>> {
    let mut w = BufWriter::new(File::create(path)?);
    writeln!(w, "{header}")?;
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
        Ok(Self {
            interval: interval.filter(|v| *v > 0.0),
            next_sample: interval.unwrap_or(0.0),
            last_sample: 0.0,
            names: wall_names,
            impulse: vec![[0.0; 3]; n],
            loads: csv_file(&dir.join("loads.csv"), LOADS_HEADER)?,
            bodies: if has_bodies {
                Some(csv_file(&dir.join("bodies.csv"), BODIES_HEADER)?)
            } else {
                None
            },
            probes: if probes.is_empty() {
                None
            } else {
                Some(Probes {
                    file: csv_file(&dir.join("probes.csv"), PROBES_HEADER)?,
                    now: vec![0.0; probes.len()],
                    max: vec![Real::NEG_INFINITY; probes.len()],
                    points: probes,
                })
            },
            energy: if energy {
                Some(csv_file(&dir.join("energy.csv"), ENERGY_HEADER)?)
            } else {
                None
            },
        })
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
