//! Polygon walls without wall particles.
//!
//! For a fluid particle i within r_e of a wall object, the wall stands for a virtual
//! lattice of spacing l0 filling the solid: rows parallel to the nearest surface
//! point's tangent, at (m + 1/2) l0 behind the surface, one column through the
//! particle's projection (Harada et al. 2008's table is this sum for a flat wall).
//! Each virtual point carries a weight `frac` in [0, 1], the share of its l0 × l0 cell
//! inside the solid, so the lattice is clipped smoothly by the real geometry: at a
//! wedge apex the lattice is cut by the other face, in a concave tank corner it fills
//! 270°. Every wall operation (number density, its gradient, the gradient-operator
//! moments, the Laplacian moments, the neighbour count) is one sum over these points
//! ([`WallTerms`]), computed exactly per particle instead of from a flat-wall table.
//!
//! Virtual pressures are extrapolated from the particle (Neumann condition), so the
//! wall adds no unknowns to the pressure equation; see `pressure`.

pub mod pressure_load;

use crate::engine::operators::VirtualPoints;
use crate::engine::resolution::Scales;
use crate::geometry::{closest_on_segment, inside, signed_distance, WallShape};
use crate::math::{cross, perp, Mat2, Real, Vec2};
use rayon::prelude::*;

/// Rigid motion state of a wall object (fixed walls: all zero).
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct WallState {
    /// World position of the object frame's origin.
    pub position: Vec2,
    pub angle: Real,
    pub velocity: Vec2,
    pub angular_velocity: Real,
    pub acceleration: Vec2,
    pub angular_acceleration: Real,
    /// World position of the centre of mass (moments are taken about it).
    pub center_of_mass: Vec2,
}

impl WallState {
    /// Velocity of the material point at world position `x`.
    #[inline]
    pub fn point_velocity(&self, x: Vec2) -> Vec2 {
        let r = x - self.center_of_mass;
        self.velocity + perp(r) * self.angular_velocity
    }

    /// Acceleration of the material point at world position `x`.
    #[inline]
    pub fn point_acceleration(&self, x: Vec2) -> Vec2 {
        let r = x - self.center_of_mass;
        self.acceleration + perp(r) * self.angular_acceleration - r * self.angular_velocity.powi(2)
    }

    /// This state advanced by `dt` at constant velocity (the predicted pose).
    pub fn advanced(&self, dt: Real) -> Self {
        Self {
            position: self.position + self.velocity * dt,
            center_of_mass: self.center_of_mass + self.velocity * dt,
            angle: self.angle + self.angular_velocity * dt,
            ..*self
        }
    }
}

/// A named wall: a fixed polyline or a rigid body's polygon.
#[derive(Debug, Clone)]
pub struct WallObject {
    pub name: String,
    /// Index into the case's `bodies`, or `None` for a fixed wall.
    pub body: Option<usize>,
    /// Shape in the object frame.
    pub shape: WallShape,
    pub state: WallState,
    /// The viscous term mirrors only the normal velocity (a symmetry plane).
    pub free_slip: bool,
}

/// A wall object placed in the world for one step.
#[derive(Debug, Clone)]
pub struct PlacedWall {
    pub surface: Vec<[Vec2; 2]>,
    pub loop_edges: Vec<[Vec2; 2]>,
    pub state: WallState,
    /// Axis-aligned bounds of the surface, for quick rejection.
    pub lo: Vec2,
    pub hi: Vec2,
}

impl PlacedWall {
    pub fn new(object: &WallObject, state: WallState) -> Self {
        let shape = object.shape.transformed(state.position, state.angle);
        let mut lo = Vec2::repeat(Real::INFINITY);
        let mut hi = Vec2::repeat(Real::NEG_INFINITY);
        for [a, b] in &shape.surface {
            lo = lo.inf(a).inf(b);
            hi = hi.sup(a).sup(b);
        }
        Self {
            loop_edges: shape.loop_edges(),
            surface: shape.surface,
            state,
            lo,
            hi,
        }
    }

    /// Nearest surface point to `p` if closer than `reach`.
    #[inline]
    pub fn nearest(&self, p: Vec2, reach: Real) -> Option<(Vec2, Real)> {
        if p.x < self.lo.x - reach
            || p.y < self.lo.y - reach
            || p.x > self.hi.x + reach
            || p.y > self.hi.y + reach
        {
            return None;
        }
        let mut best: Option<(Vec2, Real)> = None;
        // a segment whose box, widened by the reach (and a margin for round-off), misses
        // p is farther than the reach: most particles of a tank meet one segment or none
        let margin = reach * (1.0 + 1e-9);
        for [a, b] in &self.surface {
            if p.x < a.x.min(b.x) - margin
                || p.x > a.x.max(b.x) + margin
                || p.y < a.y.min(b.y) - margin
                || p.y > a.y.max(b.y) + margin
            {
                continue;
            }
            let c = closest_on_segment(p, *a, *b);
            let d = (c - p).norm();
            if d < reach && best.is_none_or(|(_, bd)| d < bd) {
                best = Some((c, d));
            }
        }
        best
    }
}

/// Kernel radii and the weights the wall sums need (see `Simulation`).
#[derive(Debug, Clone, Copy)]
pub struct WallKernels {
    pub l0: Real,
    /// Radius of number density, gradient and source.
    pub re: Real,
    /// Radius of the Laplacian.
    pub re_lap: Real,
}

/// Sums over the virtual lattice behind one wall object, seen from one particle.
/// `r` below is x_k - x_i (from the particle to the virtual point).
#[derive(Debug, Clone, Copy, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct WallTerms {
    /// Σ w(r): the wall's share of the particle number density.
    pub number_density: Real,
    /// ∇_i Σ w = -Σ w'(r) r/|r|: how n changes when the particle moves relative to the wall.
    pub number_density_gradient: Vec2,
    /// Σ w r/|r|²: gradient moment of order 1.
    pub moment1: Vec2,
    /// Σ w r rᵀ/|r|²: gradient moment of order 2 (xx, xy, yy).
    pub moment2: [Real; 3],
    /// Σ L(r): Laplacian weight sum.
    pub laplacian_sum: Real,
    /// Σ L(r) r: Laplacian first moment (for extrapolated virtual values).
    pub laplacian_moment: Vec2,
    /// Σ [|r| < r_e] frac: virtual neighbour count.
    pub count: Real,
}

impl WallTerms {
    pub fn add(&mut self, o: &WallTerms) {
        self.number_density += o.number_density;
        self.number_density_gradient += o.number_density_gradient;
        self.moment1 += o.moment1;
        for k in 0..3 {
            self.moment2[k] += o.moment2[k];
        }
        self.laplacian_sum += o.laplacian_sum;
        self.laplacian_moment += o.laplacian_moment;
        self.count += o.count;
    }

    /// moment2 applied to a vector.
    #[inline]
    pub fn moment2_times(&self, v: Vec2) -> Vec2 {
        let [xx, xy, yy] = self.moment2;
        Vec2::new(xx * v.x + xy * v.y, xy * v.x + yy * v.y)
    }
}

/// One (particle, wall object) interaction of a step.
#[derive(Debug, Clone, Copy, serde::Serialize, serde::Deserialize)]
pub struct WallContact {
    pub object: u32,
    /// Nearest surface point.
    pub point: Vec2,
    /// Unit normal from the wall into the fluid (towards the particle).
    pub normal: Vec2,
    /// Distance from the surface (0 when the particle has penetrated).
    pub distance: Real,
    /// The particle is inside the solid.
    pub penetrated: bool,
    /// Velocity and acceleration of the wall at `point`.
    pub wall_velocity: Vec2,
    pub wall_acceleration: Vec2,
    pub terms: WallTerms,
}

/// Weight functions the lattice sum evaluates.
pub trait WallWeights: Sync {
    fn w(&self, r: Real) -> Real;
    fn dw(&self, r: Real) -> Real;
    fn lap(&self, r: Real) -> Real;
}

/// The virtual-lattice sums of a particle at `x` of spacing `scale` l0 (1 but with
/// multi-resolution) against one placed wall, given its nearest surface point `xw`. The
/// virtual lattice has the particle's own spacing and radii; w(r; s r_e) = w(r/s; r_e).
pub fn wall_terms(
    x: Vec2,
    xw: Vec2,
    wall: &PlacedWall,
    k: &WallKernels,
    weights: &dyn WallWeights,
    scale: Real,
) -> (WallTerms, Vec2, bool) {
    let s = scale;
    let l0 = k.l0 * s;
    let (re, re_lap) = (k.re * s, k.re_lap * s);
    let penetrated = inside(x, &wall.loop_edges);
    let mut n = x - xw;
    let d = n.norm();
    if d > 1e-12 * l0 {
        n /= d;
        if penetrated {
            n = -n;
        }
    } else {
        // On the surface: take the normal of the nearest segment, pointing out of the solid.
        let mut best = (Real::INFINITY, Vec2::new(0.0, 1.0));
        for [a, b] in &wall.surface {
            let c = closest_on_segment(x, *a, *b);
            let dd = (c - x).norm();
            if dd < best.0 {
                best = (dd, perp(b - a).normalize());
            }
        }
        n = best.1;
        if inside(x + n * (0.01 * l0), &wall.loop_edges) {
            n = -n;
        }
    }
    // Nearest point on a vertex (outside a convex corner): align the lattice with the
    // adjacent face the particle stands most in front of, anchored on that face's line,
    // so the virtual rows continue the fluid lattice of that face (a radial lattice
    // would be turned 45° at a box corner: +3.8% n).
    let (mut xw, mut n) = (xw, n);
    if !penetrated && d > 1e-12 * l0 {
        let mut best: Option<(Real, Vec2, Vec2)> = None;
        for [a, b] in &wall.surface {
            let at_vertex = (xw - a).norm() < 1e-9 * l0 || (xw - b).norm() < 1e-9 * l0;
            if !at_vertex {
                continue;
            }
            let mut face_n = perp(b - a).normalize();
            if inside((a + b) * 0.5 + face_n * (0.01 * l0), &wall.loop_edges) {
                face_n = -face_n;
            }
            let height = (x - a).dot(&face_n);
            if height > 0.0 && best.is_none_or(|(h, _, _)| height > h) {
                best = Some((height, face_n, x - face_n * height));
            }
        }
        if let Some((_, face_n, foot)) = best {
            n = face_n;
            xw = foot;
        }
    }
    // A penetrated particle is evaluated as if it were just outside the surface.
    let xe = if penetrated || d < 0.05 * l0 {
        xw + n * (0.05 * l0)
    } else {
        x
    };
    let de = (xe - xw).norm();
    let t = perp(n);
    let reach = re.max(re_lap);
    let reach2 = reach * reach;
    let na = (reach / l0).ceil() as i32;
    let rows_behind = ((reach - de) / l0).ceil() as i32 + 1;
    let rows_front = ((reach + de) / l0).ceil() as i32;
    let mut terms = WallTerms::default();
    for b in -rows_front..=rows_behind {
        // depth of the row behind the surface: (b + 1/2) l0
        let depth = (b as Real + 0.5) * l0;
        for a in -na..=na {
            let p = xw + t * (a as Real * l0) - n * depth;
            let r = p - xe;
            let r2 = r.norm_squared();
            if r2 >= reach2 {
                continue;
            }
            // Rows behind the nearest point are inside the solid unless the geometry
            // turns away (apex): measure. Rows in front are solid only in concave corners.
            let depth_out = signed_distance(p, &wall.loop_edges);
            let frac = (0.5 + depth_out / l0).clamp(0.0, 1.0);
            if frac <= 0.0 {
                continue;
            }
            let rn = r2.sqrt().max(0.3 * l0);
            let w = weights.w(rn / s);
            if rn < re {
                terms.number_density += frac * w;
                terms.number_density_gradient -= r * (frac * (weights.dw(rn / s) / s) / rn);
                terms.moment1 += r * (frac * w / (rn * rn));
                let c = frac * w / (rn * rn);
                terms.moment2[0] += c * r.x * r.x;
                terms.moment2[1] += c * r.x * r.y;
                terms.moment2[2] += c * r.y * r.y;
                terms.count += frac;
            }
            if rn < re_lap {
                let l = frac * (weights.lap(rn / s) / (s * s));
                terms.laplacian_sum += l;
                terms.laplacian_moment += r * l;
            }
        }
    }
    (terms, n, penetrated)
}

/// Wall contacts of every particle, in CSR form (`offsets[i]..offsets[i+1]`).
#[derive(Debug, Clone, Default, serde::Serialize, serde::Deserialize)]
pub struct WallContacts {
    pub offsets: Vec<u32>,
    pub contacts: Vec<WallContact>,
}

impl WallContacts {
    #[inline]
    pub fn of(&self, i: usize) -> &[WallContact] {
        &self.contacts[self.offsets[i] as usize..self.offsets[i + 1] as usize]
    }

    /// n_i: the fluid part `fluid` plus every wall's share Σ Z (Harada et al. 2008).
    #[inline]
    pub fn number_density(&self, i: usize, fluid: Real) -> Real {
        fluid
            + self
                .of(i)
                .iter()
                .map(|c| c.terms.number_density)
                .sum::<Real>()
    }

    /// n_i after the particle moved by `dx` from where the contacts were found: each
    /// wall's share carried to first order, Z + ∇Z·dx, and kept non-negative.
    #[inline]
    pub fn number_density_moved(&self, i: usize, fluid: Real, dx: Vec2) -> Real {
        let mut n = fluid;
        for c in self.of(i) {
            n += (c.terms.number_density + c.terms.number_density_gradient.dot(&dx)).max(0.0);
        }
        n
    }

    /// `div` (particle i's fluid divergence) with the walls' share added, -c ∇Z · (u_i -
    /// u_w): the virtual points move with the wall.
    #[inline]
    pub fn with_divergence(&self, i: usize, mut div: Real, u_i: Vec2, c: Real) -> Real {
        for ct in self.of(i) {
            div -= c * ct
                .terms
                .number_density_gradient
                .dot(&(u_i - ct.wall_velocity));
        }
        div
    }

    /// The walls' share of the viscous Laplacian of particle i with velocity `u_i`,
    /// before the Laplacian coefficient: Σ (u_m - u_i) Σ L over its contacts, with the
    /// mirror velocity u_m = 2 u_w - u_i (no slip), or with only the normal component
    /// mirrored on a wall object whose `free_slip[object]` is set, so that the wall
    /// exerts no shear.
    #[inline]
    pub fn viscous_mirror(&self, i: usize, u_i: Vec2, free_slip: &[bool]) -> Vec2 {
        let mut wall = Vec2::zeros();
        for ct in self.of(i) {
            let relative = ct.wall_velocity - u_i;
            let mirrored = if free_slip[ct.object as usize] {
                ct.normal * relative.dot(&ct.normal)
            } else {
                relative
            };
            wall += mirrored * (2.0 * ct.terms.laplacian_sum);
        }
        wall
    }

    /// Each wall's virtual points for the pressure gradient of particle i, with the
    /// extrapolation gradient `neumann` of each of its contacts (p_k = p_i + c·r_ik).
    #[inline]
    pub fn virtual_points<'a>(
        &'a self,
        i: usize,
        neumann: &'a [Vec2],
    ) -> impl Iterator<Item = VirtualPoints> + 'a {
        let base = self.offsets[i] as usize;
        self.of(i).iter().enumerate().map(move |(k, c)| {
            let [xx, xy, yy] = c.terms.moment2;
            VirtualPoints {
                linear: c.terms.moment2_times(neumann[base + k]),
                moment1: c.terms.moment1,
                moment2: Mat2::new(xx, xy, xy, yy),
            }
        })
    }

    /// Each wall's Laplacian terms for particle i's pressure row: (c·Σ L r, Σ L r) with
    /// the extrapolation gradient c of the contact. The virtual pressures p_i + c·r add
    /// the first to the right-hand side and nothing to the matrix.
    #[inline]
    pub fn laplacian_terms<'a>(
        &'a self,
        i: usize,
        neumann: &'a [Vec2],
    ) -> impl Iterator<Item = (Real, Vec2)> + 'a {
        let base = self.offsets[i] as usize;
        self.of(i).iter().enumerate().map(move |(k, c)| {
            (
                neumann[base + k].dot(&c.terms.laplacian_moment),
                c.terms.laplacian_moment,
            )
        })
    }

    /// Sum of the wall terms of particle i over all objects.
    #[inline]
    pub fn total(&self, i: usize) -> WallTerms {
        let mut t = WallTerms::default();
        for c in self.of(i) {
            t.add(&c.terms);
        }
        t
    }

    /// Find every (particle, wall) pair within the largest kernel radius (of the
    /// particle's spacing) and sum its terms.
    pub fn build(
        positions: &[Vec2],
        walls: &[PlacedWall],
        k: &WallKernels,
        weights: &dyn WallWeights,
        scales: Scales,
    ) -> Self {
        const CHUNK: usize = 1024;
        let n = positions.len();
        let reach = k.re.max(k.re_lap);
        if walls.is_empty() {
            return Self {
                offsets: vec![0; n + 1],
                contacts: Vec::new(),
            };
        }
        let chunks: Vec<(Vec<u32>, Vec<WallContact>)> = (0..n.div_ceil(CHUNK))
            .into_par_iter()
            .map(|c| {
                let mut counts = Vec::with_capacity(CHUNK);
                let mut out = Vec::new();
                for i in c * CHUNK..((c + 1) * CHUNK).min(n) {
                    let x = positions[i];
                    let s = scales.of(i);
                    let before = out.len();
                    for (o, wall) in walls.iter().enumerate() {
                        let Some((xw, d)) = wall.nearest(x, reach * s) else {
                            continue;
                        };
                        let (terms, normal, penetrated) = wall_terms(x, xw, wall, k, weights, s);
                        out.push(WallContact {
                            object: o as u32,
                            point: xw,
                            normal,
                            distance: if penetrated { 0.0 } else { d },
                            penetrated,
                            wall_velocity: wall.state.point_velocity(xw),
                            wall_acceleration: wall.state.point_acceleration(xw),
                            terms,
                        });
                    }
                    counts.push((out.len() - before) as u32);
                }
                (counts, out)
            })
            .collect();
        let mut offsets = Vec::with_capacity(n + 1);
        offsets.push(0u32);
        let mut contacts = Vec::new();
        for (counts, out) in chunks {
            for cnt in counts {
                offsets.push(offsets.last().unwrap() + cnt);
            }
            contacts.extend(out);
        }
        Self { offsets, contacts }
    }
}

/// Moment (z) of force `f` applied at `x` about `center`.
#[inline]
pub fn moment_about(center: Vec2, x: Vec2, f: Vec2) -> Real {
    cross(x - center, f)
}
