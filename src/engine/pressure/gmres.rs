//! Restarted GMRES with right preconditioning, matrix-free: for the exact projection,
//! whose rows (the HS divergence of the corrected velocity) are not symmetric.
//! Right preconditioning keeps the residual it minimises the true one.

use super::pcg::{axpy, dot};
use super::{SolveError, SolveInfo, SolveParams};
use crate::math::Real;

/// Solve A x = b, A given by `apply(v, out)`, with the preconditioner
/// `precondition(r, z)` (z ≈ A⁻¹ r); `x` holds the initial guess on entry.
/// `tolerance` is relative to `reference` (a norm the caller chooses, e.g. that of the
/// whole right-hand side of which b is a correction).
pub fn gmres(
    mut apply: impl FnMut(&[Real], &mut [Real]),
    mut precondition: impl FnMut(&[Real], &mut [Real]),
    b: &[Real],
    x: &mut [Real],
    reference: Real,
    params: SolveParams,
    restart: usize,
) -> Result<SolveInfo, SolveError> {
    let n = b.len();
    let mut r = vec![0.0; n];
    let mut w = vec![0.0; n];
    let mut z = vec![0.0; n];
    let mut iterations = 0;
    loop {
        // r = b - A x
        apply(x, &mut r);
        r.iter_mut().zip(b).for_each(|(ri, bi)| *ri = bi - *ri);
        let beta = dot(&r, &r).sqrt();
        let rel = if reference > 0.0 {
            beta / reference
        } else {
            0.0
        };
        if !rel.is_finite() {
            return Err(SolveError::Breakdown);
        }
        if rel <= params.tolerance || beta == 0.0 {
            return Ok(SolveInfo {
                iterations,
                relative_residual: rel,
            });
        }
        if iterations >= params.max_iterations {
            return Err(SolveError::NotConverged {
                iterations,
                relative_residual: rel,
            });
        }
        let m = restart.min(params.max_iterations - iterations).max(1);
        let mut basis: Vec<Vec<Real>> = vec![r.iter().map(|v| v / beta).collect()];
        let mut h = vec![vec![0.0; m]; m + 1]; // h[row][col]
        let (mut cs, mut sn) = (vec![0.0; m], vec![0.0; m]);
        let mut g = vec![0.0; m + 1];
        g[0] = beta;
        let mut k = 0;
        while k < m {
            precondition(&basis[k], &mut z);
            apply(&z, &mut w);
            // modified Gram-Schmidt
            for (j, v) in basis.iter().enumerate() {
                let hj = dot(&w, v);
                h[j][k] = hj;
                axpy(&mut w, -hj, v);
            }
            let norm = dot(&w, &w).sqrt();
            h[k + 1][k] = norm;
            // previous rotations on the new column, then the new one
            for j in 0..k {
                let t = cs[j] * h[j][k] + sn[j] * h[j + 1][k];
                h[j + 1][k] = -sn[j] * h[j][k] + cs[j] * h[j + 1][k];
                h[j][k] = t;
            }
            let d = (h[k][k] * h[k][k] + h[k + 1][k] * h[k + 1][k]).sqrt();
            if d == 0.0 || !d.is_finite() {
                return Err(SolveError::Breakdown);
            }
            cs[k] = h[k][k] / d;
            sn[k] = h[k + 1][k] / d;
            h[k][k] = d;
            h[k + 1][k] = 0.0;
            g[k + 1] = -sn[k] * g[k];
            g[k] *= cs[k];
            k += 1;
            iterations += 1;
            let done = g[k].abs() / reference <= params.tolerance || norm == 0.0;
            if done || k == m {
                break;
            }
            basis.push(w.iter().map(|v| v / norm).collect());
        }
        // y = H⁻¹ g (upper triangular), x += M⁻¹ V y
        let mut y = vec![0.0; k];
        for i in (0..k).rev() {
            let s: Real = (i + 1..k).map(|j| h[i][j] * y[j]).sum();
            y[i] = (g[i] - s) / h[i][i];
        }
        let mut update = vec![0.0; n];
        for (v, &yi) in basis.iter().zip(&y) {
            axpy(&mut update, yi, v);
        }
        precondition(&update, &mut z);
        x.iter_mut().zip(&z).for_each(|(xi, zi)| *xi += zi);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A non-symmetric tridiagonal system (convection-diffusion) against its known solution.
    #[test]
    fn solves_a_nonsymmetric_system() {
        let n = 200;
        let apply = |v: &[Real], out: &mut [Real]| {
            for i in 0..n {
                let left = if i > 0 { v[i - 1] } else { 0.0 };
                let right = if i + 1 < n { v[i + 1] } else { 0.0 };
                out[i] = 2.5 * v[i] - 1.3 * left - 0.7 * right;
            }
        };
        let exact: Vec<Real> = (0..n).map(|i| (i as Real * 0.1).sin()).collect();
        let mut b = vec![0.0; n];
        apply(&exact, &mut b);
        let mut x = vec![0.0; n];
        let bnorm = dot(&b, &b).sqrt();
        let info = gmres(
            apply,
            |r, z| z.iter_mut().zip(r).for_each(|(zi, ri)| *zi = ri / 2.5),
            &b,
            &mut x,
            bnorm,
            SolveParams::relative(1e-10, 500),
            30,
        )
        .unwrap();
        let err = x
            .iter()
            .zip(&exact)
            .map(|(a, e)| (a - e).abs())
            .fold(0.0, Real::max);
        assert!(
            err < 1e-8,
            "max error {err:e} after {} iterations",
            info.iterations
        );
    }
}
