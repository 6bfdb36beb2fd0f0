//! Diagnostic: the still tank with its lattice perturbed by ±0.2 l0 (the stress scene),
//! printing the tank load against the water weight and the largest speed every 0.25 s.
//! `cargo run --release --example perturbed_tank -- cases/hydrostatic.json END [PATH=VALUE]...`
use mpsfsi::bench::perturb::{perturb_positions, PERTURBATION_SEED};
use mpsfsi::bench::stress::PERTURBATION;
use mpsfsi::case::load_case_file;
use mpsfsi::engine::Simulation;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let end: f64 = args[1].parse().unwrap();
    let case = load_case_file(std::path::Path::new(&args[0]), &args[2..]).unwrap();
    let mut sim = Simulation::new(&case);
    let l0 = case.particle_spacing;
    // AMP overrides the stress scene's ±0.2 (ratio of l0): a tiny one measures growth rates
    let amplitude = std::env::var("AMP")
        .ok()
        .and_then(|a| a.parse().ok())
        .unwrap_or(PERTURBATION);
    perturb_positions(
        &mut sim.particles.position,
        amplitude * l0,
        PERTURBATION_SEED,
    );
    sim.initialize();
    let weight = sim.particle_count() as f64 * 1000.0 * l0 * l0 * 9.81;
    // EVERY: print interval (s)
    let every: f64 = std::env::var("EVERY")
        .ok()
        .and_then(|a| a.parse().ok())
        .unwrap_or(0.25);
    let mut next = every;
    while sim.time < end {
        let dt = sim.next_dt();
        if let Err(e) = sim.step(dt) {
            println!("{e}");
            break;
        }
        if sim.time >= next - 1e-9 {
            println!(
                "t {:5.2}  load {:+9.5}%  vmax {:10.5} mm/s",
                sim.time,
                100.0 * (-sim.loads[0].force.y / weight - 1.0),
                1e3 * sim.max_particle_speed()
            );
            next += every;
            // TOP=k: where the k fastest particles are (the shape of a growing mode)
            if let Some(k) = std::env::var("TOP")
                .ok()
                .and_then(|a| a.parse::<usize>().ok())
            {
                let u = &sim.particles.velocity;
                let mut order: Vec<usize> = (0..u.len()).collect();
                order.sort_by(|&a, &b| u[b].norm().total_cmp(&u[a].norm()));
                for &i in order.iter().take(k) {
                    let x = sim.particles.position[i];
                    println!(
                        "   ({:.3}, {:.3}) u = ({:+.4}, {:+.4}) mm/s surface {}",
                        x.x,
                        x.y,
                        1e3 * u[i].x,
                        1e3 * u[i].y,
                        sim.particles.free_surface[i]
                    );
                }
            }
        }
    }
}
