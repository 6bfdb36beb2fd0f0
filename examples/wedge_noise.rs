//! Diagnostic: where along the wedge face the per-step load noise comes from.
//! Samples the pressure on each face every l0/2 (Shepard average of the particles within
//! r_e on the fluid side, as the load does) and reports, per band of z/(Vt), the mean
//! pressure coefficient and the step-to-step rms change.
//! `cargo run --release --example wedge_noise -- cases/wedge_30deg_constant_velocity.json [PATH=VALUE]...`
use mpsfsi::case::load_case_file;
use mpsfsi::coupling::Coupling;
use mpsfsi::engine::Simulation;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let case = load_case_file(std::path::Path::new(&args[0]), &args[1..]).unwrap();
    let v: f64 = 6.15;
    let t_chine = 0.5 * 0.577_350_269 / (std::f64::consts::PI * v);
    let l0 = case.particle_spacing;
    let re = case.scheme.radius * l0;
    let mut sim = Simulation::new(&case);
    let mut coupling = Coupling::new(&case, &sim).expect("a body");
    let tanb = 0.577_350_269f64;
    // bands of z/(Vt) (height above the undisturbed surface over penetration)
    let bands = [-1.0, -0.75, -0.5, -0.25, 0.0, 0.25, 0.5, 1.0, 3.0];
    let nb = bands.len() - 1;
    let (mut sum, mut sum2, mut cnt) = (vec![0.0; nb], vec![0.0; nb], vec![0usize; nb]);
    let mut prev: Option<Vec<f64>> = None;
    let (mut n_inner, mut n_surface_flip) = (0usize, 0usize);
    let mut prev_flags: Option<Vec<bool>> = None;
    // probes: below the apex (moving with it) at 3, 6, 12 l0, and fixed at (0.3, -0.3)
    let mut probe_series: Vec<Vec<f64>> = vec![Vec::new(); 4];
    while sim.time < 0.75 * t_chine {
        let dt = sim.next_dt();
        coupling.before_step(&mut sim, dt);
        sim.step(dt).unwrap();
        coupling.after_step(&mut sim, dt);
        let t = sim.time;
        let h = v * t; // penetration
                       // right face from the apex (0, -h) towards the chine; sample by arclength
        let ds = 0.5 * l0;
        let len = 0.25 / (30f64.to_radians().cos());
        let dir = nalgebra::Vector2::new(30f64.to_radians().cos(), 30f64.to_radians().sin());
        let normal = nalgebra::Vector2::new(dir.y, -dir.x); // towards the water (down-right)
        let mut ps = Vec::new();
        let mut zs = Vec::new();
        let mut s = 0.5 * ds;
        while s < len {
            let pt = nalgebra::Vector2::new(0.0, -h) + dir * s;
            let (mut sw, mut swp) = (0.0, 0.0);
            for (j, x) in sim.particles.position.iter().enumerate() {
                let r = pt - x;
                let d = r.norm();
                if d >= re || r.dot(&normal) > 0.0 {
                    continue;
                }
                let w = re / d.max(0.1 * l0) - 1.0;
                sw += w;
                swp += w * sim.particles.pressure[j];
            }
            ps.push(if sw > 0.0 { swp / sw } else { 0.0 });
            zs.push(pt.y / h);
            s += ds;
        }
        let _ = tanb;
        if t > 0.35 * t_chine {
            let pts = [
                nalgebra::Vector2::new(0.0, -h - 3.0 * l0),
                nalgebra::Vector2::new(0.0, -h - 6.0 * l0),
                nalgebra::Vector2::new(0.0, -h - 12.0 * l0),
                nalgebra::Vector2::new(0.3, -0.3),
            ];
            for (k, pt) in pts.iter().enumerate() {
                let (mut sw, mut swp) = (0.0, 0.0);
                for (j, x) in sim.particles.position.iter().enumerate() {
                    let d = (pt - x).norm();
                    if d < re {
                        let w = re / d.max(0.1 * l0) - 1.0;
                        sw += w;
                        swp += w * sim.particles.pressure[j];
                    }
                }
                probe_series[k].push(swp / sw / (500.0 * v * v));
            }
        }
        if t > 0.35 * t_chine {
            if let Some(pp) = &prev {
                for i in 0..ps.len().min(pp.len()) {
                    let z = zs[i];
                    if let Some(b) = (0..nb).find(|&b| z >= bands[b] && z < bands[b + 1]) {
                        sum[b] += ps[i] / (500.0 * v * v);
                        sum2[b] += ((ps[i] - pp[i]) / (500.0 * v * v)).powi(2);
                        cnt[b] += 1;
                    }
                }
            }
            // free-surface flag flips among particles within 2 l0 of the face
            if let Some(pf) = &prev_flags {
                if pf.len() == sim.particles.len() {
                    for (j, x) in sim.particles.position.iter().enumerate() {
                        let rel = x - nalgebra::Vector2::new(0.0, -h);
                        let along = rel.dot(&dir);
                        let off = -rel.dot(&normal);
                        if along > 0.0 && along < len && off.abs() < 2.0 * l0 {
                            n_inner += 1;
                            if pf[j] != sim.particles.free_surface[j] {
                                n_surface_flip += 1;
                            }
                        }
                    }
                }
            }
        }
        prev = Some(ps);
        prev_flags = Some(sim.particles.free_surface.clone());
    }
    println!("band z/Vt      samples  mean Cp   rms step change of Cp");
    for b in 0..nb {
        if cnt[b] > 0 {
            println!(
                "[{:5.2},{:5.2})  {:6}  {:7.3}  {:7.3}",
                bands[b],
                bands[b + 1],
                cnt[b],
                sum[b] / cnt[b] as f64,
                (sum2[b] / cnt[b] as f64).sqrt()
            );
        }
    }
    for (k, name) in ["apex-3l0", "apex-6l0", "apex-12l0", "(0.3,-0.3)"]
        .iter()
        .enumerate()
    {
        let x = &probe_series[k];
        let n = x.len() as f64;
        let m = x.iter().sum::<f64>() / n;
        let var = x.iter().map(|a| (a - m).powi(2)).sum::<f64>() / n;
        let c1 = x.windows(2).map(|w| (w[0] - m) * (w[1] - m)).sum::<f64>() / (n - 1.0) / var;
        let dif = (x.windows(2).map(|w| (w[1] - w[0]).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
        println!("probe {name:>11}: mean Cp {m:7.3}  std {:7.3}  rms step change {dif:7.3}  lag-1 acf {c1:+.2}", var.sqrt());
    }
    println!(
        "free-surface flag flips within 2 l0 of the face: {} of {} particle-steps",
        n_surface_flip, n_inner
    );
}
