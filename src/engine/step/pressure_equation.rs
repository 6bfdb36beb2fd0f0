//! The pressure Poisson equation: Neumann wall gradients, source, Laplacian rows,
//! assembly and solve.

use super::density::AtPrediction;
use super::free_surface::SurfaceValues;
use super::walls::KernelWeights;
use crate::case::WallKinematics;
use crate::engine::config::{Projection, Source};
use crate::engine::kernel::Kernel;
use crate::engine::operators::{
    for_each_lattice_coefficient, has_laplacian_neighbour, laplacian_row, Cloud, Normalisation,
};
use crate::engine::pressure::{self, concat_into, Entries, SolveParams};
use crate::engine::resolution::Scales;
use crate::engine::simulation::{SimError, Simulation};
use crate::engine::walls::WallContact;
use crate::engine::workspace::PressureSystem;
use crate::math::{vec2, Real, Vec2};
use rayon::prelude::*;

/// The extrapolation gradient c = rho (g - a_w) of every wall contact (module docs);
/// zero for the PND source (virtual points take p_i). With `wall_kinematics =
/// "neumann"` it also carries the particle's approach to the wall left over from the
/// last step, (rho/dt) min(0, (u_i - u_w)·n) n (zero when the fluid followed the wall),
/// so the virtual pressure behind the wall rises to push the particle back.
pub(super) fn neumann_gradients(sim: &Simulation, u_start: &[Vec2], dt: Real) -> Vec<Vec2> {
    let rho = sim.config.params.density;
    let g = vec2(sim.config.params.gravity);
    let extrapolate = sim.config.method.source != Source::Pnd;
    let contacts = &sim.workspace.contacts;
    let base = |c: &WallContact| {
        if extrapolate {
            (g - c.wall_acceleration) * rho
        } else {
            Vec2::zeros()
        }
    };
    if sim.config.method.wall_kinematics == WallKinematics::Source || !extrapolate {
        return contacts.contacts.par_iter().map(base).collect();
    }
    let u = u_start;
    (0..u.len())
        .into_par_iter()
        .flat_map_iter(|i| {
            contacts.of(i).iter().map(move |c| {
                let approach = (u[i] - c.wall_velocity).dot(&c.normal).min(0.0);
                base(c) + c.normal * (rho / dt * approach)
            })
        })
        .collect()
}

/// The rows of the pressure equation at `x_star` into `system` (its `neumann` already
/// set), with the source from n* and ∇·u* and the surface values of `surface`; a
/// particle with no Laplacian neighbour becomes free surface (flag and value).
pub(super) fn assemble_pressure_equation<K: Kernel>(
    sim: &mut Simulation,
    weights: &KernelWeights<K>,
    x_star: &[Vec2],
    at_star: &AtPrediction,
    surface_values: &mut SurfaceValues,
    system: &mut PressureSystem,
    dt: Real,
) {
    let np = sim.particles.len();
    let p = &sim.config.params;
    let (rho, n0, c_lap) = (p.density, p.n0, p.laplacian_coefficient);
    let x = x_star;
    let nb = &sim.workspace.neighbors;
    let scales = Scales::new(&sim.particles.scale, sim.config.multi_resolution);
    let cloud = Cloud::new(x, nb, p.re_lap).with_scales(scales);
    // Imoto's second-order Laplacian is the classic one (Imoto 2022 Theorem 3.1)
    let classic = weights.classic_laplacian();
    // a particle with no Laplacian neighbour cannot be solved for: Dirichlet
    let surface = &sim.particles.free_surface;
    let isolated: Vec<usize> = (0..np)
        .into_par_iter()
        .filter(|&i| !surface[i] && !has_laplacian_neighbour::<K>(classic, &cloud, i))
        .collect();
    for i in isolated {
        sim.particles.free_surface[i] = true;
        surface_values.dirichlet[i] = 0.0;
    }
    let dirichlet = &surface_values.dirichlet;
    let surface = &sim.particles.free_surface;
    // a particle at the edge of the graded surface test: alpha (p_i - p_surface) with
    // alpha = s / (1 - s) times the row's diagonal (`Scheme::soft_surface`)
    let softness = &surface_values.softness;
    let soften = |i: usize, diag: &mut Real, b: &mut Real| {
        let s = softness.get(i).copied().unwrap_or(0.0);
        if s > 0.0 {
            let alpha = *diag * s / (1.0 - s);
            *diag += alpha;
            *b += alpha * dirichlet[i];
        }
    };
    // the previous step's index maps, refilled (no allocation at a steady size)
    let mut unknown_of = std::mem::take(&mut system.unknown_of);
    let mut particle_of = std::mem::take(&mut system.particle_of);
    unknown_of.clear();
    unknown_of.resize(np, u32::MAX);
    particle_of.clear();
    for i in 0..np {
        if !surface[i] {
            unknown_of[i] = particle_of.len() as u32;
            particle_of.push(i as u32);
        }
    }
    // source term S of ∇²p - (rho alpha / dt²) p = S
    let div_star = &at_star.div;
    let n_prev = &sim.particles.number_density;
    let div_prev = &sim.particles.number_density_rate;
    let n_star = &at_star.n;
    // the variant chosen once per step, each its own loop
    let by_particle = |f: &(dyn Fn(usize) -> Real + Sync)| -> Vec<Real> {
        (0..np).into_par_iter().map(f).collect()
    };
    let source: Vec<Real> = match sim.config.method.source {
        Source::Pnd => by_particle(&|i| -rho / (dt * dt) * (n_star[i] - n0) / n0),
        Source::HigherOrder => by_particle(&|i| rho / dt * div_star[i]),
        Source::HigherOrderEcs => by_particle(&|i| {
            let dev = (n_prev[i] - n0) / n0;
            let alpha = dev.abs();
            let beta = (dt * div_prev[i]).abs();
            rho / dt * (div_star[i] + alpha * div_prev[i]) - beta * rho / (dt * dt) * dev
        }),
        Source::Mixed { relaxation: gamma } => by_particle(&|i| {
            rho / dt * div_star[i] - gamma * rho / (dt * dt) * (n_prev[i] - n0) / n0
        }),
    };
    let source_extra: Vec<Real> = match sim.config.method.projection {
        Projection::Exact { .. } => (0..np)
            .into_par_iter()
            .map(|i| source[i] - rho / dt * div_star[i])
            .collect(),
        Projection::Approximate => Vec::new(),
    };
    let compress = rho * sim.config.method.compressibility / (dt * dt);
    let rho_g = vec2(p.gravity) * rho;
    let well_balanced = sim.config.method.hydrostatic_ghosts;
    let contacts = &sim.workspace.contacts;
    // CHL, anisotropic and least-squares rows come from engine::operators for particles
    // away from walls; rows with wall contacts keep the tabulated (HL/classic) form,
    // which carries the Neumann condition, with the same lattice normalisation.
    let kind = sim.config.method.laplacian;
    let operator_rows = !kind.is_symmetric();
    let lattice = Normalisation::Reference(p.lattice_lap);
    let neumann = &system.neumann;
    let nu = particle_of.len();
    // the fill n*/n0 of each neighbourhood, floored (`Scheme::laplacian_fill_floor`);
    // none when disabled, so the default pays nothing per pair
    let fills: Option<Vec<Real>> = sim.config.method.laplacian_fill_floor.map(|floor| {
        n_star
            .par_iter()
            .map(|n| (n / n0).clamp(floor, 1.0))
            .collect()
    });
    let fills = fills.as_deref();
    // one off-diagonal coefficient c_ij: into the matrix when j is an unknown, else its
    // Dirichlet value into the right-hand side (returned)
    let off_diagonal = |j: usize, c: Real, out: &mut Entries| {
        let uj = unknown_of[j];
        if uj != u32::MAX {
            out.push(uj, -c);
            0.0
        } else {
            c * dirichlet[j]
        }
    };
    // row `row` appended to `out`; returns the right-hand side
    let row_entries_unscaled = |row: usize, out: &mut Entries| -> Real {
        let i = particle_of[row] as usize;
        let mut diag = compress;
        let mut b = -source[i];
        if operator_rows && contacts.of(i).is_empty() {
            for (j, c) in laplacian_row::<K>(kind, &cloud, lattice, i).off_diagonal {
                diag += c;
                b += off_diagonal(j, c, out);
            }
            soften(i, &mut diag, &mut b);
            out.push(row as u32, diag);
            return b;
        }
        // Σ L r over the neighbours present (fluid and wall lattice): zero on a full
        // lattice, the first-order error of the Laplacian where the free surface or
        // disorder truncates the neighbourhood
        let mut first_moment = Vec2::zeros();
        // a pair's weight over the mean fill of its two particles: symmetric, and 1 in
        // a full neighbourhood
        let pair_scale = |j: usize| fills.map_or(1.0, |f| 2.0 / (f[i] + f[j]));
        for_each_lattice_coefficient::<K>(classic, &cloud, c_lap, i, pair_scale, |j, r, l| {
            first_moment += r * l;
            diag += l;
            b += off_diagonal(j, l, out);
        });
        soften(i, &mut diag, &mut b);
        out.push(row as u32, diag);
        let wall_scale = fills.map_or(1.0, |f| 1.0 / f[i]);
        for (c_dot_moment, moment) in contacts.laplacian_terms(i, neumann) {
            b += c_lap * wall_scale * c_dot_moment;
            first_moment += moment * (c_lap * wall_scale);
        }
        // Hydrostatic consistency: the missing part of the neighbourhood (-Σ L r) is
        // filled with ghosts carrying the hydrostatic pressure p_i + rho g·r, so a
        // hydrostatic field solves the discrete equation whatever the arrangement.
        // Without it the row below the free surface, which misses the point 2 l0
        // above it, sets the whole column 0.14 l0 rho g (14 Pa at 1 cm) too high and lifts the top row.
        if well_balanced {
            b -= rho_g.dot(&first_moment);
        }
        b
    };
    // With multi-resolution each row is multiplied by its particle's volume s_i^d, which
    // makes the matrix symmetric (`resolution`); a uniform run skips it.
    let row_entries = |row: usize, out: &mut Entries| -> Real {
        if scales.is_uniform() {
            return row_entries_unscaled(row, out);
        }
        let before = out.len;
        let b = row_entries_unscaled(row, out);
        let volume = scales.volume(particle_of[row] as usize);
        for v in &mut out.vals[before..out.len] {
            *v *= volume;
        }
        b * volume
    };
    // Rows in parallel chunks (one task per chunk, rows in order: deterministic) written
    // straight into the previous step's matrix buffers: no allocation or zeroing per
    // step and no second copy of the matrix alive at the peak.
    const CHUNK: usize = 2048;
    let chunks = nu.div_ceil(CHUNK);
    let rows_of = |c: usize| c * CHUNK..((c + 1) * CHUNK).min(nu);
    // at most one entry per neighbour plus the diagonal
    let bounds: Vec<usize> = (0..chunks)
        .into_par_iter()
        .map(|c| {
            rows_of(c)
                .map(|row| nb.of(particle_of[row] as usize).len() + 1)
                .sum()
        })
        .collect();
    let mut m = std::mem::take(&mut system.matrix);
    let rhs_parts = m.fill_in_place(&bounds, |c, out| {
        let rows = rows_of(c);
        let mut lens = Vec::with_capacity(rows.len());
        let mut rhs = Vec::with_capacity(rows.len());
        for row in rows {
            let before = out.len;
            rhs.push(row_entries(row, out));
            lens.push((out.len - before) as u32);
        }
        (lens, rhs)
    });
    let mut rhs = std::mem::take(&mut system.rhs);
    let rhs_parts: Vec<&[Real]> = rhs_parts.iter().map(|b| &b[..]).collect();
    concat_into(&mut rhs, &rhs_parts);
    // warm start from the last pressures
    system.solution.clear();
    system.solution.extend(
        particle_of
            .iter()
            .map(|&i| sim.particles.pressure[i as usize]),
    );
    system.matrix = m;
    system.rhs = rhs;
    system.unknown_of = unknown_of;
    system.particle_of = particle_of;
    system.source_extra = source_extra;
}

/// Solve `system` (its solution stays in it, unclipped) and set the particles' pressure:
/// the solution on the unknowns, the surface values on the others.
pub(super) fn solve_pressure(
    sim: &mut Simulation,
    system: &mut PressureSystem,
    surface_values: &SurfaceValues,
) -> Result<(usize, Real), SimError> {
    let solver = &sim.config.method.solver;
    let params = SolveParams {
        energy: solver.energy_tolerance,
        ..SolveParams::relative(solver.tolerance, solver.max_iterations)
    };
    let s = system;
    let policy = pressure::ReusePolicy {
        rebuild_interval: sim.config.method.solver.amg_rebuild_interval,
        // Keep, not Galerkin: recomputing R A P saved only a quarter of the setup
        // (dam break, 10k particles, interval 10: setup 10.3 vs 13.8 ms/step rebuilding
        // every step, against 2.1 ms/step when keeping) for the same iterations (14.0)
        coarse: pressure::CoarseUpdate::Keep,
    };
    // rows are keyed by particle, so a hierarchy survives changes of the unknown set
    let info = pressure::solve_reusing(
        sim.config.method.solver.kind,
        &s.matrix,
        &s.rhs,
        &mut s.solution,
        params,
        pressure::Reuse {
            cache: &mut sim.workspace.solver_cache,
            keys: &s.particle_of,
            key_space: s.unknown_of.len(),
            policy,
        },
    )
    .map_err(|e| SimError::Solver {
        step: sim.steps + 1,
        time: sim.time,
        reason: e.to_string(),
    })?;
    let clip = sim.config.method.clip_negative_pressure;
    let p = &mut sim.particles.pressure;
    p.copy_from_slice(&surface_values.dirichlet);
    for (row, &i) in s.particle_of.iter().enumerate() {
        let v = s.solution[row];
        p[i as usize] = if clip { v.max(0.0) } else { v };
    }
    Ok((info.iterations, info.relative_residual))
}
