//! Where a case's fluid keeps `particle_spacing` (the fine boxes of `case.refinement`),
//! from the case alone: validation estimates the particle count from them and the
//! engine's layout (`engine::refinement`) coarsens the fluid outside them.
//!
//! The fine boxes of `"auto"` cover each moving body's swept path over the run,
//! widened by [`AUTO_MARGIN`] body sizes on every side; beyond them a band of
//! [`FAR_MARGIN`] body sizes keeps 2 l0, and the water farther out is laid out at 4 l0.

use super::prescribed::PrescribedVelocity;
use super::{Body, Case, Motion, Projection, Refinement, Scheme};
use crate::geometry::{bounds, centroid};
use crate::math::{rotate, vec2, Real, Vec2};

/// Margin of an automatic fine box around a body's swept path, in body sizes (the
/// larger side of the body's bounding box). The load on an entering body is decided
/// within a few wetted half-widths c of it, and c reaches half the breadth at chine
/// wetting: three quarters of a body size is then 1.5 c beyond the chine. Over eight
/// lattice offsets the shipped wedge reads C_F −3.4 ± 0.4 % with it (41 814 particles)
/// against −3.7 ± 0.7 % with one body size (54 675), docs/method.md.
pub const AUTO_MARGIN: Real = 0.75;

/// Width of the 2 l0 band around an automatic fine box, in body sizes; the water beyond
/// it is laid out at 4 l0. Half a body size: the third level takes 27 % of the particles
/// off the shipped wedge for the same force (over four lattice offsets C_F −2.5 ± 0.6 %
/// against −2.9 ± 0.9 % on two levels, both with a fine margin of one body size,
/// docs/method.md).
pub const FAR_MARGIN: Real = 0.5;

/// The rows of a fluid block of height `height` at spacing `l0`: how many, and their
/// pitch. A height that is a whole number of spacings keeps l0; any other is filled
/// with one row more, pressed together to fit, so that the block's top and bottom are
/// where the case draws them (a free surface half a pitch above the top row): rows l0
/// apart from the bottom would leave the surface of the 25° drop test's 1.1 m tank at
/// 12 mm 8 mm low. The pitch is at least (1 − 1/rows) l0 (0.36 % less there): pressed,
/// not stretched, so that no interior row reads as free surface (n* < 0.97 n0).
pub fn block_rows(height: Real, l0: Real) -> (i64, Real) {
    let spacings = height / l0;
    let whole = (spacings + 1e-9).floor();
    if spacings - whole <= 1e-9 {
        return (whole as i64, l0);
    }
    let rows = whole + 1.0;
    (rows as i64, height / rows)
}

/// The 2 l0 cells around a 4 l0 particle's square that must be coarse: its reach of
/// 4 radius l0 from the centre, 2 l0 from the square's edge, in cells of 2 l0 (4 cells
/// at r_e = 2.5 l0). That also keeps l0 particles beyond the pair radius 2.5 radius l0
/// of spacings 1 and 4.
pub fn far_clearance(radius: Real) -> i64 {
    (2.0 * radius - 1.0).ceil().max(1.0) as i64
}

/// Samples of a body's path over the run when sweeping it.
const PATH_SAMPLES: usize = 64;

/// An axis-aligned box.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FineBox {
    pub min: Vec2,
    pub max: Vec2,
}

impl FineBox {
    pub fn touches_cell(&self, lo: Vec2, hi: Vec2) -> bool {
        lo.x < self.max.x && hi.x > self.min.x && lo.y < self.max.y && hi.y > self.min.y
    }
}

/// Why `scheme` cannot run a multi-resolution layout, if it cannot: the operators with a
/// pair radius and volume factor (`engine::resolution`) are the lattice-normalised
/// Laplacians (HL, classic), the gradients of `pressure_gradient`, the approximate
/// projection and both load estimators; the per-row operator variants (CHL,
/// anisotropic, least squares) and the exact projection are single-resolution.
pub fn unsupported_by_multi_resolution(scheme: &Scheme) -> Option<&'static str> {
    use super::{GradientKind as G, LaplacianKind as L};
    if !matches!(
        scheme.laplacian,
        L::HigherOrder | L::Classic | L::SecondOrder
    ) {
        return Some("scheme.laplacian must be higher_order, classic or second_order");
    }
    if matches!(scheme.gradient, G::Anisotropic | G::LeastSquares) {
        return Some("scheme.gradient anisotropic and least_squares are single-resolution");
    }
    if scheme.projection != Projection::Approximate {
        return Some("scheme.projection must be approximate");
    }
    None
}

/// The fine boxes of a case, `None` for a uniform layout: `"none"`, or `"auto"` without
/// a moving body or with a scheme that is single-resolution only
/// ([`unsupported_by_multi_resolution`]; validation rejects explicit boxes with one).
pub fn fine_boxes(case: &Case) -> Option<Vec<FineBox>> {
    if unsupported_by_multi_resolution(&case.scheme).is_some() {
        return None;
    }
    match &case.refinement {
        Refinement::None => None,
        Refinement::Regions(r) => Some(
            r.fine
                .iter()
                .map(|b| FineBox {
                    min: vec2(b.min),
                    max: vec2(b.max),
                })
                .collect(),
        ),
        Refinement::Auto => auto_boxes(case, AUTO_MARGIN),
    }
}

/// The boxes outside which the layout may be 4 l0, where it has a third level: `"auto"`
/// with its fine boxes, each widened by [`FAR_MARGIN`] body sizes more. Explicit fine
/// boxes keep two levels (2 l0 everywhere outside them, as the case format says).
pub fn far_boxes(case: &Case) -> Option<Vec<FineBox>> {
    match &case.refinement {
        Refinement::Auto => fine_boxes(case).and(auto_boxes(case, AUTO_MARGIN + FAR_MARGIN)),
        _ => None,
    }
}

/// Each moving body's swept box widened by `margin` body sizes; `None` without one.
fn auto_boxes(case: &Case, margin: Real) -> Option<Vec<FineBox>> {
    let boxes: Vec<FineBox> = case
        .bodies
        .iter()
        .filter_map(|b| swept_box(b, case, margin))
        .collect();
    (!boxes.is_empty()).then_some(boxes)
}

/// The bounding box of a moving body over [0, time.end], widened by `margin` body sizes
/// (the larger side of its bounding box); `None`
/// for a body that does not move. Free bodies follow their initial velocity and gravity
/// (ballistic, an overestimate of the path in water); a rotating body is swept as its
/// bounding circle about the centroid.
fn swept_box(body: &Body, case: &Case, margin: Real) -> Option<FineBox> {
    if !moves(body) {
        return None;
    }
    let poly: Vec<Vec2> = body.polygon.iter().map(|p| vec2(*p)).collect();
    let c = centroid(&poly);
    let radius = poly.iter().map(|p| (p - c).norm()).fold(0.0, Real::max);
    let (lo, hi) = bounds(&poly);
    let size = (hi.x - lo.x).max(hi.y - lo.y);
    let end = case.time.end;
    let g = vec2(case.fluid.gravity);
    // displacement of the body frame and whether it turns, at time t
    let (path, turns): (Box<dyn Fn(Real) -> Vec2>, bool) = match &body.motion {
        Motion::Prescribed {
            velocity,
            angular_velocity,
            table,
        } => {
            let v = PrescribedVelocity::new(*velocity, *angular_velocity, table.as_ref());
            let turns = *angular_velocity != 0.0
                || table.iter().flatten().any(|s| s.angular_velocity != 0.0);
            let h = end / PATH_SAMPLES as Real;
            (
                Box::new(move |t: Real| {
                    // trapezoids over the samples up to t
                    let steps = (t / h).round() as usize;
                    (0..steps).fold(Vec2::zeros(), |x, k| {
                        let (a, b) = (v.at(k as Real * h), v.at((k + 1) as Real * h));
                        x + (a.velocity + b.velocity) * (0.5 * h)
                    })
                }),
                turns,
            )
        }
        Motion::Free {
            velocity,
            angular_velocity,
            ..
        } => {
            let v0 = vec2(*velocity);
            (
                Box::new(move |t: Real| v0 * t + g * (0.5 * t * t)),
                *angular_velocity != 0.0,
            )
        }
    };
    let position = vec2(body.position);
    let (mut blo, mut bhi) = (
        Vec2::repeat(Real::INFINITY),
        Vec2::repeat(Real::NEG_INFINITY),
    );
    for k in 0..=PATH_SAMPLES {
        let offset = position + path(end * k as Real / PATH_SAMPLES as Real);
        if turns {
            let centre = offset + rotate(c, body.angle);
            blo = blo.inf(&(centre - Vec2::repeat(radius)));
            bhi = bhi.sup(&(centre + Vec2::repeat(radius)));
        } else {
            for p in &poly {
                let x = offset + rotate(*p, body.angle);
                blo = blo.inf(&x);
                bhi = bhi.sup(&x);
            }
        }
    }
    let margin = Vec2::repeat(margin * size);
    Some(FineBox {
        min: blo - margin,
        max: bhi + margin,
    })
}

/// Does the body move: a free body, or a prescribed one with a velocity?
pub fn moves(body: &Body) -> bool {
    match &body.motion {
        Motion::Free { .. } => true,
        Motion::Prescribed {
            velocity,
            angular_velocity,
            table,
        } => {
            vec2(*velocity).norm() > 0.0
                || *angular_velocity != 0.0
                || table
                    .iter()
                    .flatten()
                    .any(|s| vec2(s.velocity).norm() > 0.0 || s.angular_velocity != 0.0)
        }
    }
}
