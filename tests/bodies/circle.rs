//! A circular cylinder entering calm water at constant speed, written as a user would
//! write it from the README (the shipped wedge's tank, its body a 128-sided circle of
//! D = 0.5 m, 100 spacings across, the defaults). Its slamming coefficient
//! C_s = F / (½ ρ D V²) lies between the two published first-contact values
//! (docs/references.md): von Kármán's π (no rise of the free surface) and Wagner's 2π
//! (with it). Both theories hold at small penetration, so the coefficient is averaged
//! over z/D = 0.01–0.04: below 0.01 the wetted width is a few spacings and the force
//! is the first contact's transient; the window's mean reads 4.09 (25 rows).
//!
//! The advice of `mpsfsi check` for the same body is tested with
//! `analysis::envelope::wetted_deadrise` (a circle is not a flat face).

use super::common::{run_case_rows, shipped, RHO};
use mpsfsi::run::RunStatus;
use std::f64::consts::PI;

const RADIUS: f64 = 0.25;
const SPEED: f64 = 6.15;

#[test]
fn a_circle_s_slamming_coefficient_lies_between_von_karman_and_wagner() {
    let sides = 128;
    let polygon: Vec<String> = (0..sides)
        .map(|k| {
            let a = 2.0 * PI * k as f64 / sides as f64;
            format!("[{}, {}]", RADIUS * a.sin(), RADIUS * (1.0 - a.cos()))
        })
        .collect();
    let diameter = 2.0 * RADIUS;
    let end = 0.04 * diameter / SPEED;
    let case = shipped(
        "wedge_30deg_constant_velocity.json",
        &[
            format!("bodies.0.polygon=[{}]", polygon.join(", ")),
            "output.probes=[]".to_string(),
            format!("time.end={end}"),
        ],
    );
    let (loads, _, summary) = run_case_rows(case, "circle", "wedge");
    assert_eq!(summary.status, RunStatus::Succeeded, "{:?}", summary.reason);
    let cs: Vec<f64> = loads
        .iter()
        .filter(|r| (0.01..=0.04).contains(&(SPEED * r[0] / diameter)))
        .map(|r| r[2] / (0.5 * RHO * diameter * SPEED * SPEED))
        .collect();
    assert!(cs.len() >= 20, "{} rows in the window", cs.len());
    let mean = cs.iter().sum::<f64>() / cs.len() as f64;
    println!(
        "C_s over z/D = 0.01-0.04: mean {mean:.3} over {} rows",
        cs.len()
    );
    assert!(
        (PI..=2.0 * PI).contains(&mean),
        "C_s {mean:.3} outside [pi, 2 pi]"
    );
}
