//! Compressed sparse row matrix with a parallel, deterministic product, and the bridge
//! to faer's sparse types for the direct factorisation.

use crate::math::Real;
use rayon::prelude::*;

use super::{SolveError, SolveInfo};

#[derive(Debug, Clone, Default, serde::Serialize, serde::Deserialize)]
pub struct CsrMatrix {
    pub n: usize,
    pub row_ptr: Vec<usize>,
    pub col: Vec<u32>,
    pub val: Vec<Real>,
}

impl CsrMatrix {
    /// Row i of A times x, summed in column order (deterministic). Zipped slices, so
    /// only the gather x[col] is bounds-checked: the product is the hot loop of the
    /// pressure solve (three per AMG-PCG iteration).
    #[inline(always)]
    pub fn row_dot(&self, i: usize, x: &[Real]) -> Real {
        let (lo, hi) = (self.row_ptr[i], self.row_ptr[i + 1]);
        let mut s = 0.0;
        for (v, &c) in self.val[lo..hi].iter().zip(&self.col[lo..hi]) {
            s += v * x[c as usize];
        }
        s
    }

    /// Row i of A times the vector s ∘ x (entrywise product), formed as it is read: bit
    /// for bit `row_dot` of the product vector, without writing it.
    #[inline(always)]
    pub fn row_dot_scaled(&self, i: usize, s: &[Real], x: &[Real]) -> Real {
        let (lo, hi) = (self.row_ptr[i], self.row_ptr[i + 1]);
        let mut sum = 0.0;
        for (v, &c) in self.val[lo..hi].iter().zip(&self.col[lo..hi]) {
            let c = c as usize;
            sum += v * (s[c] * x[c]);
        }
        sum
    }

    /// y = A x (each row summed in column order: deterministic).
    pub fn mul(&self, x: &[Real], y: &mut [Real]) {
        if self.n < super::pcg::PARALLEL_MIN {
            y.iter_mut()
                .enumerate()
                .for_each(|(i, yi)| *yi = self.row_dot(i, x));
            return;
        }
        y.par_iter_mut()
            .with_min_len(512)
            .enumerate()
            .for_each(|(i, yi)| *yi = self.row_dot(i, x));
    }

    pub fn diagonal(&self) -> Vec<Real> {
        (0..self.n)
            .into_par_iter()
            .map(|i| {
                (self.row_ptr[i]..self.row_ptr[i + 1])
                    .find(|&k| self.col[k] as usize == i)
                    .map_or(0.0, |k| self.val[k])
            })
            .collect()
    }

    pub fn nnz(&self) -> usize {
        self.val.len()
    }

    /// This matrix's rows replaced by those of `chunks`, in order, reusing its buffers
    /// (no allocation at a steady size). The entries are copied in parallel: serially,
    /// the copy took 4.6 of the 31 ms of assembling a 160k-particle matrix.
    pub fn fill_from_chunks(&mut self, chunks: &[RowChunk]) {
        self.n = chunks.iter().map(|c| c.lens.len()).sum();
        self.row_ptr.clear();
        self.row_ptr.reserve(self.n + 1);
        self.row_ptr.push(0);
        let mut last = 0;
        for c in chunks {
            for &l in &c.lens {
                last += l as usize;
                self.row_ptr.push(last);
            }
        }
        let cols: Vec<&[u32]> = chunks.iter().map(|c| &c.cols[..]).collect();
        let vals: Vec<&[Real]> = chunks.iter().map(|c| &c.vals[..]).collect();
        concat_into(&mut self.col, &cols);
        concat_into(&mut self.val, &vals);
    }

    /// The same matrix as a faer sparse column matrix (for factorisations).
    pub fn to_faer(&self) -> Result<faer::sparse::SparseColMat<usize, Real>, String> {
        let mut triplets = Vec::with_capacity(self.nnz());
        for i in 0..self.n {
            for k in self.row_ptr[i]..self.row_ptr[i + 1] {
                triplets.push(faer::sparse::Triplet::new(
                    i,
                    self.col[k] as usize,
                    self.val[k],
                ));
            }
        }
        faer::sparse::SparseColMat::try_new_from_triplets(self.n, self.n, &triplets)
            .map_err(|e| format!("{e:?}"))
    }
}

/// Where one chunk of rows writes its entries: a slice of the matrix's own buffers sized
/// for the chunk's bound, filled from the start (`len` entries so far). A write is two
/// stores and a counter kept in a register, where `Vec::push` checks the capacity and
/// stores the length back on every entry.
pub struct Entries<'a> {
    pub cols: &'a mut [u32],
    pub vals: &'a mut [Real],
    pub len: usize,
}

impl Entries<'_> {
    #[inline(always)]
    pub fn push(&mut self, col: u32, val: Real) {
        self.cols[self.len] = col;
        self.vals[self.len] = val;
        self.len += 1;
    }
}

impl CsrMatrix {
    /// Fill this matrix with rows written chunk by chunk, in parallel, straight into its
    /// own buffers (reused from the last fill: no second copy of the matrix alive and no
    /// zeroing at a steady size). Chunk `c` may write at most `bounds[c]` entries;
    /// `write(c, entries)` writes its rows in order and returns each row's length and
    /// whatever else it computed. The chunks' entries are then moved down over the unused
    /// space of their bounds, in order. Deterministic: the entries and their order do not
    /// depend on the thread count.
    pub fn fill_in_place<T: Send>(
        &mut self,
        bounds: &[usize],
        write: impl Fn(usize, &mut Entries) -> (Vec<u32>, T) + Sync,
    ) -> Vec<T> {
        let total: usize = bounds.iter().sum();
        // the last fill's entries stay where they are, to be overwritten: only room
        // beyond them is added, zeroed (clearing first zeroed the whole matrix on one
        // thread every step: 1.9 ms of a 160k-particle step, as the bound of rows that
        // reach the surface is always above the last fill's length)
        if self.col.len() < total {
            self.col.resize(total, 0);
            self.val.resize(total, 0.0);
        }
        let mut slices = Vec::with_capacity(bounds.len());
        let (mut cols, mut vals) = (&mut self.col[..total], &mut self.val[..total]);
        for &b in bounds {
            let (c, rest_c) = cols.split_at_mut(b);
            let (v, rest_v) = vals.split_at_mut(b);
            slices.push((c, v));
            (cols, vals) = (rest_c, rest_v);
        }
        let parts: Vec<(Vec<u32>, T)> = slices
            .into_par_iter()
            .enumerate()
            .map(|(c, (cols, vals))| {
                let mut out = Entries { cols, vals, len: 0 };
                let (lens, extra) = write(c, &mut out);
                debug_assert_eq!(lens.iter().map(|&l| l as usize).sum::<usize>(), out.len);
                (lens, extra)
            })
            .collect();
        self.row_ptr.clear();
        self.row_ptr.push(0);
        let (mut src, mut dst) = (0, 0);
        for ((lens, _), &bound) in parts.iter().zip(bounds) {
            let start = dst;
            for &l in lens {
                dst += l as usize;
                self.row_ptr.push(dst);
            }
            if src != start {
                self.col.copy_within(src..src + (dst - start), start);
                self.val.copy_within(src..src + (dst - start), start);
            }
            src += bound;
        }
        self.n = self.row_ptr.len() - 1;
        self.col.truncate(dst);
        self.val.truncate(dst);
        parts.into_iter().map(|(_, extra)| extra).collect()
    }
}

/// Rows of a matrix computed chunk by chunk: their lengths, columns and values.
#[derive(Debug, Default)]
pub struct RowChunk {
    pub lens: Vec<u32>,
    pub cols: Vec<u32>,
    pub vals: Vec<Real>,
}

/// `out` = the `pieces` one after the other, copied in parallel. Its old entries are
/// overwritten in place, so a buffer reused at a steady size is not cleared first.
pub fn concat_into<T: Copy + Default + Send + Sync>(out: &mut Vec<T>, pieces: &[&[T]]) {
    let total = pieces.iter().map(|p| p.len()).sum();
    if out.capacity() < total {
        // zeroed pages from the allocator: first touched by the parallel copy below
        *out = vec![T::default(); total];
    } else {
        out.truncate(total);
        out.resize(total, T::default());
    }
    let mut rest: &mut [T] = out;
    let mut targets = Vec::with_capacity(pieces.len());
    for p in pieces {
        let (head, tail) = std::mem::take(&mut rest).split_at_mut(p.len());
        targets.push(head);
        rest = tail;
    }
    targets
        .into_par_iter()
        .zip(pieces.par_iter())
        .for_each(|(t, p)| t.copy_from_slice(p));
}

/// Sparse LU through faer (works for symmetric and non-symmetric matrices).
pub fn solve_direct(a: &CsrMatrix, b: &[Real], x: &mut [Real]) -> Result<SolveInfo, SolveError> {
    use faer::prelude::*;
    if a.n == 0 {
        return Ok(SolveInfo::default());
    }
    let m = a.to_faer().map_err(SolveError::Factorization)?;
    let lu = m
        .sp_lu()
        .map_err(|e| SolveError::Factorization(format!("{e:?}")))?;
    let rhs = faer::Mat::<Real>::from_fn(a.n, 1, |i, _| b[i]);
    let sol = lu.solve(&rhs);
    for i in 0..a.n {
        x[i] = sol[(i, 0)];
    }
    let mut r = vec![0.0; a.n];
    a.mul(x, &mut r);
    let num: Real = r
        .iter()
        .zip(b)
        .map(|(ri, bi)| (bi - ri).powi(2))
        .sum::<Real>()
        .sqrt();
    let den: Real = b
        .iter()
        .map(|v| v * v)
        .sum::<Real>()
        .sqrt()
        .max(Real::MIN_POSITIVE);
    if !num.is_finite() {
        return Err(SolveError::Breakdown);
    }
    Ok(SolveInfo {
        iterations: 1,
        relative_residual: num / den,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn chunk(lens: &[u32], first_col: u32) -> RowChunk {
        let nnz: u32 = lens.iter().sum();
        RowChunk {
            lens: lens.to_vec(),
            cols: (first_col..first_col + nnz).collect(),
            vals: (first_col..first_col + nnz).map(Real::from).collect(),
        }
    }

    /// A matrix of `old` rows of garbage, as a reused buffer holds.
    fn stale(old: usize) -> CsrMatrix {
        CsrMatrix {
            n: old,
            row_ptr: vec![7; old + 1],
            col: vec![9; old],
            val: vec![-1.0; old],
        }
    }

    /// Rows written in place give the same matrix as the same rows copied from chunks,
    /// whatever the buffers held before and however short of its bound each chunk fell.
    #[test]
    fn fill_in_place_gives_the_rows_in_order() {
        // chunk c writes rows of lengths lens[c], entry k of the whole matrix = k
        let lens: [&[u32]; 4] = [&[2, 0, 1], &[3], &[], &[1, 1]];
        let bounds = [5, 3, 2, 4];
        let first: Vec<usize> = lens
            .iter()
            .scan(0, |k, l| {
                let f = *k;
                *k += l.iter().sum::<u32>() as usize;
                Some(f)
            })
            .collect();
        for old in [0usize, 4, 100] {
            let mut m = stale(old);
            let extra = m.fill_in_place(&bounds, |c, out| {
                let n: u32 = lens[c].iter().sum();
                for k in 0..n as usize {
                    let e = first[c] + k;
                    out.push(e as u32, e as Real);
                }
                (lens[c].to_vec(), c)
            });
            assert_eq!(extra, [0, 1, 2, 3]);
            assert_eq!(m.n, 6);
            assert_eq!(m.row_ptr, [0, 2, 2, 3, 6, 7, 8]);
            assert_eq!(m.col, [0, 1, 2, 3, 4, 5, 6, 7]);
            assert_eq!(m.val, [0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0]);
        }
    }

    /// The rows of the chunks in order, whatever the buffers held before: longer (a
    /// reused matrix that shrank), shorter, or nothing.
    #[test]
    fn fill_from_chunks_gives_the_chunks_rows_in_order() {
        let chunks = [chunk(&[2, 0, 1], 0), chunk(&[3], 3), chunk(&[], 6)];
        for old in [0usize, 4, 100] {
            let mut m = stale(old);
            m.fill_from_chunks(&chunks);
            assert_eq!(m.n, 4);
            assert_eq!(m.row_ptr, [0, 2, 2, 3, 6]);
            assert_eq!(m.col, [0, 1, 2, 3, 4, 5]);
            assert_eq!(m.val, [0.0, 1.0, 2.0, 3.0, 4.0, 5.0]);
        }
    }
}
