//! The acceleration reaction of a wedge entry: the part of the force that a change of
//! speed adds at a given depth and speed. The shipped 30° wedge at 5 mm enters at
//! constant speed, at a constant deceleration and at a constant acceleration of 150 m/s²
//! (6.15 m/s at contact; 3.90 and 8.40 m/s at 15 ms). The constant-speed run gives the
//! force coefficient C = F / (rho U² h) over the window; in 1 ms bins, each other run's
//! F - C rho U² h is regressed on rho h² dU/dt, and the slope k is the added mass that
//! multiplies the acceleration, in units of rho h². The theories (docs/references.md,
//! Wedge entry) differ in it: the momentum model's C_F/2 = 7.02, the modified
//! Logvinovich model's pi k²/2 + k² tan β - 2k = 10.46 (k = pi / (2 tan β)), Wagner's
//! flat-plate rho pi c²/2 at Wagner's c, pi³ / (8 tan² β) = 11.63. Potential flow on the
//! similarity solution's wetted geometry gives 8.31
//! (`analysis::similarity`, its `acceleration_added_mass`): the reference the test
//! asserts. Over the four axis offsets of the impact ensembles the engine reads k = 8.84
//! (8.46 / 10.09 / 7.95 / 8.85, standard error 0.46; docs/validation.md).

use super::common::{run_case_rows, shipped};
use mpsfsi::run::RunStatus;

const RHO: f64 = 1000.0;
const V0: f64 = 6.15;
/// |dU/dt| of the accelerated entries (m/s²) and the time they reach their end speed.
const ACCELERATION: f64 = 150.0;
const END: f64 = 0.015;
/// Depths of the regression (m): from a few spacings of penetration to before the
/// decelerating wedge's last depth (0.075 m at 15 ms) and its chines' wetting.
const DEPTHS: (f64, f64) = (0.025, 0.072);

/// (time, fy) of the wedge's loads.csv and (time, y, vy) of its bodies.csv.
type Run = (Vec<(f64, f64)>, Vec<(f64, f64, f64)>);

/// The shipped wedge with `motion` (JSON), its axis `offset` l0 off the lattice.
fn run(motion: &str, offset: f64, tag: &str) -> Run {
    let case = shipped(
        "wedge_30deg_constant_velocity.json",
        &[
            format!("bodies.0.motion={motion}"),
            format!("bodies.0.position=[{}, 0.0]", offset * 0.005),
            "output.load_interval=1e-4".into(),
            "output.snapshot_interval=\"none\"".into(),
        ],
    );
    let (loads, bodies, summary) = run_case_rows(case, &format!("reaction-{tag}"), "wedge");
    assert_eq!(
        summary.status,
        RunStatus::Succeeded,
        "{tag}: {:?}",
        summary.reason
    );
    let loads = loads.iter().map(|r| (r[0], r[2])).collect();
    let bodies = bodies.iter().map(|r| (r[0], r[2], r[5])).collect();
    (loads, bodies)
}

/// The mean force over [t0, t1] of interval-mean rows.
fn mean_force(loads: &[(f64, f64)], t0: f64, t1: f64) -> f64 {
    let (mut last, mut impulse) = (0.0_f64, 0.0);
    for &(t, f) in loads {
        let (a, b) = (last.max(t0), t.min(t1));
        if b > a {
            impulse += f * (b - a);
        }
        last = t;
    }
    impulse / (t1 - t0)
}

/// Depth below first contact and downward speed at `t`, interpolated between samples.
fn depth_and_speed(bodies: &[(f64, f64, f64)], t: f64) -> Option<(f64, f64)> {
    let (t1, y1, v1) = bodies[0];
    let y_contact = y1 - 0.5 * (v1 - V0) * t1;
    bodies.windows(2).find_map(|w| {
        let ((ta, ya, va), (tb, yb, vb)) = (w[0], w[1]);
        (ta <= t && t <= tb).then(|| {
            let s = (t - ta) / (tb - ta);
            (y_contact - (ya + s * (yb - ya)), -(va + s * (vb - va)))
        })
    })
}

/// (depth, speed, mean force) of the 1 ms bins whose middle lies within `DEPTHS`.
fn bins(run: &Run) -> Vec<(f64, f64, f64)> {
    let (loads, bodies) = run;
    let width = 1e-3;
    (0..)
        .map(|k| k as f64 * width)
        .take_while(|t| t + width <= END)
        .filter_map(|t| {
            let (h, u) = depth_and_speed(bodies, t + 0.5 * width)?;
            (DEPTHS.0..=DEPTHS.1)
                .contains(&h)
                .then(|| (h, u, mean_force(loads, t, t + width)))
        })
        .collect()
}

/// k of one axis offset: the regression over both accelerated runs.
fn reaction_coefficient(offset: f64) -> f64 {
    let table = |v1: f64| {
        format!(
            r#"{{"type": "prescribed", "table": [{{"time": 0.0, "velocity": [0.0, {}]}}, {{"time": {END}, "velocity": [0.0, {v1}]}}]}}"#,
            -V0
        )
    };
    let steady = bins(&run(
        &format!(r#"{{"type": "prescribed", "velocity": [0.0, {}]}}"#, -V0),
        offset,
        &format!("cs-{offset}"),
    ));
    let c = steady
        .iter()
        .map(|&(h, u, f)| f / (RHO * u * u * h))
        .sum::<f64>()
        / steady.len() as f64;
    let (mut num, mut den) = (0.0, 0.0);
    for (dudt, v1) in [
        (-ACCELERATION, -(V0 - ACCELERATION * END)),
        (ACCELERATION, -(V0 + ACCELERATION * END)),
    ] {
        for (h, u, f) in bins(&run(&table(v1), offset, &format!("{dudt}-{offset}"))) {
            let x = RHO * h * h * dudt;
            num += (f - c * RHO * u * u * h) * x;
            den += x * x;
        }
    }
    let k = num / den;
    println!("axis offset {offset} l0: C = {c:.2}, k = {k:.2}");
    k
}

#[test]
#[ignore = "7 minutes on two cores; passes: k = 8.84 over four offsets, +6.4 % against 8.31"]
fn a_wedge_entry_s_acceleration_reaction_is_the_potential_flow_added_mass() {
    let beta = 30f64.to_radians();
    let kw = std::f64::consts::PI / (2.0 * beta.tan());
    let logvinovich = std::f64::consts::PI * kw * kw / 2.0 + kw * kw * beta.tan() - 2.0 * kw;
    let momentum = mpsfsi::analysis::reference::WEDGE_30_FORCE_COEFFICIENT / 2.0;
    let potential = mpsfsi::analysis::similarity::acceleration_added_mass(30.0).unwrap();
    let ks: Vec<f64> = super::impact::AXIS_OFFSETS
        .iter()
        .map(|&d| reaction_coefficient(d))
        .collect();
    let mean = ks.iter().sum::<f64>() / ks.len() as f64;
    println!(
        "k = {mean:.2} over {ks:?}; potential flow {potential:.2}, momentum model {momentum:.2}, Logvinovich {logvinovich:.2}"
    );
    // the four offsets scatter by 0.91 about their mean: 10 % is about two standard
    // errors of it (0.46), and excludes the momentum model (-16 %) and Logvinovich's
    // (+26 %)
    assert!(
        (mean / potential - 1.0).abs() <= 0.10,
        "the acceleration reaction {mean:.2} rho h² is more than 10 % from potential flow's {potential:.2}"
    );
}
