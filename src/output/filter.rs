//! Zero-phase moving average of the load history, conserving the impulse.
//!
//! A row of `loads.csv` at time t_k is the mean force over (t_{k-1}, t_k] (t_{-1} = 0),
//! so the raw history is the piecewise-constant force f(t) on [0, T]. The filtered
//! history is the centred moving average g = f * box_w, with f continued by even
//! reflection about t = 0 and t = T, sampled the same way (interval means over the same
//! intervals):
//!
//! G_k = 1/(w Δt_k) ∫_{t_{k-1}}^{t_k} ∫_{t-w/2}^{t+w/2} f(s) ds dt.
//!
//! The box is centred, so there is no phase lag (a linear ramp maps to itself away
//! from the ends), and the reflection returns to [0, T] exactly the impulse the window
//! would carry past the ends, so ∫_0^T g dt = ∫_0^T f dt for any sampling (uniform or
//! not) and any window up to T (longer windows are clamped to T). Raw loads stay the
//! reference; `loads_filtered.csv` is for reading peaks without particle noise.

use super::loads_csv::parse_loads_csv;
use crate::case::{Case, Motion};
use crate::math::Real;
use std::collections::BTreeMap;
use std::io;
use std::path::Path;

/// Samples of the windows by default when the scene has no wedge-like entry.
pub const DEFAULT_WINDOW_SAMPLES: Real = 10.0;
/// Particle-passage periods per window for a wedge-like entry.
pub const WEDGE_WINDOW_PERIODS: Real = 4.0;

/// Second antiderivative of the box indicator 1[|x| <= h] (even, K2(0) = 0).
fn box_k2(x: Real, h: Real) -> Real {
    let a = x.abs();
    if a <= h {
        0.5 * a * a
    } else {
        h * a - 0.5 * h * h
    }
}

/// ∫_{a0}^{a1} ∫_{b0}^{b1} 1[|t - s| <= h] ds dt.
fn box_overlap(a0: Real, a1: Real, b0: Real, b1: Real, h: Real) -> Real {
    if b0 - a1 >= h || a0 - b1 >= h {
        return 0.0;
    }
    box_k2(a1 - b0, h) - box_k2(a0 - b0, h) - box_k2(a1 - b1, h) + box_k2(a0 - b1, h)
}

/// Filter one series of interval means. `times[k]` ends the interval of `values[k]`
/// (the first starts at `start`); `window` (s) is the full width of the box.
///
/// Panics if the lengths differ or the times do not increase.
pub fn moving_average(start: Real, times: &[Real], values: &[Real], window: Real) -> Vec<Real> {
    assert_eq!(times.len(), values.len(), "one value per time");
    let n = times.len();
    if n == 0 {
        return Vec::new();
    }
    let end = times[n - 1];
    let span = end - start;
    if !(window > 0.0) || !(span > 0.0) {
        return values.to_vec();
    }
    let w = window.min(span);
    let h = 0.5 * w;
    let lower = |k: usize| if k == 0 { start } else { times[k - 1] };
    for k in 0..n {
        assert!(
            times[k] > lower(k),
            "times must increase ({} after {})",
            times[k],
            lower(k)
        );
    }
    // first interval whose end is > x
    let first_after = |x: Real| times.partition_point(|t| *t <= x);
    let mut out = Vec::with_capacity(n);
    for k in 0..n {
        let (a0, a1) = (lower(k), times[k]);
        let mut sum = 0.0;
        // original intervals within reach
        let mut j = first_after(a0 - h);
        while j < n && lower(j) < a1 + h {
            sum += values[j] * box_overlap(a0, a1, lower(j), times[j], h);
            j += 1;
        }
        // mirror image about `start`: interval j maps to [2 start - t_j, 2 start - t_{j-1}]
        if a0 - h < start {
            let reach = start + (start - (a0 - h));
            let mut j = 0;
            while j < n && lower(j) < reach {
                sum += values[j]
                    * box_overlap(a0, a1, 2.0 * start - times[j], 2.0 * start - lower(j), h);
                j += 1;
            }
        }
        // mirror image about `end`
        if a1 + h > end {
            let reach = end - (a1 + h - end);
            let mut j = first_after(reach);
            while j < n {
                sum +=
                    values[j] * box_overlap(a0, a1, 2.0 * end - times[j], 2.0 * end - lower(j), h);
                j += 1;
            }
        }
        out.push(sum / (w * (a1 - a0)));
    }
    out
}

/// ∫ F dt of a series of interval means (the impulse).
pub fn impulse(start: Real, times: &[Real], values: &[Real]) -> Real {
    let mut previous = start;
    let mut sum = 0.0;
    for (t, v) in times.iter().zip(values) {
        sum += v * (t - previous);
        previous = *t;
    }
    sum
}

/// The window for a case: `output.filter_window` when set, otherwise automatic.
///
/// Automatic: for a body entering the water with speed V whose leading vertex has
/// deadrise beta (5° to 85°), the wetted half-width grows as c' = pi V / (2 tan beta)
/// (Wagner), so a new particle column is wetted every 2 l0 tan(beta) / (pi V); the
/// window is [`WEDGE_WINDOW_PERIODS`] of those periods (the force steps each time). Otherwise
/// [`DEFAULT_WINDOW_SAMPLES`] load intervals (or max_dt when loads are written every step).
/// Never below one load interval.
pub fn filter_window(case: &Case) -> Real {
    if let Some(w) = case
        .output
        .filter_window
        .filter(|w| *w > 0.0 && w.is_finite())
    {
        return w;
    }
    let sample = case
        .output
        .load_interval
        .seconds(case.time.end)
        .unwrap_or(case.time.max_dt);
    let passage = case
        .bodies
        .iter()
        .filter_map(|b| {
            let (Motion::Prescribed { velocity, .. } | Motion::Free { velocity, .. }) = &b.motion;
            let speed = (velocity[0] * velocity[0] + velocity[1] * velocity[1]).sqrt();
            let beta = vertex_deadrise(&b.polygon, b.angle, *velocity)?;
            Some(2.0 * case.particle_spacing * beta.tan() / (std::f64::consts::PI * speed))
        })
        .fold(None, |acc: Option<Real>, p| {
            Some(acc.map_or(p, |a| a.min(p)))
        });
    match passage {
        Some(p) => (WEDGE_WINDOW_PERIODS * p).max(sample),
        None => DEFAULT_WINDOW_SAMPLES * sample,
    }
}

/// Deadrise angle (rad) at the vertex of `polygon` (body frame, rotated by `angle`)
/// that leads in the direction of `velocity`: the mean angle of its two edges to the
/// plane normal to the motion. None when the body does not move or the angle is
/// outside 5°..85° (flat or needle-like: no wedge-entry time scale). It sets the time
/// scale of a wedge's entry; the smallest deadrise of the faces that lead, which sets
/// the jet-root speed and the envelope advice, is [`crate::engine::config::leading_deadrise`].
pub fn vertex_deadrise(polygon: &[[Real; 2]], angle: Real, velocity: [Real; 2]) -> Option<Real> {
    let speed = (velocity[0] * velocity[0] + velocity[1] * velocity[1]).sqrt();
    if polygon.len() < 3 || !(speed > 0.0) {
        return None;
    }
    let d = [velocity[0] / speed, velocity[1] / speed];
    let (s, c) = angle.sin_cos();
    let pts: Vec<[Real; 2]> = polygon
        .iter()
        .map(|p| [c * p[0] - s * p[1], s * p[0] + c * p[1]])
        .collect();
    let ahead = |p: &[Real; 2]| p[0] * d[0] + p[1] * d[1];
    let lead = (0..pts.len()).max_by(|&a, &b| ahead(&pts[a]).total_cmp(&ahead(&pts[b])))?;
    let n = pts.len();
    let mut sum = 0.0;
    for other in [(lead + 1) % n, (lead + n - 1) % n] {
        let e = [pts[other][0] - pts[lead][0], pts[other][1] - pts[lead][1]];
        let along = (e[0] * d[0] + e[1] * d[1]).abs();
        let across = (e[0] * d[1] - e[1] * d[0]).abs();
        sum += along.atan2(across);
    }
    let beta = 0.5 * sum;
    let deg = beta.to_degrees();
    (5.0..=85.0).contains(&deg).then_some(beta)
}

/// Read `run_dir/loads.csv`, filter each body's fx, fy, mz with a window of
/// `window_s` seconds and write `run_dir/loads_filtered.csv` (same columns, same
/// rows in the same order).
pub fn write_filtered_loads(run_dir: &Path, window_s: f64) -> io::Result<()> {
    let text = std::fs::read_to_string(run_dir.join("loads.csv"))?;
    let filtered = filter_loads_csv(&text, window_s)?;
    let tmp = run_dir.join("loads_filtered.csv.tmp");
    std::fs::write(&tmp, filtered)?;
    std::fs::rename(tmp, run_dir.join("loads_filtered.csv"))
}

/// The filtered `loads.csv` text (see the module docs).
pub fn filter_loads_csv(text: &str, window_s: f64) -> io::Result<String> {
    let rows = parse_loads_csv(text)?;
    // row indices per body, in file order
    let mut by_body: BTreeMap<&str, Vec<usize>> = BTreeMap::new();
    for (i, r) in rows.iter().enumerate() {
        by_body.entry(r.body.as_str()).or_default().push(i);
    }
    let mut filtered: Vec<[Real; 3]> = rows.iter().map(|r| [r.fx, r.fy, r.mz]).collect();
    for indices in by_body.values() {
        let times: Vec<Real> = indices.iter().map(|&i| rows[i].time).collect();
        if times.windows(2).any(|w| w[1] <= w[0]) || times.first().is_some_and(|t| *t <= 0.0) {
            return Err(io::Error::new(
                io::ErrorKind::InvalidData,
                "loads.csv times of a body must be positive and increase",
            ));
        }
        for c in 0..3 {
            let values: Vec<Real> = indices.iter().map(|&i| filtered[i][c]).collect();
            let smooth = moving_average(0.0, &times, &values, window_s);
            for (&i, v) in indices.iter().zip(smooth) {
                filtered[i][c] = v;
            }
        }
    }
    let mut out = String::with_capacity(text.len());
    out.push_str(super::LOADS_HEADER);
    out.push('\n');
    for (r, [fx, fy, mz]) in rows.iter().zip(filtered) {
        out.push_str(&format!(
            "{:.9e},{},{fx:.9e},{fy:.9e},{mz:.9e}\n",
            r.time, r.body
        ));
    }
    Ok(out)
}
