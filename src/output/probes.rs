//! Pressure probes and gauges.
//!
//! A probe fixed in the world reads the MPS weighted average of particle pressures
//! around its point, p = Σ w(|x_j - x|) p_j / Σ w (kernel of the scheme at r_e; with
//! multi-resolution each particle at its own radius, w(d; r_e s_j) = w(d/s_j; r_e)).
//! A gauge on a body reads the pressure the load integral puts on the body's surface
//! there ([`Simulation::surface_pressure`]), interpolated linearly between the
//! integral's points along its face and averaged over its diameter.

use crate::case::Case;
use crate::engine::kernel::weight;
use crate::engine::walls::pressure_load::SurfacePressure;
use crate::engine::Simulation;
use crate::geometry::closest_on_segment;
use crate::math::{vec2, Real, Vec2};

#[derive(Debug, Clone)]
pub struct ProbePoint {
    pub name: String,
    pub place: Place,
}

/// Where a probe reads.
#[derive(Debug, Clone, PartialEq)]
pub enum Place {
    /// A point fixed in the world.
    World(Vec2),
    /// A point on a wall object's surface: `segment` of `sim.walls[wall]`, `along` metres
    /// from its first end, averaged over `diameter` metres of the segment (0: a point).
    Surface {
        wall: usize,
        segment: u32,
        along: Real,
        diameter: Real,
    },
}

impl Place {
    /// The surface point of `sim.walls[wall]` nearest to `position` (in the object's
    /// frame), as a gauge place.
    pub fn on_surface(sim: &Simulation, wall: usize, position: Vec2, diameter: Real) -> Self {
        let surface = &sim.walls[wall].shape.surface;
        let (segment, along, _) = surface
            .iter()
            .enumerate()
            .filter(|(_, [a, b])| a != b)
            .map(|(k, [a, b])| {
                let q = closest_on_segment(position, *a, *b);
                (k as u32, (q - a).norm(), (q - position).norm())
            })
            .fold((0, 0.0, Real::INFINITY), |best, c| {
                if c.2 < best.2 {
                    c
                } else {
                    best
                }
            });
        Self::Surface {
            wall,
            segment,
            along,
            diameter,
        }
    }
}

/// The case's probes, gauges placed on their bodies' surfaces.
pub fn points(case: &Case, sim: &Simulation) -> Vec<ProbePoint> {
    case.output
        .probes
        .iter()
        .map(|p| {
            let at = vec2(p.position);
            let place = match &p.body {
                None => Place::World(at),
                Some(name) => {
                    let body = case.bodies.iter().position(|b| &b.name == name);
                    let wall = sim
                        .walls
                        .iter()
                        .position(|w| w.body.is_some() && w.body == body)
                        .expect("validation checked that the gauge's body exists");
                    Place::on_surface(sim, wall, at, p.diameter.unwrap_or(0.0))
                }
            };
            ProbePoint {
                name: p.name.clone(),
                place,
            }
        })
        .collect()
}

/// Pressure at every probe now (a world probe with no particle within r_e reads 0: dry).
pub fn sample(sim: &Simulation, probes: &[ProbePoint]) -> Vec<Real> {
    probes
        .iter()
        .map(|probe| match probe.place {
            Place::World(at) => world_pressure(sim, at),
            Place::Surface {
                wall,
                segment,
                along,
                diameter,
            } => {
                let points = &sim.surface_pressure[wall];
                let first = points.partition_point(|s| s.segment < segment);
                let count = points[first..].partition_point(|s| s.segment == segment);
                gauge_pressure(&points[first..first + count], along, diameter)
            }
        })
        .collect()
}

fn world_pressure(sim: &Simulation, at: Vec2) -> Real {
    let re = sim.config.params.re;
    let kind = sim.config.method.kernel;
    let scales = sim.scales();
    let (mut sw, mut swp) = (0.0, 0.0);
    let particles = sim.particles.position.iter().zip(&sim.particles.pressure);
    for (j, (x, p)) in particles.enumerate() {
        let s = scales.of(j);
        let r = (x - at).norm() / s;
        if r < re {
            let w = weight(kind, r.max(0.05 * sim.config.params.l0), re);
            sw += w;
            swp += w * p;
        }
    }
    if sw > 0.0 {
        swp / sw
    } else {
        0.0
    }
}

/// The mean over [along - diameter/2, along + diameter/2] (clipped to the segment) of
/// the pressure interpolated linearly between one segment's points, held constant
/// beyond the first and last point; the value at `along` for a zero diameter.
pub fn gauge_pressure(points: &[SurfacePressure], along: Real, diameter: Real) -> Real {
    let Some(last) = points.last() else {
        return 0.0; // before the first step
    };
    let length = last.along + 0.5 * last.length;
    let (a, b) = (
        (along - 0.5 * diameter).max(0.0),
        (along + 0.5 * diameter).min(length),
    );
    if b - a <= 1e-12 * length {
        return profile_at(points, along.clamp(0.0, length));
    }
    // exact integral of the piecewise-linear profile: split [a, b] at the points
    let mut knots: Vec<Real> = vec![a];
    knots.extend(points.iter().map(|s| s.along).filter(|&s| s > a && s < b));
    knots.push(b);
    let integral: Real = knots
        .windows(2)
        .map(|k| 0.5 * (profile_at(points, k[0]) + profile_at(points, k[1])) * (k[1] - k[0]))
        .sum();
    integral / (b - a)
}

/// The pressure at `s` metres along the segment, linear between the points.
fn profile_at(points: &[SurfacePressure], s: Real) -> Real {
    let k = points.partition_point(|q| q.along <= s);
    if k == 0 {
        return points[0].pressure;
    }
    if k == points.len() {
        return points[k - 1].pressure;
    }
    let (l, r) = (&points[k - 1], &points[k]);
    let f = (s - l.along) / (r.along - l.along);
    l.pressure + f * (r.pressure - l.pressure)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn points(values: &[Real], ds: Real) -> Vec<SurfacePressure> {
        values
            .iter()
            .enumerate()
            .map(|(k, &p)| SurfacePressure {
                segment: 0,
                along: (k as Real + 0.5) * ds,
                length: ds,
                point: Vec2::zeros(),
                normal: Vec2::y(),
                pressure: p,
            })
            .collect()
    }

    #[test]
    fn a_point_gauge_interpolates_between_the_points() {
        let pts = points(&[0.0, 10.0, 20.0, 40.0], 1.0);
        assert_eq!(gauge_pressure(&pts, 1.5, 0.0), 10.0);
        assert!((gauge_pressure(&pts, 2.0, 0.0) - 15.0).abs() < 1e-12);
        // beyond the first and last point the end values hold
        assert_eq!(gauge_pressure(&pts, 0.2, 0.0), 0.0);
        assert_eq!(gauge_pressure(&pts, 3.9, 0.0), 40.0);
    }

    #[test]
    fn a_gauge_averages_a_linear_profile_to_its_centre_value() {
        // p = 10 s on a segment 8 long: any window inside the points averages to p(centre)
        let values: Vec<Real> = (0..8).map(|k| 10.0 * (k as Real + 0.5)).collect();
        let pts = points(&values, 1.0);
        for (at, d) in [(3.0, 2.0), (4.2, 0.7), (2.0, 3.0)] {
            assert!(
                (gauge_pressure(&pts, at, d) - 10.0 * at).abs() < 1e-9,
                "{at} {d}"
            );
        }
        // clipped at the segment's end: [6, 8] holds 60..75 then 75
        let clipped = gauge_pressure(&pts, 7.5, 3.0);
        let exact = ((75.0 * 75.0 - 60.0 * 60.0) / 20.0 + 75.0 * 0.5) / 2.0;
        assert!((clipped - exact).abs() < 1e-9, "{clipped} vs {exact}");
    }

    #[test]
    fn a_gauge_reads_the_mean_of_a_step() {
        // a step profile 0 | 100 between points 1 and 2: over [1, 3] the mean is the
        // trapezoid's 50 over [1.5, 2.5] plus the flat parts
        let pts = points(&[0.0, 0.0, 100.0, 100.0], 1.0);
        let mean = gauge_pressure(&pts, 2.0, 2.0);
        assert!((mean - 50.0).abs() < 1e-9, "{mean}");
    }
}
