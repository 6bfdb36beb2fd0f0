//! Diagnostic: the particles next to the wedge's faces in the self-similar window.
//! Bands of z/(Vt) along the faces; per band, for particles within 0.8 l0 of the face:
//! mean distance d/l0, number density n/n0, Cp, relative normal velocity (u - u_w)·n / V
//! (positive: leaving the face) and the share flagged free surface.
//! Also prints the mean F / (rho V³ t) over the window.
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
    while sim.time < tb * t_chine {
        let dt = sim.next_dt();
        coupling.before_step(&mut sim, dt);
        sim.step(dt).unwrap();
        coupling.after_step(&mut sim, dt);
        if sim.time < ta * t_chine {
            continue;
        }
        cf.0 += sim.loads[k as usize].force.y / (1000.0 * v.powi(3) * (sim.time - 0.5 * dt));
        cf.1 += 1.0;
        let vt = v * sim.time;
        let p = &sim.particles;
        let n0 = sim.params.n0;
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
}
