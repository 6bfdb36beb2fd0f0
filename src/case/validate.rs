//! Validation before any work: every rejection names the dotted field path
//! (`bodies[0].polygon`, `fluid.density`) and a reason a user can act on.
//!
//! The rules, in the order they are checked (the first failure is reported):
//! 1. every number is finite (a generic walk over the serialised case, so fields
//!    added later are covered too);
//! 2. signs and ranges of scalars: density, spacing, end time, cfl, max_dt, kernel
//!    radii, solver tolerance positive; viscosity non-negative; output intervals positive;
//! 3. the domain (min < max) and the particle limit (estimated from the fluid block
//!    areas / l0², before anything is generated);
//! 4. geometry: fluid block and body polygons (>= 3 vertices, no repeated consecutive
//!    vertex, non-zero area, no crossing edges, bodies counter-clockwise), wall
//!    polylines (>= 2 points, no zero-length segment), fluid blocks and probes inside
//!    the domain, bodies clear of walls and of each other;
//! 5. body motion: free bodies with positive mass and inertia, velocity tables
//!    strictly increasing in time;
//! 6. names: walls and bodies share the `body` column of loads.csv, so their names are
//!    unique together and non-empty; probe names likewise among probes.

use super::{Body, Case, CaseError, Motion, Point, Projection, SourceKind};
use crate::geometry::{inside, segments_intersect, signed_area};
use crate::math::{vec2, Real, Vec2};
use serde::ser::{self, Serialize};
use std::collections::HashMap;

/// Limits configured by the operator of the tool (CLI flags, service config).
#[derive(Debug, Clone)]
pub struct Limits {
    /// Largest number of fluid particles a case may create.
    pub max_particles: usize,
}

impl Default for Limits {
    fn default() -> Self {
        Self {
            max_particles: 2_000_000,
        }
    }
}

type Check = Result<(), CaseError>;

/// Most vertices a polygon or polyline may have (the overlap checks are quadratic).
pub const MAX_VERTICES: usize = 10_000;

fn reject<T>(path: impl Into<String>, message: impl Into<String>) -> Result<T, CaseError> {
    Err(CaseError::new(path, message))
}

/// Check a case; `Ok` means the engine may build it.
pub fn validate(case: &Case, limits: &Limits) -> Check {
    check_finite(case)?;
    check_scalars(case)?;
    check_domain(case)?;
    check_fluid_blocks(case)?;
    check_particle_limit(case, limits)?;
    check_walls(case)?;
    check_bodies(case)?;
    check_overlaps(case)?;
    check_output(case)?;
    check_damping_zones(case)?;
    check_names(case)?;
    Ok(())
}

fn check_damping_zones(case: &Case) -> Check {
    for (i, z) in case.damping_zones.iter().enumerate() {
        if z.strength < 0.0 {
            return reject(
                format!("damping_zones[{i}].strength"),
                format!("must be >= 0 (got {})", z.strength),
            );
        }
        let length = (vec2(z.end) - vec2(z.start)).norm();
        if length < 1e-9 {
            return reject(
                format!("damping_zones[{i}].end"),
                "must differ from start: the layer runs from start to end",
            );
        }
    }
    Ok(())
}

/// Estimated number of fluid particles: the summed fluid block areas / l0²
/// (overlaps and the parts inside bodies counted, so it is an upper bound up to
/// lattice rounding). `None` when the case has no usable spacing.
pub fn estimated_particles(case: &Case) -> Option<f64> {
    let l0 = case.particle_spacing;
    if !(l0.is_finite() && l0 > 0.0) {
        return None;
    }
    let area: f64 = case
        .fluid_blocks
        .iter()
        .map(|b| signed_area(&points(&b.polygon)).abs())
        .sum();
    Some(area / (l0 * l0))
}

fn points(p: &[Point]) -> Vec<Vec2> {
    p.iter().map(|q| vec2(*q)).collect()
}

// ---------------------------------------------------------------------------
// 1. finite numbers everywhere

fn check_finite(case: &Case) -> Check {
    let mut finder = FiniteCheck {
        path: Vec::new(),
        found: None,
    };
    // the serializer itself never fails: errors only stop the walk early
    let _ = case.serialize(&mut finder);
    match finder.found {
        Some((path, value)) => reject(path, format!("must be a finite number (got {value})")),
        None => Ok(()),
    }
}

#[derive(Clone)]
enum Segment {
    Field(&'static str),
    Key(String),
    Index(usize),
}

/// A serde serializer that records the path of the first non-finite float.
struct FiniteCheck {
    path: Vec<Segment>,
    found: Option<(String, f64)>,
}

impl FiniteCheck {
    fn path_string(&self) -> String {
        let mut s = String::new();
        for seg in &self.path {
            match seg {
                Segment::Field(f) => {
                    if !s.is_empty() {
                        s.push('.');
                    }
                    s.push_str(f);
                }
                Segment::Key(k) => {
                    if !s.is_empty() {
                        s.push('.');
                    }
                    s.push_str(k);
                }
                Segment::Index(i) => s.push_str(&format!("[{i}]")),
            }
        }
        s
    }

    fn float(&mut self, v: f64) -> Result<(), Stop> {
        if !v.is_finite() {
            self.found = Some((self.path_string(), v));
            return Err(Stop);
        }
        Ok(())
    }

    fn nested<T: ?Sized + Serialize>(&mut self, seg: Segment, value: &T) -> Result<(), Stop> {
        self.path.push(seg);
        let r = value.serialize(&mut *self);
        self.path.pop();
        r
    }
}

/// Stops the walk at the first non-finite number.
#[derive(Debug)]
struct Stop;

impl std::fmt::Display for Stop {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str("non-finite number")
    }
}
impl std::error::Error for Stop {}
impl ser::Error for Stop {
    fn custom<T: std::fmt::Display>(_msg: T) -> Self {
        Stop
    }
}

/// Sequence / map / struct walker keeping the element index or key on the path.
struct Compound<'a> {
    outer: &'a mut FiniteCheck,
    index: usize,
    key: Option<String>,
}

macro_rules! ok_scalars {
    ($($name:ident: $t:ty),*) => {
        $(fn $name(self, _v: $t) -> Result<(), Stop> { Ok(()) })*
    };
}

impl<'a> ser::Serializer for &'a mut FiniteCheck {
    type Ok = ();
    type Error = Stop;
    type SerializeSeq = Compound<'a>;
    type SerializeTuple = Compound<'a>;
    type SerializeTupleStruct = Compound<'a>;
    type SerializeTupleVariant = Compound<'a>;
    type SerializeMap = Compound<'a>;
    type SerializeStruct = Compound<'a>;
    type SerializeStructVariant = Compound<'a>;

    ok_scalars!(serialize_bool: bool, serialize_i8: i8, serialize_i16: i16, serialize_i32: i32, serialize_i64: i64,
        serialize_u8: u8, serialize_u16: u16, serialize_u32: u32, serialize_u64: u64, serialize_char: char,
        serialize_str: &str, serialize_bytes: &[u8]);

    fn serialize_f32(self, v: f32) -> Result<(), Stop> {
        self.float(v as f64)
    }
    fn serialize_f64(self, v: f64) -> Result<(), Stop> {
        self.float(v)
    }
    fn serialize_none(self) -> Result<(), Stop> {
        Ok(())
    }
    fn serialize_some<T: ?Sized + Serialize>(self, value: &T) -> Result<(), Stop> {
        value.serialize(self)
    }
    fn serialize_unit(self) -> Result<(), Stop> {
        Ok(())
    }
    fn serialize_unit_struct(self, _name: &'static str) -> Result<(), Stop> {
        Ok(())
    }
    fn serialize_unit_variant(
        self,
        _n: &'static str,
        _i: u32,
        _v: &'static str,
    ) -> Result<(), Stop> {
        Ok(())
    }
    fn serialize_newtype_struct<T: ?Sized + Serialize>(
        self,
        _n: &'static str,
        value: &T,
    ) -> Result<(), Stop> {
        value.serialize(self)
    }
    fn serialize_newtype_variant<T: ?Sized + Serialize>(
        self,
        _n: &'static str,
        _i: u32,
        variant: &'static str,
        value: &T,
    ) -> Result<(), Stop> {
        self.nested(Segment::Field(variant), value)
    }
    fn serialize_seq(self, _len: Option<usize>) -> Result<Compound<'a>, Stop> {
        Ok(Compound {
            outer: self,
            index: 0,
            key: None,
        })
    }
    fn serialize_tuple(self, _len: usize) -> Result<Compound<'a>, Stop> {
        Ok(Compound {
            outer: self,
            index: 0,
            key: None,
        })
    }
    fn serialize_tuple_struct(self, _n: &'static str, _len: usize) -> Result<Compound<'a>, Stop> {
        Ok(Compound {
            outer: self,
            index: 0,
            key: None,
        })
    }
    fn serialize_tuple_variant(
        self,
        _n: &'static str,
        _i: u32,
        _v: &'static str,
        _len: usize,
    ) -> Result<Compound<'a>, Stop> {
        Ok(Compound {
            outer: self,
            index: 0,
            key: None,
        })
    }
    fn serialize_map(self, _len: Option<usize>) -> Result<Compound<'a>, Stop> {
        Ok(Compound {
            outer: self,
            index: 0,
            key: None,
        })
    }
    fn serialize_struct(self, _n: &'static str, _len: usize) -> Result<Compound<'a>, Stop> {
        Ok(Compound {
            outer: self,
            index: 0,
            key: None,
        })
    }
    fn serialize_struct_variant(
        self,
        _n: &'static str,
        _i: u32,
        _v: &'static str,
        _len: usize,
    ) -> Result<Compound<'a>, Stop> {
        Ok(Compound {
            outer: self,
            index: 0,
            key: None,
        })
    }
}

impl Compound<'_> {
    fn element<T: ?Sized + Serialize>(&mut self, value: &T) -> Result<(), Stop> {
        let i = self.index;
        self.index += 1;
        self.outer.nested(Segment::Index(i), value)
    }
}

impl ser::SerializeSeq for Compound<'_> {
    type Ok = ();
    type Error = Stop;
    fn serialize_element<T: ?Sized + Serialize>(&mut self, value: &T) -> Result<(), Stop> {
        self.element(value)
    }
    fn end(self) -> Result<(), Stop> {
        Ok(())
    }
}
impl ser::SerializeTuple for Compound<'_> {
    type Ok = ();
    type Error = Stop;
    fn serialize_element<T: ?Sized + Serialize>(&mut self, value: &T) -> Result<(), Stop> {
        self.element(value)
    }
    fn end(self) -> Result<(), Stop> {
        Ok(())
    }
}
impl ser::SerializeTupleStruct for Compound<'_> {
    type Ok = ();
    type Error = Stop;
    fn serialize_field<T: ?Sized + Serialize>(&mut self, value: &T) -> Result<(), Stop> {
        self.element(value)
    }
    fn end(self) -> Result<(), Stop> {
        Ok(())
    }
}
impl ser::SerializeTupleVariant for Compound<'_> {
    type Ok = ();
    type Error = Stop;
    fn serialize_field<T: ?Sized + Serialize>(&mut self, value: &T) -> Result<(), Stop> {
        self.element(value)
    }
    fn end(self) -> Result<(), Stop> {
        Ok(())
    }
}
impl ser::SerializeMap for Compound<'_> {
    type Ok = ();
    type Error = Stop;
    fn serialize_key<T: ?Sized + Serialize>(&mut self, key: &T) -> Result<(), Stop> {
        // keys of the case's maps are strings; anything else is named by position
        let index = self.index;
        let name = serde_json::to_value(key)
            .ok()
            .and_then(|v| v.as_str().map(str::to_string));
        self.key = Some(name.unwrap_or_else(|| index.to_string()));
        Ok(())
    }
    fn serialize_value<T: ?Sized + Serialize>(&mut self, value: &T) -> Result<(), Stop> {
        let key = self.key.take().unwrap_or_default();
        self.index += 1;
        self.outer.nested(Segment::Key(key), value)
    }
    fn end(self) -> Result<(), Stop> {
        Ok(())
    }
}
impl ser::SerializeStruct for Compound<'_> {
    type Ok = ();
    type Error = Stop;
    fn serialize_field<T: ?Sized + Serialize>(
        &mut self,
        key: &'static str,
        value: &T,
    ) -> Result<(), Stop> {
        self.outer.nested(Segment::Field(key), value)
    }
    fn end(self) -> Result<(), Stop> {
        Ok(())
    }
}
impl ser::SerializeStructVariant for Compound<'_> {
    type Ok = ();
    type Error = Stop;
    fn serialize_field<T: ?Sized + Serialize>(
        &mut self,
        key: &'static str,
        value: &T,
    ) -> Result<(), Stop> {
        self.outer.nested(Segment::Field(key), value)
    }
    fn end(self) -> Result<(), Stop> {
        Ok(())
    }
}

// ---------------------------------------------------------------------------
// 2. scalars

fn positive(path: &str, v: f64, what: &str) -> Check {
    if v > 0.0 {
        Ok(())
    } else {
        reject(path, format!("must be positive (got {v}): {what}"))
    }
}

fn non_negative(path: &str, v: f64, what: &str) -> Check {
    if v >= 0.0 {
        Ok(())
    } else {
        reject(path, format!("must not be negative (got {v}): {what}"))
    }
}

/// A share in (0, 1] (of n0, of an operator).
fn share(path: &str, v: f64, what: &str) -> Check {
    if v > 0.0 && v <= 1.0 {
        Ok(())
    } else {
        reject(path, format!("must lie in (0, 1] (got {v}): {what}"))
    }
}

fn check_scalars(case: &Case) -> Check {
    positive(
        "fluid.density",
        case.fluid.density,
        "the fluid density in kg/m³",
    )?;
    non_negative(
        "fluid.kinematic_viscosity",
        case.fluid.kinematic_viscosity,
        "the kinematic viscosity in m²/s (0 switches viscosity off)",
    )?;
    positive(
        "particle_spacing",
        case.particle_spacing,
        "the initial particle spacing l0 in m",
    )?;
    positive("time.end", case.time.end, "the simulated end time in s")?;
    positive("time.cfl", case.time.cfl, "the Courant number")?;
    positive(
        "time.max_dt",
        case.time.max_dt,
        "the largest time step in s",
    )?;

    let s = &case.scheme;
    // r_e <= l0 leaves no lattice neighbour inside the kernel: n0 would be zero
    if s.radius <= 1.0 {
        return reject(
            "scheme.radius",
            format!(
                "the kernel radius r_e/l0 must be greater than 1 (got {}); about 2.1 is usual",
                s.radius
            ),
        );
    }
    if let Some(r) = s.laplacian_radius {
        if r <= 1.0 {
            return reject(
                "scheme.laplacian_radius",
                format!("the Laplacian kernel radius r_e/l0 must be greater than 1 (got {r}); 3.1-4.0 is usual"),
            );
        }
    }
    positive(
        "scheme.solver_tolerance",
        s.solver_tolerance,
        "the relative residual at which the linear solver stops",
    )?;
    if s.solver_max_iterations == 0 {
        return reject("scheme.solver_max_iterations", "must be positive (got 0)");
    }
    if s.amg_rebuild_interval == 0 {
        return reject(
            "scheme.amg_rebuild_interval",
            "must be positive (got 0): 1 rebuilds the AMG hierarchy every step",
        );
    }
    share(
        "scheme.surface_threshold",
        s.surface_threshold,
        "a fraction of n0, about 0.97 is usual",
    )?;
    non_negative(
        "scheme.surface_asymmetry",
        s.surface_asymmetry,
        "0 disables the neighbour-distribution check",
    )?;
    non_negative(
        "scheme.gradient_stabilization",
        s.gradient_stabilization,
        "the weight of the minimum-pressure repulsion",
    )?;
    non_negative(
        "scheme.stabilization_distance",
        s.stabilization_distance,
        "a ratio of particle_spacing",
    )?;
    share(
        "scheme.laplacian_fill_floor",
        s.laplacian_fill_floor,
        "a fraction of n0, 1 disables the renormalisation",
    )?;
    non_negative(
        "scheme.mixed_relaxation",
        s.mixed_relaxation,
        "the relaxation of the PND term",
    )?;
    non_negative(
        "scheme.compressibility",
        s.compressibility,
        "the quasi-compressibility in 1/Pa",
    )?;
    non_negative(
        "scheme.collision_distance",
        s.collision_distance,
        "a ratio of particle_spacing",
    )?;
    if !(0.0..=1.0).contains(&s.collision_restitution) {
        return reject(
            "scheme.collision_restitution",
            format!("must lie in [0, 1] (got {})", s.collision_restitution),
        );
    }
    non_negative(
        "scheme.wall_repulsion_distance",
        s.wall_repulsion_distance,
        "a ratio of particle_spacing",
    )?;
    if !(0.0..=0.5).contains(&s.shifting) {
        return reject(
            "scheme.shifting",
            format!(
                "must lie in [0, 0.5]: a coefficient of l0² per step (got {})",
                s.shifting
            ),
        );
    }
    if !(0.0..=0.5).contains(&s.velocity_filter) {
        return reject(
            "scheme.velocity_filter",
            format!(
                "must lie in [0, 0.5]: the share of the neighbour mean taken per step (got {})",
                s.velocity_filter
            ),
        );
    }
    if s.projection == Projection::Exact {
        share(
            "scheme.exact_projection_blend",
            s.exact_projection_blend,
            "the share of the Laplacian kept in the exact rows",
        )?;
        if s.source == SourceKind::Pnd {
            return reject(
                "scheme.projection",
                "\"exact\" needs a divergence source (higher_order, higher_order_ecs or mixed), not \"pnd\"",
            );
        }
        if s.compressibility != 0.0 {
            return reject(
                "scheme.projection",
                "\"exact\" does not carry the quasi-compressibility: set scheme.compressibility to 0",
            );
        }
    }
    if let Some(v) = s.max_speed {
        positive(
            "scheme.max_speed",
            v,
            "the speed in m/s above which a run fails",
        )?;
    }

    let o = &case.output;
    if let Some(v) = o.load_interval {
        positive(
            "output.load_interval",
            v,
            "the interval between load rows in s (null: every step)",
        )?;
    }
    if let Some(v) = o.snapshot_interval {
        positive(
            "output.snapshot_interval",
            v,
            "the interval between snapshots in s (null: none)",
        )?;
    }
    if let Some(v) = o.filter_window {
        positive(
            "output.filter_window",
            v,
            "the width of the load filter in s (null: automatic)",
        )?;
    }
    Ok(())
}

// ---------------------------------------------------------------------------
// 3. domain and particle limit

fn check_domain(case: &Case) -> Check {
    let d = &case.domain;
    for (axis, name) in [(0, "x"), (1, "y")] {
        if d.min[axis] >= d.max[axis] {
            return reject(
                "domain",
                format!(
                    "domain.min must be below domain.max in {name} (got min {} >= max {})",
                    d.min[axis], d.max[axis]
                ),
            );
        }
    }
    Ok(())
}

fn in_domain(case: &Case, p: Point) -> bool {
    let d = &case.domain;
    (0..2).all(|k| p[k] >= d.min[k] && p[k] <= d.max[k])
}

fn check_particle_limit(case: &Case, limits: &Limits) -> Check {
    if case.fluid_blocks.is_empty() {
        return reject("fluid_blocks", "at least one fluid block is needed");
    }
    let Some(n) = estimated_particles(case) else {
        return Ok(());
    };
    if !n.is_finite() || n.round() > limits.max_particles as f64 {
        return reject(
            "particle_spacing",
            format!(
                "about {:.0} particles (estimated from the fluid block areas / particle_spacing²) exceed the limit of {}: \
                 use a larger particle_spacing or smaller fluid blocks",
                n, limits.max_particles
            ),
        );
    }
    Ok(())
}

// ---------------------------------------------------------------------------
// 4. geometry

/// A closed polygon: >= 3 vertices, no repeated consecutive vertex, non-zero area,
/// no two non-adjacent edges crossing. Returns the signed area.
fn check_polygon(path: &str, polygon: &[Point]) -> Result<f64, CaseError> {
    let n = polygon.len();
    if n < 3 {
        return reject(
            path,
            format!("a polygon needs at least 3 vertices (got {n})"),
        );
    }
    if n > MAX_VERTICES {
        return reject(
            path,
            format!("a polygon may have at most {MAX_VERTICES} vertices (got {n})"),
        );
    }
    for k in 0..n {
        let next = (k + 1) % n;
        if polygon[k] == polygon[next] {
            let hint = if next == 0 {
                " (do not repeat the first vertex at the end: polygons close themselves)"
            } else {
                ""
            };
            return reject(
                format!("{path}[{next}]"),
                format!("repeats the previous vertex {:?}{hint}", polygon[k]),
            );
        }
    }
    let pts = points(polygon);
    let area = signed_area(&pts);
    let (lo, hi) = bounds(&pts);
    let scale = (hi - lo).norm();
    if !area.is_finite() {
        return reject(
            path,
            "the coordinates are too large to compute the polygon's area",
        );
    }
    for i in 0..n {
        for j in i + 1..n {
            // adjacent edges share a vertex
            if j == i + 1 || (i == 0 && j == n - 1) {
                continue;
            }
            let (a, b) = (pts[i], pts[(i + 1) % n]);
            let (c, d) = (pts[j], pts[(j + 1) % n]);
            if segments_intersect(a, b, c, d) {
                return reject(
                    path,
                    format!(
                        "the polygon is self-intersecting: edge {i}-{} crosses edge {j}-{}",
                        (i + 1) % n,
                        (j + 1) % n
                    ),
                );
            }
        }
    }
    if area.abs() <= 1e-12 * scale * scale {
        return reject(
            path,
            "the polygon has zero area (its vertices are collinear)",
        );
    }
    Ok(area)
}

fn bounds(pts: &[Vec2]) -> (Vec2, Vec2) {
    let mut lo = Vec2::repeat(Real::INFINITY);
    let mut hi = Vec2::repeat(Real::NEG_INFINITY);
    for p in pts {
        lo = lo.inf(p);
        hi = hi.sup(p);
    }
    (lo, hi)
}

fn check_fluid_blocks(case: &Case) -> Check {
    for (i, block) in case.fluid_blocks.iter().enumerate() {
        let path = format!("fluid_blocks[{i}].polygon");
        check_polygon(&path, &block.polygon)?;
        for (k, p) in block.polygon.iter().enumerate() {
            if !in_domain(case, *p) {
                return reject(
                    format!("{path}[{k}]"),
                    format!(
                        "vertex {p:?} lies outside the domain (min {:?}, max {:?}): particles there would be removed at once",
                        case.domain.min, case.domain.max
                    ),
                );
            }
        }
    }
    Ok(())
}

fn wall_segments(case: &Case, w: usize) -> Vec<[Vec2; 2]> {
    let wall = &case.walls[w];
    let pts = points(&wall.polyline);
    let n = pts.len();
    let count = if wall.closed { n } else { n.saturating_sub(1) };
    (0..count).map(|k| [pts[k], pts[(k + 1) % n]]).collect()
}

fn check_walls(case: &Case) -> Check {
    for (i, wall) in case.walls.iter().enumerate() {
        let path = format!("walls[{i}].polyline");
        let n = wall.polyline.len();
        if n < 2 {
            return reject(
                path,
                format!("a wall polyline needs at least 2 points (got {n})"),
            );
        }
        if n > MAX_VERTICES {
            return reject(
                path,
                format!("a wall polyline may have at most {MAX_VERTICES} points (got {n})"),
            );
        }
        if wall.closed && n < 3 {
            return reject(
                path,
                format!("a closed wall needs at least 3 points (got {n})"),
            );
        }
        let segments = if wall.closed { n } else { n - 1 };
        for k in 0..segments {
            let next = (k + 1) % n;
            if wall.polyline[k] == wall.polyline[next] {
                let hint = if next == 0 {
                    " (a closed wall joins its last point to the first: do not repeat the first point)"
                } else {
                    ""
                };
                return reject(
                    format!("{path}[{next}]"),
                    format!(
                        "zero-length segment: repeats the previous point {:?}{hint}",
                        wall.polyline[k]
                    ),
                );
            }
        }
    }
    Ok(())
}

/// The body's polygon placed in the world by its position and angle.
fn placed_body(body: &Body) -> Vec<Vec2> {
    let (s, c) = body.angle.sin_cos();
    let t = vec2(body.position);
    body.polygon
        .iter()
        .map(|p| Vec2::new(c * p[0] - s * p[1], s * p[0] + c * p[1]) + t)
        .collect()
}

fn edges(pts: &[Vec2]) -> Vec<[Vec2; 2]> {
    let n = pts.len();
    (0..n).map(|k| [pts[k], pts[(k + 1) % n]]).collect()
}

fn check_bodies(case: &Case) -> Check {
    for (i, body) in case.bodies.iter().enumerate() {
        let path = format!("bodies[{i}].polygon");
        let area = check_polygon(&path, &body.polygon)?;
        if area < 0.0 {
            return reject(
                path,
                "the body polygon is clockwise: list its vertices counter-clockwise (reverse their order)",
            );
        }
        let motion = format!("bodies[{i}].motion");
        match &body.motion {
            Motion::Free { mass, inertia, .. } => {
                positive(
                    &format!("{motion}.mass"),
                    *mass,
                    "the mass in kg per metre of span",
                )?;
                if let Some(j) = inertia {
                    positive(
                        &format!("{motion}.inertia"),
                        *j,
                        "the moment of inertia in kg·m²/m (omit it to compute it from the polygon)",
                    )?;
                }
            }
            Motion::Prescribed {
                table: Some(table), ..
            } => {
                if table.is_empty() {
                    return reject(format!("{motion}.table"), "a velocity table needs at least one sample (omit it for a constant velocity)");
                }
                for k in 1..table.len() {
                    if table[k].time <= table[k - 1].time {
                        return reject(
                            format!("{motion}.table[{k}].time"),
                            format!(
                                "times in a velocity table must be strictly increasing (got {} after {})",
                                table[k].time,
                                table[k - 1].time
                            ),
                        );
                    }
                }
            }
            Motion::Prescribed { table: None, .. } => {}
        }
    }
    Ok(())
}

/// Do two closed polygons overlap (edges crossing, or one inside the other)?
fn polygons_overlap(a: &[Vec2], b: &[Vec2]) -> bool {
    let (ea, eb) = (edges(a), edges(b));
    ea.iter()
        .any(|[p, q]| eb.iter().any(|[r, s]| segments_intersect(*p, *q, *r, *s)))
        || inside(a[0], &eb)
        || inside(b[0], &ea)
}

fn check_overlaps(case: &Case) -> Check {
    let placed: Vec<Vec<Vec2>> = case.bodies.iter().map(placed_body).collect();
    for (i, body) in placed.iter().enumerate() {
        let body_edges = edges(body);
        for (w, wall) in case.walls.iter().enumerate() {
            let segs = wall_segments(case, w);
            let crosses = segs.iter().any(|[r, s]| {
                body_edges
                    .iter()
                    .any(|[p, q]| segments_intersect(*p, *q, *r, *s))
            });
            let wall_inside = wall.polyline.iter().any(|p| inside(vec2(*p), &body_edges));
            if crosses || wall_inside {
                return reject(
                    format!("bodies[{i}]"),
                    format!(
                        "the body (as placed by position and angle) overlaps wall '{}' (walls[{w}]); move it clear of the wall",
                        wall.name
                    ),
                );
            }
        }
        for (j, other) in placed.iter().enumerate().take(i) {
            if polygons_overlap(body, other) {
                return reject(
                    format!("bodies[{i}]"),
                    format!(
                        "the body (as placed by position and angle) overlaps body '{}' (bodies[{j}]); bodies must start apart",
                        case.bodies[j].name
                    ),
                );
            }
        }
    }
    Ok(())
}

// ---------------------------------------------------------------------------
// 5. output and names

fn check_output(case: &Case) -> Check {
    for (i, probe) in case.output.probes.iter().enumerate() {
        if !in_domain(case, probe.position) {
            return reject(
                format!("output.probes[{i}].position"),
                format!(
                    "probe '{}' at {:?} lies outside the domain (min {:?}, max {:?})",
                    probe.name, probe.position, case.domain.min, case.domain.max
                ),
            );
        }
    }
    Ok(())
}

fn check_names(case: &Case) -> Check {
    // walls and bodies share the `body` column of loads.csv
    let mut seen: HashMap<&str, String> = HashMap::new();
    let named = case
        .walls
        .iter()
        .enumerate()
        .map(|(i, w)| (format!("walls[{i}].name"), w.name.as_str()))
        .chain(
            case.bodies
                .iter()
                .enumerate()
                .map(|(i, b)| (format!("bodies[{i}].name"), b.name.as_str())),
        );
    for (path, name) in named {
        if name.trim().is_empty() {
            return reject(
                path,
                "a name must not be empty (it labels rows of loads.csv)",
            );
        }
        if name.contains([',', '"', '\n', '\r']) {
            return reject(path, format!("name '{name}' must not contain commas, quotes or line breaks (it is a CSV field)"));
        }
        if let Some(first) = seen.get(name) {
            return reject(
                path,
                format!("duplicate name '{name}' (already used by {first}): walls and bodies need distinct names"),
            );
        }
        seen.insert(name, path.trim_end_matches(".name").to_string());
    }
    let mut probes: HashMap<&str, usize> = HashMap::new();
    for (i, p) in case.output.probes.iter().enumerate() {
        let path = format!("output.probes[{i}].name");
        if p.name.trim().is_empty() {
            return reject(
                path,
                "a probe name must not be empty (it labels rows of probes.csv)",
            );
        }
        if p.name.contains([',', '"', '\n', '\r']) {
            return reject(
                path,
                format!(
                    "probe name '{}' must not contain commas, quotes or line breaks",
                    p.name
                ),
            );
        }
        if let Some(first) = probes.insert(p.name.as_str(), i) {
            return reject(
                path,
                format!(
                    "duplicate probe name '{}' (already used by output.probes[{first}])",
                    p.name
                ),
            );
        }
    }
    Ok(())
}
