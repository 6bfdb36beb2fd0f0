//! Dam break (Koshizuka & Oka 1996 geometry, l0 = a/40) against Martin & Moyce (1952).
//!
//! The front runs 13-21 % ahead of the experiment over 1 <= T <= 3 (+21.0 % at
//! T = 1.19 falling to +14.4 % at 2.83), and the gap does not shrink from a/40 to a/60.
//! It is a delay, not a speed: the experiment reaches each simulated front position
//! 0.29-0.33 later in T (mean 0.31) at every sample from T = 0.84 to 2.83, 17 ms at
//! Martin & Moyce's a = 57 mm, the order of a gate's release. The delay converges with
//! resolution: mean 0.262 / 0.281 / 0.310 / 0.317 at a/20 / a/30 / a/40 / a/60, spread
//! at most 0.032 at each. docs/references.md attributes the early times to the release. At
//! T = 0.41 the two agree (1.10 against 1.11): water leaves under a rising gate before
//! the column falls. Neither a turbulent wall friction nor viscosity closes the gap
//! without being fitted: a log-law wall shear on the first row changes the front by
//! under 1 %, and a uniform eddy viscosity brings it within 10 % only at about
//! 3e-3 m²/s, ten times a mixing-length estimate for this flow (kappa u_tau y,
//! 2e-4-5e-4).
//! This test therefore asserts (a) the position within 25 % for 1 <= T <= 3 (looser
//! than the issue's 10 % target, which is NOT met) and (b) that the front history is
//! the experiment's delayed by a constant: the delay varies by under 0.1 across the
//! window and lies in 0..0.45.
//!
//! The same run also follows Martin & Moyce's second measurement, the residual column
//! height at the back wall, which the gate release and the bottom friction barely touch:
//! within 0.2-5.2 % over 0.56 <= t sqrt(g/a) <= 2.0 (largest at 1.84), asserted within
//! 6 %. The bulk of the collapse is right; the disagreement is at the tip of the surge.

use super::shipped_case;
use mpsfsi::bench::stress::DAM_BREAK_LONG_CFL;
use mpsfsi::engine::Simulation;

/// (t sqrt(g/a), H/(2a)) of the residual column, from docs/references.md.
use mpsfsi::analysis::reference::MARTIN_MOYCE_COLUMN;
/// (T, Z) of Martin & Moyce (1952), n² = 2, from docs/references.md (one table for the
/// benchmark and this test).
use mpsfsi::analysis::reference::MARTIN_MOYCE_SURGE as MARTIN_MOYCE;

#[test]
fn surge_front_follows_martin_and_moyce() {
    surge_front_and_column(&shipped_case("dam_break.json", &["time.end=0.265"]), 0.06);
}

/// The same dam break on a two-level layout: fine (l0 = a/40) in the lowest a/2, where
/// the surge runs, and 2 l0 above it, so the column's coarse particles fall through the
/// jump into the fine band and run along the floor with the fine ones. The surge front
/// keeps the bounds of one spacing (it reads within 1.2 % of the uniform run's, delay
/// 0.21-0.26 against 0.23-0.26). The residual column's top is coarse, so it is held to
/// 10 %: it reads what a uniform run at 2 l0 reads (H/2a 0.515 against 0.560 at
/// t sqrt(g/a) = 1.84, -8.0 %, in both).
#[test]
fn surge_front_follows_martin_and_moyce_across_a_resolution_jump() {
    let case = shipped_case(
        "dam_break.json",
        &[
            "time.end=0.265",
            r#"refinement={"fine": [{"min": [-0.05, -0.05], "max": [0.65, 0.073]}]}"#,
        ],
    );
    let sim = Simulation::new(&case);
    let coarse = sim.particles.count_of_scale(2.0);
    assert!(
        coarse >= 500 && coarse < sim.particles.len(),
        "{coarse} of {} particles coarse",
        sim.particles.len()
    );
    surge_front_and_column(&case, 0.10);
}

fn surge_front_and_column(case: &mpsfsi::case::Case, column_tolerance: f64) {
    let a: f64 = 0.146;
    let g: f64 = 9.81;
    let mut sim = Simulation::new(case);
    let l0 = case.particle_spacing;
    let mut front = Vec::new(); // (T, Z) at the reference times
    let mut column = Vec::new(); // (t sqrt(g/a), H/2a, reference)
    let (mut k, mut kc) = (0, 0);
    while sim.time < case.time.end && k < MARTIN_MOYCE.len() {
        let dt = sim.next_dt();
        sim.step(dt)
            .unwrap_or_else(|e| panic!("dam break failed: {e}"));
        let tc = sim.time * (g / a).sqrt();
        if kc < MARTIN_MOYCE_COLUMN.len() && tc >= MARTIN_MOYCE_COLUMN[kc].0 {
            // the column at the back wall: highest particle within 2 l0 of it
            let h = sim
                .particles
                .position
                .iter()
                .filter(|p| p.x < 2.0 * l0)
                .map(|p| p.y)
                .fold(0.0, f64::max);
            column.push((tc, h / (2.0 * a), MARTIN_MOYCE_COLUMN[kc].1));
            kc += 1;
        }
        let t = sim.time * (2.0 * g / a).sqrt();
        if t >= MARTIN_MOYCE[k].0 {
            let x = sim
                .particles
                .position
                .iter()
                .map(|p| p.x)
                .fold(0.0, f64::max);
            front.push((t, x / a, MARTIN_MOYCE[k].1));
            k += 1;
        }
    }
    println!("residual column (t*, H/2a, Martin & Moyce): {column:.3?}");
    assert!(column.len() >= 9, "column reached t* = {:?}", column.last());
    for (t, h, h_ref) in &column {
        let err = h / h_ref - 1.0;
        assert!(
            err.abs() < column_tolerance,
            "t sqrt(g/a) = {t:.2}: H/2a = {h:.3} vs {h_ref} ({:+.1}%)",
            100.0 * err
        );
    }
    println!("surge front (T, Z, Martin & Moyce): {front:.3?}");
    let in_window: Vec<_> = front
        .iter()
        .filter(|(t, _, _)| (1.0..=3.0).contains(t))
        .collect();
    assert!(in_window.len() >= 10, "reached T = {:?}", front.last());
    for (t, z, z_ref) in &in_window {
        let err = z / z_ref - 1.0;
        assert!(
            err.abs() < 0.25,
            "T = {t:.2}: Z = {z:.3} vs {z_ref} ({:+.1}%)",
            100.0 * err
        );
    }
    // (b) the front history is the experiment's, delayed by a constant: for each
    // simulated position, the time at which Martin & Moyce's front reached it, minus the
    // time here. A front speed off by 6 % would drift this delay by more than 0.1 over
    // the window. The tank is 4a wide: the front stops on its far wall (Z = 4), so
    // positions within l0 of it are left out.
    let far_wall = 4.0 - l0 / a;
    let delays: Vec<(f64, f64)> = in_window
        .iter()
        .filter(|(_, z, _)| *z < far_wall)
        .map(|(t, z, _)| (*t, experiment_time(*z) - t))
        .collect();
    println!("delay behind Martin & Moyce (T, experiment's T at the same Z minus T): {delays:.3?}");
    assert!(
        delays.len() >= 9,
        "too few samples before the far wall: {delays:?}"
    );
    let (lo, hi) = delays
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), (_, d)| {
            (lo.min(*d), hi.max(*d))
        });
    assert!(
        hi - lo < 0.1,
        "the delay behind the experiment drifts from {lo:.3} to {hi:.3}: the front speed is off"
    );
    // a release lag of at most 0.45 (24 ms at Martin & Moyce's a = 57 mm)
    assert!(
        lo > 0.0 && hi < 0.45,
        "delay {lo:.3}..{hi:.3} outside 0..0.45"
    );
}

/// The time T at which Martin & Moyce's front reached Z (linear between their samples).
fn experiment_time(z: f64) -> f64 {
    let k = MARTIN_MOYCE
        .windows(2)
        .position(|w| z <= w[1].1)
        .unwrap_or_else(|| panic!("Z = {z:.3} is beyond Martin & Moyce's table"));
    let ((t0, z0), (t1, z1)) = (MARTIN_MOYCE[k], MARTIN_MOYCE[k + 1]);
    t0 + (z - z0) / (z1 - z0) * (t1 - t0)
}

/// Stress (issue 6): the dam break to 5 s at a/40, through the impact on the far wall, the
/// overturning wave and its plunge back into the flow, completes (a few runaway spray
/// particles removed within the allowance are allowed) with finite velocities throughout.
/// The shipped case is set up for it: walls 1.2 m high, so the run-up on the far wall
/// (a sheet to 1.03 m at 0.7 s) stays in the tank (with walls and domain at 0.45/0.5 m,
/// 5.3 % of the water left through the top by 0.56 s and the rest ran), and
/// `scheme.laplacian_fill_floor` 0.3. Without the floor the run fails at 0.88 s (CFL
/// 0.1). With it, it completes at CFL 0.1 and 0.12 (0 runaways) and fails at 0.2 (1.14
/// s); the case's 0.15 is on the edge: it completed, and then failed at 2.96 s after a
/// round-off change (one product reordered). So this run takes the stress scene's
/// `DAM_BREAK_LONG_CFL` (0.1).
#[test]
#[ignore = "long: about 4 minutes on two cores (the full `bench --stress` runs it too)"]
fn dam_break_runs_to_five_seconds() {
    let cfl = format!("time.cfl={DAM_BREAK_LONG_CFL}");
    let case = shipped_case("dam_break.json", &["time.end=5.0", &cfl]);
    let mut sim = Simulation::new(&case);
    while sim.time < case.time.end {
        let dt = sim.next_dt();
        sim.step(dt)
            .unwrap_or_else(|e| panic!("dam break to 5 s failed: {e}"));
        assert!(
            sim.particles
                .velocity
                .iter()
                .all(|u| u.x.is_finite() && u.y.is_finite()),
            "non-finite velocity at t = {}",
            sim.time
        );
    }
}
