use mpsfsi::case::load_case_file;
use mpsfsi::engine::Simulation;
fn main() {
    let args: Vec<String> = std::env::args().skip(2).collect();
    let steps: usize = std::env::args().nth(1).unwrap().parse().unwrap();
    let case = load_case_file(std::path::Path::new(&args[0]), &args[1..]).unwrap();
    let mut sim = Simulation::new(&case);
    for s in 0..steps {
        let dt = sim.next_dt(); sim.step(dt).unwrap();
        if (s + 1) % (steps / 4).max(1) == 0 {
            let p = &sim.particles;
            let mut idx: Vec<usize> = (0..p.len()).collect();
            idx.sort_by(|a, b| p.velocity[*b].norm().partial_cmp(&p.velocity[*a].norm()).unwrap());
            println!("after step {} t {:.4} fy {:.0}", s + 1, sim.time, sim.loads[0].force.y);
            for &i in idx.iter().take(8) {
                println!("  ({:.4},{:.4}) |u| {:.4} u ({:+.4},{:+.4}) p {:8.1} n {:.3} surf {}", p.position[i].x, p.position[i].y, p.velocity[i].norm(), p.velocity[i].x, p.velocity[i].y, p.pressure[i], p.number_density[i]/sim.params.n0, p.free_surface[i]);
            }
        }
    }
}
