//! The similarity solution of a symmetric wedge entering calm water at constant speed V
//! (no gravity, inviscid, incompressible, 2D): the solver behind the tables of
//! `mpsfsi::analysis::similarity`.
//!
//! Scaled variables: ξ = x/(Vt), η = y/(Vt), r = (ξ, η), φ = V² t Φ(ξ, η, τ) with
//! τ = ln t. The keel is at (0, −1), the undisturbed surface at η = 0, the face on
//! η = −1 + ξ tan β. On the free surface p = 0 reads Φ_τ = −Φ + r·∇Φ − ½|∇Φ|², and the
//! surface moves with the normal part of the relative velocity ∇Φ − r. A steady state in
//! τ is the similarity solution; on the face its pressure is
//! Cp = p / (½ρV²) = −2 (Φ − r·∇Φ + ½|∇Φ|²), and the vertical force of both faces is
//! C_F = F / (ρV³t) = ∫ Cp dξ over one face.
//!
//! Method (after Zhao & Faltinsen 1993, in scaled variables):
//! - Laplace's equation on the half domain ξ ≥ 0 by boundary elements: linear elements,
//!   collocation at the nodes, exact integrals near the node (two Gauss points from three
//!   element lengths on), the mirror image about ξ = 0 in the Green function. Face:
//!   ∂Φ/∂n = −cos β; free surface: Φ given; a far arc of radius `radius` c_W with the
//!   dipole condition ∂Φ/∂r = −Φ/r.
//! - The jet along the face is cut where it gets thinner than `cut` δ_W: a segment normal
//!   to the face closes it, across which the jet moves as the face does (∂Φ/∂d = cos β),
//!   and its flux leaves there.
//! - The free-surface nodes move with the relative velocity within 0.3 `radius` c_W of the
//!   keel and with its normal part only beyond 0.6 `radius` c_W (RK4, Courant number
//!   `cfl`), and are redistributed along a cubic spline after every step: `fine` δ_W at
//!   the jet root, growing by `growth` per unit length away from it, no longer than the
//!   jet's thickness in the jet.
//! - The march starts from Wagner's surface η = (ξ/c) asin(c/ξ) − 1 with a jet along the
//!   face and the potential that satisfies the dynamic condition on it, and runs to τ =
//!   `tau`, where Cp_max and C_F have settled to 1e-4 (at 15°, C_F moves by 0.07 %
//!   between τ = 3 and 4).
//!
//! Here c_W = π / (2 tan β) is Wagner's half-width and δ_W = tan β / 4 the thickness of
//! Wagner's jet root.
//!
//! `cargo run --release --example similarity -- --deadrise 30 [--check] [--fine F]
//! [--growth G] [--radius R] [--cut C] [--face-slope S] [--face-cap H] [--tau T]
//! [--cfl C]` prints Cp_max, z_max/(Vt), C_F, the added mass of the body's acceleration
//! on the converged geometry and the table of (z/(Vt), Cp) along the face,
//! in the form `analysis::similarity` stores; `--check` compares them with the stored
//! table and exits with status 1 where they differ.

use faer::prelude::Solve;
use rayon::prelude::*;
use std::f64::consts::PI;

type P = [f64; 2];

fn sub(a: P, b: P) -> P {
    [a[0] - b[0], a[1] - b[1]]
}
fn add(a: P, b: P) -> P {
    [a[0] + b[0], a[1] + b[1]]
}
fn scale(a: P, k: f64) -> P {
    [a[0] * k, a[1] * k]
}
fn dot(a: P, b: P) -> f64 {
    a[0] * b[0] + a[1] * b[1]
}
fn norm(a: P) -> f64 {
    dot(a, a).sqrt()
}
/// The normal on the left of a tangent: out of the fluid, since the contour runs
/// clockwise around it (up the face, out along the free surface, down the far arc).
fn left(t: P) -> P {
    [-t[1], t[0]]
}

/// Numerical choices, lengths in Wagner's scales δ_W = tan β / 4 and c_W = π / (2 tan β).
#[derive(Clone, Copy, Debug)]
struct Params {
    /// free-surface element at the jet root, in δ_W
    fine: f64,
    /// growth of the free-surface element per unit distance from the jet root
    growth: f64,
    /// far-arc radius, in c_W
    radius: f64,
    /// the jet is cut where it is this thin, in δ_W
    cut: f64,
    /// face element: the free surface's element nearby plus this × the distance to it
    face_slope: f64,
    /// longest face element, in the face's submerged length 1 / sin β
    face_cap: f64,
    /// length of the march in τ = ln t
    tau: f64,
    /// Courant number of the march
    cfl: f64,
}

impl Default for Params {
    /// Halving `fine`, `growth`, `face_slope` or `cut`, or doubling `radius`, moves Cp_max
    /// at 30° by at most 0.02 % and C_F by 0.05 %; `fine` = 0.2 is unstable at the root.
    fn default() -> Self {
        Params {
            fine: 0.1,
            growth: 0.1,
            radius: 15.0,
            cut: 0.3,
            face_slope: 0.25,
            face_cap: 0.05,
            tau: 6.0,
            cfl: 0.4,
        }
    }
}

/// The face of the wedge and its scales.
#[derive(Clone, Copy, Debug)]
struct Wedge {
    deadrise_deg: f64,
    beta: f64,
    /// unit tangent up the face
    tangent: P,
    /// unit normal out of the fluid (into the wedge)
    normal: P,
    keel: P,
    /// ∂Φ/∂n on the face: the body's velocity (0, −1) along its normal
    flux: f64,
    delta_w: f64,
    c_w: f64,
}

impl Wedge {
    fn new(deadrise_deg: f64) -> Self {
        let beta = deadrise_deg.to_radians();
        let (s, c) = beta.sin_cos();
        Wedge {
            deadrise_deg,
            beta,
            tangent: [c, s],
            normal: [-s, c],
            keel: [0.0, -1.0],
            flux: -c,
            delta_w: beta.tan() / 4.0,
            c_w: PI / (2.0 * beta.tan()),
        }
    }
    /// Distance of a point from the face's line, positive in the fluid.
    fn thickness(&self, p: P) -> f64 {
        -dot(sub(p, self.keel), self.normal)
    }
    /// Arc length from the keel of a point's projection on the face.
    fn along(&self, p: P) -> f64 {
        dot(sub(p, self.keel), self.tangent)
    }
    fn point(&self, s: f64) -> P {
        add(self.keel, scale(self.tangent, s))
    }
}

/// A natural cubic spline through (s_i, y_i).
struct Spline {
    s: Vec<f64>,
    y: Vec<f64>,
    m: Vec<f64>,
}

impl Spline {
    fn new(s: &[f64], y: &[f64]) -> Self {
        let n = s.len();
        let mut m = vec![0.0; n];
        if n > 2 {
            // tridiagonal system for the second derivatives (Thomas), zero at the ends
            let mut diag = vec![0.0; n];
            let mut upper = vec![0.0; n];
            let mut rhs = vec![0.0; n];
            for i in 1..n - 1 {
                let (h0, h1) = (s[i] - s[i - 1], s[i + 1] - s[i]);
                diag[i] = (h0 + h1) / 3.0;
                upper[i] = h1 / 6.0;
                rhs[i] = (y[i + 1] - y[i]) / h1 - (y[i] - y[i - 1]) / h0;
            }
            for i in 2..n - 1 {
                let w = (s[i] - s[i - 1]) / 6.0 / diag[i - 1];
                diag[i] -= w * upper[i - 1];
                rhs[i] -= w * rhs[i - 1];
            }
            for i in (1..n - 1).rev() {
                m[i] = (rhs[i] - upper[i] * m[i + 1]) / diag[i];
            }
        }
        Spline {
            s: s.to_vec(),
            y: y.to_vec(),
            m,
        }
    }
    /// The interval's index and the weights (a, b) of its ends at x.
    fn locate(&self, x: f64) -> (usize, f64, f64, f64) {
        let n = self.s.len();
        let i = self.s.partition_point(|&v| v <= x).clamp(1, n - 1) - 1;
        let h = self.s[i + 1] - self.s[i];
        (i, h, (self.s[i + 1] - x) / h, (x - self.s[i]) / h)
    }
    fn eval(&self, x: f64) -> f64 {
        let (i, h, a, b) = self.locate(x);
        a * self.y[i]
            + b * self.y[i + 1]
            + ((a * a * a - a) * self.m[i] + (b * b * b - b) * self.m[i + 1]) * h * h / 6.0
    }
    fn deriv(&self, x: f64) -> f64 {
        let (i, h, a, b) = self.locate(x);
        (self.y[i + 1] - self.y[i]) / h
            + ((1.0 - 3.0 * a * a) * self.m[i] + (3.0 * b * b - 1.0) * self.m[i + 1]) * h / 6.0
    }
}

/// Points from s0 to s1 whose spacing follows h(s): at most h, as even as that allows.
/// ∫ ds/h is integrated in steps of h/4, fine enough for the spacings here, which change
/// by less than their own size over their own size.
fn graded(s0: f64, s1: f64, h: impl Fn(f64) -> f64) -> Vec<f64> {
    let mut s = vec![s0];
    let mut g = vec![0.0];
    let mut h_prev = h(s0);
    while s[s.len() - 1] < s1 {
        let a = s[s.len() - 1];
        let b = (a + 0.25 * h_prev).min(s1);
        let h_next = h(b);
        g.push(g[g.len() - 1] + 0.5 * (b - a) * (1.0 / h_prev + 1.0 / h_next));
        s.push(b);
        h_prev = h_next;
        assert!(
            s.len() < 10_000_000,
            "the grading is too fine on [{s0}, {s1}]"
        );
    }
    let total = g[g.len() - 1];
    let n = (total.ceil() as usize).max(1);
    let mut out = Vec::with_capacity(n + 1);
    let mut k = 0;
    for j in 0..=n {
        let target = total * j as f64 / n as f64;
        while k + 2 < g.len() && g[k + 1] < target {
            k += 1;
        }
        let w = ((target - g[k]) / (g[k + 1] - g[k])).clamp(0.0, 1.0);
        out.push(s[k] + w * (s[k + 1] - s[k]));
    }
    out[0] = s0;
    out[n] = s1;
    out
}

/// Second-order three-point derivative of f along a chain with arc lengths s.
fn derivative(s: &[f64], f: &[f64]) -> Vec<f64> {
    let n = s.len();
    (0..n)
        .map(|i| {
            let j = i.clamp(1, n - 2) - 1;
            let (a, b) = (s[j + 1] - s[j], s[j + 2] - s[j + 1]);
            // weights of f[j], f[j+1], f[j+2] at s[j], s[j+1] or s[j+2]
            let w = match i - j {
                0 => [
                    -(2.0 * a + b) / (a * (a + b)),
                    (a + b) / (a * b),
                    -a / (b * (a + b)),
                ],
                1 => [-b / (a * (a + b)), (b - a) / (a * b), a / (b * (a + b))],
                _ => [
                    b / (a * (a + b)),
                    -(a + b) / (a * b),
                    (a + 2.0 * b) / (b * (a + b)),
                ],
            };
            w[0] * f[j] + w[1] * f[j + 1] + w[2] * f[j + 2]
        })
        .collect()
}

fn chord_lengths(x: &[P]) -> Vec<f64> {
    let mut s = vec![0.0; x.len()];
    for i in 1..x.len() {
        s[i] = s[i - 1] + norm(sub(x[i], x[i - 1]));
    }
    s
}

/// ∫ over the straight element a→b of ∂(ln r)/∂n N_a, ∂(ln r)/∂n N_b, ln r N_a and
/// ln r N_b, r the distance from p, n the element's outward normal, N the linear shape
/// functions. `touching`: p is one of the element's ends.
fn element_integrals(p: P, a: P, b: P, touching: bool) -> [f64; 4] {
    let ab = sub(b, a);
    let l = norm(ab);
    let t = scale(ab, 1.0 / l);
    let mid = sub(scale(add(a, b), 0.5), p);
    if dot(mid, mid) > 9.0 * l * l {
        // three element lengths away, two Gauss points (relative error below 1e-5)
        let n = left(t);
        let mut out = [0.0; 4];
        for xi in [0.5 - 0.5 / 3f64.sqrt(), 0.5 + 0.5 / 3f64.sqrt()] {
            let r = sub(add(a, scale(ab, xi)), p);
            let r2 = dot(r, r);
            let (h, g) = (dot(r, n) / r2 * 0.5 * l, 0.25 * r2.ln() * l);
            out[0] += h * (1.0 - xi);
            out[1] += h * xi;
            out[2] += g * (1.0 - xi);
            out[3] += g * xi;
        }
        return out;
    }
    // exact: u along the element from the foot of p, d the distance off its line
    let ap = sub(p, a);
    let s0 = dot(ap, t);
    let d = if touching { 0.0 } else { dot(ap, left(t)) };
    let (u1, u2) = (-s0, l - s0);
    let (r1, r2) = (u1 * u1 + d * d, u2 * u2 + d * d);
    let xlog = |x: f64| if x > 0.0 { x * x.ln() } else { 0.0 };
    let ulog = |u: f64, r: f64| if r > 0.0 { u * r.ln() } else { 0.0 };
    let (theta, log_ratio) = if d != 0.0 {
        ((d * l).atan2(d * d + u1 * u2), (r2 / r1).ln())
    } else {
        (0.0, 0.0)
    };
    let i0 = 0.5 * (ulog(u2, r2) - ulog(u1, r1)) - l + d * theta;
    let iu = 0.25 * (xlog(r2) - r2 - xlog(r1) + r1);
    let g_b = (iu + s0 * i0) / l;
    let j0 = -theta;
    let h_b = (-0.5 * d * log_ratio + s0 * j0) / l;
    [j0 - h_b, h_b, i0 - g_b, g_b]
}

/// A node's potential or an element end's flux as `k` × the node's unknown + `c`.
#[derive(Clone, Copy, Debug)]
struct Affine {
    k: f64,
    c: f64,
}

impl Affine {
    const UNKNOWN: Affine = Affine { k: 1.0, c: 0.0 };
    fn known(c: f64) -> Self {
        Affine { k: 0.0, c }
    }
    fn at(&self, x: f64) -> f64 {
        self.k * x + self.c
    }
}

/// The free surface from the jet's cut (first node) to the far arc (last node).
#[derive(Clone, Debug)]
struct Surface {
    x: Vec<P>,
    phi: Vec<f64>,
}

/// The free surface's tangents, outward normals, ∂Φ/∂s and node spacing.
struct SurfaceFrame {
    tangent: Vec<P>,
    normal: Vec<P>,
    phi_s: Vec<f64>,
    spacing: Vec<f64>,
}

fn surface_frame(surface: &Surface) -> SurfaceFrame {
    let s = chord_lengths(&surface.x);
    let coordinate = |k: usize| surface.x.iter().map(|p| p[k]).collect::<Vec<_>>();
    let dx = derivative(&s, &coordinate(0));
    let dy = derivative(&s, &coordinate(1));
    let n = s.len();
    let tangent: Vec<P> = (0..n)
        .map(|i| scale([dx[i], dy[i]], 1.0 / dx[i].hypot(dy[i])))
        .collect();
    let spacing = (0..n)
        .map(|i| {
            let before = if i > 0 { s[i] - s[i - 1] } else { f64::MAX };
            let after = if i + 1 < n { s[i + 1] - s[i] } else { f64::MAX };
            before.min(after)
        })
        .collect();
    SurfaceFrame {
        normal: tangent.iter().map(|&t| left(t)).collect(),
        tangent,
        phi_s: derivative(&s, &surface.phi),
        spacing,
    }
}

/// The closed contour of the half domain (the mirror line is in the Green function):
/// keel, face up to the foot of the cut, the cut, the free surface, the far arc.
struct Contour {
    points: Vec<P>,
    potential: Vec<Affine>,
    /// flux at the start and end of element e (points e, e + 1)
    flux: Vec<[Affine; 2]>,
    /// index of the foot of the cut, the last face node
    face_end: usize,
    /// index of the first free-surface node
    surface_start: usize,
}

/// Face nodes (arc length from the keel) up to the foot of the cut: the free surface's
/// element nearby plus `face_slope` × the distance to it, at most `face_cap` / sin β.
fn face_nodes(wedge: &Wedge, surface: &Surface, frame: &SurfaceFrame, params: &Params) -> Vec<f64> {
    let cap = params.face_cap / wedge.beta.sin();
    graded(0.0, wedge.along(surface.x[0]), |s| {
        let p = wedge.point(s);
        surface
            .x
            .iter()
            .zip(&frame.spacing)
            .fold(cap, |h, (x, sp)| {
                h.min(sp + params.face_slope * norm(sub(p, *x)))
            })
    })
}

fn build_contour(wedge: &Wedge, surface: &Surface, frame: &SurfaceFrame, face: &[f64]) -> Contour {
    let mut points = Vec::new();
    let mut potential = Vec::new();
    let mut flux = Vec::new();
    let q = surface.x[0];
    let phi_q = surface.phi[0];
    // across the cut the jet moves as the face does: ∂Φ/∂d = cos β, d off the face
    let phi_foot = phi_q + wedge.flux * wedge.thickness(q);
    // face: Φ unknown, flux the body's; Φ at the foot of the cut from the jet
    for (k, &s) in face.iter().enumerate() {
        points.push(wedge.point(s));
        if k + 1 < face.len() {
            potential.push(Affine::UNKNOWN);
            flux.push([Affine::known(wedge.flux); 2]);
        } else {
            potential.push(Affine::known(phi_foot));
        }
    }
    let face_end = points.len() - 1;
    // cut: Φ given, flux unknown; at Q the cut's flux follows from the free surface's,
    // ∇Φ = q n + Φ_s t there
    let foot = points[face_end];
    let cut_len = norm(sub(q, foot));
    let m = ((cut_len / frame.spacing[0]).ceil() as usize).max(1);
    let cut_normal = left(scale(sub(q, foot), 1.0 / cut_len));
    let at_q = Affine {
        k: dot(frame.normal[0], cut_normal),
        c: frame.phi_s[0] * dot(frame.tangent[0], cut_normal),
    };
    for j in 1..m {
        let w = j as f64 / m as f64;
        points.push(add(foot, scale(sub(q, foot), w)));
        potential.push(Affine::known(phi_foot + (phi_q - phi_foot) * w));
    }
    for j in 0..m {
        flux.push([
            Affine::UNKNOWN,
            if j + 1 == m { at_q } else { Affine::UNKNOWN },
        ]);
    }
    // free surface: Φ given, flux unknown
    let surface_start = points.len();
    for (x, phi) in surface.x.iter().zip(&surface.phi) {
        points.push(*x);
        potential.push(Affine::known(*phi));
    }
    for _ in 1..surface.x.len() {
        flux.push([Affine::UNKNOWN; 2]);
    }
    // far arc: ∂Φ/∂r = −Φ/r
    let f = surface.x[surface.x.len() - 1];
    let phi_f = surface.phi[surface.phi.len() - 1];
    let radius = norm(f);
    let theta_f = f[1].atan2(f[0]);
    let h_far = frame.spacing[frame.spacing.len() - 1];
    let n_arc = (((theta_f + PI / 2.0) * radius / h_far).ceil() as usize).max(12);
    let dipole = Affine {
        k: -1.0 / radius,
        c: 0.0,
    };
    for j in 1..=n_arc {
        let th = theta_f - (theta_f + PI / 2.0) * j as f64 / n_arc as f64;
        points.push([radius * th.cos(), radius * th.sin()]);
        potential.push(Affine::UNKNOWN);
        let start = if j == 1 {
            Affine::known(-phi_f / radius)
        } else {
            dipole
        };
        flux.push([start, dipole]);
    }
    let last = points.len() - 1;
    points[last][0] = 0.0;
    Contour {
        points,
        potential,
        flux,
        face_end,
        surface_start,
    }
}

/// Collocation at every node i: Σ_e ∫_e (Φ − Φ_i) ∂G/∂n − G ∂Φ/∂n ds = 0 with
/// G = ln r + ln r' (r' from the mirror image of node i), the free term from the
/// constant-potential mode. Returns every node's unknown.
fn solve_contour(contour: &Contour) -> Vec<f64> {
    let n = contour.points.len();
    let pts = &contour.points;
    let rows: Vec<(Vec<f64>, f64)> = (0..n)
        .into_par_iter()
        .map(|i| {
            let mut row = vec![0.0; n];
            let mut rhs = 0.0;
            let p = pts[i];
            let image = [-p[0], p[1]];
            let on_image = |x: P| norm(sub(image, x)) < 1e-12;
            let pi = contour.potential[i];
            for e in 0..n - 1 {
                let (a, b) = (pts[e], pts[e + 1]);
                let direct = element_integrals(p, a, b, i == e || i == e + 1);
                let mirrored = element_integrals(image, a, b, on_image(a) || on_image(b));
                let [h_a, h_b, g_a, g_b] = std::array::from_fn(|k| direct[k] + mirrored[k]);
                let (pa, pb) = (contour.potential[e], contour.potential[e + 1]);
                let [qa, qb] = contour.flux[e];
                row[e] += h_a * pa.k - g_a * qa.k;
                row[e + 1] += h_b * pb.k - g_b * qb.k;
                row[i] -= (h_a + h_b) * pi.k;
                rhs -= h_a * pa.c + h_b * pb.c - (h_a + h_b) * pi.c - g_a * qa.c - g_b * qb.c;
            }
            (row, rhs)
        })
        .collect();
    let m = faer::Mat::<f64>::from_fn(n, n, |i, j| rows[i].0[j]);
    let rhs = faer::Mat::<f64>::from_fn(n, 1, |i, _| rows[i].1);
    let x = m.partial_piv_lu().solve(rhs.as_ref());
    (0..n).map(|i| x[(i, 0)]).collect()
}

/// The flow under a free surface: ∇Φ at its nodes, and Φ along the face.
struct Flow {
    frame: SurfaceFrame,
    velocity: Vec<P>,
    face_s: Vec<f64>,
    face_phi: Vec<f64>,
}

fn flow(wedge: &Wedge, surface: &Surface, params: &Params) -> Flow {
    let frame = surface_frame(surface);
    let face = face_nodes(wedge, surface, &frame, params);
    let contour = build_contour(wedge, surface, &frame, &face);
    let x = solve_contour(&contour);
    let velocity = (0..surface.x.len())
        .map(|i| {
            let q = x[contour.surface_start + i];
            add(
                scale(frame.normal[i], q),
                scale(frame.tangent[i], frame.phi_s[i]),
            )
        })
        .collect();
    let face_phi = (0..=contour.face_end)
        .map(|k| contour.potential[k].at(x[k]))
        .collect();
    Flow {
        frame,
        velocity,
        face_s: face,
        face_phi,
    }
}

/// Rates of the free-surface nodes in τ, and the step at Courant number 1.
fn rates(wedge: &Wedge, surface: &Surface, params: &Params) -> (Vec<P>, Vec<f64>, f64) {
    let radius = params.radius * wedge.c_w;
    let fl = flow(wedge, surface, params);
    let n = surface.x.len();
    let mut dx = Vec::with_capacity(n);
    let mut dphi = Vec::with_capacity(n);
    let mut dt_max = f64::MAX;
    for i in 0..n {
        let r = surface.x[i];
        let u = fl.velocity[i];
        let rel = sub(u, r);
        let (t, nn) = (fl.frame.tangent[i], fl.frame.normal[i]);
        // with the fluid near the body (the jet's end always), normal motion far out
        let lagrangian = if i == 0 {
            1.0
        } else {
            ((0.6 * radius - norm(r)) / (0.3 * radius)).clamp(0.0, 1.0)
        };
        let w = add(scale(nn, dot(rel, nn)), scale(t, lagrangian * dot(rel, t)));
        let phi_tau = -surface.phi[i] + dot(r, u) - 0.5 * dot(u, u);
        if i + 1 == n {
            // the relative flow enters at the far end: it keeps the far field's state
            // (Wagner's surface, Φ = 0, both within 1e-3 of the dipole's at 15 c_W)
            dx.push([0.0; 2]);
            dphi.push(0.0);
            continue;
        }
        dx.push(w);
        dphi.push(phi_tau + dot(w, u));
        dt_max = dt_max.min(fl.frame.spacing[i] / norm(w).max(1e-12));
    }
    (dx, dphi, dt_max)
}

fn advance(surface: &Surface, dx: &[P], dphi: &[f64], dt: f64, wedge: &Wedge) -> Surface {
    let mut out = surface.clone();
    for i in 0..out.x.len() {
        out.x[i] = add(out.x[i], scale(dx[i], dt));
        out.phi[i] += dphi[i] * dt;
    }
    // the jet's end stays on the fluid side of the face
    let t = wedge.thickness(out.x[0]);
    if t < 1e-6 {
        out.x[0] = add(out.x[0], scale(wedge.normal, t - 1e-6));
    }
    out
}

/// Free-surface spacing (in ξ units): `fine` δ_W within 2 δ_W of the jet root, growing by
/// `growth` per unit length beyond, in the jet no longer than its thickness.
struct Grading {
    h_min: f64,
    growth: f64,
    width: f64,
    cut: f64,
}

impl Grading {
    fn new(wedge: &Wedge, params: &Params) -> Self {
        Grading {
            h_min: params.fine * wedge.delta_w,
            growth: params.growth,
            width: 2.0 * wedge.delta_w,
            cut: params.cut * wedge.delta_w,
        }
    }
}

/// Cut the jet and redistribute the free-surface nodes along a spline through them.
fn regrid(wedge: &Wedge, surface: &Surface, grading: &Grading) -> Surface {
    let s = chord_lengths(&surface.x);
    let coordinate = |k: usize| surface.x.iter().map(|p| p[k]).collect::<Vec<_>>();
    let xs = Spline::new(&s, &coordinate(0));
    let ys = Spline::new(&s, &coordinate(1));
    let ps = Spline::new(&s, &surface.phi);
    let at = |v: f64| [xs.eval(v), ys.eval(v)];
    let thick = |v: f64| wedge.thickness(at(v));
    // the jet root: the leftmost node
    let k_root = (0..s.len())
        .min_by(|&a, &b| surface.x[a][0].total_cmp(&surface.x[b][0]))
        .unwrap_or(0);
    // the cut, going out from the root: where the jet gets thinner than the cut; or, within
    // its last six nodes, where it thickens again by 10 % once thinner than twice the cut
    // (it tapers to its tip, so that is a blob left at the cut, removed before it can fold
    // over)
    let mut start = 0.0;
    if let Some(k) = (0..k_root).rev().find(|&k| thick(s[k]) < grading.cut) {
        let (mut lo, mut hi) = (s[k], s[k + 1]);
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            if thick(mid) < grading.cut {
                lo = mid;
            } else {
                hi = mid;
            }
        }
        start = hi;
    } else {
        let end = 6.min(k_root);
        if let Some(j) = (1..end).min_by(|&a, &b| thick(s[a]).total_cmp(&thick(s[b]))) {
            let t_min = thick(s[j]);
            if t_min < 2.0 * grading.cut && (0..j).any(|k| thick(s[k]) > 1.1 * t_min) {
                start = s[j];
            }
        }
    }
    let root = s[k_root].max(start);
    let h = |v: f64| {
        let from_root = (v - root).abs() - grading.width;
        let h = grading.h_min + grading.growth * from_root.max(0.0);
        if v < root {
            h.min(thick(v).max(grading.h_min))
        } else {
            h
        }
    };
    let nodes = graded(start, s[s.len() - 1], h);
    Surface {
        x: nodes.iter().map(|&v| at(v)).collect(),
        phi: nodes.iter().map(|&v| ps.eval(v)).collect(),
    }
}

/// Wagner's outer surface η = (ξ/c) asin(c/ξ) − 1 (c = c_W), from where it is three cuts
/// off the face, joined by the spline to a jet along the face 0.3 c_W long and 2 to 1.05
/// cuts thick; the potential makes the dynamic condition hold on that shape,
/// (Φ_s − r·t)² = |r|² − 2Φ with the relative flow running towards the jet, integrated
/// inwards from Φ = 0 at the far end.
fn wagner_start(wedge: &Wedge, params: &Params, grading: &Grading) -> Surface {
    let c = wedge.c_w;
    let radius = params.radius * c;
    let outer = |x: f64| -> P { [x, (x / c) * (c / x).asin() - 1.0] };
    let mut x_a = 1.5 * c;
    for _ in 0..60 {
        let mid = 0.5 * (c + x_a);
        if wedge.thickness(outer(mid)) > 3.0 * grading.cut {
            x_a = mid;
        }
    }
    let s_a = wedge.along(outer(x_a));
    let jet_top = s_a + 0.3 * c;
    let n_jet = 20;
    let n_outer = 200;
    let jet = (0..n_jet).map(|k| {
        let w = k as f64 / n_jet as f64;
        let s = jet_top + (s_a - jet_top) * w;
        add(
            wedge.point(s),
            scale(wedge.normal, -grading.cut * (1.05 + 0.95 * w)),
        )
    });
    let out = (0..=n_outer).map(|k| outer(x_a * (radius / x_a).powf(k as f64 / n_outer as f64)));
    let x: Vec<P> = jet.chain(out).collect();
    let coarse = Surface {
        phi: vec![0.0; x.len()],
        x,
    };
    let mut surface = regrid(wedge, &coarse, grading);
    let n = surface.x.len();
    let sl = chord_lengths(&surface.x);
    surface.phi[n - 1] = 0.0;
    for i in (0..n - 1).rev() {
        let (p0, p1) = (surface.x[i], surface.x[i + 1]);
        let t = scale(sub(p1, p0), 1.0 / (sl[i + 1] - sl[i]));
        let sub_steps = 20;
        let h = (sl[i + 1] - sl[i]) / sub_steps as f64;
        let mut phi = surface.phi[i + 1];
        for k in 0..sub_steps {
            let r = add(p1, scale(t, -h * (k as f64 + 0.5)));
            phi -= h * (dot(r, t) - (dot(r, r) - 2.0 * phi).max(0.0).sqrt());
        }
        surface.phi[i] = phi;
    }
    surface
}

/// One RK4 step of the march and the regrid; returns the step taken.
fn march_step(wedge: &Wedge, surface: &mut Surface, params: &Params, grading: &Grading) -> f64 {
    let (k1x, k1p, dt_max) = rates(wedge, surface, params);
    let dt = (params.cfl * dt_max).min(0.05);
    let (k2x, k2p, _) = rates(
        wedge,
        &advance(surface, &k1x, &k1p, 0.5 * dt, wedge),
        params,
    );
    let (k3x, k3p, _) = rates(
        wedge,
        &advance(surface, &k2x, &k2p, 0.5 * dt, wedge),
        params,
    );
    let (k4x, k4p, _) = rates(wedge, &advance(surface, &k3x, &k3p, dt, wedge), params);
    let n = surface.x.len();
    let dx: Vec<P> = (0..n)
        .map(|i| {
            scale(
                add(add(k1x[i], scale(add(k2x[i], k3x[i]), 2.0)), k4x[i]),
                1.0 / 6.0,
            )
        })
        .collect();
    let dp: Vec<f64> = (0..n)
        .map(|i| (k1p[i] + 2.0 * (k2p[i] + k3p[i]) + k4p[i]) / 6.0)
        .collect();
    *surface = regrid(wedge, &advance(surface, &dx, &dp, dt, wedge), grading);
    dt
}

/// The steady pressure along the face, Cp = −2χ − |∇χ|² with χ = Φ − ½|r|², from a spline
/// of the face's nodal potential.
struct FacePressure {
    wedge: Wedge,
    phi: Spline,
    /// arc length of the foot of the cut
    end: f64,
}

impl FacePressure {
    fn new(wedge: &Wedge, fl: &Flow) -> Self {
        FacePressure {
            wedge: *wedge,
            phi: Spline::new(&fl.face_s, &fl.face_phi),
            end: fl.face_s[fl.face_s.len() - 1],
        }
    }
    /// Cp at a height z/(Vt) on the face.
    fn cp(&self, z: f64) -> f64 {
        let w = &self.wedge;
        let s = (z + 1.0) / w.beta.sin();
        let r = w.point(s);
        let grad = add(scale(w.tangent, self.phi.deriv(s)), scale(w.normal, w.flux));
        let rel = sub(grad, r);
        -2.0 * (self.phi.eval(s) - 0.5 * dot(r, r)) - dot(rel, rel)
    }
    fn z_end(&self) -> f64 {
        -1.0 + self.end * self.wedge.beta.sin()
    }
    /// (z_max, Cp_max): the largest of 20 000 samples, refined by golden sections.
    fn peak(&self) -> (f64, f64) {
        let n = 20_000;
        let dz = (self.z_end() + 1.0) / n as f64;
        let k = (0..=n)
            .max_by(|&a, &b| {
                let (za, zb) = (-1.0 + a as f64 * dz, -1.0 + b as f64 * dz);
                self.cp(za).total_cmp(&self.cp(zb))
            })
            .unwrap_or(0);
        let z0 = -1.0 + k as f64 * dz;
        let (mut lo, mut hi) = ((z0 - dz).max(-1.0), z0 + dz);
        for _ in 0..60 {
            let m1 = lo + 0.382 * (hi - lo);
            let m2 = lo + 0.618 * (hi - lo);
            if self.cp(m1) < self.cp(m2) {
                lo = m1;
            } else {
                hi = m2;
            }
        }
        let z = 0.5 * (lo + hi);
        (z, self.cp(z))
    }
    /// C_F = ∫ Cp dξ over the face up to the cut (trapezoids on 20 000 intervals).
    fn force(&self) -> f64 {
        let n = 20_000;
        let dz = (self.z_end() + 1.0) / n as f64;
        let sum: f64 = (0..=n)
            .map(|k| {
                let w = if k == 0 || k == n { 0.5 } else { 1.0 };
                w * self.cp(-1.0 + k as f64 * dz)
            })
            .sum();
        sum * dz / self.wedge.beta.tan()
    }
    /// The stored table: steps of 0.05 in z/(Vt), 0.01 within 0.15 of the peak, the peak
    /// itself, halved where the midpoint's Cp is more than 0.1 % of Cp_max off the chord;
    /// from the keel to where Cp falls below 0.05 on the spray side.
    fn table(&self) -> Vec<(f64, f64)> {
        let (z_max, cp_max) = self.peak();
        let mut z_end = z_max;
        while z_end < self.z_end() && self.cp(z_end) >= 0.05 {
            z_end += 1e-4;
        }
        let z_end = z_end.min(self.z_end());
        let mut z: Vec<f64> = (0..)
            .map(|k| (k, -1.0 + 0.01 * k as f64))
            .take_while(|&(_, zk)| zk < z_end - 1e-4)
            .filter(|&(k, zk)| (zk - z_max).abs() <= 0.15 || k % 5 == 0)
            .map(|(_, zk)| zk)
            .filter(|zk| (zk - z_max).abs() > 1e-4)
            .chain([z_max, z_end])
            .collect();
        z.sort_by(f64::total_cmp);
        let tol = 1e-3 * cp_max;
        let mut out = vec![z[0]];
        for pair in z.windows(2) {
            let mut stack = vec![(pair[0], pair[1])];
            while let Some((a, b)) = stack.pop() {
                let m = 0.5 * (a + b);
                let chord = 0.5 * (self.cp(a) + self.cp(b));
                if (self.cp(m) - chord).abs() > tol && b - a > 2e-4 {
                    stack.push((m, b));
                    stack.push((a, m));
                } else {
                    out.push(b);
                }
            }
        }
        out.iter().map(|&z| (z, self.cp(z))).collect()
    }
}

/// The added mass of the body's acceleration on this geometry, in ρ (Vt)²: the
/// pressure's share that is proportional to the body's acceleration solves Laplace's
/// equation with p = 0 on the free surface and the body's normal acceleration on the
/// face, so it is −ρ (dV/dt) Vt Φ_a with Φ_a the unit velocity potential that vanishes on
/// the free surface (the same contour, the surface's potential set to zero). Both faces:
/// m = 2 ρ (Vt)² ∫ |Φ_a| dξ. Wagner's flat plate of half-width c gives π c²/2.
fn acceleration_added_mass(wedge: &Wedge, surface: &Surface, params: &Params) -> f64 {
    let still = Surface {
        x: surface.x.clone(),
        phi: vec![0.0; surface.phi.len()],
    };
    let fl = flow(wedge, &still, params);
    let cos = wedge.beta.cos();
    let integral: f64 = fl
        .face_s
        .windows(2)
        .zip(fl.face_phi.windows(2))
        .map(|(s, p)| 0.5 * (p[0] + p[1]) * (s[1] - s[0]) * cos)
        .sum();
    2.0 * integral.abs()
}

fn parse_args() -> (f64, Params, bool) {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let mut deadrise = 30.0;
    let mut params = Params::default();
    let mut check = false;
    let mut k = 0;
    while k < args.len() {
        if args[k] == "--check" {
            check = true;
            k += 1;
            continue;
        }
        let value: f64 = args
            .get(k + 1)
            .and_then(|v| v.parse().ok())
            .unwrap_or_else(|| panic!("{} needs a number", args[k]));
        match args[k].as_str() {
            "--deadrise" => deadrise = value,
            "--fine" => params.fine = value,
            "--growth" => params.growth = value,
            "--radius" => params.radius = value,
            "--cut" => params.cut = value,
            "--face-slope" => params.face_slope = value,
            "--face-cap" => params.face_cap = value,
            "--tau" => params.tau = value,
            "--cfl" => params.cfl = value,
            other => panic!("unknown argument {other}"),
        }
        k += 2;
    }
    (deadrise, params, check)
}

/// Compare with the stored table: Cp_max, C_F and the added mass of the acceleration
/// within 0.2 %, z_max within 0.002, every stored point within 0.5 % of Cp_max.
fn check(wedge: &Wedge, pressure: &FacePressure, added_mass: f64) -> bool {
    use mpsfsi::analysis::similarity;
    let Some(stored) = similarity::solution(wedge.deadrise_deg) else {
        println!("no stored table for {}°", wedge.deadrise_deg);
        return false;
    };
    let (z_max, cp_max) = pressure.peak();
    let force = pressure.force();
    let worst = stored
        .profile
        .iter()
        .map(|&(z, cp)| (pressure.cp(z) - cp).abs())
        .fold(0.0, f64::max);
    let checks = [
        (
            "Cp_max",
            cp_max,
            stored.cp_max,
            (cp_max / stored.cp_max - 1.0).abs() <= 2e-3,
        ),
        (
            "z_max",
            z_max,
            stored.z_max,
            (z_max - stored.z_max).abs() <= 2e-3,
        ),
        (
            "C_F",
            force,
            stored.force_coefficient,
            (force / stored.force_coefficient - 1.0).abs() <= 2e-3,
        ),
        ("worst point", worst, 0.0, worst <= 5e-3 * stored.cp_max),
        (
            "added mass of the acceleration",
            added_mass,
            stored.acceleration_added_mass.unwrap_or(f64::NAN),
            stored
                .acceleration_added_mass
                .is_some_and(|k| (added_mass / k - 1.0).abs() <= 2e-3),
        ),
    ];
    for (name, now, then, ok) in checks {
        println!(
            "check {name}: {now:.4} against {then:.4}: {}",
            if ok { "ok" } else { "FAILED" }
        );
    }
    checks.iter().all(|c| c.3)
}

fn main() {
    let (deadrise, params, check_stored) = parse_args();
    let wedge = Wedge::new(deadrise);
    let grading = Grading::new(&wedge, &params);
    let start = std::time::Instant::now();
    let mut surface = wagner_start(&wedge, &params, &grading);
    let mut tau = 0.0;
    let mut steps = 0;
    let mut next_report = 1.0;
    while tau < params.tau {
        tau += march_step(&wedge, &mut surface, &params, &grading);
        steps += 1;
        if tau >= next_report {
            next_report += 1.0;
            let pressure = FacePressure::new(&wedge, &flow(&wedge, &surface, &params));
            let (z_max, cp_max) = pressure.peak();
            eprintln!(
                "tau {tau:.2}: {steps} steps, {} surface nodes, Cp_max {cp_max:.4} at {z_max:.4}, C_F {:.4} ({:.0} s)",
                surface.x.len(),
                pressure.force(),
                start.elapsed().as_secs_f64()
            );
        }
    }
    let pressure = FacePressure::new(&wedge, &flow(&wedge, &surface, &params));
    let (z_max, cp_max) = pressure.peak();
    println!(
        "deadrise {deadrise}°: Cp_max {cp_max:.4} at z/(Vt) = {z_max:.4}, C_F {:.4} ({steps} steps to tau = {tau:.2}, {:.0} s; {params:?})",
        pressure.force(),
        start.elapsed().as_secs_f64()
    );
    let k = acceleration_added_mass(&wedge, &surface, &params);
    println!(
        "added mass of the acceleration: {k:.4} rho (Vt)^2 = {:.4} C_F/2 (Wagner's flat plate pi c_W^2/2 = {:.4})",
        k / (0.5 * pressure.force()),
        PI * wedge.c_w * wedge.c_w / 2.0
    );
    println!("(z/(Vt), Cp) along the face:");
    for (z, cp) in pressure.table() {
        println!("    ({z:.5}, {cp:.5}),");
    }
    if check_stored && !check(&wedge, &pressure, k) {
        std::process::exit(1);
    }
}
