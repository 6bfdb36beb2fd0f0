//! Diagnostic: the particles next to the wedge's faces in the self-similar window.
//! Bands of z/(Vt) along the faces; per band, for particles within 0.8 l0 of the face:
//! mean distance d/l0, number density n/n0, Cp, relative normal velocity (u - u_w)·n / V
//! (positive: leaving the face) and the share flagged free surface.
//! Also prints the mean F / (rho V³ t) over the window, and where its step-to-step noise
//! lives: the RMS change between steps of the load and of the first row's force
//! (p l0 n_y over particles within 0.8 l0), split into particles whose free-surface flag
//! flipped since the previous step and the rest, with the load's autocorrelation.
//! `TA=0.5 TB=0.6 cargo run --release --example wedge_face -- [PATH=VALUE]...`
//! (the window in units of t_chine; those are the defaults)
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
    let edges = [
        -1.0, -0.75, -0.5, -0.25, 0.0, 0.15, 0.3, 0.45, 0.6, 0.75, 1.0, 1.5,
    ];
    let nb = edges.len() - 1;
    let mut acc = vec![[0.0f64; 6]; nb];
    let mut cf = (0.0, 0.0);
    let mut acc2 = vec![[0.0f64; 2]; nb]; // second row (0.8..1.6 l0): count, sum of Cp
    let window = |name: &str, default: f64| -> f64 {
        std::env::var(name).map_or(default, |v| v.parse().expect("TA and TB are numbers"))
    };
    let (ta, tb) = (window("TA", 0.5), window("TB", 0.6));
    let mut noise = Noise::default();
    while sim.time < tb * t_chine {
        let dt = sim.next_dt();
        coupling.before_step(&mut sim, dt);
        sim.step(dt).unwrap();
        coupling.after_step(&mut sim, dt);
        noise.record(&sim, k, v, sim.time >= ta * t_chine);
        if sim.time < ta * t_chine {
            continue;
        }
        cf.0 += sim.loads[k as usize].force.y / (1000.0 * v.powi(3) * (sim.time - 0.5 * dt));
        cf.1 += 1.0;
        let vt = v * sim.time;
        let p = &sim.particles;
        let n0 = sim.config.params.n0;
        for i in 0..p.len() {
            for c in sim.wall_contacts().of(i).iter().filter(|c| c.object == k) {
                let z = c.point.y / vt;
                let Some(b) = (0..nb).find(|&b| z >= edges[b] && z < edges[b + 1]) else {
                    continue;
                };
                let d = c.distance / l0;
                let cp = p.pressure[i] / (0.5 * 1000.0 * v * v);
                if d < 0.8 {
                    let a = &mut acc[b];
                    a[0] += 1.0;
                    a[1] += d;
                    a[2] += p.number_density[i] / n0;
                    a[3] += cp;
                    a[4] += (p.velocity[i] - c.wall_velocity).dot(&c.normal) / v;
                    a[5] += p.free_surface[i] as u8 as f64;
                } else if d < 1.6 {
                    acc2[b][0] += 1.0;
                    acc2[b][1] += cp;
                }
            }
        }
    }
    println!(
        "mean C_F over {ta}..{tb} t_chine: {:.3} ({} steps)",
        cf.0 / cf.1,
        cf.1
    );
    println!("band z/(Vt)      count   d/l0   n/n0     Cp  (u-uw).n/V  surface  | 2nd row Cp");
    for b in 0..nb {
        let a = acc[b];
        let m = a[0].max(1.0);
        println!(
            "{:+.2}..{:+.2} {:8.0} {:6.3} {:6.3} {:6.3} {:+9.4} {:8.3}  | {:6.3}",
            edges[b],
            edges[b + 1],
            a[0],
            a[1] / m,
            a[2] / m,
            a[3] / m,
            a[4] / m,
            a[5] / m,
            acc2[b][1] / acc2[b][0].max(1.0)
        );
    }
    noise.report();
}

/// Step-to-step changes of the wedge's load, as F / (rho V³ t).
#[derive(Default)]
struct Noise {
    prev_flag: Vec<bool>,
    /// (load, first row, first row without the flipped particles) of the previous step
    prev: Option<(f64, f64, f64)>,
    /// sums of squared changes: load, first row, flipped particles, the rest
    squares: [f64; 4],
    loads: Vec<f64>,
    flips: f64,
}

impl Noise {
    fn record(&mut self, sim: &Simulation, k: u32, v: f64, in_window: bool) {
        let p = &sim.particles;
        let l0 = sim.config.params.l0;
        let scale = 1000.0 * v.powi(3) * sim.time;
        let (mut row, mut flipped, mut steady, mut flips) = (0.0, 0.0, 0.0, 0.0);
        for i in 0..p.len() {
            for c in sim.wall_contacts().of(i).iter().filter(|c| c.object == k) {
                if c.distance >= 0.8 * l0 {
                    continue;
                }
                let f = -p.pressure[i] * l0 * c.normal.y / scale;
                row += f;
                if i < self.prev_flag.len() && self.prev_flag[i] != p.free_surface[i] {
                    flipped += f;
                    flips += 1.0;
                } else {
                    steady += f;
                }
            }
        }
        let load = sim.loads[k as usize].force.y / scale;
        self.prev_flag = p.free_surface.clone();
        if let (true, Some((l, r, s))) = (in_window, self.prev) {
            // a flipped particle's whole force is the change it brings
            self.squares[0] += (load - l).powi(2);
            self.squares[1] += (row - r).powi(2);
            self.squares[2] += flipped.powi(2);
            self.squares[3] += (steady - s).powi(2);
            self.loads.push(load);
            self.flips += flips;
        }
        self.prev = Some((load, row, steady));
    }

    fn report(&self) {
        let m = self.loads.len();
        if m < 10 {
            return;
        }
        let n = m as f64;
        let mean = self.loads.iter().sum::<f64>() / n;
        let rms = |s: f64| (s / n).sqrt() / mean;
        println!(
            "RMS step-to-step change / mean: load {:.3}, first row {:.3}, particles whose surface flag flipped {:.3}, the rest {:.3}; {:.1} flips per step",
            rms(self.squares[0]),
            rms(self.squares[1]),
            rms(self.squares[2]),
            rms(self.squares[3]),
            self.flips / n
        );
        // autocorrelation of the load about its 9-step moving mean
        let r: Vec<f64> = (0..m)
            .map(|i| {
                let (a, b) = (i.saturating_sub(4), (i + 5).min(m));
                self.loads[i] - self.loads[a..b].iter().sum::<f64>() / (b - a) as f64
            })
            .collect();
        let c0: f64 = r.iter().map(|x| x * x).sum();
        let ac: Vec<String> = (1..5)
            .map(|lag| {
                format!(
                    "{:+.2}",
                    (lag..m).map(|i| r[i] * r[i - lag]).sum::<f64>() / c0
                )
            })
            .collect();
        println!(
            "autocorrelation of the load's fluctuation at lags 1-4 steps: {}",
            ac.join(" ")
        );
    }
}
