//! Diagnostic: the dam-break surge front against Martin & Moyce at their sample times.
//! `cargo run --release --example dam_front -- cases/dam_break.json [PATH=VALUE]...`
use mpsfsi::case::load_case_file;
use mpsfsi::engine::Simulation;
fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let case = load_case_file(std::path::Path::new(&args[0]), &args[1..]).unwrap();
    let a: f64 = 0.146;
    let g: f64 = 9.81;
    let mut sim = Simulation::new(&case);
    let t0 = std::time::Instant::now();
    let tt = [
        0.41, 0.84, 1.19, 1.43, 1.63, 1.83, 1.98, 2.20, 2.32, 2.51, 2.65, 2.83, 2.98, 3.11, 3.33,
    ];
    let zz = [
        1.11, 1.22, 1.44, 1.67, 1.89, 2.11, 2.33, 2.56, 2.78, 3.00, 3.22, 3.44, 3.67, 3.89, 4.11,
    ];
    let mut k = 0;
    while sim.time < case.time.end && k < tt.len() {
        let dt = sim.next_dt();
        if let Err(e) = sim.step(dt) {
            println!("{e}");
            break;
        }
        let t_nd = sim.time * (2.0 * g / a).sqrt();
        if t_nd >= tt[k] {
            let front = sim
                .particles
                .position
                .iter()
                .map(|p| p.x)
                .fold(0.0, f64::max)
                / a;
            println!(
                "T {:.2} Z {:.3} ref {:.2} err {:+.1}% steps {} vmax {:.2}",
                t_nd,
                front,
                zz[k],
                (front / zz[k] - 1.0) * 100.0,
                sim.steps,
                sim.max_particle_speed()
            );
            k += 1;
        }
    }
    println!(
        "particles {} wall {:.1}s iters/step {:.0}",
        sim.particle_count(),
        t0.elapsed().as_secs_f64(),
        sim.stats.total_solver_iterations as f64 / sim.steps as f64
    );
}
