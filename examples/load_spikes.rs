//! Diagnostic: steps a case as `mpsfsi run` does and, at every step whose load on body 0
//! is more than SPIKE (default 2.5) times the median of the five steps before it,
//! prints the solver's iterations, how many particles within 3 l0 of the body changed
//! their free-surface flag, and the particles there with the highest pressure: pressure
//! now and the step before, speed now and before, n/n0, the free-surface flag, fluid
//! neighbours within r_e and how many of them are free surface.
//! `END=0.012 cargo run --release --example load_spikes -- CASE [PATH=VALUE]...`
use mpsfsi::case::load_case_file;
use mpsfsi::coupling::Coupling;
use mpsfsi::engine::walls::PlacedWall;
use mpsfsi::engine::Simulation;
use mpsfsi::run::{advance, step_to_end};

fn env(name: &str, default: f64) -> f64 {
    std::env::var(name)
        .ok()
        .and_then(|v| v.parse().ok())
        .unwrap_or(default)
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let case = load_case_file(std::path::Path::new(&args[0]), &args[1..]).unwrap();
    let (end, spike) = (env("END", case.time.end), env("SPIKE", 2.5));
    let mut sim = Simulation::new(&case);
    let mut coupling = Coupling::new(&case, &sim);
    let k = sim.walls.iter().position(|w| w.body.is_some()).unwrap();
    let (l0, n0, re) = (
        case.particle_spacing,
        sim.config.params.n0,
        sim.config.params.re,
    );
    let mut history: Vec<f64> = Vec::new();
    let mut dts: Vec<f64> = Vec::new();
    let mut last_p = sim.particles.pressure.clone();
    let mut last_u = sim.particles.velocity.clone();
    let mut last_s = sim.particles.free_surface.clone();
    while sim.time < end {
        let dt = step_to_end(sim.time, end, sim.next_dt());
        let n_before = sim.particles.len();
        let rejected = sim.stats.rejected_steps;
        let info = advance(&mut sim, coupling.as_mut(), dt).unwrap();
        dts.push(info.dt);
        let retried = sim.stats.rejected_steps - rejected;
        if sim.particles.len() != n_before {
            // a runaway was removed: the indices moved, start the history again
            last_p = sim.particles.pressure.clone();
            last_u = sim.particles.velocity.clone();
            last_s = sim.particles.free_surface.clone();
            continue;
        }
        let fy = sim.loads[k].force.y;
        let mut recent: Vec<f64> = history.iter().rev().take(5).copied().collect();
        recent.sort_by(|a, b| a.partial_cmp(b).unwrap());
        let median = recent.get(recent.len() / 2).copied().unwrap_or(0.0);
        history.push(fy);
        if recent.len() == 5 && fy.abs() > spike * median.abs() && fy.abs() > 1000.0 {
            let wall = &PlacedWall::new(&sim.walls[k], sim.walls[k].state);
            let p = &sim.particles;
            let near: Vec<usize> = (0..p.len())
                .filter(|&i| wall.nearest(p.position[i], 3.0 * l0).is_some())
                .collect();
            let to_interior = near
                .iter()
                .filter(|&&i| last_s[i] && !p.free_surface[i])
                .count();
            let to_surface = near
                .iter()
                .filter(|&&i| !last_s[i] && p.free_surface[i])
                .count();
            let mut by_p = near.clone();
            by_p.sort_by(|&a, &b| p.pressure[b].partial_cmp(&p.pressure[a]).unwrap());
            println!(
                "t {:.4} ms dt {:.2e} (tried {:.2e}, {} rejections; before {:.2e} {:.2e}) F_y {:.0} (median before {:.0}), {} particles within 3 l0",
                1e3 * sim.time,
                info.dt,
                dt,
                retried,
                dts[dts.len().saturating_sub(2)],
                dts[dts.len().saturating_sub(3)],
                fy,
                median,
                near.len()
            );
            println!("  solver {} iterations, residual {:.1e}; near the body {} surface -> interior, {} interior -> surface", info.solver_iterations, info.solver_residual, to_interior, to_surface);
            for &i in by_p.iter().take(4) {
                let contacts = sim.wall_contacts();
                let (mut fluid, mut surf) = (0, 0);
                for j in 0..p.len() {
                    let d = (p.position[j] - p.position[i]).norm();
                    if j != i && d < re {
                        fluid += 1;
                        surf += p.free_surface[j] as usize;
                    }
                }
                let dist = wall
                    .nearest(p.position[i], 3.0 * l0)
                    .map(|(_, d)| d / l0)
                    .unwrap_or(f64::NAN);
                println!(
                    "  #{i} at ({:.4},{:.4}) wall {:.2} l0, contacts {}: p {:.0} (before {:.0}), |u| {:.1} (before {:.1}), n/n0 {:.3}, surface {}, {} fluid neighbours ({} surface)",
                    p.position[i].x,
                    p.position[i].y,
                    dist,
                    contacts.of(i).len(),
                    p.pressure[i],
                    last_p[i],
                    p.velocity[i].norm(),
                    last_u[i].norm(),
                    p.number_density[i] / n0,
                    p.free_surface[i],
                    fluid,
                    surf
                );
            }
        }
        last_p = sim.particles.pressure.clone();
        last_u = sim.particles.velocity.clone();
        last_s = sim.particles.free_surface.clone();
    }
}
