//! `--uncertainty` on the shipped 30° wedge against the similarity solution (C_F =
//! 14.04, docs/references.md): between 30 % and 95 % of the run, the share of rows
//! whose band holds the reference force, the band's width (mean u_fy over mean |fy|),
//! and the ladder's cost over the single run; the same for the free falls against the
//! momentum model.

use mpsfsi::analysis::uncertainty::UncertaintySummary;
use mpsfsi::case::{load_case_file, Limits, ValidCase};
use mpsfsi::run::uncertainty::run_with_uncertainty;
use mpsfsi::run::{Quiet, RunStatus};
use std::path::PathBuf;

const C_SIMILARITY: f64 = 14.04;
/// The shipped wedge's entry speed (m/s).
const V: f64 = 6.15;

struct Reading {
    coverage: f64,
    width: f64,
    particle_steps_ratio: f64,
    cost_ratio: f64,
    impulse: (f64, f64),
}

fn wedge_with_uncertainty(name: &str, overrides: &[String]) -> Reading {
    let path =
        PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("cases/wedge_30deg_constant_velocity.json");
    let case = ValidCase::new(
        load_case_file(&path, overrides).unwrap(),
        &Limits::default(),
    )
    .unwrap();
    ladder_against_similarity(name, &case, C_SIMILARITY)
}

/// Run `case` with `--uncertainty` into the target's scratch directory `name`: the run
/// directory and its uncertainty block.
fn ladder(name: &str, case: &ValidCase) -> (PathBuf, UncertaintySummary) {
    let out = PathBuf::from(env!("CARGO_TARGET_TMPDIR")).join(name);
    let _ = std::fs::remove_dir_all(&out);
    std::fs::create_dir_all(&out).unwrap();
    let summary = run_with_uncertainty(case, &out, &mut Quiet).unwrap();
    assert_eq!(summary.status, RunStatus::Succeeded, "{:?}", summary.reason);
    (out, summary.uncertainty.expect("an uncertainty block"))
}

/// The wedge's rows of `file` (an `_uncertainty.csv` of run directory `out`) between 30 %
/// and 95 % of the run's `end`: (time, `column`, its half-width `u_column`).
fn band_rows(out: &std::path::Path, file: &str, column: &str, end: f64) -> Vec<(f64, f64, f64)> {
    let text = std::fs::read_to_string(out.join(file)).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let col = |c: &str| header.iter().position(|h| *h == c).unwrap();
    let (t, body, x, ux) = (
        col("time"),
        col("body"),
        col(column),
        col(&format!("u_{column}")),
    );
    lines
        .map(|l| l.split(',').collect::<Vec<&str>>())
        .filter(|f| f[body] == "wedge")
        .map(|f| {
            (
                f[t].parse().unwrap(),
                f[x].parse().unwrap(),
                f[ux].parse().unwrap(),
            )
        })
        .filter(|(t, _, _): &(f64, f64, f64)| *t >= 0.3 * end && *t <= 0.95 * end)
        .collect()
}

/// Run `case` (a wedge named "wedge" entering at V from t = 0) with `--uncertainty` and
/// read its band against the similarity force `c_f` ρ V³ t.
fn ladder_against_similarity(name: &str, case: &ValidCase, c_f: f64) -> Reading {
    let (out, u) = ladder(name, case);
    let end = case.time.end;
    let rows = band_rows(&out, "loads_uncertainty.csv", "fy", end);
    let inside = rows
        .iter()
        .filter(|(t, fy, u)| (fy - c_f * 1000.0 * V.powi(3) * t).abs() <= *u)
        .count();
    let width: f64 = rows.iter().map(|r| r.2).sum();
    let force: f64 = rows.iter().map(|r| r.1.abs()).sum();
    let rows = rows.len();
    let wedge = u.bodies.iter().find(|b| b.name == "wedge").unwrap();
    let fy = wedge.columns.iter().find(|c| c.column == "fy").unwrap();
    let r = Reading {
        coverage: inside as f64 / rows as f64,
        width: width / force,
        particle_steps_ratio: u.particle_steps_ratio,
        cost_ratio: u.cost_ratio,
        impulse: (fy.impulse.value, fy.impulse.half_width),
    };
    println!(
        "{name}: coverage {:.3} of {rows} rows, width {:.3}, cost {:.2} (particle steps {:.2}), impulse {:.2} ± {:.2} N s/m against {:.2}; levels {:?}",
        r.coverage,
        r.width,
        r.cost_ratio,
        r.particle_steps_ratio,
        r.impulse.0,
        r.impulse.1,
        0.5 * c_f * 1000.0 * V.powi(3) * end * end,
        u.levels.iter().map(|l| (l.spacing, l.members, l.wall_time_s)).collect::<Vec<_>>()
    );
    r
}

/// At 1 cm (50 spacings across the wedge): the band holds the reference on at least
/// 90 % of the rows and the similarity impulse (367.4 N s/m), and the ladder costs
/// under 3.25 single runs in particle updates. It reads coverage 0.98, width 2.14 (the
/// issue's 10 % is not met: see docs/uncertainty.md), 3.07 particle-step runs: the
/// automatic layout's 4 l0 level takes more off the user's run than off the coarser
/// levels, whose 4 l0 squares keep a clearance from the water's edges that is wider in
/// metres.
#[test]
fn the_wedge_band_holds_the_similarity_force() {
    let r = wedge_with_uncertainty("uncertainty_wedge_1cm", &["particle_spacing=0.01".into()]);
    assert!(r.coverage >= 0.9, "coverage {}", r.coverage);
    let reference = 0.5 * C_SIMILARITY * 1000.0 * V.powi(3) * 0.015f64.powi(2);
    assert!(
        (r.impulse.0 - reference).abs() <= r.impulse.1,
        "impulse {:?} against {reference}",
        r.impulse
    );
    assert!(r.particle_steps_ratio < 3.25, "{}", r.particle_steps_ratio);
}

/// The shipped spacing (5 mm, 100 spacings across): coverage at least 0.9 and the cost
/// under 2.5 runs in particle updates. It reads coverage 1.00, cost 2.65 (wall) and
/// 2.29 (particle updates); the width, 3.43, is far from the 0.10 aimed at and is
/// printed, not asserted (docs/uncertainty.md says why).
#[test]
#[ignore = "about 100 s on two cores; numbers in docs/uncertainty.md"]
fn the_shipped_wedge_band_is_honest_and_its_cost_bounded() {
    let r = wedge_with_uncertainty("uncertainty_wedge_shipped", &[]);
    assert!(r.coverage >= 0.9, "coverage {}", r.coverage);
    assert!(r.particle_steps_ratio <= 2.5, "{}", r.particle_steps_ratio);
}

/// The user-style family (tests/bodies/impact.rs: B/l0 = 100, a tank 8B x 2.4B, run to
/// the chine time) against the similarity C_F of docs/references.md. It reads coverage
/// 1.00 at every deadrise and widths 1.61 / 1.80 / 3.52 / 2.22 (15 / 25 / 30 / 40°),
/// particle-step costs 1.86 / 2.09 / 2.13 / 2.23.
#[test]
#[ignore = "about 6 minutes on two cores; numbers in docs/uncertainty.md"]
fn the_user_style_family_bands_hold_the_similarity_force() {
    use crate::impact::{chine_time, user_wedge};
    for (deadrise, c_f) in [(15.0, 85.0), (25.0, 23.61), (30.0, 14.04), (40.0, 5.45)] {
        let text = user_wedge(deadrise, 0.005, chine_time(deadrise));
        let case = mpsfsi::case::parse_case_str(&text).unwrap();
        let case = ValidCase::new(case, &Limits::default()).unwrap();
        let r = ladder_against_similarity(&format!("uncertainty_family_{deadrise}"), &case, c_f);
        assert!(r.coverage >= 0.9, "{deadrise}°: coverage {}", r.coverage);
        assert!(
            r.particle_steps_ratio <= 2.5,
            "{deadrise}°: {}",
            r.particle_steps_ratio
        );
    }
}

/// One free fall's band against the momentum model (the free-fall reference of the
/// drop-test measurements, docs/validation.md): the share of rows between 30 % and 95 %
/// of the run whose band holds the model's force M (g - dV/dt) and downward speed, and
/// the widths, mean u_fy over mean |fy| and mean u_vy over the mean speed lost.
struct FreeFallReading {
    force_coverage: f64,
    force_width: f64,
    speed_coverage: f64,
    speed_width: f64,
    particle_steps_ratio: f64,
}

fn free_fall_with_uncertainty(mass: f64) -> FreeFallReading {
    use mpsfsi::analysis::reference::FreeFall;
    let case = mpsfsi::case::parse_case_str(&crate::impact::free_fall_case(mass, 0.0)).unwrap();
    let model = crate::common::momentum_model(&case, mass);
    let (v0, g) = (model.v0, model.g);
    let case = ValidCase::new(case, &Limits::default()).unwrap();
    let name = format!("uncertainty_free_fall_{mass}");
    let (out, u) = ladder(&name, &case);
    let end = case.time.end;
    // the model's speed and force (upward on the body) at t, from a central difference
    // of its speed over 1 µs
    let reference = |t: f64| {
        let v = model.speeds(&[t - 1e-6, t, t + 1e-6]);
        (v[1], mass * (g - (v[2] - v[0]) / 2e-6))
    };
    let share = |hits: usize, n: usize| hits as f64 / n as f64;
    let forces = band_rows(&out, "loads_uncertainty.csv", "fy", end);
    let force_hits = forces
        .iter()
        .filter(|(t, fy, u)| (fy - reference(*t).1).abs() <= *u)
        .count();
    let force_width =
        forces.iter().map(|r| r.2).sum::<f64>() / forces.iter().map(|r| r.1.abs()).sum::<f64>();
    let speeds = band_rows(&out, "bodies_uncertainty.csv", "vy", end);
    let speed_hits = speeds
        .iter()
        .filter(|(t, vy, u)| (-vy - reference(*t).0).abs() <= *u)
        .count();
    let speed_width =
        speeds.iter().map(|r| r.2).sum::<f64>() / speeds.iter().map(|r| v0 + r.1).sum::<f64>();
    let r = FreeFallReading {
        force_coverage: share(force_hits, forces.len()),
        force_width,
        speed_coverage: share(speed_hits, speeds.len()),
        speed_width,
        particle_steps_ratio: u.particle_steps_ratio,
    };
    println!(
        "{name}: force coverage {:.3} of {} rows, width {:.3}; speed coverage {:.3} of {} rows, width {:.3} of the speed lost; cost {:.2} (particle steps {:.2})",
        r.force_coverage,
        forces.len(),
        r.force_width,
        r.speed_coverage,
        speeds.len(),
        r.speed_width,
        u.cost_ratio,
        r.particle_steps_ratio,
    );
    r
}

/// The shipped free fall (241 kg/m) and a quarter of its mass at the case's 5 mm: the
/// band holds the momentum model's force and speed on at least 90 % of the rows, and the
/// ladder costs at most 2.5 single runs in particle updates. The widths are printed,
/// not asserted: like the constant-speed wedge's they are far from the 10 % aimed at
/// (docs/uncertainty.md).
#[test]
#[ignore = "about 60 s on two cores; numbers in docs/uncertainty.md"]
fn the_free_fall_bands_hold_the_momentum_model() {
    for mass in [241.0, 60.25] {
        let r = free_fall_with_uncertainty(mass);
        assert!(
            r.force_coverage >= 0.9,
            "{mass} kg/m: force coverage {}",
            r.force_coverage
        );
        assert!(
            r.speed_coverage >= 0.9,
            "{mass} kg/m: speed coverage {}",
            r.speed_coverage
        );
        assert!(
            r.particle_steps_ratio <= 2.5,
            "{mass} kg/m: {}",
            r.particle_steps_ratio
        );
    }
}
