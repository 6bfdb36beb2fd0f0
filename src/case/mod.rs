//! The case format (README.md, "Case format"): serde types with defaults, loading with
//! `--set` overrides, and validation that names the field path of every problem.
//!
//! Unknown fields are rejected (`deny_unknown_fields`): a typo in a case must not be
//! silently ignored.

pub mod layout;
mod load;
mod output;
pub mod prescribed;
mod refinement;
pub mod schema;
mod scheme;
mod validate;

pub use load::{apply_override, load_case_file, parse_case_str, parse_case_value};
pub use output::{LoadInterval, Output, Probe, SnapshotInterval};
pub use refinement::{Refinement, RefinementRegions};
pub use scheme::*;
pub use validate::{estimated_particles, validate, Limits, MAX_VERTICES};

use schemars::JsonSchema;
use serde::{Deserialize, Serialize};

/// A 2D point or vector `[x, y]` in metres (or m/s, m/s²).
pub type Point = [f64; 2];

/// Error in a case: the dotted field path (`bodies[0].polygon`) and the reason.
#[derive(Debug, Clone, PartialEq, thiserror::Error, Serialize)]
#[error("{path}: {message}")]
pub struct CaseError {
    pub path: String,
    pub message: String,
}

impl CaseError {
    pub fn new(path: impl Into<String>, message: impl Into<String>) -> Self {
        Self {
            path: path.into(),
            message: message.into(),
        }
    }
}

/// A case that passed [`validate`] against the limits of whoever will run it (the CLI's,
/// the service's configuration): the only thing `run::run_case` accepts, so a case is
/// validated once, by the caller, and never again against other limits. Read-only: a
/// change could make it invalid.
#[derive(Debug, Clone, PartialEq)]
pub struct ValidCase(Case);

impl ValidCase {
    /// Validate `case` against `limits`.
    pub fn new(case: Case, limits: &Limits) -> Result<Self, CaseError> {
        validate(&case, limits)?;
        Ok(Self(case))
    }
}

impl std::ops::Deref for ValidCase {
    type Target = Case;
    fn deref(&self) -> &Case {
        &self.0
    }
}

/// A complete simulation case.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Case {
    /// Free-form name, used in outputs.
    pub name: String,
    /// Where the expected answer of this case comes from (validation cases).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reference: Option<Reference>,
    pub fluid: Fluid,
    /// Initial particle spacing l0 (m). Every length in `scheme` is a ratio of it.
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub particle_spacing: f64,
    /// Particles leaving this box are removed and counted.
    pub domain: Domain,
    /// Polygons filled with fluid particles on a square lattice of `particle_spacing`
    /// (twice as coarse where `refinement` allows).
    #[schemars(extend("minItems" = 1))]
    pub fluid_blocks: Vec<FluidBlock>,
    /// Where the fluid may be laid out coarser than `particle_spacing`: "auto" (the
    /// default: fine around each moving body's path, twice as coarse beyond, four times
    /// as coarse far from it; uniform without a moving body), "none" (one spacing
    /// everywhere) or {"fine": [boxes]} (twice as coarse outside them).
    #[serde(default, skip_serializing_if = "Refinement::is_auto")]
    pub refinement: Refinement,
    /// Fixed walls (open or closed polylines).
    #[serde(default)]
    pub walls: Vec<Wall>,
    /// Rigid bodies (closed polygons, counter-clockwise in the body frame).
    #[serde(default)]
    pub bodies: Vec<Body>,
    pub time: TimeControl,
    /// Sponge layers that absorb waves before they reach a tank end (none by default).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub damping_zones: Vec<DampingZone>,
    #[serde(default)]
    pub output: Output,
    #[serde(default)]
    pub scheme: Scheme,
}

/// Where a validation case's expected answer comes from.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Reference {
    /// Citation: author and year, or a section of docs/references.md.
    pub source: String,
    /// What is compared and how.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub quantity: Option<String>,
    /// Expected values, free form.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub values: Option<serde_json::Value>,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Fluid {
    /// kg/m³
    #[serde(default = "default_density")]
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub density: f64,
    /// m²/s; zero switches the viscous stage off.
    #[serde(default = "default_viscosity")]
    #[schemars(range(min = 0))]
    pub kinematic_viscosity: f64,
    /// m/s²
    #[serde(default = "default_gravity")]
    pub gravity: Point,
}

fn default_density() -> f64 {
    1000.0
}
fn default_viscosity() -> f64 {
    1.0e-6
}
fn default_gravity() -> Point {
    [0.0, -9.81]
}

impl Default for Fluid {
    fn default() -> Self {
        Self {
            density: default_density(),
            kinematic_viscosity: default_viscosity(),
            gravity: default_gravity(),
        }
    }
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Domain {
    pub min: Point,
    pub max: Point,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct FluidBlock {
    /// Closed polygon (either orientation), vertices in metres.
    #[schemars(extend("minItems" = 3, "maxItems" = 10_000))]
    pub polygon: Vec<Point>,
    /// Initial velocity of the block's particles (m/s).
    #[serde(default)]
    pub velocity: Point,
}

/// Which side of a wall polyline the fluid is on, walking from the first vertex.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema, Default)]
#[serde(rename_all = "snake_case")]
pub enum FluidSide {
    /// Decided from the initial fluid (the side holding most particles near the wall).
    #[default]
    Auto,
    Left,
    Right,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Wall {
    /// Name used in `loads.csv`.
    #[schemars(extend("pattern" = r#"^[^,"\r\n]*[^\s,"][^,"\r\n]*$"#))]
    pub name: String,
    /// Vertices of the polyline (m).
    #[schemars(extend("minItems" = 2, "maxItems" = 10_000))]
    pub polyline: Vec<Point>,
    /// Join the last vertex to the first.
    #[serde(default)]
    pub closed: bool,
    /// The fluid side; the other side is solid (thickness is irrelevant to the model).
    #[serde(default)]
    pub fluid_side: FluidSide,
    /// The tangential velocity condition of the viscous term (only read when the
    /// kinematic viscosity is positive): `no_slip` (the default, a real wall) or
    /// `free_slip` (a symmetry plane: the wall resists only the normal velocity, as the
    /// periodic sides of the standing wave of Souto-Iglesias et al. 2013).
    #[serde(default)]
    pub slip: WallSlip,
}

/// Tangential velocity condition of a wall in the viscous term.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema, Default)]
#[serde(rename_all = "snake_case")]
pub enum WallSlip {
    /// The fluid at the wall moves with the wall (mirror velocity 2 u_w - u).
    #[default]
    NoSlip,
    /// Only the normal velocity is mirrored; the tangential stress is zero.
    FreeSlip,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct Body {
    #[schemars(extend("pattern" = r#"^[^,"\r\n]*[^\s,"][^,"\r\n]*$"#))]
    pub name: String,
    /// Closed polygon in the body frame, counter-clockwise (m).
    #[schemars(extend("minItems" = 3, "maxItems" = 10_000))]
    pub polygon: Vec<Point>,
    /// World position of the body-frame origin (m).
    #[serde(default)]
    pub position: Point,
    /// Rotation of the body frame (rad).
    #[serde(default)]
    pub angle: f64,
    pub motion: Motion,
}

/// How a body moves.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(tag = "type", rename_all = "snake_case", deny_unknown_fields)]
pub enum Motion {
    /// Kinematic: velocity imposed, constant or from a table.
    Prescribed {
        /// Constant velocity (m/s), used when `table` is absent.
        #[serde(default)]
        velocity: Point,
        /// Constant angular velocity (rad/s).
        #[serde(default)]
        angular_velocity: f64,
        /// Velocity time table, linearly interpolated, held constant outside.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        #[schemars(extend("minItems" = 1))]
        table: Option<Vec<VelocitySample>>,
    },
    /// Dynamic: moved by gravity, fluid force and contacts.
    Free {
        /// kg per metre of span.
        #[schemars(extend("exclusiveMinimum" = 0))]
        mass: f64,
        /// kg·m²/m about the centre of mass; from the polygon with uniform density if absent.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        #[schemars(extend("exclusiveMinimum" = 0))]
        inertia: Option<f64>,
        #[serde(default)]
        velocity: Point,
        #[serde(default)]
        angular_velocity: f64,
        /// Degrees of freedom held fixed.
        #[serde(default)]
        locked: Vec<Dof>,
    },
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct VelocitySample {
    pub time: f64,
    pub velocity: Point,
    #[serde(default)]
    pub angular_velocity: f64,
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize, JsonSchema)]
#[serde(rename_all = "snake_case")]
pub enum Dof {
    X,
    Y,
    Rotation,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct TimeControl {
    /// Simulated end time (s).
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub end: f64,
    /// Courant number: dt <= cfl * l0 / u_max, also with each particle's last
    /// acceleration, and a step in which a particle would move more than 1.5 cfl
    /// spacings is repeated shorter (the jet root of an impact; summary `steps_repeated`).
    #[serde(default = "default_cfl")]
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub cfl: f64,
    /// Upper bound on the time step (s).
    #[serde(default = "default_max_dt")]
    #[schemars(extend("exclusiveMinimum" = 0))]
    pub max_dt: f64,
}

fn default_cfl() -> f64 {
    0.2
}
fn default_max_dt() -> f64 {
    1.0e-3
}

/// A sponge layer: past the line through `start` perpendicular to `end - start`, a
/// particle's velocity is relaxed each step as u <- u / (1 + alpha dt), with
/// alpha = strength s², s the fraction of the way from `start` to `end` (1 beyond
/// `end`). Fluid at rest is untouched; waves running into the layer lose their energy
/// instead of reflecting from the wall behind it, as in an unbounded tank.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize, JsonSchema)]
#[serde(deny_unknown_fields)]
pub struct DampingZone {
    /// Inner edge of the layer (no damping there), m.
    pub start: Point,
    /// Outer edge (full damping from there on), m.
    pub end: Point,
    /// Damping rate at the outer edge, 1/s.
    #[schemars(range(min = 0))]
    pub strength: f64,
}
