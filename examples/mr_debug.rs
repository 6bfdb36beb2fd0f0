use mpsfsi::case::{apply_override, parse_case_value};
use mpsfsi::engine::Simulation;
fn main() {
    let args: Vec<String> = std::env::args().collect();
    let text = std::fs::read_to_string(&args[1]).unwrap();
    let mut v: serde_json::Value = serde_json::from_str(&text).unwrap();
    for a in &args[3..] {
        apply_override(&mut v, a).unwrap();
    }
    let case = parse_case_value(v).unwrap();
    let mut sim = Simulation::new(&case);
    let steps: usize = args[2].parse().unwrap();
    let n0 = sim.config.params.n0;
    let g = 9.81 * 1000.0;
    for s in 0..steps {
        let dt = sim.next_dt();
        sim.step(dt).unwrap();
        let p = &sim.particles;
        let mut idx: Vec<usize> = (0..p.len()).collect();
        idx.sort_by(|&a, &b| p.velocity[b].norm().total_cmp(&p.velocity[a].norm()));
        println!(
            "step {s} dt {dt:.2e} maxu {:.3e} loads {:?} contacts {}",
            p.velocity[idx[0]].norm(),
            sim.loads.iter().map(|l| l.force).collect::<Vec<_>>(),
            sim.wall_contacts().contacts.len()
        );
        if s + 1 == steps || s < 2 {
            for &i in idx.iter().take(8) {
                let x = p.position[i];
                println!("  i {i} x ({:.4},{:.4}) s {} u ({:.2e},{:.2e}) n/n0 {:.4} fs {} p {:.1} hyd {:.1}",
                    x.x, x.y, p.scale[i], p.velocity[i].x, p.velocity[i].y, p.number_density[i]/n0, p.free_surface[i], p.pressure[i], g*(0.5-x.y));
            }
        }
    }
}
