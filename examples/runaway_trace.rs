//! Diagnostic: the last steps before a run fails, around one particle. Prints dt, and for
//! the particle and its neighbours within 3 l0: position, velocity, pressure, free-surface
//! flag and number density / n0, after each step from `FROM` on.
//! `cargo run --release --example runaway_trace -- CASE PARTICLE FROM [PATH=VALUE]...`
use mpsfsi::case::load_case_file;
use mpsfsi::engine::Simulation;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let case = load_case_file(std::path::Path::new(&args[0]), &args[3..]).unwrap();
    let focus: usize = args[1].parse().unwrap();
    let from: u64 = args[2].parse().unwrap();
    let mut sim = Simulation::new(&case);
    let l0 = case.particle_spacing;
    while sim.time < case.time.end {
        let dt = sim.next_dt();
        let result = sim.step(dt);
        if sim.steps >= from {
            let p = &sim.particles;
            let c = p.position[focus];
            println!(
                "step {} dt {dt:.3e} vmax {:.2}",
                sim.steps,
                sim.max_particle_speed()
            );
            for i in 0..p.len() {
                let x = p.position[i];
                if (x - c).norm() < 3.0 * l0 {
                    println!(
                        "  {}{i} x ({:.5}, {:.5}) u ({:.3}, {:.3}) p {:.1} surface {} n/n0 {:.3}",
                        if i == focus { "*" } else { " " },
                        x.x,
                        x.y,
                        p.velocity[i].x,
                        p.velocity[i].y,
                        p.pressure[i],
                        p.free_surface[i],
                        p.number_density[i] / sim.config.params.n0
                    );
                }
            }
        }
        if let Err(e) = result {
            println!("{e}");
            break;
        }
    }
}
