//! Bodies at rest in still water: buoyancy of a fixed submerged body and the
//! equilibrium draft of a floating box (Archimedes; references.md, Hydrostatics).

use crate::common::*;
use mpsfsi::coupling::CouplingOptions;

/// A 0.4 m x 0.2 m box held fixed 0.15 m below the surface of still water carries
/// rho g A = 784.8 N/m upward (mean over the last 0.1 s of 0.4 s), within 2 %.
/// Measured with the pressure-integral load: 784.80 N/m (+0.00 %); the reaction of the
/// wall terms read -5.25 % here.
#[test]
fn fixed_submerged_body_carries_its_buoyancy() {
    let g = 9.81;
    let case = shipped(
        "floating_box.json",
        &[
            "bodies.0.position=[0.0, -0.35]".into(),
            r#"bodies.0.motion={"type": "prescribed", "velocity": [0.0, 0.0]}"#.into(),
        ],
    );
    let area = 0.4 * 0.2;
    let expect = RHO * g * area;
    let trace = run(&case, CouplingOptions::default(), Some(0.4), |_| {});
    assert!(trace.error.is_none(), "{:?}", trace.error);
    let k = trace.wall("box");
    let late: Vec<_> = trace.steps.iter().filter(|s| s.time > 0.3).collect();
    let duration: f64 = late.iter().map(|s| s.dt).sum();
    let fy = late.iter().map(|s| s.force[k].y * s.dt).sum::<f64>() / duration;
    let fx = late.iter().map(|s| s.force[k].x * s.dt).sum::<f64>() / duration;
    let err = (fy - expect) / expect;
    println!(
        "buoyancy: F_y = {fy:.2} N/m vs rho g A = {expect:.2} N/m ({:+.2} %), F_x = {fx:.2} N/m, {} particles, {} steps, {:.1} s",
        100.0 * err,
        trace.particles,
        trace.steps.len(),
        trace.wall_seconds
    );
    assert!(err.abs() < 0.02, "buoyancy off by {:.2} %", 100.0 * err);
    assert!(
        fx.abs() < 0.02 * expect,
        "net horizontal force {fx:.2} N/m on a symmetric body"
    );
}

/// A box of half the density of water (0.4 m wide, 40 kg/m) released 1 cm above its
/// equilibrium heaves to rest at the draft d = M / (rho b) = 0.1 m (within 2 %),
/// measured from the mean water level (fluid volume / tank width), and its heave decays.
#[test]
#[ignore = "fails: draft -6.4 % from the mean water level (+4.5 % from the highest particle away from the box, which the waves bias up); heave amplitude 8.2 mm in the first second, 7.0 mm in the last (the closed 2 m tank keeps the radiated waves); 4 s simulated, about a minute on two cores"]
fn floating_box_settles_at_archimedes_draft() {
    let case = shipped("floating_box.json", &[]);
    let expect = 40.0 / (RHO * 0.4);
    let l0 = case.particle_spacing;
    let mut levels = Vec::new();
    let trace = run(&case, CouplingOptions::default(), None, |sim| {
        // free surface away from the box: top of the particles with 0.5 < |x| < 0.9
        let top = sim
            .particles
            .position
            .iter()
            .filter(|p| p.x.abs() > 0.5 && p.x.abs() < 0.9)
            .map(|p| p.y)
            .fold(f64::NEG_INFINITY, f64::max);
        levels.push(top + 0.5 * l0);
    });
    assert!(trace.error.is_none(), "{:?}", trace.error);
    let end = trace.steps.last().unwrap().time;
    // centroid is 0.1 m above the bottom
    let bottom: Vec<f64> = trace.steps.iter().map(|s| s.bodies[0].y - 0.1).collect();
    let window = |from: f64, to: f64| -> Vec<usize> {
        (0..trace.steps.len())
            .filter(|&i| trace.steps[i].time >= from && trace.steps[i].time < to)
            .collect()
    };
    let last = window(end - 1.0, end + 1.0);
    let mean = |idx: &[usize], f: &dyn Fn(usize) -> f64| {
        idx.iter().map(|&i| f(i)).sum::<f64>() / idx.len() as f64
    };
    // The mean free-surface level from the fluid's volume (N l0², conserved), which the
    // sloshing of the closed tank does not bias: h = y_tank + (N l0² + b d) / W with
    // d = h - y_bottom gives d = (y_tank + N l0² / W - y_bottom) / (1 - b / W).
    let (width, tank_bottom, breadth) = (2.0, -0.5, 0.4);
    let volume = trace.particles as f64 * l0 * l0;
    let draft =
        (tank_bottom + volume / width - mean(&last, &|i| bottom[i])) / (1.0 - breadth / width);
    // the highest particle away from the box, as a second reading (waves bias it up)
    let draft_from_top = mean(&last, &|i| levels[i] - bottom[i]);
    let err = (draft - expect) / expect;
    let amplitude = |idx: &[usize]| {
        let m = mean(idx, &|i| bottom[i]);
        idx.iter()
            .map(|&i| (bottom[i] - m).abs())
            .fold(0.0, f64::max)
    };
    let (a_first, a_last) = (amplitude(&window(0.0, 1.0)), amplitude(&last));
    println!(
        "floating box: draft {draft:.4} m vs {expect:.4} m ({:+.2} %; from the highest particle away from the box {draft_from_top:.4} m), heave amplitude first second {:.4} m, last second {:.4} m, {} steps, {:.1} s",
        100.0 * err,
        a_first,
        a_last,
        trace.steps.len(),
        trace.wall_seconds
    );
    assert!(err.abs() < 0.02, "draft off by {:.2} %", 100.0 * err);
    assert!(
        a_last < 0.5 * a_first,
        "heave does not decay: {a_first:.4} -> {a_last:.4} m"
    );
}
