//! The pure measures of `bench --scaling`, `--features` and `--stress`: exponent fit,
//! `/proc` parsing, tables, perturbation, load drift, chine time. All fast.

use mpsfsi::bench::cases::{tank_case_value, tank_lattice};
use mpsfsi::bench::features::{feature_rows, FeatureSample};
use mpsfsi::bench::perturb::perturb_positions;
use mpsfsi::bench::resources::parse_status_bytes;
use mpsfsi::bench::scaling::{
    scaling_csv, scaling_csv_header, scaling_markdown, stage_difference, stage_ms_per_step,
    step_cost_fit, thread_speedup, ScalingOptions, ScalingPoint,
};
use mpsfsi::bench::stats::{fit_power_law, median, spread, window_mean};
use mpsfsi::bench::stress::{chine_time, load_drift, stress_table, StressOutcome};
use mpsfsi::engine::StageTimes;
use mpsfsi::math::Vec2;

#[test]
fn the_power_law_fit_recovers_an_exact_exponent_and_ignores_unusable_points() {
    let points: Vec<(f64, f64)> = [1e4, 4e4, 1.6e5, 6.4e5]
        .iter()
        .map(|&n| (n, 3e-3 * f64::powf(n, 1.37)))
        .collect();
    let fit = fit_power_law(&points).unwrap();
    assert!((fit.exponent - 1.37).abs() < 1e-12, "{fit:?}");
    assert!((fit.prefactor / 3e-3 - 1.0).abs() < 1e-9, "{fit:?}");
    assert!((fit.r2 - 1.0).abs() < 1e-12);
    // NaN, zero and negative points are dropped, not propagated
    let mut noisy = points.clone();
    noisy.push((2e5, f64::NAN));
    noisy.push((0.0, 1.0));
    noisy.push((3e5, -1.0));
    assert!((fit_power_law(&noisy).unwrap().exponent - 1.37).abs() < 1e-12);
    // one point or equal abscissae: no fit
    assert!(fit_power_law(&points[..1]).is_none());
    assert!(fit_power_law(&[(5.0, 1.0), (5.0, 2.0)]).is_none());
}

#[test]
fn the_power_law_fit_is_least_squares_on_log_log() {
    // y = x at x = 1, y = 4 at x = 2, y = 4 at x = 4: slopes ln4/ln2 = 2 then 0;
    // least squares over ln x = 0, ln2, 2 ln2 with ln y = 0, 2 ln2, 2 ln2 gives 1
    let fit = fit_power_law(&[(1.0, 1.0), (2.0, 4.0), (4.0, 4.0)]).unwrap();
    assert!((fit.exponent - 1.0).abs() < 1e-12, "{fit:?}");
    assert!(fit.r2 < 1.0 && fit.r2 > 0.5);
}

#[test]
fn proc_status_fields_are_read_in_bytes() {
    let status = "Name:\tmpsfsi\nVmPeak:\t  123456 kB\nVmHWM:\t    2092 kB\nVmRSS:\t    1024 kB\nThreads:\t3\n";
    assert_eq!(parse_status_bytes(status, "VmHWM"), Some(2092 * 1024));
    assert_eq!(parse_status_bytes(status, "VmRSS"), Some(1024 * 1024));
    assert_eq!(parse_status_bytes(status, "Threads"), Some(3));
    // a prefix of another key does not match
    assert_eq!(parse_status_bytes(status, "VmP"), None);
    assert_eq!(parse_status_bytes(status, "VmSwap"), None);
    assert_eq!(parse_status_bytes("VmRSS:\tlots kB\n", "VmRSS"), None);
    // this process has them (Linux)
    if std::path::Path::new("/proc/self/status").exists() {
        let (rss, hwm) = mpsfsi::bench::resources::memory_now().unwrap();
        assert!(rss > 0 && hwm >= rss);
    }
}

#[test]
fn median_and_spread_skip_non_finite_values() {
    assert_eq!(median(&[3.0, 1.0, 2.0]), Some(2.0));
    assert_eq!(median(&[4.0, 1.0, 2.0, 3.0]), Some(2.5));
    assert_eq!(median(&[f64::NAN, 5.0]), Some(5.0));
    assert_eq!(median(&[]), None);
    assert_eq!(spread(&[1.0, 4.0, 2.0, f64::NAN]), 3.0);
    assert_eq!(spread(&[1.0]), 0.0);
}

#[test]
fn stage_times_are_differenced_and_scaled_to_ms_per_step() {
    let before = StageTimes {
        solve: 1.0,
        assemble: 0.5,
        ..Default::default()
    };
    let after = StageTimes {
        solve: 3.0,
        assemble: 1.5,
        neighbors: 0.2,
        ..Default::default()
    };
    let d = stage_difference(&after, &before);
    let per = stage_ms_per_step(&d, 10);
    assert!((per.solve - 200.0).abs() < 1e-9);
    assert!((per.assemble - 100.0).abs() < 1e-9);
    assert!((per.neighbors - 20.0).abs() < 1e-9);
    assert!((per.total() - 320.0).abs() < 1e-9);
}

#[test]
fn the_scaling_tank_is_two_to_one_near_the_target_and_valid() {
    for target in [10_000, 40_000, 160_000, 1_300_000] {
        let (nx, ny) = tank_lattice(target);
        assert_eq!(nx, 2 * ny);
        let n = (nx * ny) as f64;
        assert!(
            (n / target as f64 - 1.0).abs() < 0.02,
            "{target}: {nx} x {ny}"
        );
    }
    let case = mpsfsi::case::parse_case_value(tank_case_value(10_000, 20)).unwrap();
    mpsfsi::case::validate(&case, &mpsfsi::case::Limits::default()).unwrap();
    assert_eq!(case.time.max_dt, 5.0e-4);
    assert!((case.time.end - 20.0 * 5.0e-4).abs() < 1e-12);
    assert_eq!(case.scheme.solver_tolerance, 1e-8);
    let (nx, ny) = tank_lattice(10_000);
    let estimated = mpsfsi::case::estimated_particles(&case).unwrap();
    assert!(
        (estimated / (nx * ny) as f64 - 1.0).abs() < 1e-9,
        "{estimated}"
    );
}

fn point(study: &str, threads: usize, n: usize, ms: f64) -> ScalingPoint {
    ScalingPoint {
        study: study.into(),
        threads,
        particles: n,
        steps: 20,
        build_s: 0.1,
        warmup_ms: 2.0 * ms,
        ms_per_step: ms,
        cpu_ms_per_step: threads as f64 * ms,
        stage_ms: StageTimes {
            solve: 0.7 * ms,
            assemble: 0.2 * ms,
            neighbors: 0.1 * ms,
            ..Default::default()
        },
        solver_iterations_per_step: 50.0,
        particle_steps_per_s: n as f64 / (ms * 1e-3),
        bytes_per_particle_built: 300.0,
        bytes_per_particle_peak: 1200.0,
        rss_before_mb: 10.0,
        peak_mb: 10.0 + n as f64 * 1200.0 / 1048576.0,
        status: "succeeded".into(),
        note: String::new(),
    }
}

#[test]
fn the_scaling_tables_carry_every_row_and_the_fitted_exponent() {
    let mut rows: Vec<ScalingPoint> = [10_000usize, 40_000, 160_000]
        .iter()
        .map(|&n| point("size", 2, n, 1e-3 * (n as f64).powf(1.5)))
        .collect();
    let mut failed = point("size", 2, 640_000, f64::NAN);
    failed.status = "failed".into();
    failed.note =
        "step 3, t = 0.0015 s: pressure solve failed: no convergence, 2000 iterations".into();
    rows.push(failed);
    rows.push(point("threads", 1, 40_000, 10.0));
    rows.push(point("threads", 2, 40_000, 6.0));
    rows.push(point("threads", 1, 40_000, 8.0));
    rows.push(point("threads", 2, 40_000, 5.0));
    // the fit uses the succeeded size rows only
    let fit = step_cost_fit(&rows).unwrap();
    assert!((fit.exponent - 1.5).abs() < 1e-9, "{fit:?}");
    // fastest of each thread count: 8 / 5
    let (total, solve) = thread_speedup(&rows).unwrap();
    assert!((total - 1.6).abs() < 1e-12 && (solve - 1.6).abs() < 1e-12);

    let csv = scaling_csv(&rows);
    let mut lines = csv.lines();
    assert_eq!(lines.next().unwrap(), scaling_csv_header());
    let columns = scaling_csv_header().split(',').count();
    assert_eq!(csv.lines().count(), rows.len() + 1);
    for line in csv.lines().skip(1) {
        // the note with a comma is quoted: count fields with the csv reader
        let mut reader = csv::ReaderBuilder::new()
            .has_headers(false)
            .from_reader(line.as_bytes());
        let record = reader.records().next().unwrap().unwrap();
        assert_eq!(record.len(), columns, "{line}");
    }
    assert!(csv.contains("size,2,640000,20,"));
    assert!(csv.contains("\"step 3, t = 0.0015 s: pressure solve failed"));

    let md = scaling_markdown(&rows, &ScalingOptions::default());
    assert!(md.contains("Step cost grows as N^1.50"), "{md}");
    assert!(md.contains("over 3 sizes"), "{md}");
    assert!(md.contains("Speed-up 2 threads / 1 thread: 1.60×"), "{md}");
    assert!(md.contains("| 160000 | 2 |"), "{md}");
    assert!(md.contains("failed: step 3"), "{md}");
    assert!(
        md.contains("the largest stages are solve 70%, assemble 20%, neighbors 10%"),
        "{md}"
    );
    assert!(!md.contains("cores on average"), "{md}");
    // 2-thread runs that got less than 1.5 cores say so
    for r in rows
        .iter_mut()
        .filter(|r| r.study == "threads" && r.threads == 2)
    {
        r.cpu_ms_per_step = 0.9 * r.ms_per_step;
    }
    let md = scaling_markdown(&rows, &ScalingOptions::default());
    assert!(
        md.contains("The 2-thread runs had 0.90 cores on average"),
        "{md}"
    );
}

fn sample(variant: &str, ms: f64) -> FeatureSample {
    FeatureSample {
        variant: variant.into(),
        particles: 20_000,
        steps: 30,
        ms_per_step: ms,
        cpu_ms_per_step: 2.0 * ms,
        status: "succeeded".into(),
    }
}

#[test]
fn feature_rows_compare_medians_with_the_noise_of_the_repeats() {
    let samples = vec![
        sample("bare", 100.0),
        sample("probes", 101.0),
        sample("body", 130.0),
        sample("bare", 104.0),
        sample("probes", 99.0),
        sample("body", 128.0),
        sample("bare", 98.0),
        sample("probes", 102.0),
        sample("body", 131.0),
    ];
    let variants = [
        ("bare", "nothing"),
        ("probes", "8 probes"),
        ("body", "a box"),
    ];
    let rows = feature_rows(&variants, &samples, "bare");
    assert_eq!(rows.len(), 3);
    assert_eq!(rows[0].median_ms, 100.0);
    assert_eq!(rows[0].spread_ms, 6.0);
    assert_eq!(rows[0].difference_ms, 0.0);
    assert_eq!(rows[1].median_ms, 101.0);
    assert_eq!(rows[1].difference_ms, 1.0);
    assert_eq!(rows[1].noise_ms, 6.0);
    assert!(rows[1].within_noise());
    assert_eq!(rows[2].median_ms, 130.0);
    assert_eq!(rows[2].min_ms, 128.0);
    assert_eq!(rows[2].median_cpu_ms, 260.0);
    assert!(!rows[2].within_noise());
    let md = mpsfsi::bench::features::features_markdown(&rows, 3);
    assert!(
        md.contains("| probes | 8 probes | 20000 | 101.000 |"),
        "{md}"
    );
    assert_eq!(rows[2].cpu_difference_ms, 60.0);
    assert_eq!(rows[2].cpu_noise_ms, 12.0);
    assert!(!rows[2].cpu_within_noise() && rows[1].cpu_within_noise());
    assert!(md.contains("within noise"), "{md}");
    assert!(md.contains("+30.0% (above noise)"), "{md}");
}

#[test]
fn the_perturbation_is_seeded_bounded_and_not_biased() {
    let lattice: Vec<Vec2> = (0..2000)
        .map(|k| Vec2::new((k % 50) as f64, (k / 50) as f64))
        .collect();
    let mut a = lattice.clone();
    let mut b = lattice.clone();
    perturb_positions(&mut a, 0.2, 7);
    perturb_positions(&mut b, 0.2, 7);
    assert_eq!(a, b, "same seed, same offsets");
    let mut c = lattice.clone();
    perturb_positions(&mut c, 0.2, 8);
    assert_ne!(a, c);
    let offsets: Vec<Vec2> = a.iter().zip(&lattice).map(|(p, q)| p - q).collect();
    assert!(offsets.iter().all(|d| d.x.abs() <= 0.2 && d.y.abs() <= 0.2));
    // uniform on [-0.2, 0.2]: mean ~ 0, the extremes reached, variance 0.04/3
    let n = offsets.len() as f64;
    let mean_x = offsets.iter().map(|d| d.x).sum::<f64>() / n;
    let var_x = offsets.iter().map(|d| d.x * d.x).sum::<f64>() / n;
    assert!(mean_x.abs() < 0.01, "{mean_x}");
    assert!((var_x / (0.04 / 3.0) - 1.0).abs() < 0.1, "{var_x}");
    assert!(offsets.iter().any(|d| d.x > 0.19) && offsets.iter().any(|d| d.y < -0.19));
}

#[test]
fn load_drift_compares_the_early_and_late_windows_with_the_weight() {
    // interval means every 0.1 s over 10 s: -100 until 5 s, then -110
    let times: Vec<f64> = (1..=100).map(|k| 0.1 * k as f64).collect();
    let loads: Vec<f64> = times
        .iter()
        .map(|&t| if t <= 5.0 + 1e-9 { -100.0 } else { -110.0 })
        .collect();
    let (early, late) = load_drift(&times, &loads, 10.0, -100.0);
    assert!(early.abs() < 1e-12, "{early}");
    assert!((late - 0.1).abs() < 1e-12, "{late}");
    // a window is time-weighted over the intervals inside it
    let m = window_mean(0.0, &[1.0, 3.0], &[1.0, 4.0], 0.0, 3.0).unwrap();
    assert!((m - 3.0).abs() < 1e-12);
    assert!(window_mean(0.0, &[1.0], &[1.0], 2.0, 3.0).is_none());
    // a run that stopped early has no late window
    let (_, late) = load_drift(&times[..5], &loads[..5], 10.0, -100.0);
    assert!(late.is_nan());
}

#[test]
fn the_chine_time_of_the_reference_wedge_is_b_tan_beta_over_pi_v() {
    let wedge = [
        [0.0, 0.0],
        [0.25, 0.1443],
        [0.25, 0.3],
        [-0.25, 0.3],
        [-0.25, 0.1443],
    ];
    let (contact, t) = chine_time(&wedge, [0.0, 0.0], 0.0, [0.0, -6.15], 0.0).unwrap();
    assert!(contact.abs() < 1e-12);
    // docs/references.md: t_chine = 14.9 ms
    assert!((t - 0.0149).abs() < 1e-4, "{t}");
    let (_, t20) = chine_time(&wedge, [0.0, 0.0], 0.0, [0.0, -20.0], 0.0).unwrap();
    assert!((t20 - 0.5 * 30f64.to_radians().tan() / (std::f64::consts::PI * 20.0)).abs() < 1e-4);
    // heeled 10°: the 20° side reaches its chine first (height 0.25 sin(-10°)... lower)
    let heel = 10f64.to_radians();
    let (_, th) = chine_time(&wedge, [0.0, 0.0], heel, [0.0, -6.15], 0.0).unwrap();
    let low_chine = -0.25 * heel.sin() + 0.1443 * heel.cos();
    assert!((th - 2.0 * low_chine / (std::f64::consts::PI * 6.15)).abs() < 1e-12);
    assert!(th < t);
    // the keel 0.1 m above the surface: contact after 0.1 / V
    let (contact, _) = chine_time(&wedge, [0.0, 0.1], 0.0, [0.0, -5.0], 0.0).unwrap();
    assert!((contact - 0.02).abs() < 1e-12);
    // no motion: no time scale
    assert!(chine_time(&wedge, [0.0, 0.0], 0.0, [0.0, 0.0], 0.0).is_none());
}

#[test]
fn the_stress_table_shows_failures_with_their_diagnosis() {
    let row = StressOutcome {
        name: "wedge_30ms".into(),
        description: "fast".into(),
        status: "failed".into(),
        reason: "step 40, t = 0.001300 s: runaway velocity 151 m/s | limit 150".into(),
        end_time: 0.0031,
        final_time: 0.0013,
        steps: 40,
        particles: 20_000,
        wall_time_s: 3.0,
        max_speed: f64::NAN,
        load_error_early: f64::NAN,
        load_error_late: 0.0123,
    };
    let md = stress_table(&[row]);
    assert!(
        md.contains("| wedge_30ms | failed | 0.0013 / 0.0031 | 40 | 20000 |"),
        "{md}"
    );
    assert!(md.contains("1.23%"), "{md}");
    // a pipe in the diagnosis does not break the table
    assert!(md.contains("runaway velocity 151 m/s / limit 150"), "{md}");
}

#[test]
fn a_tiny_tank_is_measured_with_stages_iterations_and_memory() {
    let value = tank_case_value(800, 3);
    let case = mpsfsi::case::parse_case_value(value).unwrap();
    let row = mpsfsi::bench::scaling::measure_engine(&case, 3, 5.0e-4, "size");
    assert_eq!(row.status, "succeeded", "{row:?}");
    assert_eq!(row.steps, 3);
    assert!(row.particles > 700 && row.particles < 900);
    assert!(row.ms_per_step > 0.0 && row.particle_steps_per_s > 0.0);
    // the first step solves from p = 0; the still tank is then an exact discrete
    // equilibrium, so the warm-started later steps may need no iteration at all
    assert!(row.solver_iterations_per_step > 0.0, "{row:?}");
    // the stages account for the step (the rest is the loop itself)
    assert!(
        row.stage_ms.total() <= row.ms_per_step * 1.001 + 1e-6,
        "{row:?}"
    );
    assert!(row.stage_ms.total() > 0.5 * row.ms_per_step, "{row:?}");
    if std::path::Path::new("/proc/self/status").exists() {
        assert!(row.peak_mb.is_finite() && row.bytes_per_particle_peak.is_finite());
    }
}

#[test]
fn a_perturbed_tank_runs_through_the_stress_driver() {
    use mpsfsi::bench::stress::{run_stress, StressKind, StressRun};
    let mut value = crate::small_tank();
    value["time"]["end"] = serde_json::json!(0.01);
    let run = StressRun {
        name: "perturbed".into(),
        description: "tiny".into(),
        case: value,
        kind: StressKind::PerturbedTank {
            amplitude: 0.2,
            seed: 1,
        },
    };
    let dir = crate::scratch_dir("stress-perturbed");
    let o = run_stress(&run, &dir);
    assert_eq!(o.status, "completed", "{o:?}");
    assert!((o.final_time - 0.01).abs() < 1e-9);
    assert_eq!(o.particles, 200);
    assert!(
        o.max_speed.is_finite() && o.load_error_late.is_finite(),
        "{o:?}"
    );
}
