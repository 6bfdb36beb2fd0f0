//! What an impact case gets without asking: the step guard, the speed guard from the
//! bodies' jet speed, and a lattice whose mirror lines stay clear of a moving body.

use mpsfsi::case::load_case_file;
use mpsfsi::engine::config::jet_root_speed;
use mpsfsi::engine::scene::MIRROR_CLEARANCE;
use mpsfsi::engine::{Attempt, Simulation};
use mpsfsi::math::{vec2, Vec2};
use std::path::PathBuf;

fn wedge(spacing: f64) -> mpsfsi::case::Case {
    let path =
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("cases/wedge_30deg_constant_velocity.json");
    load_case_file(&path, &[format!("particle_spacing={spacing}")]).unwrap()
}

/// A step the guard turns down leaves every particle as it was, bit for bit, and says
/// how far the farthest particle would have gone; a step within the guard is taken, and
/// gives what it gives a simulation that never tried the long step (both solving to the
/// relative tolerance alone, the 1e-8 the agreement is measured against).
#[test]
fn a_rejected_step_changes_nothing() {
    let started = || {
        let mut case = wedge(0.02);
        case.scheme.solver_energy_tolerance = 0.0;
        let mut sim = Simulation::new(&case);
        for _ in 0..5 {
            let dt = sim.next_dt();
            sim.step(dt).unwrap();
        }
        sim
    };
    let mut sim = started();
    let (x, u, p) = (
        sim.particles.position.clone(),
        sim.particles.velocity.clone(),
        sim.particles.pressure.clone(),
    );
    let (time, steps) = (sim.time, sim.steps);
    let limit = sim.config.control.displacement_limit * sim.config.params.l0;
    // a hundred Courant steps: the wedge moves twenty spacings and the particles under
    // it several
    let long = 100.0 * sim.next_dt();
    match sim.try_step(long).unwrap() {
        Attempt::Rejected { dt, moved } => {
            assert_eq!(dt, long);
            assert!(moved > limit, "moved {moved} within the limit {limit}");
        }
        Attempt::Taken(_) => panic!("a step of a hundred Courant steps was taken"),
    }
    assert!(sim.particles.position == x, "positions changed");
    assert!(sim.particles.velocity == u, "velocities changed");
    assert!(sim.particles.pressure == p, "pressures changed");
    assert_eq!(
        (sim.time, sim.steps, sim.stats.rejected_steps),
        (time, steps, 1)
    );
    let dt = sim.next_dt();
    assert!(matches!(sim.try_step(dt).unwrap(), Attempt::Taken(_)));
    let mut untried = started();
    assert!(matches!(untried.try_step(dt).unwrap(), Attempt::Taken(_)));
    // the preconditioner the turned-down solve refitted is kept (it moves iterates
    // within the solver tolerance, 1e-8): the next step agrees to that, not bit for bit
    let dx = largest_difference(&sim.particles.position, &untried.particles.position);
    assert!(
        dx < 1e-9 * sim.config.params.l0,
        "positions differ by {dx:e} m"
    );
    let (f, f_untried) = (sim.loads[0].force, untried.loads[0].force);
    let df = (f - f_untried).norm() / f_untried.norm();
    assert!(df < 1e-6, "the body's force differs by {df:e} of itself");
}

fn largest_difference(a: &[Vec2], b: &[Vec2]) -> f64 {
    a.iter()
        .zip(b)
        .map(|(a, b)| (a - b).norm())
        .fold(0.0, f64::max)
}

/// The automatic speed limit of a body is six times Wagner's jet-root speed
/// π V / (2 tan β) with β read off the polygon's leading faces.
#[test]
fn the_speed_guard_follows_the_jet_root_speed() {
    let case = wedge(0.01);
    let expected = std::f64::consts::PI * 6.15 / (2.0 * 30f64.to_radians().tan());
    let jet = jet_root_speed(&case.bodies[0], Vec2::zeros(), 0.0);
    assert!((jet / expected - 1.0).abs() < 1e-3, "{jet} vs {expected}");
    let sim = Simulation::new(&case);
    assert!((sim.config.control.speed_limit / (6.0 * expected) - 1.0).abs() < 1e-3);
    // a flat bottom takes the 5° floor instead of an unbounded speed
    let mut flat = case.bodies[0].clone();
    flat.polygon = vec![[-0.25, 0.0], [0.25, 0.0], [0.25, 0.1], [-0.25, 0.1]];
    let floor = std::f64::consts::PI * 6.15 / (2.0 * 5f64.to_radians().tan());
    let jet = jet_root_speed(&flat, Vec2::zeros(), 0.0);
    assert!((jet / floor - 1.0).abs() < 1e-9, "{jet} vs {floor}");
}

/// The wedge sits on the tank's axis, a mirror line of the tank-filling lattice: the
/// scene moves the lattice so that every column is at least l0/8 from the nearest line
/// mirroring the axis, and keeps still water without moving bodies on its lattice.
#[test]
fn a_moving_body_is_kept_off_the_lattice_mirror_lines() {
    for spacing in [0.01, 0.005] {
        let sim = Simulation::new(&wedge(spacing));
        let axis = vec2(wedge(spacing).bodies[0].position).x;
        let half = 0.5 * spacing;
        let off = sim
            .particles
            .position
            .iter()
            .map(|p| {
                let d = p.x - axis;
                (d - half * (d / half).round()).abs()
            })
            .fold(f64::INFINITY, f64::min);
        assert!(
            off >= MIRROR_CLEARANCE * spacing - 1e-12,
            "l0 = {spacing}: a column {off} from a mirror line"
        );
    }
    let still = load_case_file(
        &PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("cases/hydrostatic.json"),
        &[],
    )
    .unwrap();
    let sim = Simulation::new(&still);
    let l0 = still.particle_spacing;
    let first = sim.particles.position[0];
    // fill_polygon puts the lattice's first column l0/2 inside the block's left edge
    let left = still.fluid_blocks[0]
        .polygon
        .iter()
        .map(|p| p[0])
        .fold(f64::INFINITY, f64::min);
    let lattice_x = left + 0.5 * l0;
    let d = (first.x - lattice_x) / l0;
    assert!(
        (d - d.round()).abs() < 1e-9,
        "still water moved off its lattice"
    );
}

/// A run lands on its end time without a sliver of a step (whose pressure, going as
/// 1/dt², reads as a load spike): when a full step would leave less than another, the
/// last two share the rest; no step is then shorter than half the one before it.
#[test]
fn a_run_ends_without_a_sliver_of_a_step() {
    use mpsfsi::run::step_to_end;
    assert_eq!(step_to_end(0.0, 1.0, 0.3), 0.3);
    assert_eq!(step_to_end(0.0, 1.0, 0.6), 0.5);
    assert_eq!(step_to_end(0.5, 1.0, 0.6), 0.5);
    assert_eq!(step_to_end(0.9, 1.0, 0.3), 1.0 - 0.9);
    // a constant step a hair short of dividing the end: the naive clamp ends on 1e-9
    let (end, dt) = (1.0, 0.1 - 1e-10);
    let (mut t, mut steps) = (0.0, Vec::new());
    while t < end * (1.0 - 1e-12) {
        let h = step_to_end(t, end, dt);
        steps.push(h);
        t += h;
    }
    assert!((t - end).abs() < 1e-12, "ends at {t}");
    let shortest = steps.iter().copied().fold(f64::INFINITY, f64::min);
    assert!(shortest >= 0.5 * dt, "shortest step {shortest} of {dt}");
}
