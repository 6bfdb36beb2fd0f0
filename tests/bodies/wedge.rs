//! Constant-velocity entry of the 30° wedge (the default job) against the nonlinear
//! similarity solution, C_F = F / (rho V³ t) = 14.04 (docs/references.md; Zhao & Faltinsen
//! 1993). Plain Wagner (23.26) is an upper bound, von Karman (9.42) a lower bound.

use crate::common::*;
use mpsfsi::analysis::measure::{
    fit_force_coefficient, force_coefficient_from_contact, force_coefficient_from_onset,
};
use mpsfsi::analysis::reference::WEDGE_30_FACE_PRESSURE;
use mpsfsi::coupling::CouplingOptions;
use mpsfsi::engine::Simulation;
use mpsfsi::math::Vec2;
use mpsfsi::output::probes;

const V: f64 = 6.15;
const C_SIMILARITY: f64 = 14.04;
const C_WAGNER: f64 = 23.26;
/// Jet root at the chine: B tan(beta) / (pi V).
const T_CHINE: f64 = 0.5 * 0.577_350_269 / (std::f64::consts::PI * V);

/// A gauge's name, height above the keel (m) and reading at every step, (time, Cp).
pub type GaugeSeries = (String, f64, Vec<(f64, f64)>);

pub struct WedgeFit {
    pub spacing: f64,
    /// C_F with the time origin at the keel contact (the t of docs/references.md): the
    /// least-squares fit of F = C rho V³ t over the window.
    pub c: f64,
    /// Its standard error from the scatter about the fit.
    pub c_error: f64,
    /// C_F read from the onset (`measure::force_coefficient_from_onset`: origin at the
    /// first load above 1 % of the peak, rows over 20-85 % of t_chine after it), and
    /// that origin.
    pub c_onset: f64,
    pub t0_onset: f64,
    /// Two-parameter fit F = C rho V³ (t - t0): slope and origin. Reported, not asserted:
    /// with the per-step scatter of the force (about its mean, white) the slope's
    /// standard error is about 4.8 / sqrt(steps in the window) of C, ±40 % at 10 mm.
    pub c_slope: f64,
    pub t0_slope: f64,
    /// From the impulse I = ∫F dt = C rho V³ (t - t0)² / 2 (smooth, so its origin is a
    /// usable check that the force grows linearly from the keel contact).
    pub c_impulse: f64,
    pub t0_impulse: f64,
    /// Pressure coefficient along the faces, averaged over the window: (z/(Vt), Cp).
    pub profile: Vec<(f64, f64)>,
    /// The case's gauges: name, height above the keel (m) and their reading at every
    /// step, (time, Cp).
    pub gauges: Vec<GaugeSeries>,
    pub particles: usize,
    pub particle_steps: u64,
    pub steps: usize,
    pub seconds: f64,
    pub coupling_seconds: f64,
}

/// Run the shipped case with `overrides` to t_chine and fit the force over the middle
/// of the self-similar window, 0.35..0.75 t_chine (before that the penetration is only
/// a few spacings; after it the jet root nears the chine), and from its onset.
pub fn wedge_fit(overrides: &[String]) -> WedgeFit {
    let case = shipped("wedge_30deg_constant_velocity.json", overrides);
    let mut profile = PressureProfile::new(case.particle_spacing, case.scheme.radius);
    let mut points = None;
    let mut gauges: Vec<GaugeSeries> = case
        .output
        .probes
        .iter()
        .map(|p| (p.name.clone(), p.position[1], Vec::new()))
        .collect();
    let q = 0.5 * RHO * V * V;
    let trace = run(&case, CouplingOptions::default(), Some(T_CHINE), |sim| {
        profile.sample(sim);
        let points = points.get_or_insert_with(|| probes::points(&case, sim));
        for (g, p) in gauges.iter_mut().zip(probes::sample(sim, points)) {
            g.2.push((sim.time, p / q));
        }
    });
    assert!(trace.error.is_none(), "{:?}", trace.error);
    let k = trace.wall("wedge");
    let scale = RHO * V.powi(3);
    // the same estimators as the benchmark (analysis::measure): each step's load is the mean
    // over the step, sampled at its midpoint; origin at the keel contact, t = 0 (the
    // apex starts on the undisturbed surface)
    let times: Vec<f64> = trace.steps.iter().map(|s| s.time).collect();
    let forces: Vec<f64> = trace.steps.iter().map(|s| s.force[k].y).collect();
    let window = (0.35 * T_CHINE, 0.75 * T_CHINE);
    let (c, c_error) = force_coefficient_from_contact(0.0, 0.0, &times, &forces, window, RHO, V)
        .expect("samples in the window");
    let (c_slope, t0_slope) =
        fit_force_coefficient(0.0, &times, &forces, window, RHO, V).expect("samples in the window");
    let (c_onset, t0_onset) = force_coefficient_from_onset(&times, &forces, T_CHINE, RHO, V)
        .expect("rows in the window after the onset");
    // for the printed scatter about the fit
    let (t, f): (Vec<f64>, Vec<f64>) = trace
        .steps
        .iter()
        .map(|s| (s.time - 0.5 * s.dt, s.force[k].y))
        .filter(|(tm, _)| (window.0..=window.1).contains(tm))
        .unzip();
    let scatter: f64 = t
        .iter()
        .zip(&f)
        .map(|(t, f)| (f - c * scale * t).powi(2))
        .sum();
    let (mut impulse, mut ti, mut si) = (0.0, Vec::new(), Vec::new());
    for s in &trace.steps {
        impulse += s.force[k].y * s.dt;
        if s.time > 0.35 * T_CHINE && s.time < 0.75 * T_CHINE && impulse > 0.0 {
            ti.push(s.time);
            si.push((2.0 * impulse / scale).sqrt());
        }
    }
    let (ai, bi) = fit_line(&ti, &si);
    let fit = WedgeFit {
        spacing: case.particle_spacing,
        c,
        c_error,
        c_onset,
        t0_onset,
        c_slope,
        t0_slope,
        c_impulse: bi * bi,
        t0_impulse: -ai / bi,
        profile: profile.mean(),
        gauges,
        particles: trace.particles,
        particle_steps: trace.particle_steps,
        steps: trace.steps.len(),
        seconds: trace.wall_seconds,
        coupling_seconds: trace.coupling_seconds,
    };
    let mean = f.iter().sum::<f64>() / f.len() as f64;
    println!(
        "wedge l0 = {} m: C_F = {:.3} ± {:.3} ({:+.1} % vs similarity 14.04, {:+.1} % vs Wagner 23.26); from the onset {:.3} ({:+.1} %, t0 {:.3} ms); per-step scatter {:.2} of the mean force over {} steps; two-parameter slope {:.3} (t0 {:.3} ms); impulse {:.3} (t0 {:.3} ms); {} particles, {:.1} M particle-steps, {} steps, {:.1} s (coupling {:.3} s)",
        fit.spacing,
        fit.c,
        fit.c_error,
        100.0 * (fit.c / C_SIMILARITY - 1.0),
        100.0 * (fit.c / C_WAGNER - 1.0),
        fit.c_onset,
        100.0 * (fit.c_onset / C_SIMILARITY - 1.0),
        1e3 * fit.t0_onset,
        (scatter / t.len() as f64).sqrt() / mean,
        t.len(),
        fit.c_slope,
        1e3 * fit.t0_slope,
        fit.c_impulse,
        1e3 * fit.t0_impulse,
        fit.particles,
        fit.particle_steps as f64 * 1e-6,
        fit.steps,
        fit.seconds,
        fit.coupling_seconds
    );
    let (z_peak, cp_peak) = peak(&fit.profile);
    // the force the averaged profile carries: F_y = 2 ∫ p dx over one face's horizontal
    // projection, x/(Vt) = (z/(Vt) + 1) / tan 30°, so C_F = ∫ Cp d(x/(Vt))
    let dx = 0.025 / 0.577_350_269;
    let c_profile: f64 = fit.profile.iter().map(|(_, cp)| cp * dx).sum();
    println!(
        "  C_F from the averaged pressure profile {c_profile:.3}; profile (z/(Vt), Cp): {}",
        fit.profile
            .iter()
            .map(|(z, cp)| format!("{z:.3}:{cp:.2}"))
            .collect::<Vec<_>>()
            .join(" ")
    );
    println!(
        "  peak Cp {cp_peak:.3} at z/(Vt) = {z_peak:.3} (similarity 6.927 at 0.424); profile at the table's points: {}",
        CP_TABLE
            .iter()
            .map(|(z, cp)| format!("{z}: {:.2} vs {cp}", cp_at(&fit.profile, *z)))
            .collect::<Vec<_>>()
            .join(", ")
    );
    fit
}

/// Similarity solution's Cp along the wetted wall (docs/references.md), (z/(Vt), Cp).
const CP_TABLE: [(f64, f64); 8] = WEDGE_30_FACE_PRESSURE;

/// The similarity solution's largest Cp at 30° and its height over V t (Zhao &
/// Faltinsen 1993; docs/references.md).
const CP_MAX: f64 = 6.927;
const Z_MAX: f64 = 0.4243;

/// What a face gauge read over the self-similar window.
struct GaugeReading {
    name: String,
    /// Mean Cp of the steps at which the gauge sat between the keel and z/(Vt) = 0.3
    /// (wetted, below the jet root), and the similarity solution's mean over the same
    /// steps.
    mean: f64,
    reference: f64,
    steps: usize,
    /// RMS difference from the similarity solution over those steps.
    rms: f64,
    /// The largest single-step reading before t_chine and its time.
    peak: f64,
    peak_time: f64,
    /// When the similarity maximum passes the gauge, y / ((1 + z_max/(Vt)) V).
    passage: f64,
    /// The first step reading above Cp 2.
    wetted: f64,
}

/// The similarity solution's Cp at z/(Vt) along the face (`analysis::similarity`; its
/// 30° table agrees with CP_TABLE within 0.1 % at every point).
fn similarity_cp(z: f64) -> f64 {
    mpsfsi::analysis::similarity::cp_at(30.0, z).expect("the 30° table")
}

fn gauge_readings(fit: &WedgeFit) -> Vec<GaugeReading> {
    fit.gauges
        .iter()
        .map(|(name, y, series)| {
            let below_root: Vec<(f64, f64, f64)> = series
                .iter()
                .filter(|(t, _)| *t > 0.0 && *t < T_CHINE)
                .map(|&(t, cp)| (t, cp, y / (V * t) - 1.0))
                .filter(|(_, _, z)| (-1.0..=0.3).contains(z))
                .collect();
            let steps = below_root.len().max(1) as f64;
            let mean = below_root.iter().map(|r| r.1).sum::<f64>() / steps;
            let reference = below_root.iter().map(|r| similarity_cp(r.2)).sum::<f64>() / steps;
            let rms = (below_root
                .iter()
                .map(|r| (r.1 - similarity_cp(r.2)).powi(2))
                .sum::<f64>()
                / steps)
                .sqrt();
            let (peak_time, peak) = series
                .iter()
                .filter(|(t, _)| *t < T_CHINE)
                .fold((0.0, f64::MIN), |a, &b| if b.1 > a.1 { b } else { a });
            let wetted = series
                .iter()
                .find(|(_, cp)| *cp > 2.0)
                .map_or(f64::INFINITY, |r| r.0);
            GaugeReading {
                name: name.clone(),
                mean,
                reference,
                steps: below_root.len(),
                rms,
                peak,
                peak_time,
                passage: y / ((1.0 + Z_MAX) * V),
                wetted,
            }
        })
        .collect()
}

/// The largest Cp of a profile and where it is.
fn peak(profile: &[(f64, f64)]) -> (f64, f64) {
    profile
        .iter()
        .copied()
        .fold((0.0, f64::MIN), |a, b| if b.1 > a.1 { b } else { a })
}

/// Cp of a profile at z/(Vt) (nearest sample).
fn cp_at(profile: &[(f64, f64)], z: f64) -> f64 {
    profile
        .iter()
        .min_by(|a, b| (a.0 - z).abs().partial_cmp(&(b.0 - z).abs()).unwrap())
        .unwrap()
        .1
}

/// The pressure on both faces at fixed z/(Vt), as the load reads it (Shepard average of
/// the particles within r_e on the fluid side), averaged over the steps of the window:
/// the similarity solution makes Cp a function of z/(Vt) alone.
struct PressureProfile {
    l0: f64,
    re: f64,
    z: Vec<f64>,
    sum: Vec<f64>,
    samples: usize,
}

impl PressureProfile {
    fn new(l0: f64, radius: f64) -> Self {
        let z: Vec<f64> = (0..=80).map(|k| -1.0 + 0.025 * k as f64).collect();
        Self {
            l0,
            re: radius * l0,
            sum: vec![0.0; z.len()],
            z,
            samples: 0,
        }
    }

    fn sample(&mut self, sim: &Simulation) {
        let t = sim.time;
        if !(0.35 * T_CHINE..0.75 * T_CHINE).contains(&t) {
            return;
        }
        let k = sim.walls.iter().position(|w| w.body.is_some()).unwrap();
        let apex = sim.walls[k].state.position;
        let h = -apex.y; // penetration below the undisturbed surface y = 0
        let (s30, c30) = (0.5, 0.75f64.sqrt());
        let x = &sim.particles.position;
        let p = &sim.particles.pressure;
        let near: Vec<usize> = (0..x.len())
            .filter(|&j| x[j].x.abs() < 0.3 && x[j].y > apex.y - self.re && x[j].y < 0.3)
            .collect();
        for (m, z) in self.z.iter().enumerate() {
            // z/(Vt) = -1 is the keel; the apex may sit a hair above it within a step
            let along = ((z * V * t + h) / s30).max(0.0);
            let mut cp = 0.0;
            for side in [-1.0, 1.0] {
                let dir = Vec2::new(side * c30, s30);
                let normal = Vec2::new(side * s30, -c30); // into the water
                let point = apex + dir * along;
                let (mut sw, mut swp) = (0.0, 0.0);
                for &j in &near {
                    let r = point - x[j];
                    let d = r.norm();
                    if d >= self.re || r.dot(&normal) > 0.0 {
                        continue;
                    }
                    let w = self.re / d.max(0.1 * self.l0) - 1.0;
                    sw += w;
                    swp += w * p[j];
                }
                if sw > 0.0 {
                    cp += 0.5 * swp / sw / (0.5 * RHO * V * V);
                }
            }
            self.sum[m] += cp;
        }
        self.samples += 1;
    }

    fn mean(&self) -> Vec<(f64, f64)> {
        self.z
            .iter()
            .zip(&self.sum)
            .map(|(z, s)| (*z, s / self.samples.max(1) as f64))
            .collect()
    }
}

/// The default job at its own spacing, as a user writes it (5 mm, B/l0 = 100, no
/// `scheme` block, the default Courant number, the wedge on the tank's axis, the
/// automatic multi-resolution layout: 55 000 particles where a uniform 5 mm lattice
/// has 192 000) in at most 40 M particle-steps: C_F read from the onset within 5 % of
/// the similarity solution, with the
/// origin at the keel contact within 10 % (the first wetted rows lag, and it reads
/// 0.35-0.75 t_chine), and the pressure along the faces,
/// averaged over the window, within 25 % of its table and 27 % of its peak (6.927: the
/// jet root is resolved by two or three particles, and the fill floor of the pressure
/// Laplacian lowers the peak from 5.21 to 5.16). Measured numbers: docs/validation.md.
///
/// The case's four face gauges (20 / 35 / 50 / 65 % of the face height, moving with
/// the wedge) read, over the steps at which they sit between the keel and z/(Vt) = 0.3,
/// the similarity solution's mean within 7 % below 60 % of the height and 15 % above it,
/// the tolerances of the user-style family's four-run means (tests/bodies/gauges.rs): the
/// 65 % gauge sits there for about a hundred steps, and one run's mean scatters by
/// several points (measured +0.1 / −1.4 / −4.7 / −9.6 %). They wet before the maximum
/// passes them, after 0.7 of that time. Their single steps
/// scatter about it by 21–28 % of the peak (RMS), so their largest step is no reading of
/// the peak (19.5–31 against 6.927: docs/validation.md).
#[test]
fn wedge_force_and_pressure_at_default_spacing() {
    let fit = wedge_fit(&[]);
    assert!(
        fit.particle_steps <= 40_000_000,
        "{} particle-steps (40 M allowed)",
        fit.particle_steps
    );
    let onset = fit.c_onset / C_SIMILARITY - 1.0;
    assert!(
        onset.abs() < 0.05,
        "C_F from the onset = {:.3}, {:+.1} % from 14.04 (5 % allowed)",
        fit.c_onset,
        100.0 * onset
    );
    let contact = fit.c / C_SIMILARITY - 1.0;
    assert!(
        contact.abs() < 0.10,
        "C_F from the keel contact = {:.3}, {:+.1} % from 14.04 (10 % allowed)",
        fit.c,
        100.0 * contact
    );
    for g in gauge_readings(&fit) {
        println!(
            "  gauge {}: mean Cp {:.3} over {} steps at z/(Vt) -1 ... 0.3 vs the similarity solution's {:.3} ({:+.1} %); RMS difference {:.2} ({:.0} % of 6.927); largest step {:.2} at {:.2} ms (the maximum passes at {:.2} ms); first above Cp 2 at {:.2} ms",
            g.name,
            g.mean,
            g.steps,
            g.reference,
            100.0 * (g.mean / g.reference - 1.0),
            g.rms,
            100.0 * g.rms / CP_MAX,
            g.peak,
            1e3 * g.peak_time,
            1e3 * g.passage,
            1e3 * g.wetted
        );
        // the face height fraction of the name (face_65: 65 %)
        let fraction: f64 = g.name["face_".len()..].parse::<f64>().unwrap() / 100.0;
        let allowed = if fraction < 0.6 { 0.07 } else { 0.15 };
        assert!(
            (g.mean / g.reference - 1.0).abs() < allowed,
            "gauge {}: mean Cp {:.3} vs {:.3} ({:.0} % allowed)",
            g.name,
            g.mean,
            g.reference,
            100.0 * allowed
        );
        assert!(
            g.wetted < g.passage && g.wetted > 0.7 * g.passage,
            "gauge {}: wetted at {:.2} ms, the maximum passes at {:.2} ms",
            g.name,
            1e3 * g.wetted,
            1e3 * g.passage
        );
    }
    let (_, cp_peak) = peak(&fit.profile);
    assert!(
        (cp_peak / 6.927 - 1.0).abs() < 0.27,
        "peak Cp {cp_peak:.3} vs 6.927"
    );
    for (z, cp) in CP_TABLE {
        let got = cp_at(&fit.profile, z);
        assert!(
            (got / cp - 1.0).abs() < 0.25,
            "Cp at z/(Vt) = {z}: {got:.3} vs {cp}"
        );
    }
}

/// C_F averaged over `members` runs with the wedge's axis at (1/8 + (k + 1/2) / (8 members))
/// l0 from the nearest mirror line of the lattice (k = 0..members). The scene moves an axis
/// closer than l0/8 to a line out to l0/8 (`engine::scene::MIRROR_CLEARANCE`), and an
/// axis at d and at l0/2 - d are mirror images, so [l0/8, l0/4] holds every distinct
/// arrangement. Each run is an independent draw of the per-step force noise, so the
/// ensemble's standard error is the spread of the members over sqrt(members). Returns
/// (mean, standard error, members' values).
pub fn wedge_ensemble(l0: f64, members: usize, extra: &[String]) -> (f64, f64, Vec<f64>) {
    let values: Vec<f64> = (0..members)
        .map(|k| {
            let shift = l0 * (0.125 + 0.125 * (k as f64 + 0.5) / members as f64);
            let mut o = vec![
                format!("particle_spacing={l0}"),
                format!("bodies.0.position=[{shift},0.0]"),
            ];
            o.extend(extra.iter().cloned());
            let fit = wedge_fit(&o);
            println!(
                "l0 = {l0}, shift {shift:.5} m: C_F {:.3} from the keel contact, {:.3} from the onset",
                fit.c, fit.c_onset
            );
            fit.c
        })
        .collect();
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let spread = if values.len() > 1 {
        (values.iter().map(|c| (c - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt()
    } else {
        f64::NAN
    };
    (mean, spread / n.sqrt(), values)
}

/// The error falls across three spacings that divide the tank (4 m x 1.2 m of water)
/// into whole rows and columns, 10 / 4 / 2.5 mm, each an ensemble of lattice offsets
/// (`WEDGE_ENSEMBLE` members, by default 8 / 4 / 1: the per-step noise is largest, and a
/// run cheapest, at the coarsest spacing; at 2.5 mm one run takes most of an hour).
/// With r_e = 2.5 l0 (the default) the error falls with refinement; with 2.1 l0 it rose
/// (+1.9 / +5.2 / +11.5 % at 10 / 5 / 2.5 mm): the support of the number density,
/// gradient and source makes the difference, not the Laplacian's.
/// `WEDGE_SPACINGS=0.01,0.008` and `WEDGE_SET="scheme.x=y ..."` rerun it for diagnosis.
#[test]
#[ignore = "over an hour on two cores; numbers in docs/validation.md"]
fn wedge_force_coefficient_converges_with_spacing() {
    let spacings: Vec<f64> = std::env::var("WEDGE_SPACINGS")
        .map(|v| v.split(',').map(|x| x.parse().unwrap()).collect())
        .unwrap_or(vec![0.01, 0.004, 0.0025]);
    let extra: Vec<String> = std::env::var("WEDGE_SET")
        .map(|v| v.split(' ').map(String::from).collect())
        .unwrap_or_default();
    let members = |l0: f64| -> usize {
        std::env::var("WEDGE_ENSEMBLE")
            .map(|v| v.parse().unwrap())
            .unwrap_or(if l0 >= 0.01 {
                8
            } else if l0 >= 0.004 {
                4
            } else {
                1
            })
    };
    let ensembles: Vec<(f64, f64, Vec<f64>)> = spacings
        .iter()
        .map(|&l0| wedge_ensemble(l0, members(l0), &extra))
        .collect();
    for (l0, (c, se, values)) in spacings.iter().zip(&ensembles) {
        println!("l0 = {l0}: C_F = {c:.3} ± {se:.3} from {values:.3?}");
    }
    let errs: Vec<f64> = ensembles
        .iter()
        .map(|(c, _, _)| (c - C_SIMILARITY).abs() / C_SIMILARITY)
        .collect();
    println!("C_F errors by spacing {spacings:?}: {errs:?}");
    assert!(
        errs.windows(2).all(|w| w[0] > w[1]),
        "error does not decrease with spacing: {errs:?}"
    );
    assert!(errs[errs.len() - 1] < 0.10);
}

/// Coarse run kept in the default suite: at 1 cm the force must already grow linearly
/// from the keel contact with a coefficient between the von Karman (9.42) and Wagner
/// (23.26) bounds. Linear growth is checked on the impulse, whose origin the per-step
/// scatter does not move much. The pressure is asserted at the default spacing
/// (`wedge_force_and_pressure_at_default_spacing`): at 1 cm the peak is resolved by two
/// or three particles. It reads C_F = 12.50 ± 1.30 (-11.0 %), 13.21 from the onset, impulse
/// origin -0.64 ms.
#[test]
fn wedge_force_grows_linearly_at_one_centimetre() {
    let fit = wedge_fit(&["particle_spacing=0.01".into()]);
    assert!(
        fit.c > 9.42 && fit.c < C_WAGNER,
        "C_F = {:.3} outside the von Karman / Wagner bounds",
        fit.c
    );
    assert!(
        fit.t0_impulse.abs() < 0.25 * T_CHINE,
        "force does not start near the keel contact: t0 = {:.3} ms",
        1e3 * fit.t0_impulse
    );
}
