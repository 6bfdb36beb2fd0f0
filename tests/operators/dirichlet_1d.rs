//! Paper 002 §5.5 (Souto-Iglesias et al. 2013): one-dimensional boundary value problems
//! on [0, 1] with the interaction range h = r_e = 0.1 fixed and dx = h / k, k = 2 … 64
//! (more neighbours as k grows: the many-neighbour limit of the paper). Weight
//! w = h/r - 1.
//!
//! - §5.5.1: f'' = 0, f(0) = 0, f(1) = 1 (exact f = x). The paper: the classic MPS
//!   solution (Dirichlet particles carry the boundary values) is exact at h/dx = 2 and,
//!   as dx/h → 0, "does not converge to the analytical one" but tends to a constant in
//!   the interior; the corrected Laplacian converges.
//! - §5.5.2: f'' = 2, f'(0) = 0, f(1) = 1 (exact f = x², our choice of the constant-sign
//!   source). Classic Neumann treatment: dummy particles on [-h, 0) carry f_0 (Tsukamoto
//!   et al. 2011). The paper: the classic solution does not converge; the corrected
//!   formulation recovers the exact solution.
//!
//! The corrected operator (Souto-Iglesias et al. 2013 eqs. 74-75; the text copy lacks the formulas, so the
//! one-dimensional boundary term is derived here from the same principle, the
//! normalisation by Γ and Green's identity on the truncated support):
//!
//! ⟨f''⟩_i = (1/Γ_i) [ 2/(λ0 n0) Σ_{j∈Ω} w f_ij + Σ_B 2 W(r_iB) (f_B - f_i) / r_iB ],
//!
//! with W the Laplacian-equivalent SPH kernel of w (Souto-Iglesias et al. 2013 eq. 29): -W'/r ∝ w, so
//! W ∝ (h - r)² for this weight, normalised to unit integral on the line; Γ_i = ∫_Ω W
//! (discretely, the sum over the particles in Ω relative to the full line); B the two
//! end points. Expanding f to second order, the classic sum over the truncated support
//! is f''Γ - 2f'(W(b) - W(a)) - f''(bW(b) - aW(a)) and the boundary sums cancel both
//! spurious terms exactly. At a Neumann end point itself (r_iB → 0) the boundary term is
//! -2 W(0) f'_n, zero for the homogeneous condition.

use mpsfsi::case::{LaplacianKind, SolverKind};
use mpsfsi::engine::kernel::Koshizuka;
use mpsfsi::engine::neighbors::NeighborList;
use mpsfsi::engine::operators::{laplacian_row, Cloud, LatticeConstants, Normalisation};
use mpsfsi::engine::pressure::{solve, CsrMatrix, SolveParams};
use mpsfsi::math::{Real, Vec2};

const H: Real = 0.1;
const RATIOS: [usize; 6] = [2, 4, 8, 16, 32, 64];

#[derive(Clone, Copy, PartialEq)]
enum Problem {
    /// §5.5.1
    ZeroLaplacianDirichlet,
    /// §5.5.2
    ConstantSourceMixed,
}

impl Problem {
    fn exact(self, x: Real) -> Real {
        match self {
            Problem::ZeroLaplacianDirichlet => x,
            Problem::ConstantSourceMixed => x * x,
        }
    }
    fn source(self) -> Real {
        match self {
            Problem::ZeroLaplacianDirichlet => 0.0,
            Problem::ConstantSourceMixed => 2.0,
        }
    }
}

/// Dense-ish linear system in CSR from (row -> [(col, value)]).
pub fn csr_from_rows(rows: &[Vec<(usize, Real)>]) -> CsrMatrix {
    let mut m = CsrMatrix {
        n: rows.len(),
        row_ptr: vec![0],
        col: Vec::new(),
        val: Vec::new(),
    };
    for row in rows {
        let mut r = row.clone();
        r.sort_by_key(|&(c, _)| c);
        let mut merged: Vec<(usize, Real)> = Vec::new();
        for (c, v) in r {
            match merged.last_mut() {
                Some(last) if last.0 == c => last.1 += v,
                _ => merged.push((c, v)),
            }
        }
        for (c, v) in merged {
            m.col.push(c as u32);
            m.val.push(v);
        }
        m.row_ptr.push(m.col.len());
    }
    m
}

pub fn solve_direct(rows: &[Vec<(usize, Real)>], b: &[Real]) -> Vec<Real> {
    let a = csr_from_rows(rows);
    let mut x = vec![0.0; b.len()];
    solve(
        SolverKind::Direct,
        &a,
        b,
        &mut x,
        SolveParams::relative(1e-12, 1),
    )
    .expect("direct solve");
    x
}

/// Max |f - exact| of the classic MPS solution (reference n0, λ; boundary particles
/// carry Dirichlet values; Neumann by dummies holding f_0).
fn classic_error(problem: Problem, ratio: usize) -> Real {
    let dx = H / ratio as Real;
    let n = ratio * 10; // particles 0..=n on [0, 1]
    let dummies = if problem == Problem::ConstantSourceMixed {
        ratio
    } else {
        0
    };
    // positions: real particles first, then dummies at -k dx
    let mut pos: Vec<Vec2> = (0..=n).map(|k| Vec2::new(k as Real * dx, 0.0)).collect();
    pos.extend((1..=dummies).map(|k| Vec2::new(-(k as Real) * dx, 0.0)));
    let nb = NeighborList::build(&pos, H);
    let cloud = Cloud::one_dimensional(&pos, &nb, H);
    let consts = LatticeConstants::compute::<Koshizuka>(dx, H, 1);
    let first_unknown = if problem == Problem::ConstantSourceMixed {
        0
    } else {
        1
    };
    let unknowns: Vec<usize> = (first_unknown..n).collect(); // particle k -> unknown k - first
    let index =
        |k: usize| -> Option<usize> { (k >= first_unknown && k < n).then(|| k - first_unknown) };
    let mut rows = Vec::new();
    let mut b = Vec::new();
    for &i in &unknowns {
        let row = laplacian_row::<Koshizuka>(
            LaplacianKind::Classic,
            &cloud,
            Normalisation::Reference(consts),
            i,
        );
        let mut r = vec![(index(i).unwrap(), row.diagonal)];
        let mut rhs = problem.source();
        for &(j, c) in &row.off_diagonal {
            let j = if j > n { 0 } else { j }; // a dummy holds f_0
            match index(j) {
                Some(u) => r.push((u, c)),
                None => rhs -= c * problem.exact(pos[j].x), // Dirichlet particle
            }
        }
        rows.push(r);
        b.push(rhs);
    }
    let f = solve_direct(&rows, &b);
    unknowns
        .iter()
        .zip(&f)
        .map(|(&k, v)| (v - problem.exact(pos[k].x)).abs())
        .fold(0.0, Real::max)
}

/// Max |f - exact| with the boundary-corrected Laplacian (module doc).
fn corrected_error(problem: Problem, ratio: usize) -> Real {
    let dx = H / ratio as Real;
    let n = ratio * 10;
    let pos: Vec<Vec2> = (0..=n).map(|k| Vec2::new(k as Real * dx, 0.0)).collect();
    let nb = NeighborList::build(&pos, H);
    let cloud = Cloud::one_dimensional(&pos, &nb, H);
    let consts = LatticeConstants::compute::<Koshizuka>(dx, H, 1);
    // W ∝ (h - r)², normalised so that dx Σ_{k∈Z} W(|k| dx) = 1
    let line_sum: Real = (-(ratio as i64)..=ratio as i64)
        .map(|k| (H - (k as Real * dx).abs()).max(0.0).powi(2))
        .sum();
    let kernel_w = |r: Real| (H - r).max(0.0).powi(2) / (dx * line_sum);
    let first_unknown = if problem == Problem::ConstantSourceMixed {
        0
    } else {
        1
    };
    let index =
        |k: usize| -> Option<usize> { (k >= first_unknown && k < n).then(|| k - first_unknown) };
    let boundaries = [0usize, n];
    let mut rows = Vec::new();
    let mut b = Vec::new();
    for i in first_unknown..n {
        let xi = pos[i].x;
        let gamma: Real = dx
            * (0..=n)
                .map(|j| kernel_w((pos[j].x - xi).abs()))
                .sum::<Real>();
        let row = laplacian_row::<Koshizuka>(
            LaplacianKind::Classic,
            &cloud,
            Normalisation::Reference(consts),
            i,
        );
        let mut coeffs: Vec<(usize, Real)> = row.off_diagonal.clone();
        for &bnd in &boundaries {
            let r = (pos[bnd].x - xi).abs();
            if bnd != i && r < H {
                coeffs.push((bnd, 2.0 * kernel_w(r) / r));
            }
            // at the Neumann end point itself the term is -2 W(0) f'_n = 0 (f'(0) = 0)
        }
        let mut r = vec![(
            index(i).unwrap(),
            -coeffs.iter().map(|c| c.1).sum::<Real>() / gamma,
        )];
        let mut rhs = problem.source();
        for (j, c) in coeffs {
            match index(j) {
                Some(u) => r.push((u, c / gamma)),
                None => rhs -= c / gamma * problem.exact(pos[j].x),
            }
        }
        rows.push(r);
        b.push(rhs);
    }
    let f = solve_direct(&rows, &b);
    (first_unknown..n)
        .zip(&f)
        .map(|(k, v)| (v - problem.exact(pos[k].x)).abs())
        .fold(0.0, Real::max)
}

fn check(problem: Problem, label: &str, exact_at_two: bool) {
    let classic: Vec<Real> = RATIOS.iter().map(|&k| classic_error(problem, k)).collect();
    let corrected: Vec<Real> = RATIOS
        .iter()
        .map(|&k| corrected_error(problem, k))
        .collect();
    println!("{label}: h/dx {RATIOS:?}\n  classic   max error {classic:.3?}\n  corrected max error {corrected:.3?}");
    // "the solution for h/dx = 2 is exact" (nearest neighbours: the centred difference)
    // (the Neumann case is not: dummies holding f_0 put the condition half a spacing
    // outside x = 0, an O(dx) error for our f = x²; the paper's exact solution of
    // §5.5.2 is not in the text copy)
    assert!(
        !exact_at_two || classic[0] < 1e-10,
        "{label}: classic at h/dx = 2 should be exact, error {:.3e}",
        classic[0]
    );
    // the classic solution drifts away as neighbours grow
    for w in classic[1..].windows(2) {
        assert!(
            w[1] > w[0],
            "{label}: classic error should grow with h/dx: {classic:.3?}"
        );
    }
    assert!(
        *classic.last().unwrap() > 0.05,
        "{label}: classic solution should drift visibly: {classic:.3?}"
    );
    // the corrected formulation converges: monotone decrease, below 1 % at the finest
    for w in corrected[1..].windows(2) {
        assert!(
            w[1] < w[0],
            "{label}: corrected error should decrease with h/dx: {corrected:.3?}"
        );
    }
    assert!(
        *corrected.last().unwrap() < 0.01,
        "{label}: corrected error at h/dx = 64: {:.3e}",
        corrected.last().unwrap()
    );
}

#[test]
fn zero_laplacian_dirichlet_classic_drifts_corrected_converges() {
    check(
        Problem::ZeroLaplacianDirichlet,
        "Souto-Iglesias et al. 2013 §5.5.1",
        true,
    );
}

#[test]
fn constant_source_mixed_classic_drifts_corrected_converges() {
    check(
        Problem::ConstantSourceMixed,
        "Souto-Iglesias et al. 2013 §5.5.2",
        false,
    );
}
