//! Diagnostic: the wedge's vertical load per step, split into its pressure and
//! repulsion parts, with the slope fit of the test (0.35..0.75 t_chine), the force the
//! fluid actually received (its momentum change minus the tank's load) and row-passage
//! averages. SERIES=1 also prints every step (`S t_ms pressure repulsion momentum`).
//! `cargo run --release --example wedge_loads -- cases/wedge_30deg_constant_velocity.json [PATH=VALUE]...`
use mpsfsi::case::load_case_file;
use mpsfsi::coupling::Coupling;
use mpsfsi::engine::Simulation;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let case = load_case_file(std::path::Path::new(&args[0]), &args[1..]).unwrap();
    let v: f64 = 6.15;
    let t_chine = 0.5 * 0.577_350_269 / (std::f64::consts::PI * v);
    let scale = 1000.0 * v.powi(3);
    let mut sim = Simulation::new(&case);
    let mut coupling = Coupling::new(&case, &sim).expect("a body");
    let k = sim.wall_names().iter().position(|n| n == "wedge").unwrap();
    let (mut t, mut fp, mut fr) = (Vec::new(), Vec::new(), Vec::new());
    let mut fm = Vec::new();
    let m = sim.config.params.particle_mass;
    let momentum = |s: &Simulation| s.particles.velocity.iter().map(|u| u.y).sum::<f64>() * m;
    let clock = std::time::Instant::now();
    while sim.time < 0.8 * t_chine {
        let dt = sim.next_dt();
        let p0 = momentum(&sim);
        coupling.before_step(&mut sim, dt);
        sim.step(dt).unwrap();
        coupling.after_step(&mut sim, dt);
        let l = &sim.loads[k];
        t.push(sim.time - 0.5 * dt);
        fp.push(l.pressure_force.y);
        fr.push(l.repulsion_force.y);
        // what the fluid received from the walls: -(dP/dt) minus the tank's reaction
        let tank = sim
            .loads
            .iter()
            .enumerate()
            .filter(|(j, _)| *j != k)
            .map(|(_, l)| l.force.y)
            .sum::<f64>();
        fm.push(-(momentum(&sim) - p0) / dt - tank);
    }
    let fit = |f: &[f64]| {
        let sel: Vec<(f64, f64)> = t
            .iter()
            .zip(f)
            .filter(|(a, _)| **a > 0.35 * t_chine && **a < 0.75 * t_chine)
            .map(|(a, b)| (*a, *b))
            .collect();
        let n = sel.len() as f64;
        let mx = sel.iter().map(|s| s.0).sum::<f64>() / n;
        let my = sel.iter().map(|s| s.1).sum::<f64>() / n;
        let b = sel.iter().map(|s| (s.0 - mx) * (s.1 - my)).sum::<f64>()
            / sel.iter().map(|s| (s.0 - mx).powi(2)).sum::<f64>();
        let rms = (sel
            .iter()
            .map(|s| (s.1 - (my + b * (s.0 - mx))).powi(2))
            .sum::<f64>()
            / n)
            .sqrt();
        (b / scale, my, rms)
    };
    let total: Vec<f64> = fp.iter().zip(&fr).map(|(a, b)| a + b).collect();
    for (name, f) in [
        ("pressure", &fp),
        ("repulsion", &fr),
        ("total", &total),
        ("momentum", &fm),
    ] {
        let (c, mean, rms) = fit(f);
        println!("{name:>9}: C slope {c:7.3}  mean {mean:9.1} N/m  rms about fit {rms:9.1}");
    }
    // binned time series (bins of l0 / V: one particle row)
    let bin = case.particle_spacing / v;
    let mut b = 0.0;
    while b < 0.8 * t_chine {
        let idx: Vec<usize> = (0..t.len())
            .filter(|&i| t[i] >= b && t[i] < b + bin)
            .collect();
        if !idx.is_empty() {
            let m = |f: &[f64]| idx.iter().map(|&i| f[i]).sum::<f64>() / idx.len() as f64;
            let tm = b + 0.5 * bin;
            println!(
                "t {:6.3} ms  C(p) {:6.2}  C(rep) {:6.2}  C {:6.2}",
                tm * 1e3,
                m(&fp) / (scale * tm),
                m(&fr) / (scale * tm),
                m(&total) / (scale * tm)
            );
        }
        b += bin;
    }
    if std::env::var_os("SERIES").is_some() {
        for i in 0..t.len() {
            println!("S {:.6} {:.1} {:.1} {:.1}", t[i] * 1e3, fp[i], fr[i], fm[i]);
        }
    }
    println!(
        "steps {} wall {:.1}s",
        sim.steps,
        clock.elapsed().as_secs_f64()
    );
}
