use crate::scratch_dir;
use mpsfsi::case::parse_case_value;
use mpsfsi::output::filter::{filter_window, impulse, moving_average, write_filtered_loads};
use mpsfsi::output::loads_csv::{parse_loads_csv, LoadRow};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

fn uniform_times(n: usize, dt: f64) -> Vec<f64> {
    (1..=n).map(|k| k as f64 * dt).collect()
}

#[test]
fn the_impulse_of_a_random_signal_is_kept_to_1e_12() {
    let mut rng = ChaCha8Rng::seed_from_u64(42);
    // uniform sampling, and irregular sampling (loads written every step)
    let uniform = uniform_times(500, 1e-4);
    let mut t = 0.0;
    let irregular: Vec<f64> = (0..500)
        .map(|_| {
            t += rng.random_range(2e-5..3e-4);
            t
        })
        .collect();
    for times in [uniform, irregular] {
        let values: Vec<f64> = times
            .iter()
            .map(|_| rng.random_range(-1.0..1.0) * 1e3 + 200.0)
            .collect();
        let raw = impulse(0.0, &times, &values);
        let span = *times.last().unwrap();
        for window in [1e-4, 7.3e-4, 3e-3, 0.5 * span, 2.0 * span] {
            let filtered = moving_average(0.0, &times, &values, window);
            let kept = impulse(0.0, &times, &filtered);
            assert!(
                ((kept - raw) / raw).abs() < 1e-12,
                "window {window}: {kept} vs {raw}"
            );
        }
    }
}

#[test]
fn a_constant_stays_constant_and_a_ramp_is_not_shifted() {
    let times = uniform_times(200, 1e-3);
    let constant = vec![3.5; times.len()];
    for v in moving_average(0.0, &times, &constant, 9e-3) {
        assert!((v - 3.5).abs() < 1e-12);
    }
    // interval means of f = 2 + 50 t are f at the interval midpoints
    let ramp: Vec<f64> = times.iter().map(|t| 2.0 + 50.0 * (t - 0.5e-3)).collect();
    let window = 9e-3;
    let smooth = moving_average(0.0, &times, &ramp, window);
    let mut interior = 0;
    for (k, t) in times.iter().enumerate() {
        if *t - 1e-3 > window && *t < times.last().unwrap() - window {
            assert!(
                (smooth[k] - ramp[k]).abs() < 1e-9,
                "zero phase: sample {k} moved from {} to {}",
                ramp[k],
                smooth[k]
            );
            interior += 1;
        }
    }
    assert!(interior > 150);
}

#[test]
fn the_filter_removes_most_of_white_noise() {
    let mut rng = ChaCha8Rng::seed_from_u64(3);
    let times = uniform_times(2000, 1e-4);
    let noise: Vec<f64> = times.iter().map(|_| rng.random_range(-1.0..1.0)).collect();
    let smooth = moving_average(0.0, &times, &noise, 1e-3);
    let rms = |v: &[f64]| (v.iter().map(|x| x * x).sum::<f64>() / v.len() as f64).sqrt();
    // a 10-sample box divides the noise amplitude by about sqrt(10)
    assert!(
        rms(&smooth) < 0.45 * rms(&noise),
        "{} vs {}",
        rms(&smooth),
        rms(&noise)
    );
}

#[test]
fn filtered_loads_csv_keeps_rows_and_each_bodys_impulse() {
    let dir = scratch_dir("filtered-loads");
    let mut rng = ChaCha8Rng::seed_from_u64(11);
    let mut text = String::from("time,body,fx,fy,mz\n");
    for k in 1..=300 {
        let t = k as f64 * 1e-4;
        for body in ["tank", "wedge"] {
            text.push_str(&format!(
                "{t:.9e},{body},{:.9e},{:.9e},{:.9e}\n",
                rng.random_range(-5.0..5.0),
                1e4 * t + rng.random_range(0.0..300.0),
                rng.random_range(-1.0..3.0)
            ));
        }
    }
    std::fs::write(dir.join("loads.csv"), &text).unwrap();
    write_filtered_loads(&dir, 1.2e-3).unwrap();
    let raw = parse_loads_csv(&text).unwrap();
    let out = std::fs::read_to_string(dir.join("loads_filtered.csv")).unwrap();
    assert!(out.starts_with("time,body,fx,fy,mz\n"));
    let filtered = parse_loads_csv(&out).unwrap();
    assert_eq!(filtered.len(), raw.len());
    for (a, b) in raw.iter().zip(&filtered) {
        assert_eq!((a.time, &a.body), (b.time, &b.body));
    }
    assert!(
        raw.iter()
            .zip(&filtered)
            .any(|(a, b)| (a.fy - b.fy).abs() > 1.0),
        "the loads are smoothed"
    );
    for body in ["tank", "wedge"] {
        let pick = |rows: &[LoadRow], c: usize| -> (Vec<f64>, Vec<f64>) {
            rows.iter()
                .filter(|r| r.body == body)
                .map(|r| (r.time, [r.fx, r.fy, r.mz][c]))
                .unzip()
        };
        for c in 0..3 {
            let (t, v) = pick(&raw, c);
            let (_, w) = pick(&filtered, c);
            let (a, b) = (impulse(0.0, &t, &v), impulse(0.0, &t, &w));
            // the CSV keeps 10 significant digits
            assert!(
                (a - b).abs() <= 1e-8 * v.iter().map(|x| x.abs()).sum::<f64>() * 1e-4,
                "{body} component {c}: {a} vs {b}"
            );
        }
    }
}

fn wedge_case(filter: serde_json::Value) -> serde_json::Value {
    serde_json::json!({
        "name": "wedge",
        "fluid": { "density": 1000.0, "kinematic_viscosity": 0.0, "gravity": [0.0, 0.0] },
        "particle_spacing": 0.005,
        "domain": { "min": [-1.05, -1.05], "max": [1.05, 0.6] },
        "fluid_blocks": [ { "polygon": [[-1.0, -1.0], [1.0, -1.0], [1.0, 0.0], [-1.0, 0.0]] } ],
        "walls": [ { "name": "tank", "polyline": [[-1.0, 0.3], [-1.0, -1.0], [1.0, -1.0], [1.0, 0.3]] } ],
        "bodies": [ {
            "name": "wedge",
            "polygon": [[0.0, 0.0], [0.25, 0.1443], [0.25, 0.3], [-0.25, 0.3], [-0.25, 0.1443]],
            "motion": { "type": "prescribed", "velocity": [0.0, -6.15] }
        } ],
        "time": { "end": 0.015, "max_dt": 1.0e-4 },
        "output": { "load_interval": 1.0e-5, "filter_window": filter }
    })
}

#[test]
fn the_automatic_window_spans_a_few_particle_passages_of_a_wedge() {
    let case = parse_case_value(wedge_case(serde_json::Value::Null)).unwrap();
    let beta = (0.1443f64 / 0.25).atan();
    let passage = 2.0 * 0.005 * beta.tan() / (std::f64::consts::PI * 6.15);
    let w = filter_window(&case);
    assert!(
        (w - 4.0 * passage).abs() < 1e-9 * passage,
        "{w} vs {}",
        4.0 * passage
    );
    // a stated window wins
    assert_eq!(
        filter_window(&parse_case_value(wedge_case(serde_json::json!(2e-3))).unwrap()),
        2e-3
    );
    // no body: ten load intervals
    let mut tank = crate::small_tank();
    tank["output"]["load_interval"] = serde_json::json!(0.004);
    assert!((filter_window(&parse_case_value(tank).unwrap()) - 0.04).abs() < 1e-15);
}
