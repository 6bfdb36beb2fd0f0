//! Summary statistics of the studies' timings and loads: medians and spreads of
//! repeats, power-law fits of cost against size, windowed means of a load series.

/// A least-squares fit of y = prefactor * x^exponent on log-log axes.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PowerFit {
    pub exponent: f64,
    pub prefactor: f64,
    /// Coefficient of determination of the log-log fit.
    pub r2: f64,
}

/// Least squares of ln y against ln x over the points with x, y > 0 and finite.
/// None with fewer than two such points or all x equal.
pub fn fit_power_law(points: &[(f64, f64)]) -> Option<PowerFit> {
    let logs: Vec<(f64, f64)> = points
        .iter()
        .filter(|(x, y)| x.is_finite() && y.is_finite() && *x > 0.0 && *y > 0.0)
        .map(|(x, y)| (x.ln(), y.ln()))
        .collect();
    if logs.len() < 2 {
        return None;
    }
    let n = logs.len() as f64;
    let mx = logs.iter().map(|p| p.0).sum::<f64>() / n;
    let my = logs.iter().map(|p| p.1).sum::<f64>() / n;
    let sxx: f64 = logs.iter().map(|p| (p.0 - mx).powi(2)).sum();
    let sxy: f64 = logs.iter().map(|p| (p.0 - mx) * (p.1 - my)).sum();
    let syy: f64 = logs.iter().map(|p| (p.1 - my).powi(2)).sum();
    if sxx <= 0.0 {
        return None;
    }
    let exponent = sxy / sxx;
    let intercept = my - exponent * mx;
    let r2 = if syy > 0.0 {
        (sxy * sxy) / (sxx * syy)
    } else {
        1.0
    };
    Some(PowerFit {
        exponent,
        prefactor: intercept.exp(),
        r2,
    })
}

/// Median of the finite values (None when there are none).
pub fn median(values: &[f64]) -> Option<f64> {
    let mut v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return None;
    }
    v.sort_by(f64::total_cmp);
    let n = v.len();
    Some(if n % 2 == 1 {
        v[n / 2]
    } else {
        0.5 * (v[n / 2 - 1] + v[n / 2])
    })
}

/// Max - min of the finite values (0 for fewer than two).
pub fn spread(values: &[f64]) -> f64 {
    let v: Vec<f64> = values.iter().copied().filter(|x| x.is_finite()).collect();
    if v.len() < 2 {
        return 0.0;
    }
    v.iter().cloned().fold(f64::NEG_INFINITY, f64::max)
        - v.iter().cloned().fold(f64::INFINITY, f64::min)
}

/// Time-weighted mean of interval means (`times[k]` ends the interval of `values[k]`,
/// the first starting at `start`) over the intervals lying in [from, to].
pub fn window_mean(start: f64, times: &[f64], values: &[f64], from: f64, to: f64) -> Option<f64> {
    let (mut sum, mut span) = (0.0, 0.0);
    let mut previous = start;
    for (t, v) in times.iter().zip(values) {
        if previous >= from - 1e-12 && *t <= to + 1e-12 {
            sum += v * (t - previous);
            span += t - previous;
        }
        previous = *t;
    }
    (span > 0.0).then(|| sum / span)
}
