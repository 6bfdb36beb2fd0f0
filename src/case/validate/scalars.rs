//! Rules 2 and 3: signs and ranges of the scalars, the domain, the particle limit,
//! and the damping layers.

use super::{estimated_particles, reject, Check, Limits};
use crate::case::{Case, Projection, SourceKind};
use crate::math::vec2;

pub(super) fn positive(path: &str, v: f64, what: &str) -> Check {
    if v > 0.0 {
        Ok(())
    } else {
        reject(path, format!("must be positive (got {v}): {what}"))
    }
}

pub(super) fn non_negative(path: &str, v: f64, what: &str) -> Check {
    if v >= 0.0 {
        Ok(())
    } else {
        reject(path, format!("must not be negative (got {v}): {what}"))
    }
}

/// A share in (0, 1] (of n0, of an operator).
pub(super) fn share(path: &str, v: f64, what: &str) -> Check {
    if v > 0.0 && v <= 1.0 {
        Ok(())
    } else {
        reject(path, format!("must lie in (0, 1] (got {v}): {what}"))
    }
}

pub(super) fn check_scalars(case: &Case) -> Check {
    positive(
        "fluid.density",
        case.fluid.density,
        "the fluid density in kg/m³",
    )?;
    non_negative(
        "fluid.kinematic_viscosity",
        case.fluid.kinematic_viscosity,
        "the kinematic viscosity in m²/s (0 switches viscosity off)",
    )?;
    positive(
        "particle_spacing",
        case.particle_spacing,
        "the initial particle spacing l0 in m",
    )?;
    positive("time.end", case.time.end, "the simulated end time in s")?;
    positive("time.cfl", case.time.cfl, "the Courant number")?;
    positive(
        "time.max_dt",
        case.time.max_dt,
        "the largest time step in s",
    )?;

    let s = &case.scheme;
    // r_e <= l0 leaves no lattice neighbour inside the kernel: n0 would be zero
    if s.radius <= 1.0 {
        return reject(
            "scheme.radius",
            format!(
                "the kernel radius r_e/l0 must be greater than 1 (got {}); about 2.1 is usual",
                s.radius
            ),
        );
    }
    if let Some(r) = s.laplacian_radius {
        if r <= 1.0 {
            return reject(
                "scheme.laplacian_radius",
                format!("the Laplacian kernel radius r_e/l0 must be greater than 1 (got {r}); 3.1-4.0 is usual"),
            );
        }
    }
    positive(
        "scheme.solver_tolerance",
        s.solver_tolerance,
        "the relative residual at which the linear solver stops",
    )?;
    non_negative(
        "scheme.solver_energy_tolerance",
        s.solver_energy_tolerance,
        "the relative energy-norm error at which the pressure solve stops; 0 disables it",
    )?;
    if s.solver_max_iterations == 0 {
        return reject("scheme.solver_max_iterations", "must be positive (got 0)");
    }
    if s.amg_rebuild_interval == 0 {
        return reject(
            "scheme.amg_rebuild_interval",
            "must be positive (got 0): 1 rebuilds the AMG hierarchy every step",
        );
    }
    share(
        "scheme.surface_threshold",
        s.surface_threshold,
        "a fraction of n0, about 0.97 is usual",
    )?;
    non_negative(
        "scheme.surface_asymmetry",
        s.surface_asymmetry,
        "0 disables the neighbour-distribution check",
    )?;
    non_negative(
        "scheme.gradient_stabilization",
        s.gradient_stabilization,
        "the weight of the minimum-pressure repulsion",
    )?;
    non_negative(
        "scheme.stabilization_distance",
        s.stabilization_distance,
        "a ratio of particle_spacing",
    )?;
    share(
        "scheme.laplacian_fill_floor",
        s.laplacian_fill_floor,
        "a fraction of n0, 1 disables the renormalisation",
    )?;
    non_negative(
        "scheme.mixed_relaxation",
        s.mixed_relaxation,
        "the relaxation of the PND term",
    )?;
    non_negative(
        "scheme.compressibility",
        s.compressibility,
        "the quasi-compressibility in 1/Pa",
    )?;
    non_negative(
        "scheme.collision_distance",
        s.collision_distance,
        "a ratio of particle_spacing",
    )?;
    if !(0.0..=1.0).contains(&s.collision_restitution) {
        return reject(
            "scheme.collision_restitution",
            format!("must lie in [0, 1] (got {})", s.collision_restitution),
        );
    }
    non_negative(
        "scheme.wall_repulsion_distance",
        s.wall_repulsion_distance,
        "a ratio of particle_spacing",
    )?;
    if !(0.0..=0.5).contains(&s.shifting) {
        return reject(
            "scheme.shifting",
            format!(
                "must lie in [0, 0.5]: a coefficient of l0² per step (got {})",
                s.shifting
            ),
        );
    }
    if !(0.0..=0.5).contains(&s.velocity_filter) {
        return reject(
            "scheme.velocity_filter",
            format!(
                "must lie in [0, 0.5]: the share of the neighbour mean taken per step (got {})",
                s.velocity_filter
            ),
        );
    }
    if s.projection == Projection::Exact {
        share(
            "scheme.exact_projection_blend",
            s.exact_projection_blend,
            "the share of the Laplacian kept in the exact rows",
        )?;
        if s.source == SourceKind::Pnd {
            return reject(
                "scheme.projection",
                "\"exact\" needs a divergence source (higher_order, higher_order_ecs or mixed), not \"pnd\"",
            );
        }
        if s.compressibility != 0.0 {
            return reject(
                "scheme.projection",
                "\"exact\" does not carry the quasi-compressibility: set scheme.compressibility to 0",
            );
        }
    }
    if let Some(v) = s.max_speed {
        positive(
            "scheme.max_speed",
            v,
            "the speed in m/s above which a run fails",
        )?;
    }

    let o = &case.output;
    if let crate::case::LoadInterval::Every(v) = o.load_interval {
        positive(
            "output.load_interval",
            v,
            "the interval between load rows in s (\"auto\": a thousand over the run, null: every step)",
        )?;
    }
    if let crate::case::SnapshotInterval::Every(v) = o.snapshot_interval {
        positive(
            "output.snapshot_interval",
            v,
            "the interval between snapshots in s (\"auto\": ten over the run, \"none\": none)",
        )?;
    }
    if let Some(v) = o.filter_window {
        positive(
            "output.filter_window",
            v,
            "the width of the load filter in s (null: automatic)",
        )?;
    }
    Ok(())
}

// ---------------------------------------------------------------------------
// 3. domain and particle limit

pub(super) fn check_domain(case: &Case) -> Check {
    let d = &case.domain;
    for (axis, name) in [(0, "x"), (1, "y")] {
        if d.min[axis] >= d.max[axis] {
            return reject(
                "domain",
                format!(
                    "domain.min must be below domain.max in {name} (got min {} >= max {})",
                    d.min[axis], d.max[axis]
                ),
            );
        }
    }
    Ok(())
}

pub(super) fn check_particle_limit(case: &Case, limits: &Limits) -> Check {
    if case.fluid_blocks.is_empty() {
        return reject("fluid_blocks", "at least one fluid block is needed");
    }
    let Some(n) = estimated_particles(case) else {
        return Ok(());
    };
    if !n.is_finite() || n.round() > limits.max_particles as f64 {
        return reject(
            "particle_spacing",
            format!(
                "about {:.0} particles (estimated from the fluid block areas / particle_spacing², and / (2 particle_spacing)² outside the fine boxes of a multi-resolution layout) exceed the limit of {}: \
                 use a larger particle_spacing or smaller fluid blocks",
                n, limits.max_particles
            ),
        );
    }
    Ok(())
}

// ---------------------------------------------------------------------------
// damping layers

pub(super) fn check_damping_zones(case: &Case) -> Check {
    for (i, z) in case.damping_zones.iter().enumerate() {
        if z.strength < 0.0 {
            return reject(
                format!("damping_zones[{i}].strength"),
                format!("must be >= 0 (got {})", z.strength),
            );
        }
        let length = (vec2(z.end) - vec2(z.start)).norm();
        if length < 1e-9 {
            return reject(
                format!("damping_zones[{i}].end"),
                "must differ from start: the layer runs from start to end",
            );
        }
    }
    Ok(())
}

/// Explicit fine boxes: each non-empty (min < max), and a scheme whose operators run
/// on a multi-resolution layout.
pub(super) fn check_refinement(case: &Case) -> Check {
    let crate::case::Refinement::Regions(regions) = &case.refinement else {
        return Ok(());
    };
    if regions.fine.is_empty() {
        return reject(
            "refinement.fine",
            "must list at least one box (\"none\" lays out one spacing everywhere)",
        );
    }
    for (k, b) in regions.fine.iter().enumerate() {
        if !(b.min[0] < b.max[0] && b.min[1] < b.max[1]) {
            return reject(
                format!("refinement.fine[{k}]"),
                format!("min {:?} must be below max {:?} in x and y", b.min, b.max),
            );
        }
    }
    if let Some(why) = crate::case::layout::unsupported_by_multi_resolution(&case.scheme) {
        return reject(
            "refinement",
            format!("fine boxes need a multi-resolution scheme: {why} (or set \"none\")"),
        );
    }
    Ok(())
}
