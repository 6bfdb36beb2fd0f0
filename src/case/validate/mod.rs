//! Validation before any work: every rejection names the dotted field path
//! (`bodies[0].polygon`, `fluid.density`) and a reason a user can act on.
//!
//! The rules, in the order they are checked (the first failure is reported):
//! 1. every number is finite (a generic walk over the serialised case, so fields
//!    added later are covered too): [`finite`];
//! 2. signs and ranges of scalars: density, spacing, end time, cfl, max_dt, kernel
//!    radii, solver tolerance positive; viscosity non-negative; output intervals
//!    positive: [`scalars`];
//! 3. the domain (min < max): [`scalars`];
//! 4. geometry: fluid block and body polygons (>= 3 vertices, no repeated consecutive
//!    vertex, non-zero area, no crossing edges, bodies counter-clockwise), wall
//!    polylines (>= 2 points, no zero-length segment), fluid blocks and probes inside
//!    the domain, bodies clear of walls and of each other: [`geometry`];
//! 5. body motion: free bodies with positive mass and inertia, velocity tables
//!    strictly increasing in time (checked with each body's polygon): [`geometry`];
//! 6. refinement: explicit fine boxes non-empty, with a scheme that runs on a
//!    multi-resolution layout; then the particle limit, estimated from the fluid
//!    block areas and the fine boxes before anything is generated
//!    ([`estimated_particles`]): [`scalars`];
//! 7. names: walls and bodies share the `body` column of loads.csv, so their names are
//!    unique together and non-empty; probe names likewise among probes: [`names`].

mod finite;
mod geometry;
mod names;
mod scalars;

use super::layout::{far_clearance, FineBox};
use super::{Case, CaseError, Point};
use crate::geometry::{bounds, signed_area};
use crate::math::{vec2, Vec2};

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
    finite::check_finite(case)?;
    scalars::check_scalars(case)?;
    scalars::check_domain(case)?;
    geometry::check_fluid_blocks(case)?;
    geometry::check_walls(case)?;
    geometry::check_bodies(case)?;
    geometry::check_overlaps(case)?;
    geometry::check_output(case)?;
    scalars::check_damping_zones(case)?;
    scalars::check_refinement(case)?;
    scalars::check_particle_limit(case, limits)?;
    names::check_names(case)?;
    Ok(())
}

/// Estimated number of fluid particles: the summed fluid block areas / l0², each scaled
/// by l0 over its row pitch (`layout::block_rows`; overlaps and the parts inside bodies
/// counted, so an upper bound up to lattice rounding). On a
/// multi-resolution layout the area outside the fine boxes counts at (2 l0)², except a
/// band along each block's boundary where cut cells stay fine (2 l0 wide along a slanted
/// edge; l0 along an axis-aligned one, where at most the last row of sites is left over
/// when the block's rows or columns are odd in number); with a third
/// level the area outside the far boxes counts at (4 l0)², except a band along the
/// boundary as wide as a 4 l0 square's clearance. `None` when the case has no usable
/// spacing.
pub fn estimated_particles(case: &Case) -> Option<f64> {
    let l0 = case.particle_spacing;
    if !(l0.is_finite() && l0 > 0.0) {
        return None;
    }
    let boxes = super::layout::fine_boxes(case);
    let far = super::layout::far_boxes(case);
    let radius = case.scheme.neighbour_radius();
    let cells: f64 = case
        .fluid_blocks
        .iter()
        .map(|b| {
            let poly = points(&b.polygon);
            // rows pressed to fit the block's height hold up to one row more
            let (lo, hi) = bounds(&poly);
            let (_, pitch) = super::layout::block_rows(hi.y - lo.y, l0);
            let area = signed_area(&poly).abs() * (l0 / pitch);
            let inside = |boxes: &[FineBox], band: f64| -> f64 {
                let a: f64 = boxes
                    .iter()
                    .map(|bx| clipped_area(&poly, bx.min, bx.max))
                    .sum();
                (a + band).min(area)
            };
            let fine = match &boxes {
                None => area,
                Some(boxes) => inside(boxes, cut_cell_band(&poly, l0)),
            };
            match &far {
                None => fine + 0.25 * (area - fine),
                // a 4 l0 square keeps its clearance of 2 l0 cells from the block's edge
                Some(far) => {
                    let band = (2 * far_clearance(radius) + 4) as f64 * l0 * perimeter(&poly);
                    let within = inside(far, band).max(fine);
                    fine + 0.25 * (within - fine) + 0.0625 * (area - within)
                }
            }
        })
        .sum();
    Some(cells / (l0 * l0))
}

/// The area along a block's boundary whose 2 l0 cells may stay fine: l0 wide along an
/// axis-aligned edge, 2 l0 along a slanted one.
fn cut_cell_band(poly: &[Vec2], l0: f64) -> f64 {
    (0..poly.len())
        .map(|k| {
            let d = poly[(k + 1) % poly.len()] - poly[k];
            let aligned = d.x.abs() < 1e-12 * d.norm() || d.y.abs() < 1e-12 * d.norm();
            d.norm() * if aligned { l0 } else { 2.0 * l0 }
        })
        .sum()
}

fn perimeter(poly: &[Vec2]) -> f64 {
    (0..poly.len())
        .map(|k| (poly[(k + 1) % poly.len()] - poly[k]).norm())
        .sum()
}

/// Area of a polygon inside the box [lo, hi] (Sutherland-Hodgman: the box is convex,
/// the polygon need not be).
fn clipped_area(poly: &[Vec2], lo: Vec2, hi: Vec2) -> f64 {
    let mut out: Vec<Vec2> = poly.to_vec();
    // each half-plane as (axis, bound, keep below)
    for (axis, bound, below) in [
        (0, lo.x, false),
        (0, hi.x, true),
        (1, lo.y, false),
        (1, hi.y, true),
    ] {
        let keep = |p: &Vec2| {
            if below {
                p[axis] <= bound
            } else {
                p[axis] >= bound
            }
        };
        let input = std::mem::take(&mut out);
        for k in 0..input.len() {
            let (a, b) = (input[k], input[(k + 1) % input.len()]);
            match (keep(&a), keep(&b)) {
                (true, true) => out.push(b),
                (true, false) => out.push(a + (b - a) * ((bound - a[axis]) / (b[axis] - a[axis]))),
                (false, true) => {
                    out.push(a + (b - a) * ((bound - a[axis]) / (b[axis] - a[axis])));
                    out.push(b);
                }
                (false, false) => {}
            }
        }
    }
    if out.len() < 3 {
        0.0
    } else {
        signed_area(&out).abs()
    }
}

fn points(p: &[Point]) -> Vec<Vec2> {
    p.iter().map(|q| vec2(*q)).collect()
}
