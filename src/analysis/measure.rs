//! The error measures of the benchmark and the validation tests, as pure functions of a
//! run's outputs so that each can be tested on synthetic data.

use super::reference::{MARTIN_MOYCE_SURGE, SURGE_COMPARISON_RANGE};
use crate::math::Real;

/// Time-weighted mean of a series of interval means (`times[k]` ends the interval of
/// `values[k]`, the first starting at `start`) over the intervals ending after `from`.
/// None when no interval qualifies.
pub fn interval_mean_after(
    start: Real,
    times: &[Real],
    values: &[Real],
    from: Real,
) -> Option<Real> {
    let (mut sum, mut span) = (0.0, 0.0);
    let mut previous = start;
    for (t, v) in times.iter().zip(values) {
        if previous >= from {
            sum += v * (t - previous);
            span += t - previous;
        }
        previous = *t;
    }
    (span > 0.0).then(|| sum / span)
}

/// Mean and standard deviation of point samples taken at or after `from`.
pub fn sample_stats_after(times: &[Real], values: &[Real], from: Real) -> Option<(Real, Real)> {
    let picked: Vec<Real> = times
        .iter()
        .zip(values)
        .filter(|(t, _)| **t >= from)
        .map(|(_, v)| *v)
        .collect();
    if picked.is_empty() {
        return None;
    }
    let n = picked.len() as Real;
    let mean = picked.iter().sum::<Real>() / n;
    let var = picked.iter().map(|v| (v - mean).powi(2)).sum::<Real>() / n;
    Some((mean, var.sqrt()))
}

/// |measured - expected| / |expected|.
pub fn relative_error(measured: Real, expected: Real) -> Real {
    (measured - expected).abs() / expected.abs()
}

/// The surge front of a dam break: the largest x of the particles within `band` of the
/// floor (y - floor < band) that have another such particle within `2 l0` (a lone
/// droplet ahead of the front does not count), plus l0/2 (a particle stands for a cell
/// of width l0). None when no particle is near the floor.
pub fn surge_front(points: &[(Real, Real)], floor: Real, band: Real, l0: Real) -> Option<Real> {
    let mut near: Vec<(Real, Real)> = points
        .iter()
        .copied()
        .filter(|(_, y)| *y - floor < band)
        .collect();
    near.sort_by(|a, b| b.0.total_cmp(&a.0));
    let reach2 = (2.0 * l0).powi(2);
    for (i, p) in near.iter().enumerate() {
        // candidates are sorted by x descending: a companion lies within 2 l0 in x
        let companion = near[i + 1..]
            .iter()
            .take_while(|q| p.0 - q.0 <= 2.0 * l0)
            .chain(near[..i].iter().rev().take_while(|q| q.0 - p.0 <= 2.0 * l0))
            .any(|q| (q.0 - p.0).powi(2) + (q.1 - p.1).powi(2) <= reach2);
        if companion {
            return Some(p.0 + 0.5 * l0);
        }
    }
    None
}

/// Linear interpolation of a series sorted by its first coordinate; None outside it.
pub fn interpolate(series: &[(Real, Real)], x: Real) -> Option<Real> {
    let k = series.partition_point(|p| p.0 < x);
    if k < series.len() && series[k].0 == x {
        return Some(series[k].1);
    }
    if k == 0 || k == series.len() {
        return None;
    }
    let (a, b) = (series[k - 1], series[k]);
    Some(a.1 + (b.1 - a.1) * (x - a.0) / (b.0 - a.0))
}

/// RMS relative error of a simulated surge front (T, Z) against Martin & Moyce for the
/// reference points with T in [`SURGE_COMPARISON_RANGE`], the simulated front
/// interpolated linearly at the reference T. None when the simulation does not cover
/// every such point.
pub fn surge_front_rms_error(front: &[(Real, Real)]) -> Option<Real> {
    let mut sorted = front.to_vec();
    sorted.sort_by(|a, b| a.0.total_cmp(&b.0));
    let (lo, hi) = SURGE_COMPARISON_RANGE;
    let mut sum = 0.0;
    let mut count = 0;
    for &(t, z) in MARTIN_MOYCE_SURGE
        .iter()
        .filter(|(t, _)| *t >= lo && *t <= hi)
    {
        let simulated = interpolate(&sorted, t)?;
        sum += ((simulated - z) / z).powi(2);
        count += 1;
    }
    (count > 0).then(|| (sum / count as Real).sqrt())
}

/// Least-squares line y = a + b x; None with fewer than two distinct x.
pub fn fit_line(points: &[(Real, Real)]) -> Option<(Real, Real)> {
    let n = points.len() as Real;
    if points.len() < 2 {
        return None;
    }
    let mx = points.iter().map(|p| p.0).sum::<Real>() / n;
    let my = points.iter().map(|p| p.1).sum::<Real>() / n;
    let sxx: Real = points.iter().map(|p| (p.0 - mx).powi(2)).sum();
    let sxy: Real = points.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    (sxx > 0.0).then(|| {
        let b = sxy / sxx;
        (my - b * mx, b)
    })
}

/// Interval-mean samples (`times[k]` ends the interval of `values[k]`, the first
/// starting at `start`) as (interval midpoint, value) for the midpoints inside `window`:
/// for a linear signal the interval mean is its value at the midpoint.
fn window_samples(
    start: Real,
    times: &[Real],
    values: &[Real],
    window: (Real, Real),
) -> Vec<(Real, Real)> {
    let mut previous = start;
    let mut points = Vec::new();
    for (t, v) in times.iter().zip(values) {
        let mid = 0.5 * (previous + t);
        if mid >= window.0 && mid <= window.1 {
            points.push((mid, *v));
        }
        previous = *t;
    }
    points
}

/// The force coefficient of a constant-velocity entry with the time origin at the keel
/// contact (`contact`, the t of docs/references.md): the one-parameter least squares of
/// F = C rho V³ (t - contact) over the interval-mean samples (as for
/// `fit_force_coefficient`) in `window`. Returns (C, its standard error from the
/// scatter about the fit). The two-parameter fit below has a slope error of about
/// 4.8/sqrt(samples) of C when the per-step force scatters by its own mean, as the
/// wedge's does; this one about 1/sqrt(samples).
pub fn force_coefficient_from_contact(
    contact: Real,
    start: Real,
    times: &[Real],
    force: &[Real],
    window: (Real, Real),
    density: Real,
    speed: Real,
) -> Option<(Real, Real)> {
    let scale = density * speed.powi(3);
    let points = window_samples(start, times, force, window);
    let sxx: Real = points.iter().map(|p| (p.0 - contact).powi(2)).sum();
    if points.len() < 2 || sxx <= 0.0 {
        return None;
    }
    let slope = points.iter().map(|p| (p.0 - contact) * p.1).sum::<Real>() / sxx;
    let scatter: Real = points
        .iter()
        .map(|p| (p.1 - slope * (p.0 - contact)).powi(2))
        .sum();
    let error = (scatter / (points.len() - 1) as Real).sqrt() / sxx.sqrt();
    Some((slope / scale, error / scale))
}

/// The rows a user's C_F is fitted over: from 20 % to 85 % of `t_chine` after the onset
/// t0 (`force_coefficient_from_onset`, `step_scatter`), as fractions of `t_chine`.
pub const ONSET_FIT_WINDOW: (Real, Real) = (0.2, 0.85);

/// Is a row `s` seconds after the onset inside [`ONSET_FIT_WINDOW`]?
fn in_onset_window(s: Real, t_chine: Real) -> bool {
    (ONSET_FIT_WINDOW.0 * t_chine..=ONSET_FIT_WINDOW.1 * t_chine).contains(&s)
}

/// The force coefficient of a constant-velocity entry as a user reads it from loads.csv
/// (and as the impact tests do): the onset t0 is the time of the first row whose |F|
/// exceeds 1 % of the largest |F| of the run, and C the least-squares slope of
/// F = C rho V³ (t - t0) through that origin over the rows between 20 % and 85 % of
/// Wagner's chine-wetting time `t_chine` after t0. Rows are taken at their times as
/// written. The onset absorbs the lag of the first wetted rows, which the keel-contact
/// origin (`force_coefficient_from_contact`) counts as missing force. Returns (C, t0).
pub fn force_coefficient_from_onset(
    times: &[Real],
    force: &[Real],
    t_chine: Real,
    density: Real,
    speed: Real,
) -> Option<(Real, Real)> {
    let peak = force.iter().fold(0.0, |m: Real, f| m.max(f.abs()));
    let first = force.iter().position(|f| f.abs() > 0.01 * peak)?;
    let t0 = times[first];
    let (mut sft, mut stt) = (0.0, 0.0);
    for (t, f) in times.iter().zip(force) {
        let s = t - t0;
        if in_onset_window(s, t_chine) {
            sft += f * s;
            stt += s * s;
        }
    }
    (stt > 0.0).then(|| (sft / stt / (density * speed.powi(3)), t0))
}

/// The per-step scatter of an impact load: the RMS of the row-to-row change of F over
/// the rows between 20 % and 85 % of `t_chine` after the onset `t0` (the window of
/// `force_coefficient_from_onset`), divided by the mean F there. Rows are steps when
/// the load interval is below dt. None with fewer than two rows or a zero mean.
pub fn step_scatter(times: &[Real], force: &[Real], t0: Real, t_chine: Real) -> Option<Real> {
    let f: Vec<Real> = times
        .iter()
        .zip(force)
        .filter(|(t, _)| in_onset_window(*t - t0, t_chine))
        .map(|(_, f)| *f)
        .collect();
    let mean = f.iter().sum::<Real>() / f.len() as Real;
    if f.len() < 2 || mean == 0.0 {
        return None;
    }
    let ms = f.windows(2).map(|w| (w[1] - w[0]).powi(2)).sum::<Real>() / (f.len() - 1) as Real;
    Some(ms.sqrt() / mean.abs())
}

/// The force coefficient of a constant-velocity entry: fit F = C rho V³ (t - t0) to the
/// interval-mean force samples (`times[k]` ends the interval of `force[k]`, the first
/// starting at `start`) whose interval midpoints lie in `window` (for a linear force the
/// interval mean is the value at the midpoint). Returns (C, t0).
pub fn fit_force_coefficient(
    start: Real,
    times: &[Real],
    force: &[Real],
    window: (Real, Real),
    density: Real,
    speed: Real,
) -> Option<(Real, Real)> {
    let points = window_samples(start, times, force, window);
    let (a, b) = fit_line(&points)?;
    let c = b / (density * speed.powi(3));
    (b != 0.0).then(|| (c, -a / b))
}

/// The maxima of a sampled oscillating series, each refined by the parabola through
/// the sample and its neighbours; of maxima closer than `min_separation`, the larger
/// is kept (ripples on a crest are not crests).
pub fn oscillation_peaks(
    times: &[Real],
    values: &[Real],
    min_separation: Real,
) -> Vec<(Real, Real)> {
    let mut peaks: Vec<(Real, Real)> = Vec::new();
    for i in 1..times.len().saturating_sub(1) {
        let (a, b, c) = (values[i - 1], values[i], values[i + 1]);
        if !(b > a && b >= c) {
            continue;
        }
        let curvature = a - 2.0 * b + c;
        let offset = if curvature < 0.0 {
            0.5 * (a - c) / curvature
        } else {
            0.0
        };
        let h = 0.5 * (times[i + 1] - times[i - 1]);
        let peak = (times[i] + offset * h, b - 0.25 * (a - c) * offset);
        match peaks.last_mut() {
            Some(last) if peak.0 - last.0 < min_separation => {
                if peak.1 > last.1 {
                    *last = peak;
                }
            }
            _ => peaks.push(peak),
        }
    }
    peaks
}

/// Exponential decay rate gamma of positive peaks (value ∝ exp(-gamma t)): the least
/// squares line through (t, ln value). None with fewer than two peaks.
pub fn exponential_decay_rate(peaks: &[(Real, Real)]) -> Option<Real> {
    let logs: Option<Vec<(Real, Real)>> = peaks
        .iter()
        .map(|&(t, v)| (v > 0.0).then(|| (t, v.ln())))
        .collect();
    let (_, slope) = fit_line(&logs?)?;
    Some(-slope)
}

/// The mean of the relative errors of [`velocity_loss_errors`].
pub fn mean_error(errors: &[(Real, Real)]) -> Real {
    errors.iter().map(|e| e.1).sum::<Real>() / errors.len() as Real
}

/// The velocity loss of a free-falling body against a model's: for each sample
/// (time, downward speed) with time in [from, to], (time, (V0 - V) / (V0 - V_model) - 1).
pub fn velocity_loss_errors(
    model: &impl super::reference::FreeFall,
    samples: &[(Real, Real)],
    from: Real,
    to: Real,
) -> Vec<(Real, Real)> {
    let samples: Vec<(Real, Real)> = samples.iter().copied().filter(|s| s.0 <= to).collect();
    let times: Vec<Real> = samples.iter().map(|s| s.0).collect();
    let v0 = model.initial_speed();
    samples
        .iter()
        .zip(model.speeds(&times))
        .filter(|(s, _)| s.0 >= from)
        .map(|(&(t, v), vm)| (t, (v0 - v) / (v0 - vm) - 1.0))
        .collect()
}
