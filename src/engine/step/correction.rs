//! Pressure-gradient correction of velocity and position, and the loads on walls.

use crate::case::{GradientKind, WallLoadKind};
use crate::engine::kernel::Kernel;
use crate::engine::operators::{
    gradient_row, minimum_over_neighbourhood, pressure_gradient, Cloud, Normalisation,
    PressureGradient,
};
use crate::engine::params::DIM;
use crate::engine::simulation::{Simulation, WallLoad};
use crate::engine::walls::pressure_load::{pressure_loads, surface_pressures};
use crate::engine::walls::{moment_about, PlacedWall};
use crate::math::{vec2, Real, Vec2};
use rayon::prelude::*;

/// ∇p of every particle at `x_star`: the case's gradient form with the virtual wall
/// points, whose pressure follows the contacts' Neumann gradients `neumann`.
pub(super) fn pressure_gradients<K: Kernel>(
    sim: &Simulation,
    x_star: &[Vec2],
    neumann: &[Vec2],
) -> Vec<Vec2> {
    let prm = &sim.config.params;
    let (re, c_grad, n0) = (prm.re, prm.gradient_coefficient, prm.n0);
    let x = x_star;
    let p = &sim.particles.pressure;
    let nb = &sim.workspace.neighbors;
    let n = x.len();
    let cloud = Cloud::new(x, nb, re).with_scales(sim.scales());
    let form = sim.config.method.gradient;
    // minimum pressure over each neighbourhood, for CMPS, which reads it at both ends of
    // a pair (the other forms find their own where they need it)
    let p_min: Option<Vec<Real>> = (form == GradientKind::Cmps).then(|| {
        (0..n)
            .into_par_iter()
            .map(|i| minimum_over_neighbourhood(&cloud, p, i))
            .collect()
    });
    let gradient = PressureGradient {
        kind: form,
        classic: c_grad,
        n0,
        dim: DIM,
        stabilization: sim.config.method.stabilization.strength,
        close: sim.config.method.stabilization.distance * sim.config.params.l0,
    };
    let contacts = &sim.workspace.contacts;
    // Anisotropic and least-squares gradients (Imoto 2022 eq. 28 and LSMPS) away from
    // walls, in the linear form Σ g_ij (p_j - p_i) like GC; particles with wall contacts
    // use GC, whose moment matrix includes the virtual wall points.
    let operator_gradient = matches!(form, GradientKind::Anisotropic | GradientKind::LeastSquares);
    let lattice = Normalisation::Reference(prm.lattice);
    (0..n)
        .into_par_iter()
        .map(|i| {
            if operator_gradient && contacts.of(i).is_empty() {
                return gradient_row::<K>(form, &cloud, lattice, i)
                    .iter()
                    .map(|&(j, g)| g * (p[j] - p[i]))
                    .sum();
            }
            let walls = contacts.virtual_points(i, neumann);
            pressure_gradient::<K>(&gradient, &cloud, p, p_min.as_deref(), i, walls)
        })
        .collect()
}

/// The largest |x^{n+1} - x^n| = dt |u* - dt/rho ∇p| the correction would give.
pub(super) fn largest_displacement(sim: &Simulation, gradient: &[Vec2], dt: Real) -> Real {
    let scale = dt / sim.config.params.density;
    sim.particles
        .velocity
        .par_iter()
        .zip(gradient.par_iter())
        .map(|(u, g)| (u - g * scale).norm())
        .reduce(|| 0.0, Real::max)
        * dt
}

/// u^{n+1} = u* - dt/rho ∇p, x^{n+1} = x* - dt²/rho ∇p with ∇p `total` at `x_star`,
/// and the wall loads.
pub(super) fn correct_velocity_and_position<K: Kernel>(
    sim: &mut Simulation,
    walls: &[PlacedWall],
    (x_star, neumann): (&[Vec2], &[Vec2]),
    total: &[Vec2],
    dt: Real,
    loads: &mut [WallLoad],
) {
    let prm = &sim.config.params;
    let (re, rho, c_grad, m) = (
        prm.re,
        prm.density,
        prm.gradient_coefficient,
        prm.particle_mass,
    );
    let x = x_star;
    let p = &sim.particles.pressure;
    let nb = &sim.workspace.neighbors;
    let n = x.len();
    let contacts = &sim.workspace.contacts;
    // the surface pressure is read with either estimator: gauges and snapshots show it
    let w = |d: Real| K::w(d, re);
    let surfaces = surface_pressures(
        x,
        p,
        sim.scales(),
        &nb.grid,
        walls,
        &w,
        rho,
        vec2(prm.gravity),
        prm.l0,
        re,
    );
    if sim.config.method.wall_load == WallLoadKind::PressureIntegral {
        for (load, (f, moment)) in loads.iter_mut().zip(pressure_loads(walls, &surfaces)) {
            load.pressure_force += f;
            load.moment += moment;
        }
    }
    // Loads: the conservative (antisymmetric) wall term, virtual pressure p_k = p_i + c·r:
    // Σ_k (p_i + p_k) r w / r² — a pressure integral over the wall through the MPS wall
    // operator, whose sum over a still tank is the fluid's weight.
    let reaction = sim.config.method.wall_load == WallLoadKind::Reaction;
    let scales = sim.scales();
    for i in (0..n).filter(|_| reaction) {
        let base = contacts.offsets[i] as usize;
        for (k, c) in contacts.of(i).iter().enumerate() {
            let gw = (c.terms.moment1 * (2.0 * p[i]) + c.terms.moment2_times(neumann[base + k]))
                * c_grad;
            let f = gw * (m * scales.volume(i) / rho);
            let load = &mut loads[c.object as usize];
            load.pressure_force += f;
            load.moment += moment_about(walls[c.object as usize].state.center_of_mass, c.point, f);
        }
    }
    sim.surface_pressure = surfaces;
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
