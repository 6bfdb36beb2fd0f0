//! The exact projection (`scheme.projection = "exact"`): the pressure whose corrected
//! velocity u = u* - dt/rho ∇p has, row by row, the HS divergence (wall terms included,
//! the wall's virtual points moving with the wall) that the source asks for.
//!
//! The usual MPS projection solves ∇²p = (rho/dt) ∇·u* with the HL Laplacian, which is
//! not the product of the HS divergence and the corrected gradient that then move the
//! particles: next to a wall the two disagree. On a flat plate started impulsively on
//! still water the row under the plate leaves 24-27 % faster than the plate and the
//! added mass comes out 8-13 % high, growing with refinement (tests/bodies/plate_impulse.rs).
//! Here the rows of particles whose neighbours are all unknowns are the HS divergence of
//! the corrected velocity, matrix-free, blended with a share theta of the HL row
//! (`scheme.exact_projection_blend`: the HS divergence of the corrected gradient does not
//! see the odd-even pressure mode, and the blend gives that mode back its stiffness).
//! Rows next to the free surface keep the HL Laplacian: enforcing the HS divergence
//! of a thin sheet at a jet root blew the wedge up within 11 ms. The approximate
//! solution is the start, GMRES corrects it, preconditioned by the Laplacian's AMG cycle.
//!
//! What it changes (details on `case::Projection::Exact`): the plate's added mass
//! comes within 2.1 % of Wagner's at 10 / 5 / 2.5 mm with the default blend 0.1, but the
//! wedge's slamming force does not fall, and blends below 0.1 let the floating box go
//! unstable.
//! A run costs 2.4-2.7 times the approximate one: the GMRES iterations (about 14 a step
//! at 1 cm) each apply the gradient, the divergence and an AMG cycle.

use crate::engine::kernel::Kernel;
use crate::engine::operators::{corrected_gradient_row, hs_divergence_row, Cloud, GradientRow};
use crate::engine::pressure::{self, SolveParams};
use crate::engine::simulation::{SimError, Simulation};
use crate::engine::workspace::PressureSystem;
use crate::math::{Real, Vec2};
use rayon::prelude::*;

/// GMRES stops at this residual relative to the pressure equation's right-hand side:
/// the plate's added mass is the same to four digits at 1e-3 and 1e-6 (about 14
/// against 30 iterations a step on the wedge at 1 cm).
const EXACT_TOLERANCE: Real = 1e-3;
/// Krylov vectors kept before a restart.
const RESTART: usize = 20;

/// The corrected gradient's linear part at every particle (`operators::corrected_gradient_row`),
/// ∇p_i = Σ_j g_ij (p_j - p_i) + b_i, its coefficients stored by particle for the
/// neighbours within r_e.
struct Gradient {
    offsets: Vec<usize>,
    /// (neighbour, g_ij) for the neighbours within r_e.
    coefficients: Vec<(usize, Vec2)>,
    /// The virtual points' Neumann part (pressure-independent), normalised.
    wall: Vec<Vec2>,
}

impl Gradient {
    fn new<K: Kernel>(sim: &Simulation, cloud: &Cloud, neumann: &[Vec2]) -> Self {
        let prm = &sim.config.params;
        let contacts = &sim.workspace.contacts;
        let rows: Vec<(GradientRow, Vec2)> = (0..cloud.len())
            .into_par_iter()
            .map(|i| {
                let walls = contacts.virtual_points(i, neumann);
                corrected_gradient_row::<K>(cloud, prm.n0, prm.gradient_coefficient, i, walls)
            })
            .collect();
        let mut offsets = Vec::with_capacity(cloud.len() + 1);
        let mut coefficients = Vec::with_capacity(cloud.neighbors.indices.len());
        let mut wall = Vec::with_capacity(cloud.len());
        offsets.push(0);
        for (c, b) in rows {
            coefficients.extend(c);
            offsets.push(coefficients.len());
            wall.push(b);
        }
        Self {
            offsets,
            coefficients,
            wall,
        }
    }

    /// ∇p at every particle; `homogeneous` leaves out the Neumann part.
    fn apply(&self, p: &[Real], homogeneous: bool) -> Vec<Vec2> {
        (0..p.len())
            .into_par_iter()
            .map(|i| {
                let mut g = if homogeneous {
                    Vec2::zeros()
                } else {
                    self.wall[i]
                };
                for &(j, c) in &self.coefficients[self.offsets[i]..self.offsets[i + 1]] {
                    g += c * (p[j] - p[i]);
                }
                g
            })
            .collect()
    }
}

/// Correct the pressure solved with the HL Laplacian (unknown rows in
/// `system.solution`, not yet clipped; the others at their `dirichlet` value) so that
/// the rows of particles away from the free surface carry the exact projection at
/// `x_star`; writes `sim.particles.pressure` and `system.exact_correction`. Returns the
/// GMRES iterations.
pub(super) fn correct_to_exact_projection<K: Kernel>(
    sim: &mut Simulation,
    (x_star, dirichlet): (&[Vec2], &[Real]),
    system: &mut PressureSystem,
    blend: Real,
    dt: Real,
) -> Result<usize, SimError> {
    // the Laplacian's hierarchy preconditions; taken out while `sim` is borrowed
    let mut cache = std::mem::take(&mut sim.workspace.solver_cache);
    let prm = &sim.config.params;
    let (rho, re, c_div) = (prm.density, prm.re, prm.divergence_coefficient);
    let s = &*system;
    let surface = &sim.particles.free_surface;
    let nb = &sim.workspace.neighbors;
    let contacts = &sim.workspace.contacts;
    let x = x_star;
    let u_star = &sim.particles.velocity;
    let rows = s.particle_of.len();
    // rows whose whole neighbourhood is unknown take the exact projection
    let exact: Vec<bool> = s
        .particle_of
        .iter()
        .map(|&i| nb.of(i as usize).iter().all(|&j| !surface[j as usize]))
        .collect();
    let extras: Vec<Real> = s
        .particle_of
        .iter()
        .map(|&i| s.source_extra[i as usize])
        .collect();
    // the exact projection's gradient and divergence rows are single-resolution
    let cloud = Cloud::new(x, nb, re);
    let gradient = Gradient::new::<K>(sim, &cloud, &s.neumann);
    // HS divergence coefficients of the exact rows: ∇·u_i = Σ_j e_ij·(u_j - u_i) + wall
    let divergence: Vec<Vec<(usize, Vec2)>> = s
        .particle_of
        .par_iter()
        .zip(exact.par_iter())
        .map(|(&i, &e)| {
            if e {
                hs_divergence_row::<K>(&cloud, c_div, i as usize)
            } else {
                Vec::new()
            }
        })
        .collect();
    let theta = blend;
    // F(p): the exact rows' source evaluated at the corrected velocity, the other rows'
    // Laplacian residual; affine in p, `homogeneous` is its linear part
    let residual = |unknowns: &[Real], homogeneous: bool, out: &mut [Real]| {
        let mut p = if homogeneous {
            vec![0.0; x.len()]
        } else {
            dirichlet.to_vec()
        };
        for (row, &i) in s.particle_of.iter().enumerate() {
            p[i as usize] = unknowns[row];
        }
        let g = gradient.apply(&p, homogeneous);
        let scale = dt / rho;
        let u: Vec<Vec2> = (0..x.len())
            .into_par_iter()
            .map(|i| {
                let start = if homogeneous {
                    Vec2::zeros()
                } else {
                    u_star[i]
                };
                start - g[i] * scale
            })
            .collect();
        s.matrix.mul(unknowns, out);
        out.par_iter_mut().enumerate().for_each(|(row, o)| {
            let i = s.particle_of[row] as usize;
            if !homogeneous {
                *o -= s.rhs[row];
            }
            if !exact[row] {
                return;
            }
            let laplacian = *o;
            let mut div = 0.0;
            for &(j, e) in &divergence[row] {
                div += e.dot(&(u[j] - u[i]));
            }
            for ct in contacts.of(i) {
                let wall = if homogeneous {
                    Vec2::zeros()
                } else {
                    ct.wall_velocity
                };
                div -= c_div * ct.terms.number_density_gradient.dot(&(u[i] - wall));
            }
            let projection = rho / dt * div + if homogeneous { 0.0 } else { extras[row] };
            *o = (1.0 - theta) * projection + theta * laplacian;
        });
    };
    let p0 = s.solution.clone();
    let mut f0 = vec![0.0; rows];
    residual(&p0, false, &mut f0);
    let b: Vec<Real> = f0.iter().map(|v| -v).collect();
    let reference = s.rhs.iter().map(|v| v * v).sum::<Real>().sqrt();
    // the correction is a near-wall pattern that changes little from step to step
    let mut delta: Vec<Real> = s
        .particle_of
        .iter()
        .map(|&i| s.exact_correction.get(i as usize).copied().unwrap_or(0.0))
        .collect();
    // Jacobi where there is no hierarchy (other solvers), its diagonal taken once
    let mut diag: Option<Vec<Real>> = None;
    let info = pressure::gmres(
        |v, out| residual(v, true, out),
        |r, z| {
            if !cache.precondition(&s.matrix, r, z) {
                let diag = diag.get_or_insert_with(|| s.matrix.diagonal());
                z.iter_mut()
                    .zip(r)
                    .zip(diag.iter())
                    .for_each(|((zi, ri), di)| *zi = ri / di);
            }
        },
        &b,
        &mut delta,
        reference,
        SolveParams::relative(EXACT_TOLERANCE, sim.config.method.solver.max_iterations),
        RESTART,
    );
    sim.workspace.solver_cache = cache;
    let info = info.map_err(|e| SimError::Solver {
        step: sim.steps + 1,
        time: sim.time,
        reason: format!("exact projection: {e}"),
    })?;
    let clip = sim.config.method.clip_negative_pressure;
    let s = system;
    let p = &mut sim.particles.pressure;
    s.exact_correction.clear();
    s.exact_correction.resize(p.len(), 0.0);
    for (row, &i) in s.particle_of.iter().enumerate() {
        let v = p0[row] + delta[row];
        p[i as usize] = if clip { v.max(0.0) } else { v };
        s.exact_correction[i as usize] = delta[row];
    }
    Ok(info.iterations)
}
