//! Wall loads as a pressure integral over the wetted surface (`scheme.wall_load =
//! "pressure_integral"`).
//!
//! The reaction of the wall terms (the other estimator) weighs each near-wall particle's
//! pressure with the wall lattice's moment at its distance d, which grows like 1/d: a
//! particle a tenth of a spacing closer than the lattice's l0/2 adds tens of percent to
//! its share. Where particles leave the lattice next to a wall (impact, a disordered
//! tank) that reading swings with every row the wall meets. Here the pressure is
//! interpolated onto points along the surface instead, and integrated: F = -∫ p n ds.
//!
//! At a surface point s the pressure is the Shepard average of the near fluid particles'
//! pressures carried to s with the Neumann condition of the wall,
//! p(s) = Σ w_j [p_j + rho (g - a_w)·(s - x_j)] / max(Σ w_j, floor),
//! so a hydrostatic field is read exactly. With multi-resolution each particle weighs
//! with its own radius, w(d; r_e s_j) = w(d/s_j; r_e): its volume over its kernel's
//! area is the same at every level, so the floor ([`FLOOR_SHARE`]) carries over. Negative
//! values are clipped (the fluid cannot pull on a wall). Only particles on the fluid
//! side of a segment count.

use super::{moment_about, PlacedWall};
use crate::engine::neighbors::CellGrid;
use crate::engine::resolution::Scales;
use crate::geometry::inside;
use crate::math::{perp, Real, Vec2};
use rayon::prelude::*;

/// The floor of the Shepard sum, as a share of what a point with fluid on its whole side
/// collects (at the default r_e = 2.5 l0, a tenth is the weight of one particle 1.4
/// spacings away): a point the fluid barely reaches (the contact line, spray) fades to
/// zero instead of taking one distant particle's value. It is no larger because a point
/// under a thin layer of water, where a wedge's pressure peaks at the jet root, would
/// read its average scaled down. With half the full side the 30° wedge at 1 cm lost
/// 6.7 % of its impulse by 0.6-0.9 t_chine (mean of four lattice offsets; 4.2 % with a
/// tenth), and the 5 mm free-fall wedge lost 5.1 % too little speed (4.1 %).
const FLOOR_SHARE: Real = 0.1;

/// Sample points per particle spacing along the surface.
const SAMPLES_PER_SPACING: Real = 2.0;

/// The pressure the load integral reads at one point of a wall object's surface: the
/// point stands for `length` of its segment, centred `along` metres from the segment's
/// first end. The points of a wall come in the order of its segments, and along each.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SurfacePressure {
    /// Index into the wall's surface segments.
    pub segment: u32,
    pub along: Real,
    pub length: Real,
    pub point: Vec2,
    /// Outward (fluid-side) normal.
    pub normal: Vec2,
    /// Pa, clipped at zero.
    pub pressure: Real,
}

/// How many equal pieces a segment `len` long is cut into for the integral (one every
/// l0/2): the snapshots' surface cells use the same cut.
pub fn pieces(len: Real, l0: Real) -> usize {
    (len * SAMPLES_PER_SPACING / l0).ceil().max(1.0) as usize
}

/// Points every l0/2 along each segment of `wall`, with normals towards the fluid (the
/// pressure not yet read).
fn surface_points(wall: &PlacedWall, l0: Real) -> Vec<SurfacePressure> {
    let mut points = Vec::new();
    for (segment, [a, b]) in wall.surface.iter().enumerate() {
        let edge = b - a;
        let len = edge.norm();
        if len == 0.0 {
            continue;
        }
        let mut normal = perp(edge / len);
        // the solid lies on one side of every surface segment: point away from it
        let probe = (a + b) * 0.5 + normal * (1e-3 * l0);
        if inside(probe, &wall.loop_edges) {
            normal = -normal;
        }
        let k = pieces(len, l0);
        let ds = len / k as Real;
        for m in 0..k {
            let share = (m as Real + 0.5) / k as Real;
            points.push(SurfacePressure {
                segment: segment as u32,
                along: len * share,
                length: ds,
                point: a + edge * share,
                normal,
                pressure: 0.0,
            });
        }
    }
    points
}

/// Weight a surface point collects from fluid filling its whole side on the lattice, at
/// the least favourable lateral offset of the lattice.
fn full_side_weight(w: &dyn Fn(Real) -> Real, l0: Real, re: Real) -> Real {
    let span = (re / l0).ceil() as i64 + 1;
    [0.0, 0.25, 0.5]
        .iter()
        .map(|&offset| {
            let mut sum = 0.0;
            for i in -span..=span {
                for k in 0..=span {
                    let r = Vec2::new((i as Real + offset) * l0, (k as Real + 0.5) * l0);
                    let d = r.norm();
                    if d < re {
                        sum += w(d);
                    }
                }
            }
            sum
        })
        .fold(Real::INFINITY, Real::min)
}

/// The pressure along every wall object's surface (one list per wall, points every
/// l0/2). `grid` sorts `x` into cells at least `re` wide.
#[allow(clippy::too_many_arguments)]
pub fn surface_pressures(
    x: &[Vec2],
    p: &[Real],
    scales: Scales,
    grid: &CellGrid,
    walls: &[PlacedWall],
    w: &(dyn Fn(Real) -> Real + Sync),
    rho: Real,
    gravity: Vec2,
    l0: Real,
    re: Real,
) -> Vec<Vec<SurfacePressure>> {
    let floor = FLOOR_SHARE * full_side_weight(w, l0, re);
    let reach = (re * scales.range().1 / grid.cell_size).ceil() as isize;
    walls
        .iter()
        .map(|wall| {
            let mut points = surface_points(wall, l0);
            points.par_iter_mut().for_each(|s| {
                let c = (gravity - wall.state.point_acceleration(s.point)) * rho;
                let (mut sw, mut swp) = (0.0, 0.0);
                grid.for_each_near(s.point, reach, |j| {
                    let r = s.point - x[j];
                    let d = r.norm();
                    let sj = scales.of(j);
                    if d >= re * sj || r.dot(&s.normal) > 0.0 {
                        return; // out of reach, or behind the surface
                    }
                    let wj = w(d / sj);
                    sw += wj;
                    swp += wj * (p[j] + c.dot(&r));
                });
                s.pressure = (swp / sw.max(floor)).max(0.0);
            });
            points
        })
        .collect()
}

/// Force and moment (about each object's centre of mass) of the surface pressure on
/// every wall object: F = -∫ p n ds.
pub fn pressure_loads(
    walls: &[PlacedWall],
    surfaces: &[Vec<SurfacePressure>],
) -> Vec<(Vec2, Real)> {
    walls
        .iter()
        .zip(surfaces)
        .map(|(wall, points)| {
            let com = wall.state.center_of_mass;
            points
                .iter() // summed in order: the same bits on any number of threads
                .map(|s| {
                    let f = -s.normal * (s.pressure * s.length);
                    (f, moment_about(com, s.point, f))
                })
                .fold((Vec2::zeros(), 0.0), |a, b| (a.0 + b.0, a.1 + b.1))
        })
        .collect()
}
