//! Pressure-gradient correction of velocity and position, and the loads on walls.

use crate::case::{GradientKind, WallLoadKind};
use crate::engine::kernel::Kernel;
use crate::engine::math::{vec2, Mat2, Real, Vec2};
use crate::engine::operators::{gradient_row, Cloud, LatticeConstants, Normalisation};
use crate::engine::params::DIM;
use crate::engine::simulation::{Simulation, WallLoad};
use crate::engine::walls::pressure_load::pressure_loads;
use crate::engine::walls::{moment_about, PlacedWall};
use rayon::prelude::*;

pub(super) fn correct_velocity_and_position<K: Kernel>(
    sim: &mut Simulation,
    walls: &[PlacedWall],
    dt: Real,
    loads: &mut [WallLoad],
) {
    let prm = &sim.params;
    let (re, rho, c_grad, m, n0) = (
        prm.re,
        prm.density,
        prm.gradient_coefficient,
        prm.particle_mass,
        prm.n0,
    );
    let x = &sim.scratch.x_star;
    let p = &sim.particles.pressure;
    let nb = &sim.neighbors;
    let n = x.len();
    // minimum pressure over each neighbourhood (stability of the classic gradient)
    let p_min: Vec<Real> = (0..n)
        .into_par_iter()
        .map(|i| {
            nb.of(i)
                .iter()
                .filter(|&&j| (x[j as usize] - x[i]).norm() < re)
                .map(|&j| p[j as usize])
                .fold(p[i], Real::min)
        })
        .collect();
    let form = sim.scheme.gradient;
    let kappa = sim.scheme.gradient_stabilization;
    let close = sim.scheme.stabilization_distance * sim.params.l0;
    let contacts = &sim.contacts;
    let neumann = &sim.scratch.neumann;
    // Anisotropic and least-squares gradients (engine::operators, paper 000 eq. 28 and
    // LSMPS) away from walls, in the linear form Σ g_ij (p_j - p_i) like GC; particles
    // with wall contacts use GC, whose moment matrix includes the virtual wall points.
    let operator_gradient = matches!(form, GradientKind::Anisotropic | GradientKind::LeastSquares);
    let cloud = Cloud::new(x, nb, re);
    let lattice = Normalisation::Reference(LatticeConstants::compute::<K>(prm.l0, re, 2));
    // The gradient that moves the particles (fluid neighbours + virtual wall points).
    let total: Vec<Vec2> = (0..n)
        .into_par_iter()
        .map(|i| {
            let wall_contacts = contacts.of(i);
            if operator_gradient && wall_contacts.is_empty() {
                return gradient_row::<K>(form, &cloud, lattice, i)
                    .iter()
                    .map(|&(j, g)| g * (p[j] - p[i]))
                    .sum();
            }
            let base = contacts.offsets[i] as usize;
            let (mut s_fluid, mut s_min, mut s_sym) = (Vec2::zeros(), Vec2::zeros(), Vec2::zeros());
            let mut s_close = Vec2::zeros();
            let mut moment = Mat2::zeros();
            for &j in nb.of(i) {
                let j = j as usize;
                let r = x[j] - x[i];
                let d2 = r.norm_squared();
                let d = d2.sqrt();
                if d >= re || d == 0.0 {
                    continue;
                }
                let w = K::w(d, re) / d2;
                s_fluid += r * ((p[j] - p[i]) * w);
                s_min += r * ((p[j] - p_min[i]) * w);
                if d < close {
                    s_close += r * w;
                }
                s_sym += match form {
                    GradientKind::Cmps => r * ((p[i] + p[j] - p_min[i] - p_min[j]) * w),
                    _ => r * ((p[i] + p[j]) * w),
                };
                moment += r * r.transpose() * w;
            }
            // virtual points: p_k - p_i = c · r_ik
            let mut wall_linear = Vec2::zeros();
            let mut wall_m1 = Vec2::zeros();
            for (k, c) in wall_contacts.iter().enumerate() {
                wall_linear += c.terms.moment2_times(neumann[base + k]);
                wall_m1 += c.terms.moment1;
                let [xx, xy, yy] = c.terms.moment2;
                moment += Mat2::new(xx, xy, xy, yy);
            }
            let classic = (s_min + wall_m1 * (p[i] - p_min[i]) + wall_linear) * c_grad;
            match form {
                GradientKind::MinimumPressure => classic,
                GradientKind::Symmetric => (s_sym + wall_m1 * (2.0 * p[i]) + wall_linear) * c_grad,
                GradientKind::Cmps => {
                    (s_sym + wall_m1 * (2.0 * (p[i] - p_min[i])) + wall_linear) * c_grad
                }
                _ => {
                    // plus the repulsive part of the minimum-pressure form, (p_i - p̂_i) Σ r w / r²,
                    // over pairs closer than `stabilization_distance`: silent on the lattice (still
                    // water stays still), pushing particles apart where they cluster
                    let stabilizer = s_close * ((p[i] - p_min[i]) * kappa * c_grad);
                    match corrected_gradient_matrix(&moment, n0) {
                        Some(c) => c * (s_fluid + wall_linear) / n0 + stabilizer,
                        None => classic,
                    }
                }
            }
        })
        .collect();
    if sim.scheme.wall_load == WallLoadKind::PressureIntegral {
        let w = |d: Real| K::w(d, re);
        let integral = pressure_loads(
            x,
            p,
            &nb.grid,
            walls,
            &w,
            rho,
            vec2(prm.gravity),
            prm.l0,
            re,
        );
        for (load, (f, moment)) in loads.iter_mut().zip(integral) {
            load.pressure_force += f;
            load.moment += moment;
        }
    }
    // Loads: the conservative (antisymmetric) wall term, virtual pressure p_k = p_i + c·r:
    // Σ_k (p_i + p_k) r w / r² — a pressure integral over the wall through the MPS wall
    // operator, whose sum over a still tank is the fluid's weight.
    let reaction = sim.scheme.wall_load == WallLoadKind::Reaction;
    for i in (0..n).filter(|_| reaction) {
        let base = contacts.offsets[i] as usize;
        for (k, c) in contacts.of(i).iter().enumerate() {
            let gw = (c.terms.moment1 * (2.0 * p[i]) + c.terms.moment2_times(neumann[base + k]))
                * c_grad;
            let f = gw * (m / rho);
            let load = &mut loads[c.object as usize];
            load.pressure_force += f;
            load.moment += moment_about(walls[c.object as usize].state.center_of_mass, c.point, f);
        }
    }
    let scale = dt / rho;
    let parts = &mut sim.particles;
    parts
        .velocity
        .par_iter_mut()
        .zip(total.par_iter())
        .for_each(|(u, g)| *u -= g * scale);
    parts
        .position
        .par_iter_mut()
        .zip(x.par_iter())
        .zip(total.par_iter())
        .for_each(|((pos, xs), g)| *pos = xs - g * (scale * dt));
}

/// The GC matrix C = [(1/n0) Σ w r rᵀ / r²]⁻¹ from the moments Σ w r rᵀ / r² (fluid
/// and virtual wall points); on the full lattice C = d I. `None` where the moments are
/// too degenerate to invert safely (below 0.3 of the lattice's determinant): the
/// gradient then falls back to the classic normalisation.
pub(super) fn corrected_gradient_matrix(moment: &Mat2, n0: Real) -> Option<Mat2> {
    let mm = moment / n0;
    let lattice_det = (1.0 / DIM).powi(2);
    if mm.determinant() > 0.3 * lattice_det {
        mm.try_inverse()
    } else {
        None
    }
}
