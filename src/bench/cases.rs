//! The scenes the studies start from: the shipped case files, the Koshizuka & Oka dam
//! break when `cases/dam_break.json` is absent, and the still tank of the scaling and
//! feature-cost studies; with the case-format errors of building them as `io::Error`s.

use crate::analysis::reference::KOSHIZUKA_OKA_COLUMN_WIDTH;
use crate::case::{self, Case, Limits};
use crate::math::Real;
use serde_json::{json, Value};
use std::io;
use std::path::{Path, PathBuf};

/// The repository's `cases/` folder.
pub fn cases_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("cases")
}

/// A case file as JSON (overrides are applied to the value before parsing). A case that
/// does not choose its snapshots gets none: the study times the engine, and a run that
/// needs snapshots (the dam break's surge front) sets its own interval.
pub fn read_case_value(path: &Path) -> io::Result<Value> {
    let text = std::fs::read_to_string(path)?;
    let mut v: Value = serde_json::from_str(&text).map_err(|e| {
        io::Error::new(
            io::ErrorKind::InvalidData,
            format!("{}: {e}", path.display()),
        )
    })?;
    if v.pointer("/output/snapshot_interval").is_none() {
        set_override(&mut v, "output.snapshot_interval=\"none\"")?;
    }
    Ok(v)
}

fn invalid(e: impl ToString) -> io::Error {
    io::Error::new(io::ErrorKind::InvalidData, e.to_string())
}

/// Apply one PATH=VALUE override to a case value.
pub fn set_override(v: &mut Value, o: &str) -> io::Result<()> {
    case::apply_override(v, o).map_err(invalid)
}

/// Parse a case value (not validated: see [`parse_unlimited`] and `case::ValidCase`).
pub fn parse_case(v: Value) -> io::Result<Case> {
    case::parse_case_value(v).map_err(invalid)
}

/// Parse and validate a case value with no limit on the particle count (the scaling
/// study goes past the service's limit on purpose).
pub fn parse_unlimited(v: Value) -> io::Result<case::ValidCase> {
    case::ValidCase::new(
        parse_case(v)?,
        &Limits {
            max_particles: usize::MAX,
        },
    )
    .map_err(invalid)
}

/// The shipped dam break, or the Koshizuka & Oka one built by [`dam_break_case`] when
/// `cases/dam_break.json` does not exist.
pub fn dam_break_value() -> io::Result<Value> {
    let path = cases_dir().join("dam_break.json");
    if path.exists() {
        read_case_value(&path)
    } else {
        Ok(dam_break_case(KOSHIZUKA_OKA_COLUMN_WIDTH))
    }
}

/// The Koshizuka & Oka (1996) dam break (column L × 2L in a tank 4L wide, L = 0.146 m),
/// used when `cases/dam_break.json` does not exist.
pub fn dam_break_case(a: Real) -> Value {
    let t3 = 3.05 / (2.0 * 9.81 / a).sqrt();
    json!({
        "name": "dam-break",
        "reference": {
            "source": "docs/references.md, Dam break: Martin & Moyce (1952), Phil. Trans. R. Soc. A 244; Koshizuka & Oka (1996) geometry",
            "quantity": "surge front x/a against T = t sqrt(2 g / a), RMS relative error for 1 <= T <= 3"
        },
        "fluid": { "density": 1000.0, "kinematic_viscosity": 1.0e-6, "gravity": [0.0, -9.81] },
        "particle_spacing": a / 20.0,
        "domain": { "min": [-0.2 * a, -0.2 * a], "max": [4.2 * a, 8.6 * a] },
        "fluid_blocks": [ { "polygon": [[0.0, 0.0], [a, 0.0], [a, 2.0 * a], [0.0, 2.0 * a]] } ],
        // walls tall enough for the run-up on the far wall (as the shipped case)
        "walls": [ { "name": "tank", "polyline": [[0.0, 8.2 * a], [0.0, 0.0], [4.0 * a, 0.0], [4.0 * a, 8.2 * a]] } ],
        "time": { "end": t3, "cfl": 0.15, "max_dt": 1.0e-3 },
        "output": { "load_interval": 0.005, "snapshot_interval": 0.05 / (2.0 * 9.81 / a).sqrt() },
        "scheme": { "laplacian_fill_floor": 0.3 }
    })
}

/// Width, left edge and floor of a dam-break column (the first fluid block's bounding box).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ColumnGeometry {
    pub width: Real,
    pub left: Real,
    pub floor: Real,
}

pub fn column_geometry(case: &Case) -> Option<ColumnGeometry> {
    let block = case.fluid_blocks.first()?;
    let xs = block.polygon.iter().map(|p| p[0]);
    let ys = block.polygon.iter().map(|p| p[1]);
    let left = xs.clone().fold(Real::INFINITY, Real::min);
    let right = xs.fold(Real::NEG_INFINITY, Real::max);
    let floor = ys.fold(Real::INFINITY, Real::min);
    (right > left).then_some(ColumnGeometry {
        width: right - left,
        left,
        floor,
    })
}

/// Particle spacing of the scaling tank (that of `cases/hydrostatic.json`).
pub const TANK_SPACING: f64 = 0.01;
/// Fixed time step of the scaling runs (`cases/hydrostatic.json`'s max_dt).
pub const TANK_DT: f64 = 5.0e-4;

/// Lattice columns and rows of a 2:1 tank of about `target` particles.
pub fn tank_lattice(target: usize) -> (usize, usize) {
    let ny = ((target as f64 / 2.0).sqrt().round() as usize).max(2);
    (2 * ny, ny)
}

/// The still tank of `cases/hydrostatic.json` scaled to about `target` fluid particles
/// at spacing [`TANK_SPACING`], stepped `steps` steps at the fixed dt [`TANK_DT`]
/// (max_dt = dt, end = steps dt), the default solver stops, no probes or snapshots.
pub fn tank_case_value(target: usize, steps: u64) -> Value {
    let l0 = TANK_SPACING;
    let (nx, ny) = tank_lattice(target);
    let (w, h) = (nx as f64 * l0, ny as f64 * l0);
    let m = 0.1 * h.max(0.1);
    json!({
        "name": format!("scaling-tank-{}", nx * ny),
        "fluid": { "density": 1000.0, "kinematic_viscosity": 0.0, "gravity": [0.0, -9.81] },
        "particle_spacing": l0,
        "domain": { "min": [-m, -m], "max": [w + m, 1.4 * h + m] },
        "fluid_blocks": [ { "polygon": [[0.0, 0.0], [w, 0.0], [w, h], [0.0, h]] } ],
        "walls": [ { "name": "tank", "polyline": [[0.0, 1.4 * h], [0.0, 0.0], [w, 0.0], [w, 1.4 * h]] } ],
        "time": { "end": steps as f64 * TANK_DT, "cfl": 0.2, "max_dt": TANK_DT },
        "output": { "load_interval": 0.01, "snapshot_interval": null, "probes": [] },
        "scheme": { "solver_tolerance": 1.0e-8 }
    })
}
