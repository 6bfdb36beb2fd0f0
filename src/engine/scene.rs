//! From a case to the initial state: fluid particles on a square lattice of l0 inside
//! the fluid blocks, outside every solid and at least [`SURFACE_CLEARANCE`] from every
//! wall and body surface, and the wall objects with their solid regions.

use super::params::MpsParameters;
use super::particles::Particles;
use super::refinement::FarLevel;
use super::walls::{WallObject, WallState};
use crate::case::{Case, FluidSide, Motion};
use crate::geometry::{centroid, closest_on_segment, inside, WallShape};
use crate::math::{cross, rotate, vec2, Real, Vec2};
use std::collections::HashSet;

/// Line segments, each as its two end points.
type Segments = Vec<[Vec2; 2]>;

/// Least distance, in spacings, from a lattice point kept as a fluid particle to a wall
/// or body surface.
///
/// The virtual wall lattice puts its first row l0/2 behind the surface, so the fluid's
/// first row belongs l0/2 in front of it. A face along a lattice line at a cell boundary
/// has its first row there whatever the clearance below l0/2. Any other face (inclined,
/// or off the lattice) meets the lattice at distances spread evenly over a spacing:
/// keeping only points l0/2 clear put the first row at 0.5-1.5 l0, leaving a strip
/// l0/2 wide empty on average, and its particles short of n0 read as free surface
/// (p = 0) inside the water. A fixed box 0.37 l0 off the lattice then failed within
/// 0.2 s of still water, and a submerged 30° wedge ran away from its apex. At 0.1 l0 both
/// hold still water exactly (tests/bodies/hydrostatics.rs); a particle 0.1 l0 from the
/// surface starts about 20 % above n0, which the first pressure solve pushes back.
pub const SURFACE_CLEARANCE: Real = 0.1;

/// How far, in spacings, the lattice keeps the axis of the first moving body from its
/// nearest mirror line (the lines through and halfway between particle columns): a
/// body closer than this moves the whole lattice sideways until it is this far.
/// A symmetric body on a mirror line keeps the two sides' particles mirror images until
/// round-off breaks the symmetry, and while they are, the faces' pressure noise adds
/// coherently: the 25° wedge at 5 mm read C_F +0.8 % from the similarity solution on the
/// line and -3.0 % 0.22 l0 off it (10-17 % apart with r_e = 2.1 l0); at 1 cm a shift of
/// l0/32 already read like one of l0/10. Random jitter of 0.002 l0 instead broke the
/// symmetry too but seeded number-density errors the source turns into pressure noise
/// (the impulsively started plate lost 2.1 % of its added mass at 1 cm). Scenes without a
/// moving body (still water, a fixed submerged body) keep their lattice.
pub const MIRROR_CLEARANCE: Real = 0.125;

pub struct Scene {
    pub particles: Particles,
    pub walls: Vec<WallObject>,
    pub domain_min: Vec2,
    pub domain_max: Vec2,
}

/// Lattice points inside `polygon`, anchored half a spacing from its lower-left bound:
/// columns l0 apart, rows at the pitch [`crate::case::layout::block_rows`] gives its
/// height (l0 when the height is whole spacings). Returns the points and the row pitch.
pub fn fill_polygon(polygon: &[Vec2], l0: Real) -> (Vec<Vec2>, Real) {
    let n = polygon.len();
    let edges: Vec<[Vec2; 2]> = (0..n).map(|k| [polygon[k], polygon[(k + 1) % n]]).collect();
    let (lo, hi) = crate::geometry::bounds(polygon);
    let nx = ((hi.x - lo.x) / l0 + 1e-9).floor() as i64;
    let (ny, dy) = crate::case::layout::block_rows(hi.y - lo.y, l0);
    let mut pts = Vec::new();
    for j in 0..ny.max(0) {
        for i in 0..nx.max(0) {
            let p = Vec2::new(lo.x + (i as Real + 0.5) * l0, lo.y + (j as Real + 0.5) * dy);
            if inside(p, &edges) {
                pts.push(p);
            }
        }
    }
    (pts, dy)
}

/// Thickness given to open wall polylines: deeper than any kernel reach.
pub fn wall_thickness(params: &MpsParameters) -> Real {
    2.0 * params.neighbour_radius() + 2.0 * params.l0
}

/// World-frame state of body `b` at t = 0.
pub fn initial_body_state(case: &Case, b: usize) -> WallState {
    let body = &case.bodies[b];
    let poly: Vec<Vec2> = body.polygon.iter().map(|p| vec2(*p)).collect();
    let position = vec2(body.position);
    let com = position + rotate(centroid(&poly), body.angle);
    let (velocity, angular_velocity) = match &body.motion {
        Motion::Prescribed {
            velocity,
            angular_velocity,
            table,
        } => match table.as_ref().and_then(|t| t.first()) {
            Some(first) => (vec2(first.velocity), first.angular_velocity),
            None => (vec2(*velocity), *angular_velocity),
        },
        Motion::Free {
            velocity,
            angular_velocity,
            ..
        } => (vec2(*velocity), *angular_velocity),
    };
    WallState {
        position,
        angle: body.angle,
        velocity,
        angular_velocity,
        center_of_mass: com,
        ..Default::default()
    }
}

pub fn build_scene(case: &Case, params: &MpsParameters) -> Scene {
    build_scene_placed(case, params, None)
}

/// [`build_scene`] with the lattice placed at `phase` (0..1) of the range an ensemble
/// samples, or where [`build_scene`] puts it when None. With a moving body, the first
/// one's axis ends (1 + phase) l0/8 from its nearest mirror line, so the phases span the
/// distinct arrangements [l0/8, l0/4] (an axis at d and at l0/2 - d are mirror images);
/// without one, the lattice moves (phase - 1/2) l0/2 sideways, so the first column next
/// to a wall stays 1/4 to 3/4 of a spacing from it.
pub fn build_scene_placed(case: &Case, params: &MpsParameters, phase: Option<Real>) -> Scene {
    let l0 = params.l0;
    // 1. candidate fluid particles, one per lattice site even where blocks overlap
    let mut seen: HashSet<(i64, i64)> = HashSet::new();
    let mut candidates: Vec<(Vec2, Vec2)> = Vec::new();
    // the row pitch of the first block: the multi-resolution layout merges its lattice
    let mut row_pitch = None;
    for block in &case.fluid_blocks {
        let poly: Vec<Vec2> = block.polygon.iter().map(|p| vec2(*p)).collect();
        let (points, dy) = fill_polygon(&poly, l0);
        if !points.is_empty() {
            row_pitch.get_or_insert(dy);
        }
        for p in points {
            let key = (
                (p.x / (0.25 * l0)).round() as i64,
                (p.y / (0.25 * l0)).round() as i64,
            );
            if seen.insert(key) {
                candidates.push((p, vec2(block.velocity)));
            }
        }
    }
    // 1b. the first moving body's axis off the lattice's mirror lines (or where an
    // ensemble member places it)
    let moving = case.bodies.iter().find(|b| crate::case::layout::moves(b));
    let shift = match (moving, candidates.first(), phase) {
        (Some(body), Some(&(first, _)), None) => mirror_shift(body_axis(body), first.x, l0),
        (Some(body), Some(&(first, _)), Some(phase)) => {
            mirror_offset(body_axis(body), first.x, l0) - (1.0 + phase) * 0.125 * l0
        }
        (None, _, Some(phase)) => (phase - 0.5) * 0.5 * l0,
        _ => 0.0,
    };
    if shift != 0.0 {
        for (p, _) in &mut candidates {
            p.x += shift;
        }
    }
    // 2. wall objects: fixed walls (side from the fluid when automatic), then bodies
    let thickness = wall_thickness(params);
    let mut walls = Vec::new();
    for wall in &case.walls {
        let pts: Vec<Vec2> = wall.polyline.iter().map(|p| vec2(*p)).collect();
        let solid_left = match wall.fluid_side {
            FluidSide::Left => false,
            FluidSide::Right => true,
            FluidSide::Auto => fluid_is_right(
                &pts,
                wall.closed,
                &candidates,
                2.0 * params.neighbour_radius(),
            ),
        };
        walls.push(WallObject {
            name: wall.name.clone(),
            body: None,
            shape: WallShape::from_polyline(&pts, wall.closed, solid_left, thickness),
            state: WallState::default(),
            free_slip: wall.slip == crate::case::WallSlip::FreeSlip,
        });
    }
    for (b, body) in case.bodies.iter().enumerate() {
        let poly: Vec<Vec2> = body.polygon.iter().map(|p| vec2(*p)).collect();
        walls.push(WallObject {
            name: body.name.clone(),
            body: Some(b),
            shape: WallShape::solid_polygon(&poly),
            state: initial_body_state(case, b),
            free_slip: false,
        });
    }
    // 3. keep the candidates outside every solid and clear of every surface
    let placed: Vec<(Segments, Segments)> = walls
        .iter()
        .map(|w| {
            let s = w.shape.transformed(w.state.position, w.state.angle);
            (s.surface.clone(), s.loop_edges())
        })
        .collect();
    let clearance = SURFACE_CLEARANCE * l0;
    let (mut pos, mut vel) = (Vec::new(), Vec::new());
    'next: for (p, v) in candidates {
        for (surface, loops) in &placed {
            if inside(p, loops) {
                continue 'next;
            }
            if surface
                .iter()
                .any(|[a, b]| (closest_on_segment(p, *a, *b) - p).norm() < clearance)
            {
                continue 'next;
            }
        }
        pos.push(p);
        vel.push(v);
    }
    // grown by doubling they held up to twice their length for the whole run (3.3 of
    // 150 MB at the step's peak, 160k particles)
    pos.shrink_to_fit();
    vel.shrink_to_fit();
    // 4. multi-resolution: 2 × 2 sites merged outside the fine boxes, and 2 × 2 of those
    // outside the far boxes
    let particles = match crate::case::layout::fine_boxes(case) {
        None => Particles::with_positions(pos, vel),
        Some(boxes) => {
            let far_boxes = crate::case::layout::far_boxes(case);
            let far = far_boxes.as_deref().map(|boxes| FarLevel {
                boxes,
                // in spacings as the scheme states it, as the particle estimate takes
                // it: (r_e l0) / l0 lands one ulp above 2.5 at some spacings (3.7 mm
                // among them), which widened the clearance by a cell
                radius: case.scheme.neighbour_radius(),
            });
            let sites = pos.into_iter().zip(vel).collect();
            let (pos, vel, scale) = super::refinement::coarsen(
                sites,
                Vec2::new(l0, row_pitch.unwrap_or(l0)),
                &boxes,
                far,
            );
            let mut particles = Particles::with_positions(pos, vel);
            particles.scale = scale;
            particles
        }
    };
    Scene {
        particles,
        walls,
        domain_min: vec2(case.domain.min),
        domain_max: vec2(case.domain.max),
    }
}

/// The world x of a body's centroid (the axis of a symmetric body entering vertically).
fn body_axis(body: &crate::case::Body) -> Real {
    let poly: Vec<Vec2> = body.polygon.iter().map(|p| vec2(*p)).collect();
    vec2(body.position).x + rotate(centroid(&poly), body.angle).x
}

/// Signed distance of `axis` from the nearest mirror line of a lattice with a column at
/// `column`, in (-l0/4, l0/4].
fn mirror_offset(axis: Real, column: Real, l0: Real) -> Real {
    let half = 0.5 * l0;
    (axis - column) - half * ((axis - column) / half).round()
}

/// The sideways shift of a lattice with a column at `column` that puts `axis` at least
/// `MIRROR_CLEARANCE` l0 from the nearest mirror line (0 when it already is).
fn mirror_shift(axis: Real, column: Real, l0: Real) -> Real {
    let off = mirror_offset(axis, column, l0);
    let clear = MIRROR_CLEARANCE * l0;
    if off.abs() >= clear {
        0.0
    } else if off >= 0.0 {
        // move the lattice left: the axis ends `clear` right of the line
        off - clear
    } else {
        off + clear
    }
}

/// Is most of the fluid near this polyline on its right-hand side?
fn fluid_is_right(points: &[Vec2], closed: bool, fluid: &[(Vec2, Vec2)], reach: Real) -> bool {
    let n = points.len();
    let segs = if closed { n } else { n - 1 };
    let (mut left, mut right) = (0usize, 0usize);
    for (p, _) in fluid {
        let mut best = (Real::INFINITY, 0.0);
        for k in 0..segs {
            let (a, b) = (points[k], points[(k + 1) % n]);
            let d = (closest_on_segment(*p, a, b) - p).norm();
            if d < best.0 {
                best = (d, cross(b - a, p - a));
            }
        }
        if best.0 < reach {
            if best.1 > 0.0 {
                left += 1;
            } else {
                right += 1;
            }
        }
    }
    right > left
}
