//! Polygon geometry shared by case validation, the scene, the walls and the
//! coupling: areas, centroids, closest points, even-odd containment, segment
//! crossings, and [`WallShape`] (the surface segments the fluid sees and the closed
//! loops that bound the solid behind them, in the object's own frame).
//!
//! An open tank polyline becomes a solid by offsetting it to the side away from the
//! fluid by a thickness larger than any kernel radius (mitred joins), so a concave
//! tank corner is solid on 270° and a convex apex on its true angle: the wall terms
//! sum a virtual lattice clipped to this solid, never a flat half-plane.

use crate::math::{cross, perp, rotate, Real, Vec2};

/// A wall object in its own frame: fixed walls have the identity pose.
#[derive(Debug, Clone)]
pub struct WallShape {
    /// Segments that face the fluid.
    pub surface: Vec<[Vec2; 2]>,
    /// Closed loops bounding the solid (even-odd).
    pub loops: Vec<Vec<Vec2>>,
}

impl WallShape {
    /// A closed polygon whose interior is solid (a body, or a closed wall with fluid outside).
    pub fn solid_polygon(polygon: &[Vec2]) -> Self {
        let n = polygon.len();
        let surface = (0..n).map(|k| [polygon[k], polygon[(k + 1) % n]]).collect();
        Self {
            surface,
            loops: vec![polygon.to_vec()],
        }
    }

    /// A polyline with solid on its left (`solid_left`) or right, `thickness` deep.
    /// A closed polyline whose inside is solid is a solid polygon; one whose inside is
    /// fluid becomes a ring between it and its offset.
    pub fn from_polyline(points: &[Vec2], closed: bool, solid_left: bool, thickness: Real) -> Self {
        if closed {
            let ccw = signed_area(points) > 0.0;
            if ccw == solid_left {
                return Self::solid_polygon(points);
            }
            let offset = offset_polyline(points, true, solid_left, thickness);
            let n = points.len();
            let surface = (0..n).map(|k| [points[k], points[(k + 1) % n]]).collect();
            return Self {
                surface,
                loops: vec![points.to_vec(), offset],
            };
        }
        let offset = offset_polyline(points, false, solid_left, thickness);
        let surface = points.windows(2).map(|w| [w[0], w[1]]).collect();
        let mut ring: Vec<Vec2> = points.to_vec();
        ring.extend(offset.iter().rev());
        Self {
            surface,
            loops: vec![ring],
        }
    }

    /// Edges of all loops.
    pub fn loop_edges(&self) -> Vec<[Vec2; 2]> {
        let mut e = Vec::new();
        for l in &self.loops {
            for k in 0..l.len() {
                e.push([l[k], l[(k + 1) % l.len()]]);
            }
        }
        e
    }

    /// This shape moved by a rigid pose.
    pub fn transformed(&self, position: Vec2, angle: Real) -> Self {
        let t = |p: &Vec2| rotate(*p, angle) + position;
        Self {
            surface: self.surface.iter().map(|[a, b]| [t(a), t(b)]).collect(),
            loops: self
                .loops
                .iter()
                .map(|l| l.iter().map(t).collect())
                .collect(),
        }
    }
}

/// Twice-signed area / 2 (positive when counter-clockwise).
/// The axis-aligned bounds (lower-left, upper-right) of `points`.
pub fn bounds(points: &[Vec2]) -> (Vec2, Vec2) {
    let mut lo = Vec2::repeat(Real::INFINITY);
    let mut hi = Vec2::repeat(Real::NEG_INFINITY);
    for p in points {
        lo = lo.inf(p);
        hi = hi.sup(p);
    }
    (lo, hi)
}

pub fn signed_area(points: &[Vec2]) -> Real {
    let n = points.len();
    (0..n)
        .map(|k| cross(points[k], points[(k + 1) % n]))
        .sum::<Real>()
        / 2.0
}

/// Area centroid of a simple polygon.
pub fn centroid(points: &[Vec2]) -> Vec2 {
    let n = points.len();
    let a = signed_area(points);
    let mut c = Vec2::zeros();
    for k in 0..n {
        let (p, q) = (points[k], points[(k + 1) % n]);
        c += (p + q) * cross(p, q);
    }
    c / (6.0 * a)
}

/// Second moment of area about the centroid (per unit density), for inertia.
pub fn polar_moment_about_centroid(points: &[Vec2]) -> Real {
    let n = points.len();
    let a = signed_area(points);
    let mut j = 0.0;
    for k in 0..n {
        let (p, q) = (points[k], points[(k + 1) % n]);
        j += cross(p, q) * (p.dot(&p) + p.dot(&q) + q.dot(&q));
    }
    let j_origin = j / 12.0;
    let c = centroid(points);
    (j_origin - a * c.dot(&c)).abs()
}

fn offset_polyline(points: &[Vec2], closed: bool, left: bool, thickness: Real) -> Vec<Vec2> {
    let n = points.len();
    let side = if left { 1.0 } else { -1.0 };
    let normal = |k: usize| -> Vec2 {
        let d = points[(k + 1) % n] - points[k];
        perp(d).normalize() * side
    };
    (0..n)
        .map(|k| {
            let (n_in, n_out) = if closed {
                (normal((k + n - 1) % n), normal(k))
            } else if k == 0 {
                (normal(0), normal(0))
            } else if k == n - 1 {
                (normal(n - 2), normal(n - 2))
            } else {
                (normal(k - 1), normal(k))
            };
            let m = n_in + n_out;
            let m = if m.norm() < 1e-9 {
                n_out
            } else {
                m.normalize()
            };
            let cos_half = m.dot(&n_out).max(0.25);
            points[k] + m * (thickness / cos_half)
        })
        .collect()
}

/// Closest point on segment [a, b] to p.
#[inline]
pub fn closest_on_segment(p: Vec2, a: Vec2, b: Vec2) -> Vec2 {
    let ab = b - a;
    let len2 = ab.norm_squared();
    if len2 == 0.0 {
        return a;
    }
    let t = ((p - a).dot(&ab) / len2).clamp(0.0, 1.0);
    a + ab * t
}

/// Even-odd inside test against a set of edges.
#[inline]
pub fn inside(p: Vec2, edges: &[[Vec2; 2]]) -> bool {
    let mut c = false;
    for [a, b] in edges {
        if (a.y > p.y) != (b.y > p.y) {
            let x = a.x + (p.y - a.y) * (b.x - a.x) / (b.y - a.y);
            if p.x < x {
                c = !c;
            }
        }
    }
    c
}

/// Signed distance to the solid bounded by `edges`: positive inside.
#[inline]
pub fn signed_distance(p: Vec2, edges: &[[Vec2; 2]]) -> Real {
    let mut d2 = Real::INFINITY;
    for [a, b] in edges {
        d2 = d2.min((closest_on_segment(p, *a, *b) - p).norm_squared());
    }
    let d = d2.sqrt();
    if inside(p, edges) {
        d
    } else {
        -d
    }
}

/// Do two segments properly intersect (share a point other than a common endpoint)?
pub fn segments_intersect(a: Vec2, b: Vec2, c: Vec2, d: Vec2) -> bool {
    let d1 = cross(b - a, c - a);
    let d2 = cross(b - a, d - a);
    let d3 = cross(d - c, a - c);
    let d4 = cross(d - c, b - c);
    ((d1 > 0.0 && d2 < 0.0) || (d1 < 0.0 && d2 > 0.0))
        && ((d3 > 0.0 && d4 < 0.0) || (d3 < 0.0 && d4 > 0.0))
}
