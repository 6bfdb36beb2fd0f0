//! Diagnostic: at the end of a run (END s, default the case's), compare the pressure down
//! vertical lines with rho g (h - y), where h is the mean water level from the fluid's
//! volume (N l0² over the tank width W, plus the displaced body area), and print the
//! local surface (highest particle per lattice column + l0/2) around each line.
//! `W=4 cargo run --release --example level_check -- CASE [PATH=VALUE]...`
use mpsfsi::case::load_case_file;
use mpsfsi::coupling::Coupling;
use mpsfsi::engine::Simulation;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let case = load_case_file(std::path::Path::new(&args[0]), &args[1..]).unwrap();
    let end: f64 = std::env::var("END")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(case.time.end);
    let width: f64 = std::env::var("W")
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(4.0);
    let bottom: f64 = -0.5;
    let mut sim = Simulation::new(&case);
    let mut coupling = Coupling::new(&case, &sim);
    while sim.time < end {
        let dt = sim.next_dt();
        if let Some(c) = coupling.as_mut() {
            c.before_step(&mut sim, dt);
        }
        sim.step(dt).unwrap();
        if let Some(c) = coupling.as_mut() {
            c.after_step(&mut sim, dt);
        }
    }
    let l0 = case.particle_spacing;
    let p = &sim.particles;
    // displaced area of a box body: its polygon below the level (iterate once)
    let mut level = bottom + p.len() as f64 * l0 * l0 / width;
    for w in sim.walls.iter().filter(|w| w.body.is_some()) {
        let y_body = w.state.position.y; // box polygon from y = 0 in the body frame
        for _ in 0..3 {
            let sub = (level - y_body).max(0.0);
            level = bottom + (p.len() as f64 * l0 * l0 + 0.4 * sub) / width;
        }
        println!(
            "body bottom {:.4}, draft from the volume level {:.4}",
            y_body,
            level - y_body
        );
    }
    println!(
        "volume level {level:.4}; body loads {:?}",
        sim.loads
            .iter()
            .map(|l| (l.force.y, l.repulsion_force.y))
            .collect::<Vec<_>>()
    );
    for x0 in [0.0, 0.1, 0.3, 0.5, 0.7, 1.5] {
        let near: Vec<usize> = (0..p.len())
            .filter(|&i| (p.position[i].x - x0).abs() < 0.5 * l0)
            .collect();
        let top = near
            .iter()
            .map(|&i| p.position[i].y)
            .fold(f64::MIN, f64::max)
            + 0.5 * l0;
        let mut line = format!(
            "x {x0}: local surface {top:.4} ({:+.1} mm):",
            1e3 * (top - level)
        );
        for depth in [0.05, 0.1, 0.2, 0.4] {
            let y = level - depth;
            let j = *near
                .iter()
                .min_by(|&&a, &&b| {
                    (p.position[a].y - y)
                        .abs()
                        .partial_cmp(&(p.position[b].y - y).abs())
                        .unwrap()
                })
                .unwrap();
            let expect = 1000.0 * 9.81 * (level - p.position[j].y);
            line += &format!(
                "  d {depth}: p - rho g (h - y) = {:+.1} Pa",
                p.pressure[j] - expect
            );
        }
        println!("{line}");
    }
}
