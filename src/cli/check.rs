//! `mpsfsi check CASE [--set PATH=VALUE]...`: validate, build the scene, report.

use super::report_case_error;
use mpsfsi::analysis::envelope::impact_advice;
use mpsfsi::case::{estimated_particles, load_case_file, validate, CaseError, Limits};
use mpsfsi::engine::params::MpsParameters;
use mpsfsi::engine::scene::build_scene;
use mpsfsi::run::estimate_steps;
use std::path::Path;

pub fn check(case_path: &Path, overrides: &[String], max_particles: Option<usize>) -> i32 {
    let case = match load_case_file(case_path, overrides) {
        Ok(case) => case,
        Err(e) => return report_case_error(&e),
    };
    let mut limits = Limits::default();
    if let Some(m) = max_particles {
        limits.max_particles = m;
    }
    if let Err(e) = validate(&case, &limits) {
        return report_case_error(&e);
    }
    let params = MpsParameters::new(&case);
    let scene = build_scene(&case, &params);
    let particles = scene.particles.len();
    if particles == 0 {
        return report_case_error(&CaseError::new(
            "fluid_blocks",
            "no fluid particle remains (the blocks are smaller than one spacing, or lie inside walls or bodies)",
        ));
    }
    let s = &case.scheme;
    println!("case {}: valid", case.name);
    println!(
        "particles: {particles} (estimate from block areas: {:.0})",
        estimated_particles(&case).unwrap_or(0.0)
    );
    let count = |scale: f64| scene.particles.count_of_scale(scale);
    let (coarse, far) = (count(2.0), count(4.0));
    let l0 = case.particle_spacing;
    if far > 0 {
        println!(
            "layout: multi-resolution, {} particles of {l0} m, {coarse} of {} m and {far} of {} m (refinement)",
            particles - coarse - far,
            2.0 * l0,
            4.0 * l0
        );
    } else if coarse > 0 {
        println!(
            "layout: multi-resolution, {} particles of {l0} m and {coarse} of {} m (refinement)",
            particles - coarse,
            2.0 * l0
        );
    } else {
        println!("layout: one spacing, {} m", case.particle_spacing);
    }
    println!(
        "estimated steps: {} (end time {} s, cfl {}, max_dt {} s)",
        estimate_steps(&case),
        case.time.end,
        case.time.cfl,
        case.time.max_dt
    );
    for advice in impact_advice(&case) {
        println!("advice: {advice}");
    }
    println!(
        "walls: {}, bodies: {}, probes: {}",
        case.walls.len(),
        case.bodies.len(),
        case.output.probes.len()
    );
    println!(
        "kernel: {} with r_e = {} l0 = {:.6} m, Laplacian r_e = {} l0 = {:.6} m, n0 = {:.6}, lambda = {:.6e} m²",
        name_of(&s.kernel),
        s.radius,
        params.re,
        s.laplacian_radius(),
        params.re_lap,
        params.n0,
        params.lambda
    );
    println!(
        "scheme: gradient {}, laplacian {}, source {}, solver {}",
        name_of(&s.gradient),
        name_of(&s.laplacian),
        name_of(&s.source),
        name_of(&s.solver)
    );
    0
}

/// The serde name of a unit enum variant (`higher_order`).
fn name_of<T: serde::Serialize>(value: &T) -> String {
    serde_json::to_value(value)
        .ok()
        .and_then(|v| v.as_str().map(str::to_string))
        .unwrap_or_default()
}
