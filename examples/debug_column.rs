use mpsfsi::case::load_case_file;
use mpsfsi::engine::Simulation;
fn main() {
    let args: Vec<String> = std::env::args().skip(2).collect();
    let steps: usize = std::env::args().nth(1).unwrap().parse().unwrap();
    let case = load_case_file(std::path::Path::new(&args[0]), &args[1..]).unwrap();
    let mut sim = Simulation::new(&case);
    for s in 0..steps {
        let dt = sim.next_dt();
        let r = sim.step(dt);
        let p = &sim.particles;
        let (mut im, mut vm) = (0, 0.0);
        for i in 0..p.len() { let v = p.velocity[i].norm(); if v > vm { vm = v; im = i; } }
        let nmax = p.number_density.iter().cloned().fold(0.0, f64::max) / sim.params.n0;
        let nmin = p.number_density.iter().cloned().fold(1e9, f64::min) / sim.params.n0;
        println!("step {s} dt {dt:.5} it {:?} fy {:.1} vmax {vm:.4} at ({:.4},{:.4}) p {:.1} n {:.3} surf {} | nmax {nmax:.3} nmin {nmin:.3}",
            r.as_ref().map(|i| i.solver_iterations), sim.loads[0].force.y, p.position[im].x, p.position[im].y, p.pressure[im], p.number_density[im]/sim.params.n0, p.free_surface[im]);
        if r.is_err() { println!("{:?}", r); break; }
    }
}
