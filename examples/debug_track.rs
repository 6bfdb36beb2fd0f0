use mpsfsi::case::load_case_file;
use mpsfsi::engine::Simulation;
fn main() {
    let args: Vec<String> = std::env::args().skip(4).collect();
    let steps: usize = std::env::args().nth(1).unwrap().parse().unwrap();
    let tx: f64 = std::env::args().nth(2).unwrap().parse().unwrap();
    let ty: f64 = std::env::args().nth(3).unwrap().parse().unwrap();
    let case = load_case_file(std::path::Path::new(&args[0]), &args[1..]).unwrap();
    let mut sim = Simulation::new(&case);
    let p = &sim.particles;
    let id = (0..p.len()).min_by(|a, b| ((p.position[*a] - nalgebra::Vector2::new(tx, ty)).norm()).partial_cmp(&(p.position[*b] - nalgebra::Vector2::new(tx, ty)).norm()).unwrap()).unwrap();
    let nb: Vec<usize> = (0..p.len()).filter(|&j| (p.position[j] - p.position[id]).norm() < 0.0155 && j != id).collect();
    for s in 0..steps {
        let dt = sim.next_dt(); sim.step(dt).unwrap();
        let p = &sim.particles;
        let mut line = format!("{s:4} i ({:.4},{:.5}) v ({:+.4},{:+.4}) p {:7.1} n {:.4} div {:+.3} |", p.position[id].x, p.position[id].y, p.velocity[id].x, p.velocity[id].y, p.pressure[id], p.number_density[id]/sim.params.n0, p.number_density_rate[id]);
        for &j in nb.iter().take(4) { line += &format!(" vy{:+.4} p{:6.0}", p.velocity[j].y, p.pressure[j]); }
        println!("{line}");
    }
}
