use mpsfsi::case::load_case_file;
use mpsfsi::engine::Simulation;
fn main() {
    let args: Vec<String> = std::env::args().skip(2).collect();
    let steps: usize = std::env::args().nth(1).unwrap().parse().unwrap();
    let case = load_case_file(std::path::Path::new(&args[0]), &args[1..]).unwrap();
    let mut sim = Simulation::new(&case);
    for _ in 0..steps { let dt = sim.next_dt(); sim.step(dt).unwrap(); }
    let p = &sim.particles;
    for yrow in [0.005, 0.015, 0.025] {
        let mut row: Vec<usize> = (0..p.len()).filter(|&i| (p.position[i].y - yrow).abs() < 0.004 && p.position[i].x < 0.12).collect();
        row.sort_by(|a, b| p.position[*a].x.partial_cmp(&p.position[*b].x).unwrap());
        for i in row { println!("x {:.4} y {:.4} p {:8.1} u ({:+.5},{:+.5}) n/n0 {:.4} div {:+.4}", p.position[i].x, p.position[i].y, p.pressure[i], p.velocity[i].x, p.velocity[i].y, p.number_density[i]/sim.params.n0, p.number_density_rate[i]); }
        println!();
    }
}
