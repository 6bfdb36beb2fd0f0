//! Scalar and vector types, in one place.

pub type Real = f64;
pub type Vec2 = nalgebra::Vector2<Real>;
pub type Mat2 = nalgebra::Matrix2<Real>;

/// 2D cross product (z component).
#[inline]
pub fn cross(a: Vec2, b: Vec2) -> Real {
    a.x * b.y - a.y * b.x
}

/// `[x, y]` from a case file.
#[inline]
pub fn vec2(p: [Real; 2]) -> Vec2 {
    Vec2::new(p[0], p[1])
}

/// Counter-clockwise perpendicular.
#[inline]
pub fn perp(a: Vec2) -> Vec2 {
    Vec2::new(-a.y, a.x)
}

/// Rotate by `angle` (rad).
#[inline]
pub fn rotate(a: Vec2, angle: Real) -> Vec2 {
    let (s, c) = angle.sin_cos();
    Vec2::new(c * a.x - s * a.y, s * a.x + c * a.y)
}

/// Σ f(i, &mut y[i]) over i, where f may update y[i] in place: a fused pass over a
/// vector that gives, bit for bit, the sum [`deterministic_sum`] would give in a
/// separate pass (the same chunks, summed in the same order). `parallel` lets short
/// vectors stay on one thread.
pub fn deterministic_sum_mut<F>(y: &mut [Real], parallel: bool, f: F) -> Real
where
    F: Fn(usize, &mut Real) -> Real + Sync,
{
    use rayon::prelude::*;
    let chunk_sum = |c: usize, ys: &mut [Real]| {
        let mut s = 0.0;
        for (k, v) in ys.iter_mut().enumerate() {
            s += f(c * SUM_CHUNK + k, v);
        }
        s
    };
    if !parallel {
        let mut total = 0.0;
        for (c, ys) in y.chunks_mut(SUM_CHUNK).enumerate() {
            total += chunk_sum(c, ys);
        }
        return total;
    }
    let partial: Vec<Real> = y
        .par_chunks_mut(SUM_CHUNK)
        .enumerate()
        .map(|(c, ys)| chunk_sum(c, ys))
        .collect();
    partial.iter().sum()
}

/// [`deterministic_sum_mut`] of two sums at once: Σ f(i, &mut y[i]).0 and .1, each bit
/// for bit what a separate pass of [`deterministic_sum_mut`] or [`deterministic_sum`]
/// gives (the same chunks, summed in the same order).
pub fn deterministic_sums_mut<F>(y: &mut [Real], parallel: bool, f: F) -> (Real, Real)
where
    F: Fn(usize, &mut Real) -> (Real, Real) + Sync,
{
    use rayon::prelude::*;
    let chunk_sums = |c: usize, ys: &mut [Real]| {
        let (mut s, mut t) = (0.0, 0.0);
        for (k, v) in ys.iter_mut().enumerate() {
            let (a, b) = f(c * SUM_CHUNK + k, v);
            s += a;
            t += b;
        }
        (s, t)
    };
    if !parallel {
        let (mut s, mut t) = (0.0, 0.0);
        for (c, ys) in y.chunks_mut(SUM_CHUNK).enumerate() {
            let (a, b) = chunk_sums(c, ys);
            s += a;
            t += b;
        }
        return (s, t);
    }
    let partial: Vec<(Real, Real)> = y
        .par_chunks_mut(SUM_CHUNK)
        .enumerate()
        .map(|(c, ys)| chunk_sums(c, ys))
        .collect();
    (
        partial.iter().map(|p| p.0).sum(),
        partial.iter().map(|p| p.1).sum(),
    )
}

/// The fixed chunk of the deterministic sums.
const SUM_CHUNK: usize = 2048;

/// Sum of `f(i)` for `i in 0..n` whose result does not depend on the number of
/// threads: fixed chunks are summed in parallel, the partial sums in index order.
pub fn deterministic_sum<F>(n: usize, f: F) -> Real
where
    F: Fn(usize) -> Real + Sync,
{
    use rayon::prelude::*;
    const CHUNK: usize = SUM_CHUNK;
    let chunks = n.div_ceil(CHUNK);
    if chunks <= 8 {
        let mut total = 0.0;
        for c in 0..chunks {
            let mut s = 0.0;
            for i in c * CHUNK..((c + 1) * CHUNK).min(n) {
                s += f(i);
            }
            total += s;
        }
        return total;
    }
    let partial: Vec<Real> = (0..chunks)
        .into_par_iter()
        .map(|c| {
            let mut s = 0.0;
            for i in c * CHUNK..((c + 1) * CHUNK).min(n) {
                s += f(i);
            }
            s
        })
        .collect();
    partial.iter().sum()
}
