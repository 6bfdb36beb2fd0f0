//! Published drop tests of light models (tests/data/drop_tests/README.md: sources, the
//! models, the digitisation's uncertainty), written as a user would write them from the
//! README with the defaults and 100 spacings across the body, against the experiment
//! and against the published potential-flow solution of the same drop.
//!
//! The criteria are the drop-test work's: the velocity (the cylinder's record is its
//! penetration) within a mean 5 % and every point within 10 %, and the velocity lost
//! since entry within a mean 10 %. Neither model meets them yet: the engine's bodies
//! slow too little, against the experiment and against the published potential-flow
//! curve alike (numbers in docs/validation.md), and those tests are ignored. The wedge
//! follows quasi-steady potential flow (the similarity solution's force at its depth and
//! speed plus the potential-flow added mass of its acceleration) within a mean 1.3 %,
//! and that model itself reads 7.1 % (worst +14.7 %) from the experiment: what is left
//! is between the theory and the experiment, which a time-stepping potential-flow
//! solution of the decelerating drop would arbitrate.

use super::common::run_case_rows;
use mpsfsi::analysis::reference::{FreeFall, FreeFallModel, PotentialFlowFreeFall};
use mpsfsi::case::load_case_file;
use mpsfsi::run::RunStatus;
use std::f64::consts::PI;
use std::path::PathBuf;

fn data(name: &str) -> PathBuf {
    PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("tests/data/drop_tests")
        .join(name)
}

/// The two columns of a digitised curve.
fn curve(name: &str) -> Vec<(f64, f64)> {
    let path = data(name);
    let text = std::fs::read_to_string(&path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    text.lines()
        .skip(1)
        .map(|l| {
            let (a, b) = l.split_once(',').expect("two columns");
            (a.parse().expect("a number"), b.parse().expect("a number"))
        })
        .collect()
}

/// The case `name` of tests/data/drop_tests run with the defaults: `body`'s bodies.csv
/// rows as (time, y, downward velocity).
fn run_drop(name: &str, body: &str) -> Vec<(f64, f64, f64)> {
    let case = load_case_file(&data(name), &[]).unwrap_or_else(|e| panic!("{name}: {e}"));
    let (_, bodies, summary) = run_case_rows(case, name, body);
    assert_eq!(
        summary.status,
        RunStatus::Succeeded,
        "{name}: {:?}",
        summary.reason
    );
    bodies.iter().map(|r| (r[0], r[2], -r[5])).collect()
}

/// Linear interpolation of `column` of `rows` at time t (None outside them).
fn at(rows: &[(f64, f64, f64)], t: f64, column: impl Fn(&(f64, f64, f64)) -> f64) -> Option<f64> {
    rows.windows(2).find_map(|w| {
        let (a, b) = (&w[0], &w[1]);
        (a.0 <= t && t <= b.0)
            .then(|| column(a) + (column(b) - column(a)) * (t - a.0) / (b.0 - a.0))
    })
}

/// Mean and largest |relative error| of (computed, reference) pairs.
fn errors(pairs: &[(f64, f64)]) -> (f64, f64) {
    let e: Vec<f64> = pairs.iter().map(|(c, r)| ((c - r) / r).abs()).collect();
    let mean = e.iter().sum::<f64>() / e.len() as f64;
    (mean, e.iter().cloned().fold(0.0, f64::max))
}

const WEDGE_ENTRY_SPEED: f64 = 5.05;
/// Points whose speed lost since entry is below this (m/s) are left out of the lost
/// speed's relative error: the digitisation's 0.05 m/s would be a tenth of it.
const LEAST_LOSS: f64 = 0.5;

#[test]
#[ignore = "fails: 25° wedge of 94 kg/m at 12 mm, 10 s on two cores: velocity mean +7.8 %, worst +16.6 % (20 ms), speed lost 11.2 % short, against the experiment"]
fn a_light_wedge_slows_as_the_experiment_s_did() {
    let run = run_drop("wedge_25deg_94kg.json", "wedge");
    let mut report = Vec::new();
    for source in ["experiment", "potential_flow"] {
        let reference = curve(&format!("wedge_25deg_94kg_velocity_{source}.csv"));
        let pairs: Vec<(f64, f64)> = reference
            .iter()
            .filter_map(|&(ms, v)| at(&run, ms * 1e-3, |r| r.2).map(|c| (c, v)))
            .collect();
        let lost: Vec<(f64, f64)> = pairs
            .iter()
            .filter(|(_, v)| WEDGE_ENTRY_SPEED - v >= LEAST_LOSS)
            .map(|(c, v)| (WEDGE_ENTRY_SPEED - c, WEDGE_ENTRY_SPEED - v))
            .collect();
        let (mean, worst) = errors(&pairs);
        let (lost_mean, _) = errors(&lost);
        println!(
            "{source}: {} points, velocity mean {:.1} %, worst {:.1} %; speed lost mean {:.1} % ({} points)",
            pairs.len(),
            100.0 * mean,
            100.0 * worst,
            100.0 * lost_mean,
            lost.len()
        );
        report.push((source, pairs.len(), mean, worst, lost_mean));
    }
    let (_, points, mean, worst, lost_mean) = report[0];
    assert!(points >= 35, "{points} experimental points inside the run");
    assert!(mean <= 0.05, "velocity mean error {:.1} %", 100.0 * mean);
    assert!(worst <= 0.10, "velocity worst error {:.1} %", 100.0 * worst);
    assert!(
        lost_mean <= 0.10,
        "speed lost mean error {:.1} %",
        100.0 * lost_mean
    );
}

/// The 25° wedge drop against quasi-steady potential flow (`PotentialFlowFreeFall` with
/// the 25° similarity solution's C_F = 23.55 and its added mass of the acceleration,
/// 13.45 rho h², 1.14 C_F/2), at the experiment's 40 times: the velocity within a mean
/// 3 % and every point within 5 %. Reads 1.3 % (worst -3.1 % at 11 ms), 0.6 % at 6 mm.
/// With the momentum model's added mass (C_F/2) instead, the same run reads 2.3 % (worst
/// +5.1 %), 1.7 % at 6 mm.
#[test]
fn a_light_wedge_drop_follows_quasi_steady_potential_flow() {
    let similarity = mpsfsi::analysis::similarity::solution(25.0).unwrap();
    let model = PotentialFlowFreeFall {
        v0: WEDGE_ENTRY_SPEED,
        g: GRAVITY,
        mass: 94.0,
        density: 1000.0,
        force_coefficient: similarity.force_coefficient,
        acceleration_added_mass: mpsfsi::analysis::similarity::acceleration_added_mass(25.0)
            .unwrap(),
    };
    let run = run_drop("wedge_25deg_94kg.json", "wedge");
    let times: Vec<f64> = curve("wedge_25deg_94kg_velocity_experiment.csv")
        .iter()
        .map(|p| p.0 * 1e-3)
        .collect();
    let pairs: Vec<(f64, f64)> = times
        .iter()
        .zip(model.speeds(&times))
        .filter_map(|(&t, v)| at(&run, t, |r| r.2).map(|c| (c, v)))
        .collect();
    let (mean, worst) = errors(&pairs);
    println!(
        "against quasi-steady potential flow: {} points, velocity mean {:.1} %, worst {:.1} %",
        pairs.len(),
        100.0 * mean,
        100.0 * worst
    );
    assert!(pairs.len() >= 35, "{} points inside the run", pairs.len());
    assert!(mean <= 0.03, "velocity mean error {:.1} %", 100.0 * mean);
    assert!(worst <= 0.05, "velocity worst error {:.1} %", 100.0 * worst);
}

const CYLINDER_DIAMETER: f64 = 0.11;
const GRAVITY: f64 = 9.81;

#[test]
#[ignore = "fails: half-buoyant cylinder at 1.1 mm, 10 minutes on two cores: penetration mean +9.2 %, worst +23.7 % (the first point) against the experiment"]
fn a_half_buoyant_cylinder_sinks_as_the_experiment_s_did() {
    let run = run_drop("cylinder_rho500.json", "cylinder");
    // the height at first contact, back from the first row (its error, a t²/2 at 30 g
    // over half a millisecond, is 3e-4 D)
    let (t1, y1, v1) = *run.first().expect("rows");
    let y0 = y1 + v1 * t1;
    let time_scale = (CYLINDER_DIAMETER / GRAVITY).sqrt();
    let mut report = Vec::new();
    for source in ["experiment", "potential_flow"] {
        let reference = curve(&format!("cylinder_rho500_penetration_{source}.csv"));
        // the first contact itself (penetration 0) has no relative error
        let pairs: Vec<(f64, f64)> = reference
            .iter()
            .filter(|(_, z)| *z > 0.05)
            .filter_map(|&(ts, z)| {
                at(&run, ts * time_scale, |r| r.1).map(|y| ((y0 - y) / CYLINDER_DIAMETER, z))
            })
            .collect();
        let (mean, worst) = errors(&pairs);
        println!(
            "{source}: {} points, penetration mean {:.1} %, worst {:.1} %",
            pairs.len(),
            100.0 * mean,
            100.0 * worst
        );
        for (c, z) in &pairs {
            println!("  {z:.3} D measured, {c:.3} D computed");
        }
        report.push((pairs.len(), mean, worst));
    }
    let (points, mean, worst) = report[0];
    assert_eq!(points, 5, "experimental points inside the run");
    assert!(mean <= 0.05, "penetration mean error {:.1} %", 100.0 * mean);
    assert!(
        worst <= 0.10,
        "penetration worst error {:.1} %",
        100.0 * worst
    );
}

/// The digitised wedge curves against the two bounds of a momentum balance, the
/// momentum model of the free-fall references (`FreeFallModel`: (M + C_F ρ h²/2) V =
/// M (V0 + g t)) closed with von Kármán's C_F = π / tan² β (no pile-up: the least
/// force) and with Wagner's π³ / (4 tan² β) (the most), the flat plate's ρπc²/2 at
/// either theory's wetted half-width. Every point, within the digitisation's 0.05 m/s,
/// lies between them: a check of the data (a point off its curve, a wrong deadrise or
/// mass per metre), not of the engine.
#[test]
fn the_wedge_drop_data_lies_between_the_momentum_bounds() {
    let tan2 = 25f64.to_radians().tan().powi(2);
    let model = |force_coefficient: f64| FreeFallModel {
        v0: WEDGE_ENTRY_SPEED,
        g: GRAVITY,
        mass: 94.0,
        force_coefficient,
        density: 1000.0,
    };
    let (karman, wagner) = (model(PI / tan2), model(PI.powi(3) / (4.0 * tan2)));
    for source in ["experiment", "potential_flow"] {
        let points = curve(&format!("wedge_25deg_94kg_velocity_{source}.csv"));
        assert!(points.len() >= 30, "{source}: {} points", points.len());
        assert!(
            (points[0].1 - WEDGE_ENTRY_SPEED).abs() < 0.05,
            "{source} starts at {}",
            points[0].1
        );
        let times: Vec<f64> = points.iter().map(|p| p.0 * 1e-3).collect();
        let (most, least) = (karman.speeds(&times), wagner.speeds(&times));
        for ((&(ms, v), most), least) in points.iter().zip(most).zip(least) {
            assert!(
                v <= most + 0.05 && v >= least - 0.05,
                "{source} at {ms} ms: {v} m/s outside {least:.3}-{most:.3}"
            );
        }
    }
}

/// The digitised cylinder curves: the penetration grows with time and stays below the
/// free fall's V0 t + g t²/2 (the water only slows the body), within 0.02 D.
#[test]
fn the_cylinder_drop_data_is_a_possible_motion() {
    let entry_speed = 2.955;
    let time_scale = (CYLINDER_DIAMETER / GRAVITY).sqrt();
    for source in ["experiment", "potential_flow"] {
        let points = curve(&format!("cylinder_rho500_penetration_{source}.csv"));
        assert!(points.len() >= 6, "{source}: {} points", points.len());
        for w in points.windows(2) {
            assert!(w[1].0 > w[0].0 && w[1].1 > w[0].1, "{source}: {w:?}");
        }
        for &(ts, z) in &points {
            let t = ts * time_scale;
            let free = (entry_speed * t + GRAVITY * t * t / 2.0) / CYLINDER_DIAMETER;
            assert!(
                z <= free + 0.02,
                "{source} at {ts}: {z} D beyond free fall {free:.3} D"
            );
        }
    }
}
