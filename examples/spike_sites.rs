//! Diagnostic: at each step, the force on body 0 and the three particles whose pressure
//! departs most from hydrostatic, with their position relative to the body's position.
//! `cargo run --release --example spike_sites -- CASE [PATH=VALUE]...`
use mpsfsi::case::load_case_file;
use mpsfsi::coupling::Coupling;
use mpsfsi::engine::Simulation;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let case = load_case_file(std::path::Path::new(&args[0]), &args[1..]).unwrap();
    let end: f64 = std::env::var("END")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(0.012);
    let mut sim = Simulation::new(&case);
    let mut coupling = Coupling::new(&case, &sim).unwrap();
    let k = sim.walls.iter().position(|w| w.body.is_some()).unwrap();
    let l0 = case.particle_spacing;
    let top = sim
        .particles
        .position
        .iter()
        .map(|p| p.y)
        .fold(f64::MIN, f64::max)
        + 0.5 * l0;
    let g = -case.fluid.gravity[1];
    while sim.time < end {
        let dt = sim.next_dt();
        coupling.before_step(&mut sim, dt);
        sim.step(dt).unwrap();
        coupling.after_step(&mut sim, dt);
        let c = sim.walls[k].state.position;
        let p = &sim.particles;
        let mut dev: Vec<(f64, usize)> = (0..p.len())
            .map(|i| ((p.pressure[i] - 1000.0 * g * (top - p.position[i].y)), i))
            .collect();
        dev.sort_by(|a, b| b.0.abs().partial_cmp(&a.0.abs()).unwrap());
        let mut line = format!(
            "t {:6.3} ms F ({:8.0},{:8.0}) |",
            1e3 * sim.time,
            sim.loads[k].force.x,
            sim.loads[k].force.y
        );
        for (d, i) in dev.iter().take(3) {
            let r = (p.position[*i] - c) / l0;
            line += &format!(
                " dp {:7.0} at ({:6.2},{:6.2}) l0 n/n0 {:.3} |",
                d,
                r.x,
                r.y,
                p.number_density[*i] / sim.config.params.n0
            );
        }
        println!("{line}");
    }
}
