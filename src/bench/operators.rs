//! The operator convergence study of Imoto (2022) §5 (Figs. 3-4): on
//! Ω = [0,1]², f = sin(x + 2y) and exp(x + 2y), spacings dx = 2⁻³ … 2⁻⁶, regular lattice,
//! the lattice perturbed by U[-0.2dx, 0.2dx] in each coordinate (seeded), and the
//! anisotropic lattice of Fig. 4 (spacing dx/2 along x, dx along y). The error is the
//! paper's relative truncation error
//!
//! E_D = (1/#Λ) Σ_{i∈Λ} |Df(x_i) - ⟨Df⟩_i| / max_Ω |Df|,
//!
//! Λ the particles inside Ω. Particles fill Ω extended by r_e on every side, so each
//! particle of Λ has a full neighbourhood, as in the paper's interior set Ω_h^in.
//! Weight: w = r_e/r - 1 (the paper's "infinite model") with r_e = 3.1 dx for every
//! operator (Imoto 2022 does not state h). With this weight the HL and CHL kernels are
//! both proportional to r_e/r³, so they coincide on the regular lattice. Variant names
//! are those of the case file's `scheme` block where the variant is a scheme choice.

use super::perturb::SplitMix64;
use super::stats::fit_power_law;
use crate::case::{GradientKind, LaplacianKind};
use crate::engine::kernel::Koshizuka;
use crate::engine::neighbors::NeighborList;
use crate::engine::operators::{self, Cloud, LatticeConstants, Normalisation};
use crate::math::{Real, Vec2};
use std::io;
use std::path::Path;

/// One line of the convergence table.
#[derive(Debug, Clone, PartialEq)]
pub struct ConvergenceRow {
    /// Operator and variant, e.g. `laplacian/classic`.
    pub variant: String,
    /// `sin(x+2y)` or `exp(x+2y)`.
    pub field: String,
    /// `regular`, `perturbed` or `anisotropic`.
    pub lattice: String,
    pub dx: Real,
    /// E_D of Imoto (2022) §5.
    pub error: Real,
    /// Least-squares slope of log E against log dx over the variant's rows (same field
    /// and lattice).
    pub order: Real,
}

/// Ratio r_e / dx of the study.
pub const RADIUS_RATIO: Real = 3.1;
/// Spacings of the study (Imoto 2022 §5).
pub const SPACINGS: [Real; 4] = [0.125, 0.0625, 0.03125, 0.015625];
/// Seed of the perturbed lattices.
pub const PERTURBATION_SEED: u64 = 2022;

/// The test fields of Imoto (2022) §5.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Field {
    /// sin(x + 2y)
    Sine,
    /// exp(x + 2y)
    Exponential,
}

impl Field {
    pub const ALL: [Field; 2] = [Field::Sine, Field::Exponential];

    pub fn name(self) -> &'static str {
        match self {
            Field::Sine => "sin(x+2y)",
            Field::Exponential => "exp(x+2y)",
        }
    }
    pub fn value(self, p: Vec2) -> Real {
        let s = p.x + 2.0 * p.y;
        match self {
            Field::Sine => s.sin(),
            Field::Exponential => s.exp(),
        }
    }
    /// f', f'' of the one-variable profile g(s), s = x + 2y.
    fn derivatives(self, p: Vec2) -> (Real, Real) {
        let s = p.x + 2.0 * p.y;
        match self {
            Field::Sine => (s.cos(), -s.sin()),
            Field::Exponential => (s.exp(), s.exp()),
        }
    }
    pub fn gradient(self, p: Vec2) -> Vec2 {
        Vec2::new(1.0, 2.0) * self.derivatives(p).0
    }
    /// (∂xx, ∂yy, ∂xy)
    pub fn hessian(self, p: Vec2) -> (Real, Real, Real) {
        let g2 = self.derivatives(p).1;
        (g2, 4.0 * g2, 2.0 * g2)
    }
    pub fn laplacian(self, p: Vec2) -> Real {
        5.0 * self.derivatives(p).1
    }
    /// max over Ω = [0,1]² of |g'| and |g''| (|sin|, |cos| reach 1 on s ∈ [0, 3]; exp at s = 3).
    fn max_profile(self) -> Real {
        match self {
            Field::Sine => 1.0,
            Field::Exponential => 3.0_f64.exp(),
        }
    }
}

/// The particle distributions of the study.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LatticeKind {
    Regular,
    /// Each coordinate perturbed by U[-0.2 dx, 0.2 dx] (Imoto 2022 Fig. 3b).
    Perturbed,
    /// Spacing dx/2 along x, dx along y (Imoto 2022 Fig. 4a).
    Anisotropic,
}

impl LatticeKind {
    pub fn name(self) -> &'static str {
        match self {
            LatticeKind::Regular => "regular",
            LatticeKind::Perturbed => "perturbed",
            LatticeKind::Anisotropic => "anisotropic",
        }
    }
}

/// Positions covering [0,1]² extended by r_e, and the indices of those inside [0,1]².
pub fn lattice(kind: LatticeKind, dx: Real, seed: u64) -> (Vec<Vec2>, Vec<usize>) {
    let re = RADIUS_RATIO * dx;
    let (hx, hy) = match kind {
        LatticeKind::Anisotropic => (dx / 2.0, dx),
        _ => (dx, dx),
    };
    let mut rng = SplitMix64::new(seed);
    let margin_x = (re / hx).ceil() as i64 + 1;
    let margin_y = (re / hy).ceil() as i64 + 1;
    let (nx, ny) = ((1.0 / hx).round() as i64, (1.0 / hy).round() as i64);
    let mut pos = Vec::new();
    let mut inside = Vec::new();
    for b in -margin_y..=ny + margin_y {
        for a in -margin_x..=nx + margin_x {
            let mut p = Vec2::new(a as Real * hx, b as Real * hy);
            if kind == LatticeKind::Perturbed {
                p.x += (2.0 * rng.unit() - 1.0) * 0.2 * dx;
                p.y += (2.0 * rng.unit() - 1.0) * 0.2 * dx;
            }
            if (0.0..=1.0).contains(&p.x) && (0.0..=1.0).contains(&p.y) {
                inside.push(pos.len());
            }
            pos.push(p);
        }
    }
    (pos, inside)
}

/// The operators of the study.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum StudiedOperator {
    Gradient(GradientKind),
    Laplacian(LaplacianKind),
    /// Imoto's regular second derivatives (∂xx, ∂yy), Imoto (2022) eq. 26.
    RegularSecondDerivative,
    /// Imoto's mixed derivative ∂xy, Imoto (2022) eq. 27.
    MixedDerivative,
    /// Paper 000 eq. 29 (anisotropic ∂xx, ∂yy).
    AnisotropicSecondDerivative,
}

impl StudiedOperator {
    pub fn name(self) -> String {
        let snake = |s: String| s.trim_matches('"').to_string();
        match self {
            // evaluated in its linear form (see `relative_error`)
            StudiedOperator::Gradient(GradientKind::MinimumPressure | GradientKind::Cmps) => {
                "gradient/classic (eq. 13)".into()
            }
            StudiedOperator::Gradient(k) => format!(
                "gradient/{}",
                snake(serde_json::to_string(&k).unwrap_or_default())
            ),
            StudiedOperator::Laplacian(k) => format!(
                "laplacian/{}",
                snake(serde_json::to_string(&k).unwrap_or_default())
            ),
            StudiedOperator::RegularSecondDerivative => "second_derivative/regular (eq. 26)".into(),
            StudiedOperator::MixedDerivative => "second_derivative/mixed (eq. 27)".into(),
            StudiedOperator::AnisotropicSecondDerivative => {
                "second_derivative/anisotropic (eq. 29)".into()
            }
        }
    }

    /// All operators of the table.
    pub fn all() -> Vec<StudiedOperator> {
        use GradientKind as G;
        use LaplacianKind as L;
        vec![
            StudiedOperator::Gradient(G::MinimumPressure),
            StudiedOperator::Gradient(G::Corrected),
            StudiedOperator::Gradient(G::Anisotropic),
            StudiedOperator::Gradient(G::LeastSquares),
            StudiedOperator::Laplacian(L::Classic),
            StudiedOperator::Laplacian(L::HigherOrder),
            StudiedOperator::Laplacian(L::CorrectedHigherOrder),
            StudiedOperator::Laplacian(L::SecondOrder),
            StudiedOperator::Laplacian(L::Anisotropic),
            StudiedOperator::Laplacian(L::LeastSquares),
            StudiedOperator::RegularSecondDerivative,
            StudiedOperator::MixedDerivative,
            StudiedOperator::AnisotropicSecondDerivative,
        ]
    }
}

/// E_D of one operator on one distribution. The classic gradient ("minimum_pressure")
/// is evaluated in its linear form Σ g_ij f_ij (Imoto 2022 eq. 13; the minimum-pressure
/// shift is a stabiliser, not part of the consistency study); classic, second-order and
/// HL/CHL Laplacians use the particle's own n_i, λ_i as Imoto (2022) §3.1 does.
pub fn relative_error(
    op: StudiedOperator,
    field: Field,
    positions: &[Vec2],
    inside: &[usize],
    re: Real,
) -> Real {
    let nb = NeighborList::build(positions, re);
    let cloud = Cloud::new(positions, &nb, re);
    let f: Vec<Real> = positions.iter().map(|&p| field.value(p)).collect();
    let m = field.max_profile();
    let norm = Normalisation::Local;
    let errors: Vec<Real> = match op {
        StudiedOperator::Gradient(kind) => inside
            .iter()
            .map(|&i| {
                let row = if kind == GradientKind::MinimumPressure {
                    classic_gradient_row(&cloud, i)
                } else {
                    operators::gradient_row::<Koshizuka>(kind, &cloud, norm, i)
                };
                let g: Vec2 = row.iter().map(|&(j, c)| c * (f[j] - f[i])).sum();
                (g - field.gradient(positions[i])).norm() / (m * 5.0_f64.sqrt())
            })
            .collect(),
        StudiedOperator::Laplacian(kind) => inside
            .iter()
            .map(|&i| {
                let row = operators::laplacian_row::<Koshizuka>(kind, &cloud, norm, i);
                (row.apply(i, &f) - field.laplacian(positions[i])).abs() / (5.0 * m)
            })
            .collect(),
        StudiedOperator::RegularSecondDerivative | StudiedOperator::AnisotropicSecondDerivative => {
            let d = if op == StudiedOperator::RegularSecondDerivative {
                operators::second_derivatives::<Koshizuka>(&cloud, &f)
            } else {
                operators::anisotropic_second_derivatives::<Koshizuka>(&cloud, &f)
            };
            inside
                .iter()
                .map(|&i| {
                    let (xx, yy, _) = field.hessian(positions[i]);
                    Vec2::new(d[i].xx - xx, d[i].yy - yy).norm() / (17.0_f64.sqrt() * m)
                })
                .collect()
        }
        StudiedOperator::MixedDerivative => {
            let d = operators::second_derivatives::<Koshizuka>(&cloud, &f);
            inside
                .iter()
                .map(|&i| (d[i].xy - field.hessian(positions[i]).2).abs() / (2.0 * m))
                .collect()
        }
    };
    errors.iter().sum::<Real>() / errors.len().max(1) as Real
}

fn classic_gradient_row(cloud: &Cloud, i: usize) -> Vec<(usize, Vec2)> {
    operators::gradient_row::<Koshizuka>(GradientKind::Cmps, cloud, Normalisation::Local, i)
}

/// Least-squares slope of ln(error) against ln(dx) over the positive errors; NaN with
/// fewer than two.
pub fn fitted_order(points: &[(Real, Real)]) -> Real {
    fit_power_law(points).map_or(Real::NAN, |fit| fit.exponent)
}

/// The rows of one operator, field and lattice over [`SPACINGS`].
pub fn convergence_rows(
    op: StudiedOperator,
    field: Field,
    kind: LatticeKind,
) -> Vec<ConvergenceRow> {
    let errors: Vec<(Real, Real)> = SPACINGS
        .iter()
        .map(|&dx| {
            let (pos, inside) = lattice(kind, dx, PERTURBATION_SEED);
            (
                dx,
                relative_error(op, field, &pos, &inside, RADIUS_RATIO * dx),
            )
        })
        .collect();
    let order = fitted_order(&errors);
    errors
        .into_iter()
        .map(|(dx, error)| ConvergenceRow {
            variant: op.name(),
            field: field.name().into(),
            lattice: kind.name().into(),
            dx,
            error,
            order,
        })
        .collect()
}

/// The whole table: every operator, both fields, the three distributions.
pub fn convergence_table() -> Vec<ConvergenceRow> {
    let mut rows = Vec::new();
    for kind in [
        LatticeKind::Regular,
        LatticeKind::Perturbed,
        LatticeKind::Anisotropic,
    ] {
        for field in Field::ALL {
            for op in StudiedOperator::all() {
                rows.extend(convergence_rows(op, field, kind));
            }
        }
    }
    rows
}

/// The table as Markdown (one line per row; the fitted order repeats within a group).
pub fn convergence_markdown(rows: &[ConvergenceRow]) -> String {
    let mut s = String::from("| variant | field | lattice | dx | E_D | fitted order |\n| --- | --- | --- | --- | --- | --- |\n");
    for r in rows {
        s.push_str(&format!(
            "| {} | {} | {} | 2^{} | {:.3e} | {:.2} |\n",
            r.variant,
            r.field,
            r.lattice,
            r.dx.log2().round() as i64,
            r.error,
            r.order
        ));
    }
    s
}

/// Lattice constants of the study's weight at spacing `dx` (exposed for the tests).
pub fn study_constants(dx: Real) -> LatticeConstants {
    LatticeConstants::compute::<Koshizuka>(dx, RADIUS_RATIO * dx, 2)
}

/// `--operators`: the convergence study as `operators.md`.
pub fn write_operators(out_dir: &Path) -> io::Result<()> {
    let rows = convergence_table();
    let mut md = String::from("# Operator convergence study (Imoto 2022 §5)\n\n");
    md.push_str(&convergence_markdown(&rows));
    std::fs::write(out_dir.join("operators.md"), md)
}
