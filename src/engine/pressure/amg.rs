//! Smoothed-aggregation algebraic multigrid (Vaněk, Mandel & Brezina 1996) as a
//! preconditioner for conjugate gradients on the pressure Poisson matrix.
//!
//! Setup (from scratch every few steps, since the particles move; in between the
//! hierarchy is reused, see [`super::reuse`]): greedy aggregation of strongly
//! connected unknowns, the piecewise-constant tentative prolongator smoothed by one damped
//! Jacobi step, P = (I - ω D⁻¹A) P₀, Galerkin coarse operators A_c = Pᵀ A P, down to a
//! small level that is factorised densely (Cholesky). Application: one symmetric V(1,1)
//! cycle with damped Jacobi smoothing, so the preconditioner is symmetric positive
//! definite and plain CG applies.
//!
//! Every level operation is a row-parallel loop in which each row is computed by one
//! task in a fixed order, and the aggregation is sequential: results do not depend on
//! the number of threads.

use super::{CsrMatrix, RowChunk};
use crate::math::{deterministic_sum, deterministic_sum_mut, Real};
use nalgebra::{DMatrix, DVector};
use rayon::prelude::*;
use std::borrow::Cow;

/// Levels with fewer rows run their loops on one thread.
const PARALLEL_ROWS: usize = 8192;
/// Coarsening stops at this many unknowns; the last level is factorised densely.
const COARSEST: usize = 200;
/// A level that coarsens worse than this (n_c / n) is the last.
const MAX_COARSENING_RATIO: Real = 0.6;
/// Dense factorisation only up to this size; beyond it the last level is smoothed.
const DENSE_MAX: usize = 2000;
const MAX_LEVELS: usize = 20;
/// Strength of connection: |a_ij| >= θ sqrt(a_ii a_jj). On the particle Laplacian at
/// r_e 2.1-2.5 l0 a lattice row gives its shells 0.15-0.17 (distance l0), 0.053-0.060
/// (√2 l0) and 0.019-0.021 (2 l0) of the diagonal; θ between the last two makes the
/// nearest eight strong, so an aggregate is a 3 × 3 block. With the nearest four only
/// (θ 0.08), coarsening by 6 instead of 9 made the coarse operators denser (operator
/// complexity 1.42 against 1.16): the 30° wedge at 5 mm took 2 more iterations a solve
/// with 0.035 but its solve time fell by a fifth (setup halved, each iteration 25 %
/// cheaper).
const STRENGTH: Real = 0.035;

/// Row operation `f(i, &mut y[i])` over all rows, in parallel when the level is large.
fn for_rows<F>(y: &mut [Real], f: F)
where
    F: Fn(usize, &mut Real) + Sync + Send,
{
    if y.len() < PARALLEL_ROWS {
        y.iter_mut().enumerate().for_each(|(i, v)| f(i, v));
    } else {
        y.par_iter_mut()
            .with_min_len(1024)
            .enumerate()
            .for_each(|(i, v)| f(i, v));
    }
}

/// `task(k, buffers)` for k in 0..count, in parallel when asked, each task with buffers
/// from `init` (one set per rayon split); the results in the order of k.
fn tasks_in_order<W, T: Send>(
    count: usize,
    parallel: bool,
    init: impl Fn() -> W + Sync + Send,
    task: impl Fn(usize, &mut W) -> T + Sync + Send,
) -> Vec<T> {
    if parallel {
        (0..count)
            .into_par_iter()
            .map_init(init, |w, k| task(k, w))
            .collect()
    } else {
        let mut w = init();
        (0..count).map(|k| task(k, &mut w)).collect()
    }
}

/// Rows of a chunked build.
const CHUNK: usize = 1024;

/// Assemble a CSR matrix from rows computed by `row(i, acc)`, in parallel chunks of
/// rows (each row by one task, in a fixed order: deterministic).
fn build_rows<F>(n: usize, width: usize, row: F) -> CsrMatrix
where
    F: Fn(usize, &mut Accumulator) + Sync + Send,
{
    let chunks = tasks_in_order(
        n.div_ceil(CHUNK),
        n >= PARALLEL_ROWS,
        || Accumulator::new(width),
        |c, acc| acc.chunk(c * CHUNK..((c + 1) * CHUNK).min(n), &row),
    );
    let mut m = CsrMatrix::default();
    m.fill_from_chunks(&chunks);
    m
}

/// A matrix read row by row: a CSR matrix, or the rows of A P that a block of [`galerkin`]
/// keeps.
trait Rows: Sync {
    fn row(&self, j: usize) -> (&[u32], &[Real]);
}

impl Rows for CsrMatrix {
    #[inline(always)]
    fn row(&self, j: usize) -> (&[u32], &[Real]) {
        let (lo, hi) = (self.row_ptr[j], self.row_ptr[j + 1]);
        (&self.col[lo..hi], &self.val[lo..hi])
    }
}

/// Gustavson accumulator: the rows of a chunk are written straight into `cols`/`vals`;
/// `position[c]` remembers where column c went, as a running index over everything this
/// accumulator wrote (`offset` is the running index of `cols[0]`), valid when it is >=
/// `start` (the first entry of the current row): nothing is reset between rows.
struct Accumulator {
    position: Vec<usize>,
    offset: usize,
    start: usize,
    cols: Vec<u32>,
    vals: Vec<Real>,
}

impl Accumulator {
    fn new(width: usize) -> Self {
        Self {
            position: vec![usize::MAX; width],
            offset: 0,
            start: 0,
            cols: Vec::new(),
            vals: Vec::new(),
        }
    }

    /// The rows `rows`, each by `row(i, self)`, in place of what the accumulator held;
    /// returns their lengths.
    fn rows(
        &mut self,
        rows: impl ExactSizeIterator<Item = usize>,
        row: impl Fn(usize, &mut Self),
    ) -> Vec<u32> {
        self.offset += self.cols.len();
        self.cols.clear();
        self.vals.clear();
        let mut lens = Vec::with_capacity(rows.len());
        for i in rows {
            let before = self.cols.len();
            self.start = self.offset + before;
            row(i, self);
            lens.push((self.cols.len() - before) as u32);
        }
        lens
    }

    /// [`Self::rows`] as a chunk of a matrix (the entries copied out).
    fn chunk(
        &mut self,
        rows: impl ExactSizeIterator<Item = usize>,
        row: impl Fn(usize, &mut Self),
    ) -> RowChunk {
        let lens = self.rows(rows, row);
        RowChunk {
            lens,
            cols: self.cols.clone(),
            vals: self.vals.clone(),
        }
    }

    #[inline(always)]
    fn add(&mut self, c: u32, v: Real) {
        let p = self.position[c as usize];
        if p != usize::MAX && p >= self.start {
            self.vals[p - self.offset] += v;
        } else {
            self.position[c as usize] = self.offset + self.cols.len();
            self.cols.push(c);
            self.vals.push(v);
        }
    }
}

/// Row i of X Y (X: rows × k, Y: k × width), summed in X's column order.
#[inline(always)]
fn product_row(x: &CsrMatrix, y: &impl Rows, i: usize, acc: &mut Accumulator) {
    for k in x.row_ptr[i]..x.row_ptr[i + 1] {
        let (j, xv) = (x.col[k] as usize, x.val[k]);
        let (cols, vals) = y.row(j);
        for (&c, &v) in cols.iter().zip(vals) {
            acc.add(c, xv * v);
        }
    }
}

/// Transpose of an n × width matrix (sequential counting sort: deterministic).
fn transpose(m: &CsrMatrix, width: usize) -> CsrMatrix {
    let mut count = vec![0usize; width + 1];
    for &c in &m.col {
        count[c as usize + 1] += 1;
    }
    for c in 0..width {
        count[c + 1] += count[c];
    }
    let row_ptr = count.clone();
    let mut next = count;
    let mut col = vec![0u32; m.nnz()];
    let mut val = vec![0.0; m.nnz()];
    for i in 0..m.n {
        for k in m.row_ptr[i]..m.row_ptr[i + 1] {
            let c = m.col[k] as usize;
            col[next[c]] = i as u32;
            val[next[c]] = m.val[k];
            next[c] += 1;
        }
    }
    CsrMatrix {
        n: width,
        row_ptr,
        col,
        val,
    }
}

const NONE: u32 = u32::MAX;

/// Greedy aggregation of the strong-connection graph (Vaněk et al., phases 1-3).
/// Returns the aggregate of each unknown and the number of aggregates.
fn aggregate(a: &CsrMatrix, diag: &[Real]) -> (Vec<u32>, usize) {
    let n = a.n;
    let root: Vec<Real> = diag.iter().map(|d| d.abs().sqrt()).collect();
    let is_strong = |k: usize, i: usize| -> bool {
        let j = a.col[k] as usize;
        j != i && a.val[k].abs() >= STRENGTH * root[i] * root[j]
    };
    let mut flags = vec![false; a.nnz()];
    if n < PARALLEL_ROWS {
        for i in 0..n {
            for k in a.row_ptr[i]..a.row_ptr[i + 1] {
                flags[k] = is_strong(k, i);
            }
        }
    } else {
        // rows split the flags into disjoint ranges
        let mut rest: &mut [bool] = &mut flags;
        let mut pieces = Vec::new();
        for c in 0..n.div_ceil(4096) {
            let (lo, hi) = (c * 4096, ((c + 1) * 4096).min(n));
            let (head, tail) = rest.split_at_mut(a.row_ptr[hi] - a.row_ptr[lo]);
            pieces.push((lo, hi, head));
            rest = tail;
        }
        pieces.into_par_iter().for_each(|(lo, hi, out)| {
            let base = a.row_ptr[lo];
            for i in lo..hi {
                for k in a.row_ptr[i]..a.row_ptr[i + 1] {
                    out[k - base] = is_strong(k, i);
                }
            }
        });
    }
    let strong = |_i: usize, k: usize| -> bool { flags[k] };
    let mut agg = vec![NONE; n];
    let mut count = 0u32;
    // phase 1: a root whose strong neighbours are all free takes them all
    for i in 0..n {
        if agg[i] != NONE {
            continue;
        }
        let range = a.row_ptr[i]..a.row_ptr[i + 1];
        let mut has_strong = false;
        let mut free = true;
        for k in range.clone() {
            if strong(i, k) {
                has_strong = true;
                if agg[a.col[k] as usize] != NONE {
                    free = false;
                    break;
                }
            }
        }
        if !has_strong || !free {
            continue;
        }
        agg[i] = count;
        for k in range {
            if strong(i, k) {
                agg[a.col[k] as usize] = count;
            }
        }
        count += 1;
    }
    // phase 2: the rest join the phase-1 aggregate they are most strongly connected to
    let phase1 = agg.clone();
    for i in 0..n {
        if agg[i] != NONE {
            continue;
        }
        let mut best = (0.0, NONE);
        for k in a.row_ptr[i]..a.row_ptr[i + 1] {
            let j = a.col[k] as usize;
            if strong(i, k) && phase1[j] != NONE && a.val[k].abs() > best.0 {
                best = (a.val[k].abs(), phase1[j]);
            }
        }
        agg[i] = best.1;
    }
    // phase 3: what is left forms aggregates with its free strong neighbours
    for i in 0..n {
        if agg[i] != NONE {
            continue;
        }
        agg[i] = count;
        for k in a.row_ptr[i]..a.row_ptr[i + 1] {
            let j = a.col[k] as usize;
            if strong(i, k) && agg[j] == NONE {
                agg[j] = count;
            }
        }
        count += 1;
    }
    (agg, count as usize)
}

#[derive(serde::Serialize, serde::Deserialize)]
struct Level {
    /// The operator; empty on the finest level, whose operator is the caller's matrix
    /// (not copied, and a different matrix each solve when the hierarchy is reused).
    a: CsrMatrix,
    /// Damped Jacobi smoother: ω / a_ii.
    smoother: Vec<Real>,
    /// Its ω, from the matrix the level was built from.
    omega: Real,
    /// Prolongation (n × n_c) and restriction Pᵀ.
    p: CsrMatrix,
    r: CsrMatrix,
}

/// Work vectors of one level: residual, coarse right-hand side and coarse correction.
#[derive(serde::Serialize, serde::Deserialize)]
struct Work {
    res: Vec<Real>,
    bc: Vec<Real>,
    xc: Vec<Real>,
}

/// Solve on the last level.
#[derive(serde::Serialize, serde::Deserialize)]
enum Coarsest {
    /// Dense Cholesky factor of the last operator.
    Dense {
        factor: nalgebra::Cholesky<Real, nalgebra::Dyn>,
        rhs: DVector<Real>,
    },
    /// Too large to factor (coarsening stalled): a few symmetric Jacobi sweeps.
    Smooth {
        a: CsrMatrix,
        smoother: Vec<Real>,
        tmp: Vec<Real>,
    },
}

const COARSE_SWEEPS: usize = 4;

impl Coarsest {
    fn new(a: CsrMatrix) -> Self {
        let n = a.n;
        if n <= DENSE_MAX {
            let mut dense = DMatrix::<Real>::zeros(n, n);
            for i in 0..n {
                for k in a.row_ptr[i]..a.row_ptr[i + 1] {
                    dense[(i, a.col[k] as usize)] += a.val[k];
                }
            }
            // a singular last level (a pure-Neumann cluster) gets a growing diagonal shift
            let mut shift = 0.0;
            for _ in 0..8 {
                let mut m = dense.clone();
                if shift > 0.0 {
                    for i in 0..n {
                        m[(i, i)] *= 1.0 + shift;
                    }
                }
                if let Some(factor) = m.cholesky() {
                    return Coarsest::Dense {
                        factor,
                        rhs: DVector::zeros(n),
                    };
                }
                shift = if shift == 0.0 { 1e-10 } else { shift * 100.0 };
            }
        }
        let smoother = jacobi_weights(&a);
        Coarsest::Smooth {
            tmp: vec![0.0; n],
            a,
            smoother,
        }
    }

    fn solve(&mut self, b: &[Real], x: &mut [Real]) {
        match self {
            Coarsest::Dense { factor, rhs } => {
                rhs.as_mut_slice().copy_from_slice(b);
                factor.solve_mut(rhs);
                x.copy_from_slice(rhs.as_slice());
            }
            Coarsest::Smooth { a, smoother, tmp } => {
                for_rows(x, |i, xi| *xi = smoother[i] * b[i]);
                for _ in 1..COARSE_SWEEPS {
                    for_rows(tmp, |i, ti| {
                        *ti = x[i] + smoother[i] * (b[i] - a.row_dot(i, x))
                    });
                    x.copy_from_slice(tmp);
                }
            }
        }
    }
}

fn diagonal(a: &CsrMatrix) -> Vec<Real> {
    let mut d = vec![0.0; a.n];
    // each entry from its own row, in column order: deterministic in parallel
    for_rows(&mut d, |i, di| *di = row_diagonal(a, i));
    d
}

/// a_ii: the entries of row i in column i, summed in column order.
#[inline]
fn row_diagonal(a: &CsrMatrix, i: usize) -> Real {
    (a.row_ptr[i]..a.row_ptr[i + 1])
        .filter(|&k| a.col[k] as usize == i)
        .map(|k| a.val[k])
        .sum::<Real>()
}

/// Row i's Gershgorin radius of D⁻¹A, Σ_k |a_ik| / a_ii (1 where a_ii is not positive).
#[inline]
fn row_radius(a: &CsrMatrix, i: usize, diag: Real) -> Real {
    let s: Real = (a.row_ptr[i]..a.row_ptr[i + 1])
        .map(|k| a.val[k].abs())
        .sum();
    if diag > 0.0 {
        s / diag
    } else {
        1.0
    }
}

/// [`diagonal`] and the Gershgorin bound of the spectral radius of D⁻¹A (2 for the fine
/// Laplacian) in one pass over the matrix; the bound's maximum does not depend on the
/// order of the reduction, so it is deterministic in parallel.
fn diagonal_and_radius(a: &CsrMatrix) -> (Vec<Real>, Real) {
    let mut diag = vec![0.0; a.n];
    let row = |i: usize, d: &mut Real| {
        *d = row_diagonal(a, i);
        row_radius(a, i, *d)
    };
    let radius = if a.n < PARALLEL_ROWS {
        diag.iter_mut()
            .enumerate()
            .map(|(i, d)| row(i, d))
            .fold(1.0, Real::max)
    } else {
        diag.par_iter_mut()
            .with_min_len(1024)
            .enumerate()
            .map(|(i, d)| row(i, d))
            .reduce(|| 1.0, Real::max)
    };
    (diag, radius)
}

/// ω/a_ii with ω = 4/(3ρ): damped Jacobi, convergent for SPD A (ω ρ < 2).
fn jacobi_weights(a: &CsrMatrix) -> Vec<Real> {
    let (diag, radius) = diagonal_and_radius(a);
    weights(&diag, 4.0 / (3.0 * radius))
}

/// ω / a_ii of every row (0 where the diagonal is not positive).
fn weights(diag: &[Real], omega: Real) -> Vec<Real> {
    let weight = |&d: &Real| if d > 0.0 { omega / d } else { 0.0 };
    if diag.len() < PARALLEL_ROWS {
        diag.iter().map(weight).collect()
    } else {
        diag.par_iter().with_min_len(1024).map(weight).collect()
    }
}

/// The smoother of a refitted level: the ω of its build, lowered if need be to 1.9/G of
/// the new matrix so that the smoother stays convergent.
fn refitted_weights(a: &CsrMatrix, omega: Real) -> Vec<Real> {
    let (diag, radius) = diagonal_and_radius(a);
    weights(&diag, omega.min(1.9 / radius))
}

/// Power iterations of [`largest_eigenvalue`].
const POWER_ITERATIONS: usize = 12;

/// The largest eigenvalue of D⁻¹A, estimated from below by power iteration: the largest
/// Rayleigh quotient v·Av / v·Dv (D⁻¹A is similar to the symmetric D^-½AD^-½) from a
/// fixed pseudo-random start, so deterministic. The Gershgorin bound overestimates it,
/// which made the smoother's weight smaller than it need be.
fn largest_eigenvalue(a: &CsrMatrix, diag: &[Real]) -> Real {
    let n = a.n;
    // at least the Rayleigh quotient of a unit vector e_i, a_ii / a_ii = 1
    let mut lambda: Real = 1.0;
    let mut v: Vec<Real> = (0..n as u64)
        .map(|i| {
            let h = (i + 1).wrapping_mul(0x9E37_79B9_7F4A_7C15) >> 11;
            h as Real / (1u64 << 53) as Real - 0.5
        })
        .collect();
    let mut av = vec![0.0; n];
    for _ in 0..POWER_ITERATIONS {
        {
            let v: &[Real] = &v;
            for_rows(&mut av, |i, y| *y = a.row_dot(i, v));
        }
        let vav = deterministic_sum(n, |i| v[i] * av[i]);
        let vdv = deterministic_sum(n, |i| diag[i] * v[i] * v[i]);
        if !(vdv > 0.0) {
            break;
        }
        lambda = lambda.max(vav / vdv);
        // v = D⁻¹A v, rescaled to about unit D-norm (only its direction matters)
        let scale = 1.0 / (vdv.sqrt() * lambda);
        for_rows(&mut v, |i, vi| {
            *vi = if diag[i] > 0.0 {
                av[i] / diag[i] * scale
            } else {
                0.0
            }
        });
    }
    lambda
}

/// Damped Jacobi smoothing weight from the largest eigenvalue λ of D⁻¹A: 1.6/λ (4/5 on the
/// 5-point Laplacian, whose λ is 2: the weight that damps its high frequencies best),
/// never above 1.9/G, G the Gershgorin bound (≥ λ), so that ωλ < 2 and the cycle stays
/// symmetric positive definite however low the estimate. On the 30° wedge's matrices at
/// 5 mm a fresh hierarchy then takes 11-12 iterations where 4/(3G) took 15-17, the still
/// tank of the scaling study 5.2 a step instead of 6.8.
fn smoothing_weight(lambda: Real, gershgorin: Real) -> Real {
    (1.6 / lambda).min(1.9 / gershgorin)
}

/// The multigrid hierarchy below a fine matrix that it does not hold: transfers,
/// coarse operators, smoothers and work vectors. Owned, so that it can outlive the
/// matrix it was built from and precondition the next one ([`super::SolverCache`]).
#[derive(serde::Serialize, serde::Deserialize)]
pub(crate) struct Hierarchy {
    levels: Vec<Level>,
    work: Vec<Work>,
    coarsest: Coarsest,
}

/// Smoothed prolongator of one level: row i of (I - ω D⁻¹A) P₀, P₀ the aggregates.
fn smoothed_prolongator(
    a: &CsrMatrix,
    diag: &[Real],
    omega: Real,
    agg: &[u32],
    nc: usize,
) -> CsrMatrix {
    build_rows(a.n, nc, |i, acc| {
        let w = if diag[i] > 0.0 { omega / diag[i] } else { 0.0 };
        acc.add(agg[i], 1.0);
        for k in a.row_ptr[i]..a.row_ptr[i + 1] {
            acc.add(agg[a.col[k] as usize], -w * a.val[k]);
        }
    })
}

/// Coarse rows computed together by [`galerkin`].
const GALERKIN_BLOCK: usize = 1024;

/// Galerkin coarse operator R A P, by blocks of coarse rows: a block first computes the
/// rows of A P that its rows of R read, then its rows of R (A P). A P is never whole: it
/// was, with the chunks that computed it, the memory peak of a step (47 of 170 MB at
/// 160k particles). A row of A P read by two blocks is computed twice, the same way, so
/// the coarse operator is the one of the whole product, bit for bit.
fn galerkin(a: &CsrMatrix, p: &CsrMatrix, r: &CsrMatrix) -> CsrMatrix {
    let (n, nc) = (a.n, r.n);
    let block = |b: usize, work: &mut GalerkinWork| -> RowChunk {
        let coarse = b * GALERKIN_BLOCK..((b + 1) * GALERKIN_BLOCK).min(nc);
        let read = &r.col[r.row_ptr[coarse.start]..r.row_ptr[coarse.end]];
        work.fine.clear();
        work.fine.extend_from_slice(read);
        work.fine.sort_unstable();
        work.fine.dedup();
        for (k, &j) in work.fine.iter().enumerate() {
            work.local[j as usize] = k as u32;
        }
        let fine = std::mem::take(&mut work.fine);
        let lens = work.ap.rows(fine.iter().map(|&j| j as usize), |j, acc| {
            product_row(a, p, j, acc)
        });
        work.starts.clear();
        work.starts.push(0);
        for &l in &lens {
            work.starts.push(work.starts.last().unwrap() + l);
        }
        let ap = LocalRows {
            local: &work.local,
            starts: &work.starts,
            cols: &work.ap.cols,
            vals: &work.ap.vals,
        };
        let rows = work.rac.chunk(coarse, |i, acc| product_row(r, &ap, i, acc));
        for &j in &fine {
            work.local[j as usize] = u32::MAX;
        }
        work.fine = fine;
        rows
    };
    let parts = tasks_in_order(
        nc.div_ceil(GALERKIN_BLOCK),
        n >= PARALLEL_ROWS,
        || GalerkinWork::new(n, nc),
        block,
    );
    let mut m = CsrMatrix::default();
    m.fill_from_chunks(&parts);
    m
}

/// One task's buffers for [`galerkin`].
struct GalerkinWork {
    /// The fine rows a block of R reads, sorted.
    fine: Vec<u32>,
    /// Where fine row j sits among them (u32::MAX when it is not one).
    local: Vec<u32>,
    starts: Vec<u32>,
    /// The block's rows of A P, then of R A P.
    ap: Accumulator,
    rac: Accumulator,
}

impl GalerkinWork {
    fn new(n: usize, nc: usize) -> Self {
        Self {
            fine: Vec::new(),
            local: vec![u32::MAX; n],
            starts: Vec::new(),
            ap: Accumulator::new(nc),
            rac: Accumulator::new(nc),
        }
    }
}

/// Some rows of A P, kept by [`galerkin`] for one block.
struct LocalRows<'a> {
    local: &'a [u32],
    starts: &'a [u32],
    cols: &'a [u32],
    vals: &'a [Real],
}

impl Rows for LocalRows<'_> {
    #[inline(always)]
    fn row(&self, j: usize) -> (&[u32], &[Real]) {
        let k = self.local[j] as usize;
        let (lo, hi) = (self.starts[k] as usize, self.starts[k + 1] as usize);
        (&self.cols[lo..hi], &self.vals[lo..hi])
    }
}

impl Hierarchy {
    /// Build the hierarchy of a symmetric positive definite matrix.
    pub(crate) fn new(a: &CsrMatrix) -> Self {
        let mut levels = Vec::new();
        let mut current = Cow::Borrowed(a);
        while current.n > COARSEST && levels.len() < MAX_LEVELS {
            let (diag, radius) = diagonal_and_radius(&current);
            let (agg, nc) = aggregate(&current, &diag);
            if nc == 0 || nc as Real > MAX_COARSENING_RATIO * current.n as Real {
                break;
            }
            let lambda = largest_eigenvalue(&current, &diag);
            let omega = smoothing_weight(lambda, radius);
            // the prolongator's smoothing step as in Vaněk et al.: 4/(3λ)
            let p = smoothed_prolongator(&current, &diag, 4.0 / (3.0 * lambda), &agg, nc);
            let r = transpose(&p, nc);
            let coarse = galerkin(&current, &p, &r);
            let smoother = weights(&diag, omega);
            let a_level = match std::mem::replace(&mut current, Cow::Owned(coarse)) {
                // the finest operator stays the caller's
                Cow::Borrowed(_) => CsrMatrix::default(),
                Cow::Owned(m) => m,
            };
            levels.push(Level {
                a: a_level,
                smoother,
                omega,
                p,
                r,
            });
        }
        let work = levels
            .iter()
            .enumerate()
            .map(|(l, level)| Work {
                res: vec![0.0; if l == 0 { a.n } else { level.a.n }],
                bc: vec![0.0; level.r.n],
                xc: vec![0.0; level.r.n],
            })
            .collect();
        let coarsest = Coarsest::new(current.into_owned());
        Self {
            levels,
            work,
            coarsest,
        }
    }

    /// Levels above the last (0 when the fine matrix itself is solved on the last level,
    /// and the hierarchy cannot serve another matrix).
    pub(crate) fn coarsened_levels(&self) -> usize {
        self.levels.len()
    }

    /// Fit the finest level to a new set of fine unknowns: new row `i` was old row
    /// `old_row[i]` (or is new: `u32::MAX`), and `new_row[k]` is the new row of old row
    /// `k` (or `u32::MAX`: gone). P keeps the rows of the unknowns that stay, a new
    /// unknown gets an empty row (only the smoother acts on it), R = Pᵀ follows. The
    /// entries keep their order, so the result is deterministic.
    pub(crate) fn remap_fine_rows(&mut self, old_row: &[u32], new_row: &[u32]) {
        let Some(level) = self.levels.first_mut() else {
            return;
        };
        let p = &level.p;
        let mut row_ptr = Vec::with_capacity(old_row.len() + 1);
        row_ptr.push(0);
        let mut len = 0;
        for &o in old_row {
            if o != NONE {
                len += p.row_ptr[o as usize + 1] - p.row_ptr[o as usize];
            }
            row_ptr.push(len);
        }
        let mut col = Vec::with_capacity(len);
        let mut val = Vec::with_capacity(len);
        for &o in old_row {
            if o != NONE {
                let range = p.row_ptr[o as usize]..p.row_ptr[o as usize + 1];
                col.extend_from_slice(&p.col[range.clone()]);
                val.extend_from_slice(&p.val[range]);
            }
        }
        level.p = CsrMatrix {
            n: old_row.len(),
            row_ptr,
            col,
            val,
        };
        let r = &mut level.r;
        let mut kept = 0;
        let mut start = 0;
        for c in 0..r.n {
            let end = r.row_ptr[c + 1];
            for k in start..end {
                let to = new_row[r.col[k] as usize];
                if to != NONE {
                    r.col[kept] = to;
                    r.val[kept] = r.val[k];
                    kept += 1;
                }
            }
            start = end;
            r.row_ptr[c + 1] = kept;
        }
        r.col.truncate(kept);
        r.val.truncate(kept);
        self.work[0].res.resize(old_row.len(), 0.0);
    }

    /// The damped Jacobi smoother of the finest level from a new fine matrix (the
    /// coarse levels are kept as they are).
    pub(crate) fn refresh_fine_smoother(&mut self, a: &CsrMatrix) {
        if let Some(level) = self.levels.first_mut() {
            level.smoother = refitted_weights(a, level.omega);
        }
    }

    /// Recompute the coarse operators (Galerkin products with the kept transfers) and
    /// the smoothers from a new fine matrix. False when a coarse operator lost a
    /// positive diagonal (an aggregate whose unknowns all left): rebuild instead.
    pub(crate) fn refresh_operators(&mut self, a: &CsrMatrix) -> bool {
        let mut current = Cow::Borrowed(a);
        for level in &mut self.levels {
            let coarse = galerkin(&current, &level.p, &level.r);
            if diagonal(&coarse).iter().any(|&d| !(d > 0.0)) {
                return false;
            }
            level.smoother = refitted_weights(&current, level.omega);
            if let Cow::Owned(m) = std::mem::replace(&mut current, Cow::Owned(coarse)) {
                level.a = m;
            }
        }
        self.coarsest = Coarsest::new(current.into_owned());
        true
    }

    /// z = M⁻¹ r for the fine matrix `a`: one V(1,1) cycle from zero.
    pub(crate) fn apply(&mut self, a: &CsrMatrix, r: &[Real], z: &mut [Real]) {
        cycle(
            &self.levels,
            &mut self.work,
            &mut self.coarsest,
            Some(a),
            r,
            z,
        );
    }

    /// [`apply`](Self::apply), returning r·z (bit for bit the sum CG's `dot` gives)
    /// from the post-smoothing pass that writes z, so CG's r·z needs no pass of its own.
    pub(crate) fn apply_dot(&mut self, a: &CsrMatrix, r: &[Real], z: &mut [Real]) -> Real {
        // the fixed-chunk sum gives the same bits on one thread or two
        let parallel = z.len() >= PARALLEL_ROWS;
        let Some((level, _)) = self.levels.split_first() else {
            self.coarsest.solve(r, z);
            return deterministic_sum_mut(z, parallel, |i, zi| r[i] * *zi);
        };
        descend(&self.levels, &mut self.work, &mut self.coarsest, Some(a), r);
        let y = &self.work[0].res;
        let s = &level.smoother;
        deterministic_sum_mut(z, parallel, |i, zi| {
            *zi = post_smoothed(a, s, r, y, i);
            r[i] * *zi
        })
    }

    /// Unknowns per level below the finest, then the last.
    fn coarse_sizes(&self) -> Vec<usize> {
        let mut s: Vec<usize> = self.levels.iter().skip(1).map(|l| l.a.n).collect();
        s.push(match &self.coarsest {
            Coarsest::Dense { rhs, .. } => rhs.len(),
            Coarsest::Smooth { a, .. } => a.n,
        });
        s
    }

    /// Σ nnz over the levels below the finest.
    fn coarse_nnz(&self) -> usize {
        let mut total: usize = self.levels.iter().skip(1).map(|l| l.a.nnz()).sum();
        total += match &self.coarsest {
            Coarsest::Dense { rhs, .. } => rhs.len() * rhs.len(),
            Coarsest::Smooth { a, .. } => a.nnz(),
        };
        total
    }
}

/// The multigrid hierarchy of one matrix, applied as z = M⁻¹ r.
pub struct Amg<'a> {
    a: &'a CsrMatrix,
    hierarchy: Hierarchy,
}

impl<'a> Amg<'a> {
    /// Build the hierarchy of a symmetric positive definite matrix.
    pub fn new(a: &'a CsrMatrix) -> Self {
        Self {
            a,
            hierarchy: Hierarchy::new(a),
        }
    }

    /// Number of levels including the last (directly solved) one.
    pub fn depth(&self) -> usize {
        self.hierarchy.levels.len() + 1
    }

    /// Unknowns per level, finest first.
    pub fn sizes(&self) -> Vec<usize> {
        let mut s = Vec::new();
        if !self.hierarchy.levels.is_empty() {
            s.push(self.a.n);
        }
        s.extend(self.hierarchy.coarse_sizes());
        s
    }

    /// Σ nnz over the levels / nnz of the finest.
    pub fn operator_complexity(&self) -> Real {
        if self.hierarchy.levels.is_empty() {
            return self.hierarchy.coarse_nnz() as Real / self.a.nnz().max(1) as Real;
        }
        let fine = self.a.nnz().max(1);
        (fine + self.hierarchy.coarse_nnz()) as Real / fine as Real
    }

    /// z = M⁻¹ r: one V(1,1) cycle from zero.
    pub fn apply(&mut self, r: &[Real], z: &mut [Real]) {
        self.hierarchy.apply(self.a, r, z);
    }
}

/// One V(1,1) cycle from zero on `levels[0]`, whose operator is `fine` on the finest
/// level: x = M⁻¹ b.
fn cycle(
    levels: &[Level],
    work: &mut [Work],
    coarsest: &mut Coarsest,
    fine: Option<&CsrMatrix>,
    b: &[Real],
    x: &mut [Real],
) {
    let Some((level, _)) = levels.split_first() else {
        coarsest.solve(b, x);
        return;
    };
    descend(levels, work, coarsest, fine, b);
    let (a, s, y) = (fine.unwrap_or(&level.a), &level.smoother, &work[0].res);
    for_rows(x, |i, xi| *xi = post_smoothed(a, s, b, y, i));
}

/// The V-cycle of [`cycle`] up to its post-smoothing: the iterate after the coarse
/// correction, left in `work[0].res`. Each pass does what it can of the next: the
/// residual forms the pre-smoothed iterate s b as it reads it, and the prolongation
/// adds the correction to s b in the residual's buffer (free once restricted), so
/// that the level takes four passes where it took six (pre-smoothing, residual,
/// restriction, prolongation, post-smoothing and a copy). The arithmetic is the same,
/// in the same order. `levels` is not empty.
fn descend(
    levels: &[Level],
    work: &mut [Work],
    coarsest: &mut Coarsest,
    fine: Option<&CsrMatrix>,
    b: &[Real],
) {
    let (level, rest) = levels.split_first().expect("a level to smooth");
    let (w, rest_work) = work.split_first_mut().expect("one work entry per level");
    let Work { res, bc, xc } = w;
    let (a, s) = (fine.unwrap_or(&level.a), &level.smoother);
    // residual of the pre-smoothed iterate s b (damped Jacobi from zero), restriction
    for_rows(res, |i, ri| *ri = b[i] - a.row_dot_scaled(i, s, b));
    {
        let res: &[Real] = res;
        for_rows(bc, |c, v| *v = level.r.row_dot(c, res));
    }
    cycle(rest, rest_work, coarsest, None, bc, xc);
    // prolongation of the coarse correction onto s b
    let xc: &[Real] = xc;
    for_rows(res, |i, yi| *yi = s[i] * b[i] + level.p.row_dot(i, xc));
}

/// Row i of the post-smoothing y + s (b - A y).
#[inline(always)]
fn post_smoothed(a: &CsrMatrix, s: &[Real], b: &[Real], y: &[Real], i: usize) -> Real {
    y[i] + s[i] * (b[i] - a.row_dot(i, y))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::engine::pressure::{conjugate_gradient, Preconditioner, SolveParams};

    /// 5-point Laplacian on an m × m grid with Dirichlet boundary.
    fn poisson5(m: usize) -> CsrMatrix {
        let n = m * m;
        let mut a = CsrMatrix {
            n,
            row_ptr: vec![0],
            col: Vec::new(),
            val: Vec::new(),
        };
        for i in 0..m {
            for j in 0..m {
                let idx = |i: usize, j: usize| (i * m + j) as u32;
                if i > 0 {
                    a.col.push(idx(i - 1, j));
                    a.val.push(-1.0);
                }
                if j > 0 {
                    a.col.push(idx(i, j - 1));
                    a.val.push(-1.0);
                }
                a.col.push(idx(i, j));
                a.val.push(4.0);
                if j + 1 < m {
                    a.col.push(idx(i, j + 1));
                    a.val.push(-1.0);
                }
                if i + 1 < m {
                    a.col.push(idx(i + 1, j));
                    a.val.push(-1.0);
                }
                a.row_ptr.push(a.col.len());
            }
        }
        a
    }

    fn solve_amg(a: &CsrMatrix, b: &[Real]) -> (usize, Vec<Real>) {
        let mut x = vec![0.0; a.n];
        let info = conjugate_gradient(
            a,
            b,
            &mut x,
            SolveParams::relative(1e-8, 500),
            Preconditioner::Amg,
        )
        .unwrap();
        (info.iterations, x)
    }

    fn residual(a: &CsrMatrix, b: &[Real], x: &[Real]) -> Real {
        let mut ax = vec![0.0; a.n];
        a.mul(x, &mut ax);
        let num: Real = ax.iter().zip(b).map(|(p, q)| (p - q).powi(2)).sum();
        let den: Real = b.iter().map(|q| q * q).sum();
        (num / den).sqrt()
    }

    /// The MPS Laplacian (-Σ w_ij (p_j - p_i), w = r_e/r - 1, r_e = 2.1 l0) of a jittered
    /// m × m particle lattice (unit spacing); the particles of the top row are the free
    /// surface (Dirichlet, eliminated), the others have walls (Neumann: no terms).
    pub(super) fn particle_laplacian(m: usize, seed: u64) -> CsrMatrix {
        let mut state = seed.wrapping_mul(6364136223846793005).wrapping_add(1);
        let mut rnd = || {
            state = state
                .wrapping_mul(6364136223846793005)
                .wrapping_add(1442695040888963407);
            ((state >> 11) as Real / (1u64 << 53) as Real) - 0.5
        };
        let pos: Vec<(Real, Real)> = (0..m * m)
            .map(|k| {
                let (i, j) = (k / m, k % m);
                (j as Real + 0.3 * rnd(), i as Real + 0.3 * rnd())
            })
            .collect();
        let re = 2.1;
        let reach = 3isize;
        let mut a = CsrMatrix {
            n: (m - 1) * m,
            row_ptr: vec![0],
            col: Vec::new(),
            val: Vec::new(),
        };
        // unknowns are the rows i < m - 1 (row-major), the top row is the surface
        for k in 0..(m - 1) * m {
            let (i, j) = ((k / m) as isize, (k % m) as isize);
            let mut diag = 0.0;
            let mut entries = Vec::new();
            for di in -reach..=reach {
                for dj in -reach..=reach {
                    let (ii, jj) = (i + di, j + dj);
                    if (di, dj) == (0, 0)
                        || ii < 0
                        || jj < 0
                        || ii >= m as isize
                        || jj >= m as isize
                    {
                        continue;
                    }
                    let l = (ii as usize) * m + jj as usize;
                    let (dx, dy) = (pos[l].0 - pos[k].0, pos[l].1 - pos[k].1);
                    let r = (dx * dx + dy * dy).sqrt();
                    if r >= re {
                        continue;
                    }
                    let w = re / r - 1.0;
                    diag += w;
                    if l < (m - 1) * m {
                        entries.push((l as u32, -w));
                    }
                }
            }
            entries.push((k as u32, diag));
            entries.sort_by_key(|e| e.0);
            for (c, v) in entries {
                a.col.push(c);
                a.val.push(v);
            }
            a.row_ptr.push(a.col.len());
        }
        a
    }

    #[test]
    fn particle_laplacian_converges_with_few_iterations_at_any_size() {
        let mut its = Vec::new();
        for m in [40, 100, 200] {
            let a = particle_laplacian(m, 7);
            let b: Vec<Real> = (0..a.n)
                .map(|i| 1.0 + ((i * 31) % 17) as Real * 0.1)
                .collect();
            let (it, x) = solve_amg(&a, &b);
            assert!(residual(&a, &b, &x) < 1e-8);
            its.push(it);
        }
        eprintln!("particle Laplacian, CG-AMG iterations at 1.6k, 10k, 40k: {its:?}");
        assert!(its[2] <= its[0] + 8, "{its:?}");
        assert!(its[2] < 30, "{its:?}");
    }

    /// Process CPU seconds (user + system), robust to other load on the machine.
    fn cpu_seconds() -> Real {
        let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
        let fields: Vec<&str> = stat
            .rsplit(')')
            .next()
            .unwrap_or("")
            .split_whitespace()
            .collect();
        let ticks = |k: usize| {
            fields
                .get(k)
                .and_then(|v| v.parse::<Real>().ok())
                .unwrap_or(0.0)
        };
        (ticks(11) + ticks(12)) / 100.0
    }

    /// CPU time of setup, cycle and product on a 160k-unknown particle Laplacian:
    /// `RAYON_NUM_THREADS=1 cargo test --release --lib amg_timing -- --ignored --nocapture`.
    #[test]
    #[ignore]
    fn amg_timing() {
        let a = particle_laplacian(400, 3);
        let b: Vec<Real> = (0..a.n)
            .map(|i| 1.0 + ((i * 31) % 17) as Real * 0.1)
            .collect();
        let mut z = vec![0.0; a.n];
        let reps = 10;
        let t = cpu_seconds();
        for _ in 0..reps {
            std::hint::black_box(Amg::new(&a));
        }
        let setup = (cpu_seconds() - t) / reps as Real;
        let mut amg = Amg::new(&a);
        let t = cpu_seconds();
        for _ in 0..5 * reps {
            amg.apply(&b, &mut z);
        }
        let cycle = (cpu_seconds() - t) / (5 * reps) as Real;
        let t = cpu_seconds();
        for _ in 0..20 * reps {
            a.mul(&b, &mut z);
        }
        let spmv = (cpu_seconds() - t) / (20 * reps) as Real;
        let (it, _) = solve_amg(&a, &b);
        eprintln!(
            "n {} nnz {} levels {:?} complexity {:.2}: CPU setup {:.1} ms = {:.0} spmv, cycle {:.1} ms = {:.1} spmv, spmv {:.2} ms, iterations {it}",
            a.n,
            a.nnz(),
            amg.sizes(),
            amg.operator_complexity(),
            setup * 1e3,
            setup / spmv,
            cycle * 1e3,
            cycle / spmv,
            spmv * 1e3
        );
    }

    #[test]
    fn degenerate_matrices_diagonal_and_tiny() {
        // no connections at all: coarsening stalls, the only level is smoothed
        let n = 5000;
        let diag = CsrMatrix {
            n,
            row_ptr: (0..=n).collect(),
            col: (0..n as u32).collect(),
            val: (0..n).map(|i| 1.0 + (i % 7) as Real).collect(),
        };
        let b: Vec<Real> = (0..n).map(|i| (i % 5) as Real - 2.0).collect();
        let (it, x) = solve_amg(&diag, &b);
        assert!(residual(&diag, &b, &x) < 1e-8 && it <= 2, "{it}");
        // smaller than the coarsest level: one dense solve, one iteration
        let a = poisson5(8);
        let b = vec![1.0; a.n];
        let (it, x) = solve_amg(&a, &b);
        assert!(residual(&a, &b, &x) < 1e-8 && it <= 1, "{it}");
    }

    #[test]
    fn poisson_5_point_iterations_do_not_grow_with_n() {
        let mut its = Vec::new();
        for m in [32, 128, 400] {
            let a = poisson5(m);
            let b: Vec<Real> = (0..a.n).map(|i| ((i * 7919) % 13) as Real - 6.0).collect();
            let (it, x) = solve_amg(&a, &b);
            assert!(residual(&a, &b, &x) < 1e-8);
            its.push(it);
        }
        eprintln!("5-point Poisson, CG-AMG iterations at 1k, 16k, 160k: {its:?}");
        assert!(its[2] <= 2 * its[0].max(8), "{its:?}");
        assert!(its[2] < 40, "{its:?}");
    }

    /// The energy-norm stop (`SolveParams::energy`) against an exact solution: on the
    /// jittered particle Laplacian, with the right-hand side of a known field (smooth and
    /// rough parts), the iterate returned is within the share of the field asked for in
    /// the A-norm, sooner than the relative residual 1e-8 would stop.
    #[test]
    fn the_energy_stop_bounds_the_error_it_asks_for() {
        let a = particle_laplacian(60, 7);
        let exact: Vec<Real> = (0..a.n)
            .map(|i| (0.013 * i as Real).sin() + 0.1 * (1.7 * i as Real).cos())
            .collect();
        let mut b = vec![0.0; a.n];
        a.mul(&exact, &mut b);
        let a_norm = |v: &[Real]| {
            let mut av = vec![0.0; a.n];
            a.mul(v, &mut av);
            v.iter().zip(&av).map(|(x, y)| x * y).sum::<Real>().sqrt()
        };
        let (relative_iterations, _) = solve_amg(&a, &b);
        for energy in [1e-2, 1e-3, 1e-4] {
            let mut x = vec![0.0; a.n];
            let params = SolveParams {
                energy,
                ..SolveParams::relative(1e-14, 500)
            };
            let info = conjugate_gradient(&a, &b, &mut x, params, Preconditioner::Amg).unwrap();
            let error: Vec<Real> = x.iter().zip(&exact).map(|(x, e)| x - e).collect();
            let share = a_norm(&error) / a_norm(&exact);
            assert!(share <= energy, "asked {energy}, got {share:e}");
            assert!(
                info.iterations < relative_iterations,
                "{energy}: {} iterations against {relative_iterations} to 1e-8",
                info.iterations
            );
        }
    }
}

#[cfg(test)]
mod galerkin_blocks {
    use super::*;

    /// The coarse operator built block by block is the whole product R (A P), bit for
    /// bit, on a level of several blocks (rows of A P computed twice included).
    #[test]
    fn blocked_galerkin_is_the_whole_product() {
        let a = super::tests::particle_laplacian(200, 5);
        let diag = diagonal(&a);
        let (agg, nc) = aggregate(&a, &diag);
        assert!(nc > 2 * GALERKIN_BLOCK, "{nc} coarse rows: too few blocks");
        let lambda = largest_eigenvalue(&a, &diag);
        let p = smoothed_prolongator(&a, &diag, 4.0 / (3.0 * lambda), &agg, nc);
        let r = transpose(&p, nc);
        let ap = build_rows(a.n, nc, |i, acc| product_row(&a, &p, i, acc));
        let whole = build_rows(nc, nc, |i, acc| product_row(&r, &ap, i, acc));
        let blocked = galerkin(&a, &p, &r);
        assert_eq!(blocked.row_ptr, whole.row_ptr);
        assert_eq!(blocked.col, whole.col);
        let bits = |m: &CsrMatrix| m.val.iter().map(|v| v.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(&blocked), bits(&whole));
    }
}
