//! Diagnostic: a run's violence over time. Every `EVERY` seconds prints the max speed
//! and where, the count of particles above 5 m/s, the max pressure and where, and the
//! particles removed so far.
//! `cargo run --release --example splash_history -- CASE EVERY [PATH=VALUE]...`
use mpsfsi::case::load_case_file;
use mpsfsi::engine::Simulation;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let case = load_case_file(std::path::Path::new(&args[0]), &args[2..]).unwrap();
    let every: f64 = args[1].parse().unwrap();
    let mut sim = Simulation::new(&case);
    let mut next = 0.0;
    while sim.time < case.time.end {
        let dt = sim.next_dt();
        if let Err(e) = sim.step(dt) {
            println!("failed: {e}");
            break;
        }
        if sim.time >= next {
            next += every;
            let p = &sim.particles;
            let (mut vi, mut vmax, mut pi, mut pmax, mut fast) = (0, 0.0, 0, 0.0, 0);
            let ymax = p.position.iter().map(|x| x.y).fold(f64::MIN, f64::max);
            for i in 0..p.len() {
                let s = p.velocity[i].norm();
                if s > vmax {
                    (vi, vmax) = (i, s);
                }
                if s > 5.0 {
                    fast += 1;
                }
                if p.pressure[i] > pmax {
                    (pi, pmax) = (i, p.pressure[i]);
                }
            }
            println!(
                "t {:.3} dt {dt:.2e} vmax {vmax:.2} at ({:.3},{:.3}) fast {fast} pmax {:.0} at ({:.3},{:.3}) surf {} removed {} n {} ymax {ymax:.3}",
                sim.time,
                p.position[vi].x,
                p.position[vi].y,
                pmax,
                p.position[pi].x,
                p.position[pi].y,
                p.free_surface[pi],
                sim.stats.removed,
                p.len()
            );
        }
    }
}
