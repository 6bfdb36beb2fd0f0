//! Rule 4 (geometry) with rule 5 (body motion, checked body by body with each
//! polygon): polygons, wall polylines, what lies inside the domain, overlaps.

use super::scalars::positive;
use super::{points, reject, Check, MAX_VERTICES};
use crate::case::{Body, Case, CaseError, Motion, Point};
use crate::geometry::{bounds, inside, segments_intersect, signed_area};
use crate::math::{vec2, Real, Vec2};

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

fn in_domain(case: &Case, p: Point) -> bool {
    let d = &case.domain;
    (0..2).all(|k| p[k] >= d.min[k] && p[k] <= d.max[k])
}

pub(super) fn check_fluid_blocks(case: &Case) -> Check {
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

pub(super) fn check_walls(case: &Case) -> Check {
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

pub(super) fn check_bodies(case: &Case) -> Check {
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

pub(super) fn check_overlaps(case: &Case) -> Check {
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

pub(super) fn check_output(case: &Case) -> Check {
    for (i, probe) in case.output.probes.iter().enumerate() {
        match &probe.body {
            None => {
                if probe.diameter.is_some() {
                    return reject(
                        format!("output.probes[{i}].diameter"),
                        "a diameter applies to a gauge on a body: name the body in output.probes[].body, or drop the diameter",
                    );
                }
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
            Some(name) => check_gauge(case, i, probe, name)?,
        }
    }
    Ok(())
}

/// A gauge names a body and sits on its surface (in the body's frame), within half a
/// spacing: farther out it would read the fluid beside the body, not the surface.
fn check_gauge(case: &Case, i: usize, probe: &crate::case::Probe, name: &str) -> Check {
    let Some(body) = case.bodies.iter().find(|b| b.name == name) else {
        let names: Vec<&str> = case.bodies.iter().map(|b| b.name.as_str()).collect();
        return reject(
            format!("output.probes[{i}].body"),
            format!(
                "gauge '{}' names body '{name}', which the case does not have (bodies: {})",
                probe.name,
                if names.is_empty() {
                    "none".to_string()
                } else {
                    names.join(", ")
                }
            ),
        );
    };
    if let Some(d) = probe.diameter {
        positive(
            &format!("output.probes[{i}].diameter"),
            d,
            "the length of surface the gauge averages over",
        )?;
    }
    let polygon = points(&body.polygon);
    let at = vec2(probe.position);
    let distance = (0..polygon.len())
        .map(|k| {
            let (a, b) = (polygon[k], polygon[(k + 1) % polygon.len()]);
            (crate::geometry::closest_on_segment(at, a, b) - at).norm()
        })
        .fold(Real::INFINITY, Real::min);
    let limit = 0.5 * case.particle_spacing;
    if !(distance <= limit) {
        return reject(
            format!("output.probes[{i}].position"),
            format!(
                "gauge '{}' at {:?} in the frame of body '{name}' is {distance:.3e} m from its surface; a gauge must lie within half a particle spacing ({limit:.3e} m) of the surface it reads (positions are in the coordinates of the body's polygon)",
                probe.name, probe.position
            ),
        );
    }
    Ok(())
}
