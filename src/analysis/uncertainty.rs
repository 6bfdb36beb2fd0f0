//! The numerical uncertainty of a reading from a resolution ladder: the least-squares
//! grid convergence index of Eça & Hoekstra (2014, J. Comput. Phys. 262, 104-130), with
//! the scatter of a lattice-offset ensemble as its random part.
//!
//! Given readings phi_i at spacings h_i (i = 0 the finest, at least four levels):
//! 1. Fit phi = phi_0 + alpha h^p in the least-squares sense, once with equal weights and
//!    once with weights 1/h (the finer levels count more), and keep the fit whose
//!    standard deviation U_s is smaller. p is the observed order.
//! 2. When 0.5 <= p < 2.1 the error estimate is that fit's |phi_fit(h_0) - phi_0|.
//!    Otherwise the estimate comes from whichever of the fixed-order fits (p = 1, p = 2,
//!    and p = 1 and 2 together) has the smallest U_s.
//! 3. With the data range Delta = (max phi - min phi) / (levels - 1): when U_s < Delta,
//!    U = Fs eps + U_s + |phi_0 - phi_fit(h_0)|, with the safety factor Fs = 1.25 for an
//!    order in [0.5, 2.1) and 3 otherwise; when the fit scatters more than the data
//!    range (U_s >= Delta), U = 3 U_s / Delta (eps + U_s + |phi_0 - phi_fit(h_0)|).
//! 4. The random part (the ensemble's) adds in quadrature: the levels and the lattice
//!    offset are independent sources.
//!
//! U_s = sqrt(n / (n - k) * sum w r^2 / sum w) for a fit of k parameters to n levels.

use crate::math::Real;
use serde::{Deserialize, Serialize};

/// Range of observed orders in which the ladder is taken as converging as expected, and
/// the safety factors inside and outside it (Eça & Hoekstra 2014, section 4).
pub const ORDER_RANGE: (Real, Real) = (0.5, 2.1);
pub const SAFETY_IN_RANGE: Real = 1.25;
pub const SAFETY_OUTSIDE: Real = 3.0;

/// How the half-width of one reading was obtained.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Fit {
    /// phi_0 + alpha h^p with p fitted
    ObservedOrder,
    /// phi_0 + alpha h
    FirstOrder,
    /// phi_0 + alpha h^2
    SecondOrder,
    /// phi_0 + alpha_1 h + alpha_2 h^2
    FirstAndSecondOrder,
    /// every level reads the same
    Constant,
}

/// The numerical uncertainty of one reading of the finest level.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Estimate {
    /// The finest level's reading.
    pub value: Real,
    /// 95 % half-width: the discretisation part and the random part in quadrature.
    pub half_width: Real,
    /// Observed order of the fit phi_0 + alpha h^p (NaN-free: 0 when every level reads the same).
    pub order: Real,
    /// Safety factor applied (1.25 or 3), or the scatter factor 3 U_s / Delta when the
    /// fit scatters more than the data range.
    pub safety_factor: Real,
    /// The fit the error estimate comes from.
    pub fit: Fit,
    /// The extrapolated value phi_0 of that fit.
    pub extrapolated: Real,
    /// The random part alone (95 %).
    pub random: Real,
}

impl Estimate {
    /// Is the observed order inside [`ORDER_RANGE`] with a fit tighter than the data?
    pub fn well_behaved(&self) -> bool {
        self.fit == Fit::Constant
            || (self.fit == Fit::ObservedOrder && self.safety_factor == SAFETY_IN_RANGE)
    }
}

/// One least-squares fit: its value at each level and its standard deviation.
#[derive(Debug, Clone)]
struct Fitted {
    phi0: Real,
    at: Vec<Real>,
    std: Real,
    order: Real,
}

/// Weighted linear least squares of phi on the basis functions (columns) `basis`, with
/// a constant term first. Returns the coefficients, or None when singular.
fn linear_fit(basis: &[Vec<Real>], phi: &[Real], w: &[Real]) -> Option<Vec<Real>> {
    let k = basis.len() + 1;
    let col = |j: usize, i: usize| if j == 0 { 1.0 } else { basis[j - 1][i] };
    let mut a = nalgebra::DMatrix::<Real>::zeros(k, k);
    let mut b = nalgebra::DVector::<Real>::zeros(k);
    for i in 0..phi.len() {
        for r in 0..k {
            b[r] += w[i] * col(r, i) * phi[i];
            for c in 0..k {
                a[(r, c)] += w[i] * col(r, i) * col(c, i);
            }
        }
    }
    let x = a.lu().solve(&b)?;
    x.iter()
        .all(|v| v.is_finite())
        .then(|| x.iter().copied().collect())
}

/// The fit of `basis` (plus a constant) with `params` parameters in all (the order
/// counts as one when it was fitted).
fn fitted(
    basis: &[Vec<Real>],
    phi: &[Real],
    w: &[Real],
    order: Real,
    params: usize,
) -> Option<Fitted> {
    let coef = linear_fit(basis, phi, w)?;
    let n = phi.len();
    let at: Vec<Real> = (0..n)
        .map(|i| {
            coef[0]
                + (0..basis.len())
                    .map(|j| coef[j + 1] * basis[j][i])
                    .sum::<Real>()
        })
        .collect();
    let dof = n.saturating_sub(params).max(1) as Real;
    let wsum: Real = w.iter().sum();
    let ss: Real = (0..n).map(|i| w[i] * (phi[i] - at[i]).powi(2)).sum();
    Some(Fitted {
        phi0: coef[0],
        at,
        std: (n as Real / dof * ss / wsum).sqrt(),
        order,
    })
}

/// phi_0 + alpha h^p with p fitted: the p of the smallest residual over 0.05..8, found
/// on a grid of 0.05 and refined by golden section.
fn observed_order_fit(h: &[Real], phi: &[Real], w: &[Real]) -> Option<Fitted> {
    let residual = |p: Real| -> Real {
        let hp: Vec<Real> = h.iter().map(|x| x.powf(p)).collect();
        match linear_fit(std::slice::from_ref(&hp), phi, w) {
            Some(c) => (0..phi.len())
                .map(|i| w[i] * (phi[i] - c[0] - c[1] * hp[i]).powi(2))
                .sum(),
            None => Real::INFINITY,
        }
    };
    let grid: Vec<Real> = (1..=160).map(|k| 0.05 * k as Real).collect();
    let (best, _) = grid
        .iter()
        .map(|&p| (p, residual(p)))
        .min_by(|a, b| a.1.total_cmp(&b.1))?;
    let (mut lo, mut hi) = ((best - 0.05).max(0.05), (best + 0.05).min(8.0));
    let g = 0.5 * (5.0_f64.sqrt() - 1.0);
    for _ in 0..40 {
        let (a, b) = (hi - g * (hi - lo), lo + g * (hi - lo));
        if residual(a) < residual(b) {
            hi = b;
        } else {
            lo = a;
        }
    }
    let p = 0.5 * (lo + hi);
    let hp: Vec<Real> = h.iter().map(|x| x.powf(p)).collect();
    fitted(&[hp], phi, w, p, 3)
}

fn fixed_order_fits(h: &[Real], phi: &[Real], w: &[Real]) -> Vec<(Fit, Fitted)> {
    let h1: Vec<Real> = h.to_vec();
    let h2: Vec<Real> = h.iter().map(|x| x * x).collect();
    let mut fits = Vec::new();
    if let Some(f) = fitted(std::slice::from_ref(&h1), phi, w, 1.0, 2) {
        fits.push((Fit::FirstOrder, f));
    }
    if let Some(f) = fitted(std::slice::from_ref(&h2), phi, w, 2.0, 2) {
        fits.push((Fit::SecondOrder, f));
    }
    if phi.len() >= 4 {
        if let Some(f) = fitted(&[h1, h2], phi, w, 1.5, 3) {
            fits.push((Fit::FirstAndSecondOrder, f));
        }
    }
    fits
}

/// The 95 % half-width of the finest reading `phi[0]` from readings `phi` at spacings
/// `h` (any unit, `h[0]` the finest; at least four levels) and the 95 % random part
/// `random` (0 without an ensemble).
pub fn half_width(h: &[Real], phi: &[Real], random: Real) -> Estimate {
    assert!(h.len() == phi.len() && h.len() >= 4, "four levels or more");
    let n = phi.len();
    let rel: Vec<Real> = h.iter().map(|x| x / h[0]).collect();
    let (lo, hi) = phi
        .iter()
        .fold((Real::INFINITY, Real::NEG_INFINITY), |(a, b), &x| {
            (a.min(x), b.max(x))
        });
    let range = (hi - lo) / (n - 1) as Real;
    let constant = Estimate {
        value: phi[0],
        half_width: random,
        order: 0.0,
        safety_factor: SAFETY_IN_RANGE,
        fit: Fit::Constant,
        extrapolated: phi[0],
        random,
    };
    if !(range > 1e-300 * hi.abs().max(lo.abs()).max(1e-300)) || !range.is_finite() {
        return constant;
    }
    let equal = vec![1.0; n];
    let inverse: Vec<Real> = rel.iter().map(|x| 1.0 / x).collect();
    let best =
        |fits: Vec<(Fit, Fitted)>| fits.into_iter().min_by(|a, b| a.1.std.total_cmp(&b.1.std));
    let observed = best(
        [&equal, &inverse]
            .iter()
            .filter_map(|w| observed_order_fit(&rel, phi, w).map(|f| (Fit::ObservedOrder, f)))
            .collect(),
    );
    let order = observed.as_ref().map_or(0.0, |(_, f)| f.order);
    let in_range = (ORDER_RANGE.0..ORDER_RANGE.1).contains(&order);
    let chosen = if in_range {
        observed
    } else {
        best(
            [&equal, &inverse]
                .iter()
                .flat_map(|w| fixed_order_fits(&rel, phi, w))
                .collect(),
        )
    };
    let Some((fit, f)) = chosen else {
        // no fit solvable: the data range, three times, as for anomalous data
        let u = SAFETY_OUTSIDE * (hi - lo);
        return Estimate {
            half_width: u.hypot(random),
            safety_factor: SAFETY_OUTSIDE,
            ..constant
        };
    };
    let eps = (f.at[0] - f.phi0).abs();
    let off = (phi[0] - f.at[0]).abs();
    let (u, factor) = if f.std < range {
        let fs = if in_range {
            SAFETY_IN_RANGE
        } else {
            SAFETY_OUTSIDE
        };
        (fs * eps + f.std + off, fs)
    } else {
        let fs = SAFETY_OUTSIDE * f.std / range;
        (fs * (eps + f.std + off), fs)
    };
    Estimate {
        value: phi[0],
        half_width: u.hypot(random),
        order,
        safety_factor: factor,
        fit,
        extrapolated: f.phi0,
        random,
    }
}

/// Two-sided 95 % Student t quantile with `dof` degrees of freedom (1..=10 tabulated,
/// the normal 1.96 beyond): the factor from an ensemble's standard deviation to the 95 %
/// half-width of one more draw, before the sqrt(1 + 1/m) of the draw itself.
pub fn student_t95(dof: usize) -> Real {
    const T: [Real; 10] = [
        12.706, 4.303, 3.182, 2.776, 2.571, 2.447, 2.365, 2.306, 2.262, 2.228,
    ];
    match dof {
        0 => Real::INFINITY,
        d if d <= 10 => T[d - 1],
        _ => 1.96,
    }
}

/// Sample mean and standard deviation of an ensemble's readings (std 0 for one member).
pub fn mean_and_std(values: &[Real]) -> (Real, Real) {
    let n = values.len() as Real;
    let mean = values.iter().sum::<Real>() / n;
    let std = if values.len() > 1 {
        (values.iter().map(|v| (v - mean).powi(2)).sum::<Real>() / (n - 1.0)).sqrt()
    } else {
        0.0
    };
    (mean, std)
}

/// The uncertainty block of summary.json.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct UncertaintySummary {
    /// Spacing ratio between consecutive levels.
    pub ratio: Real,
    /// The window (s) every level's loads and probes were filtered with: the user's run's.
    pub filter_window_s: Real,
    pub levels: Vec<LevelSummary>,
    /// Per body: the impulse and the peak of each of fx, fy, mz.
    pub bodies: Vec<SeriesUncertainty>,
    /// Per probe: the same of its pressure (filtered with the loads' window).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub probes: Vec<SeriesUncertainty>,
    /// Wall time of all the parts (s), and its ratio to the user's run alone.
    pub wall_time_s: f64,
    pub cost_ratio: f64,
    /// Particle updates of all the parts over the user's run's (machine-independent cost).
    pub particle_steps_ratio: Real,
    /// Readings whose observed order fell outside the expected range (safety factor 3).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub notes: Vec<String>,
    /// The envelope advice of the coarsest level that the user's spacing does not have.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub advice: Vec<String>,
}

/// One level of the ladder.
#[derive(Debug, Clone, Default, PartialEq, Serialize, Deserialize)]
pub struct LevelSummary {
    /// 0 is the user's spacing.
    pub level: usize,
    pub spacing: Real,
    /// Runs at this level (the lattice-offset ensemble at the coarsest).
    pub members: usize,
    /// Fluid particles at the end of the first run of the level.
    pub particles: usize,
    pub wall_time_s: f64,
    pub particle_steps: u64,
}

/// A body's (or a probe's) readings.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SeriesUncertainty {
    pub name: String,
    pub columns: Vec<ComponentUncertainty>,
}

/// One column (fx, fy, mz or pressure) of a series.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ComponentUncertainty {
    pub column: String,
    /// Integral over the run (N s/m for forces).
    pub impulse: Estimate,
    /// The filtered value of largest magnitude (each level's own).
    pub peak: Estimate,
    /// Fraction of the rows whose fit was well behaved (safety factor 1.25).
    pub rows_well_behaved: Real,
}
