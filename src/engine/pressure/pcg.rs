//! Krylov solvers over [`CsrMatrix`]: preconditioned conjugate gradients (Jacobi or
//! IC(0)) for the symmetric systems, BiCGSTAB (Jacobi) for the others. Dot products
//! use fixed-chunk reductions so iterates do not depend on the thread count.

use super::amg::Hierarchy;
use super::{CsrMatrix, SolveError, SolveInfo, SolveParams};
use crate::math::{deterministic_sum, deterministic_sum_mut, deterministic_sums_mut, Real};
use rayon::prelude::*;

#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Preconditioner {
    Jacobi,
    IncompleteCholesky,
    /// Smoothed-aggregation algebraic multigrid, one V-cycle ([`super::amg`]).
    Amg,
}

/// Below this many unknowns vector operations run on one thread: rayon's fork/join
/// costs more than the arithmetic below it (the 30° wedge at 1 cm, 17k unknowns: the
/// solve took 5 % less time with its vector passes on two threads than on one).
pub(crate) const PARALLEL_MIN: usize = 8192;

pub(crate) fn dot(a: &[Real], b: &[Real]) -> Real {
    if a.len() < PARALLEL_MIN {
        // same chunking as deterministic_sum, so the result does not depend on the path
        let mut total = 0.0;
        for (ca, cb) in a.chunks(2048).zip(b.chunks(2048)) {
            let mut s = 0.0;
            for (x, y) in ca.iter().zip(cb) {
                s += x * y;
            }
            total += s;
        }
        return total;
    }
    deterministic_sum(a.len(), |i| a[i] * b[i])
}

pub(crate) fn axpy(y: &mut [Real], alpha: Real, x: &[Real]) {
    if y.len() < PARALLEL_MIN {
        y.iter_mut().zip(x).for_each(|(yi, xi)| *yi += alpha * xi);
        return;
    }
    y.par_iter_mut()
        .with_min_len(1024)
        .zip(x.par_iter())
        .for_each(|(yi, xi)| *yi += alpha * xi);
}

/// Total nanoseconds of preconditioner setup in this process (benchmarks only).
pub(crate) static SETUP_NANOS: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(0);

/// `f(i, &mut y[i])` for every i, in parallel for long vectors (elementwise: deterministic).
fn for_each_index<F>(y: &mut [Real], f: F)
where
    F: Fn(usize, &mut Real) + Sync + Send,
{
    if y.len() < PARALLEL_MIN {
        y.iter_mut().enumerate().for_each(|(i, v)| f(i, v));
        return;
    }
    y.par_iter_mut()
        .with_min_len(1024)
        .enumerate()
        .for_each(|(i, v)| f(i, v));
}

/// x += alpha p, then p = z + beta p, in one pass.
fn update_iterate(x: &mut [Real], p: &mut [Real], z: &[Real], alpha: Real, beta: Real) {
    let update = |(i, (xi, pi)): (usize, (&mut Real, &mut Real))| {
        *xi += alpha * *pi;
        *pi = z[i] + beta * *pi;
    };
    if x.len() < PARALLEL_MIN {
        x.iter_mut().zip(p.iter_mut()).enumerate().for_each(update);
    } else {
        x.par_iter_mut()
            .zip(p.par_iter_mut())
            .with_min_len(1024)
            .enumerate()
            .for_each(update);
    }
}

/// Zero-fill incomplete Cholesky factor L (lower, CSR of the lower triangle incl. diagonal).
struct Ic0 {
    n: usize,
    row_ptr: Vec<usize>,
    col: Vec<u32>,
    val: Vec<Real>,
}

impl Ic0 {
    fn new(a: &CsrMatrix) -> Option<Self> {
        let n = a.n;
        let mut row_ptr = vec![0usize; n + 1];
        let mut col = Vec::new();
        let mut val = Vec::new();
        for i in 0..n {
            let mut entries: Vec<(u32, Real)> = (a.row_ptr[i]..a.row_ptr[i + 1])
                .filter(|&k| a.col[k] as usize <= i)
                .map(|k| (a.col[k], a.val[k]))
                .collect();
            entries.sort_by_key(|e| e.0);
            for (c, v) in entries {
                col.push(c);
                val.push(v);
            }
            row_ptr[i + 1] = col.len();
        }
        // IC(0): for each row i, for each k < i in the pattern: l_ik = (a_ik - Σ_{j<k} l_ij l_kj) / l_kk
        let diag_pos: Vec<usize> = (0..n).map(|i| row_ptr[i + 1] - 1).collect();
        for i in 0..n {
            let (ri0, ri1) = (row_ptr[i], row_ptr[i + 1]);
            for p in ri0..ri1 {
                let k = col[p] as usize;
                // Σ_{j<k} l_ij l_kj over the shared pattern (both rows sorted)
                let (mut a_, mut b_) = (ri0, row_ptr[k]);
                let mut s = 0.0;
                while a_ < p && b_ < diag_pos[k] {
                    let (ca, cb) = (col[a_], col[b_]);
                    if ca == cb {
                        s += val[a_] * val[b_];
                        a_ += 1;
                        b_ += 1;
                    } else if ca < cb {
                        a_ += 1;
                    } else {
                        b_ += 1;
                    }
                }
                if k == i {
                    let d = val[p] - s;
                    if d <= 0.0 || !d.is_finite() {
                        return None;
                    }
                    val[p] = d.sqrt();
                } else {
                    val[p] = (val[p] - s) / val[diag_pos[k]];
                }
            }
        }
        Some(Self {
            n,
            row_ptr,
            col,
            val,
        })
    }

    /// z = (L Lᵀ)⁻¹ r
    fn apply(&self, r: &[Real], z: &mut [Real]) {
        let n = self.n;
        // forward: L y = r
        for i in 0..n {
            let mut s = r[i];
            let end = self.row_ptr[i + 1] - 1;
            for p in self.row_ptr[i]..end {
                s -= self.val[p] * z[self.col[p] as usize];
            }
            z[i] = s / self.val[end];
        }
        // backward: Lᵀ x = y (column-oriented sweep over the rows of L)
        for i in (0..n).rev() {
            let end = self.row_ptr[i + 1] - 1;
            z[i] /= self.val[end];
            let zi = z[i];
            for p in self.row_ptr[i]..end {
                z[self.col[p] as usize] -= self.val[p] * zi;
            }
        }
    }
}

/// What both Krylov solvers start from: r = b - A x, written into `r` (resized to the
/// system), and ||b||. `None` when there is nothing to solve (empty system, or b = 0
/// and then x = 0).
fn start(a: &CsrMatrix, b: &[Real], x: &mut [Real], r: &mut Vec<Real>) -> Option<Real> {
    if a.n == 0 {
        return None;
    }
    let bnorm = dot(b, b).sqrt();
    if bnorm == 0.0 {
        x.iter_mut().for_each(|v| *v = 0.0);
        return None;
    }
    // every entry is written by the product: no zeroing of the kept buffer
    r.resize(a.n, 0.0);
    a.mul(x, r);
    for_each_index(r, |i, ri| *ri = b[i] - *ri);
    Some(bnorm)
}

fn inverse_diagonal(a: &CsrMatrix) -> Vec<Real> {
    a.diagonal()
        .iter()
        .map(|d| if *d != 0.0 { 1.0 / d } else { 1.0 })
        .collect()
}

/// Add the time since `clock` to the process-wide setup counter.
pub(crate) fn count_setup(clock: std::time::Instant) {
    SETUP_NANOS.fetch_add(
        clock.elapsed().as_nanos() as u64,
        std::sync::atomic::Ordering::Relaxed,
    );
}

/// Has CG's next iterate x + alpha p reached `params.energy`? Its error in the energy
/// norm, ||x* - x||_A, is below the step CG just took, sqrt(alpha r·z), once an
/// iteration cuts the error by √2 or more (the step's square is this iterate's squared
/// error less the next one's; the AMG-preconditioned solves cut it 3-4 times);
/// `energy` is x·(b - r) = x·A x at that iterate.
fn energy_converged(params: &SolveParams, step_energy: Real, energy: Real) -> bool {
    params.energy > 0.0 && step_energy <= params.energy * params.energy * energy
}

/// Preconditioned conjugate gradients; `x` is the initial guess.
pub fn conjugate_gradient(
    a: &CsrMatrix,
    b: &[Real],
    x: &mut [Real],
    params: SolveParams,
    pre: Preconditioner,
) -> Result<SolveInfo, SolveError> {
    if a.n == 0 || dot(b, b) == 0.0 {
        // nothing to solve: no preconditioner to build
        return pcg_with(a, b, x, params, |r, z| z.copy_from_slice(r));
    }
    let setup = std::time::Instant::now();
    match pre {
        Preconditioner::Jacobi => {
            let inv_diag = inverse_diagonal(a);
            count_setup(setup);
            pcg_with(a, b, x, params, |r, z| {
                for_each_index(z, |i, zi| *zi = r[i] * inv_diag[i])
            })
        }
        Preconditioner::IncompleteCholesky => {
            let ic = Ic0::new(a);
            let inv_diag = match ic {
                Some(_) => Vec::new(),
                None => inverse_diagonal(a),
            };
            count_setup(setup);
            pcg_with(a, b, x, params, |r, z| match &ic {
                Some(ic) => ic.apply(r, z),
                None => for_each_index(z, |i, zi| *zi = r[i] * inv_diag[i]),
            })
        }
        Preconditioner::Amg => {
            let mut amg = Hierarchy::new(a);
            count_setup(setup);
            pcg_with(a, b, x, params, |r, z| amg.apply(a, r, z))
        }
    }
}

/// The work vectors of conjugate gradients (residual r, preconditioned residual z,
/// direction p, product q), kept by a caller that solves again and again
/// (`SolverCache`): reused rather than allocated, they sit at the same addresses from
/// solve to solve. Allocated per solve, their placement followed the step's other
/// allocations, and the 30° wedge's solve moved by 3-5 % with changes to code outside
/// it.
#[derive(Default)]
pub(crate) struct CgVectors {
    r: Vec<Real>,
    z: Vec<Real>,
    p: Vec<Real>,
    q: Vec<Real>,
}

/// Conjugate gradients with the preconditioner `precondition(r, z)`: z = M⁻¹ r, M
/// symmetric positive definite.
pub(crate) fn pcg_with(
    a: &CsrMatrix,
    b: &[Real],
    x: &mut [Real],
    params: SolveParams,
    mut precondition: impl FnMut(&[Real], &mut [Real]),
) -> Result<SolveInfo, SolveError> {
    let mut work = CgVectors::default();
    pcg_in(a, b, x, params, &mut work, |r, z| {
        precondition(r, z);
        dot(r, z)
    })
}

/// [`pcg_with`] in the work vectors `work`, with a preconditioner that also returns
/// r·z, bit for bit as [`dot`] gives it (so that it can fuse the sum into its last
/// pass).
pub(crate) fn pcg_in(
    a: &CsrMatrix,
    b: &[Real],
    x: &mut [Real],
    params: SolveParams,
    work: &mut CgVectors,
    mut precondition: impl FnMut(&[Real], &mut [Real]) -> Real,
) -> Result<SolveInfo, SolveError> {
    let n = a.n;
    let CgVectors { r, z, p, q } = work;
    let Some(bnorm) = start(a, b, x, r) else {
        return Ok(SolveInfo::default());
    };
    // each is written before it is read (z by the preconditioner, p from z, q by the
    // product): sized, not zeroed
    for v in [&mut *z, &mut *p, &mut *q] {
        v.resize(n, 0.0);
    }
    let mut rz = precondition(r, z);
    p.copy_from_slice(z);
    let mut rel = dot(r, r).sqrt() / bnorm;
    let mut it = 0;
    while rel > params.tolerance {
        if it >= params.max_iterations {
            return Err(SolveError::NotConverged {
                iterations: it,
                relative_residual: rel,
            });
        }
        // fused passes: q = A p with p·q, r -= alpha q with r·r, and x += alpha p with
        // p = z + beta p; each sum is the one a separate `dot` gives, bit for bit
        let parallel = n >= PARALLEL_MIN;
        let pq = deterministic_sum_mut(q, parallel, |i, qi| {
            *qi = a.row_dot(i, p);
            p[i] * *qi
        });
        if !(pq.is_finite()) || pq == 0.0 {
            return Err(SolveError::Breakdown);
        }
        let alpha = rz / pq;
        let update = |i: usize, ri: &mut Real| {
            *ri += -alpha * q[i];
            *ri * *ri
        };
        // with the energy stop, x·(b - r) at the next iterate in the same pass
        let (rr, energy) = if params.energy > 0.0 {
            deterministic_sums_mut(r, parallel, |i, ri| {
                (update(i, ri), (x[i] + alpha * p[i]) * (b[i] - *ri))
            })
        } else {
            (deterministic_sum_mut(r, parallel, update), 0.0)
        };
        rel = rr.sqrt() / bnorm;
        if !rel.is_finite() {
            return Err(SolveError::Breakdown);
        }
        it += 1;
        if rel <= params.tolerance || energy_converged(&params, alpha * rz, energy) {
            // converged: the last iterate needs no new direction, so no preconditioner
            // application (one V-cycle of the 4-16 a step takes)
            for_each_index(x, |i, xi| *xi += alpha * p[i]);
            break;
        }
        let rz_new = precondition(r, z);
        let beta = rz_new / rz;
        rz = rz_new;
        update_iterate(x, p, z, alpha, beta);
    }
    Ok(SolveInfo {
        iterations: it,
        relative_residual: rel,
    })
}

/// BiCGSTAB with a Jacobi preconditioner, for non-symmetric operators.
pub fn bicgstab(
    a: &CsrMatrix,
    b: &[Real],
    x: &mut [Real],
    params: SolveParams,
) -> Result<SolveInfo, SolveError> {
    let n = a.n;
    let mut r0 = Vec::new();
    let Some(bnorm) = start(a, b, x, &mut r0) else {
        return Ok(SolveInfo::default());
    };
    let inv_diag = inverse_diagonal(a);
    let jac = |v: &[Real], out: &mut [Real]| {
        out.par_iter_mut()
            .enumerate()
            .for_each(|(i, o)| *o = v[i] * inv_diag[i])
    };
    let mut r = r0.clone();
    let (mut rho, mut alpha, mut omega) = (1.0, 1.0, 1.0);
    let mut v = vec![0.0; n];
    let mut p = vec![0.0; n];
    let (mut y, mut s, mut zz, mut t) = (vec![0.0; n], vec![0.0; n], vec![0.0; n], vec![0.0; n]);
    let mut rel = dot(&r, &r).sqrt() / bnorm;
    let mut it = 0;
    while rel > params.tolerance {
        if it >= params.max_iterations {
            return Err(SolveError::NotConverged {
                iterations: it,
                relative_residual: rel,
            });
        }
        let rho_new = dot(&r0, &r);
        if rho_new == 0.0 || !rho_new.is_finite() {
            return Err(SolveError::Breakdown);
        }
        let beta = (rho_new / rho) * (alpha / omega);
        rho = rho_new;
        p.par_iter_mut()
            .enumerate()
            .for_each(|(i, pi)| *pi = r[i] + beta * (*pi - omega * v[i]));
        jac(&p, &mut y);
        a.mul(&y, &mut v);
        alpha = rho / dot(&r0, &v);
        s.par_iter_mut()
            .enumerate()
            .for_each(|(i, si)| *si = r[i] - alpha * v[i]);
        jac(&s, &mut zz);
        a.mul(&zz, &mut t);
        let tt = dot(&t, &t);
        omega = if tt > 0.0 { dot(&t, &s) / tt } else { 0.0 };
        x.par_iter_mut()
            .enumerate()
            .for_each(|(i, xi)| *xi += alpha * y[i] + omega * zz[i]);
        r.par_iter_mut()
            .enumerate()
            .for_each(|(i, ri)| *ri = s[i] - omega * t[i]);
        rel = dot(&r, &r).sqrt() / bnorm;
        if !rel.is_finite() {
            return Err(SolveError::Breakdown);
        }
        it += 1;
        if omega == 0.0 && rel > params.tolerance {
            return Err(SolveError::Breakdown);
        }
    }
    Ok(SolveInfo {
        iterations: it,
        relative_residual: rel,
    })
}
