//! Diagnostic: where the wedge's step-to-step force noise lives. Per step, the force of
//! the first row (p l0 n_y over particles within 0.8 l0 of the wedge) split into
//! particles whose free-surface flag flipped since the previous step and the rest;
//! prints the RMS step-to-step change of each part over the window, as a share of the
//! mean force, and the per-step force noise of the load itself.
//! `TA=0.3 TB=0.8 cargo run --release --example wedge_flicker -- [PATH=VALUE]...`
use mpsfsi::case::load_case_file;
use mpsfsi::coupling::{Coupling, CouplingOptions};
use mpsfsi::engine::Simulation;

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("cases/wedge_30deg_constant_velocity.json");
    let case = load_case_file(&path, &args).unwrap();
    let v = 6.15;
    let t_chine = 0.5 * 0.577_350_269 / (std::f64::consts::PI * v);
    let mut sim = Simulation::new(&case);
    let mut coupling = Coupling::with_options(&case, &sim, CouplingOptions::default()).unwrap();
    let k = sim.wall_names().iter().position(|n| n == "wedge").unwrap() as u32;
    let l0 = case.particle_spacing;
    let window = |name: &str, default: f64| -> f64 {
        std::env::var(name).map_or(default, |v| v.parse().expect("TA and TB are numbers"))
    };
    let (ta, tb) = (window("TA", 0.3), window("TB", 0.8));
    let mut prev_flag: Vec<bool> = Vec::new();
    let mut prev: Option<(f64, f64, f64, f64)> = None; // (load, row, flipped part, steady part) / (rho V^3 t)
    let mut acc = [0.0f64; 6]; // sums of squares of changes: load, row, flipped, steady; n; mean load
    let mut flips = 0.0;
    let mut series = Vec::new();
    while sim.time < tb * t_chine {
        let dt = sim.next_dt();
        coupling.before_step(&mut sim, dt);
        sim.step(dt).unwrap();
        coupling.after_step(&mut sim, dt);
        let p = &sim.particles;
        let scale = 1000.0 * v.powi(3) * sim.time;
        let (mut row, mut flipped, mut steady, mut nflip) = (0.0, 0.0, 0.0, 0.0);
        for i in 0..p.len() {
            for c in sim.wall_contacts().of(i).iter().filter(|c| c.object == k) {
                if c.distance >= 0.8 * l0 {
                    continue;
                }
                let f = -p.pressure[i] * l0 * c.normal.y / scale;
                row += f;
                if i < prev_flag.len() && prev_flag[i] != p.free_surface[i] {
                    flipped += f;
                    nflip += 1.0;
                } else {
                    steady += f;
                }
            }
        }
        let load = sim.loads[k as usize].force.y / scale;
        prev_flag = p.free_surface.clone();
        if sim.time >= ta * t_chine {
            if let Some((l, r, _, s)) = prev {
                // a flipped particle's whole force is the change it brings
                acc[0] += (load - l).powi(2);
                acc[1] += (row - r).powi(2);
                acc[2] += flipped.powi(2);
                acc[3] += (steady - s).powi(2);
                acc[4] += 1.0;
                acc[5] += load;
                flips += nflip;
                series.push(load);
            }
        }
        prev = Some((load, row, flipped, steady));
    }
    let n = acc[4];
    let mean = acc[5] / n;
    println!(
        "window {ta}..{tb} t_chine, {n} steps: mean F/(rho V^3 t) {mean:.2}; RMS step change / mean: load {:.3}, first row {:.3}, flipped particles {:.3}, the rest {:.3}; {:.1} flips per step",
        (acc[0] / n).sqrt() / mean,
        (acc[1] / n).sqrt() / mean,
        (acc[2] / n).sqrt() / mean,
        (acc[3] / n).sqrt() / mean,
        flips / n
    );
    // autocorrelation of the load about its 9-step moving mean, lags 1..4
    let m = series.len();
    let smooth: Vec<f64> = (0..m)
        .map(|i| {
            let (a, b) = (i.saturating_sub(4), (i + 5).min(m));
            series[a..b].iter().sum::<f64>() / (b - a) as f64
        })
        .collect();
    let r: Vec<f64> = series.iter().zip(&smooth).map(|(x, s)| x - s).collect();
    let c0: f64 = r.iter().map(|x| x * x).sum();
    let ac: Vec<String> = (1..5)
        .map(|lag| {
            let c: f64 = (lag..m).map(|i| r[i] * r[i - lag]).sum();
            format!("{:+.2}", c / c0)
        })
        .collect();
    println!(
        "autocorrelation of the load's fluctuation at lags 1-4 steps: {}",
        ac.join(" ")
    );
}
