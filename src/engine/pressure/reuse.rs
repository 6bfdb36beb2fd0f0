//! The AMG hierarchy carried from one pressure solve to the next (issue 6).
//!
//! Building the hierarchy (aggregation, smoothed prolongator, Galerkin products) cost
//! 40-60% of a solve when it was rebuilt every step, while the matrix of the next step
//! differs little: particles move at most a fraction of a spacing per step (CFL 0.2).
//! So the hierarchy built at one step preconditions the next ones, with its finest
//! level fitted to the new matrix:
//!
//! - the fine unknowns are the particles off the free surface, a set that changes from
//!   step to step: the fine rows of the prolongator are keyed by particle index, so a
//!   particle that stays keeps its row, one that joins gets an empty row (the smoother
//!   alone acts on it: it lies next to the surface, where p = 0 is imposed), one that
//!   leaves takes its row with it;
//! - the fine smoother (damped Jacobi) is recomputed from the new matrix every solve;
//! - the coarse operators are either kept as built ([`CoarseUpdate::Keep`]: the setup
//!   of a reused step is almost free) or recomputed as Galerkin products R A P of the
//!   new matrix with the kept transfers ([`CoarseUpdate::Galerkin`]).
//!
//! Soundness: the V(1,1) cycle with a convergent symmetric smoother on the finest level
//! and any symmetric positive semi-definite coarse correction is symmetric positive
//! definite, so CG keeps converging to the same tolerance: reuse changes the number of
//! iterations, never the accuracy. The hierarchy is rebuilt from scratch every
//! `rebuild_interval` solves, when the iterations of the last solve grew past
//! [`growth_limit`] of those right after the last rebuild, when the particles were
//! renumbered (the keys changed meaning), and, as a safety net, when a solve with a
//! reused hierarchy fails (it is then repeated from the same initial guess).
//!
//! Every decision depends only on the matrices and the iteration counts, which do not
//! depend on the number of threads: results stay deterministic.

use super::amg::Hierarchy;
use super::pcg::{count_setup, pcg_in, pcg_with, CgVectors};
use super::{CsrMatrix, SolveError, SolveInfo, SolveParams};
use crate::math::Real;

/// What a reused hierarchy does with its coarse operators.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum CoarseUpdate {
    /// Keep the coarse operators of the last rebuild (setup of a reused solve: the
    /// fine smoother and, when the unknowns changed, the remapped transfers).
    Keep,
    /// Recompute them as Galerkin products of the new matrix with the kept transfers.
    /// Not the engine's choice: it saves only the aggregation and the prolongator
    /// smoothing, about a quarter of a build (the products are the rest), and with
    /// many unknowns joining and leaving it took more iterations than `Keep` (32 against
    /// 22, fresh 19, in tests/engine/amg_reuse.rs).
    Galerkin,
}

/// When a hierarchy is reused.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ReusePolicy {
    /// Solves per hierarchy: 1 rebuilds it every solve (no reuse).
    pub rebuild_interval: usize,
    pub coarse: CoarseUpdate,
}

/// A reused hierarchy is dropped when its last solve took more than this many
/// iterations, given the count of the solve right after it was built: 1.5x, plus 2
/// for the small counts where one or two iterations are noise.
pub fn growth_limit(iterations_after_build: usize) -> usize {
    iterations_after_build + iterations_after_build / 2 + 2
}

/// How the hierarchies of a sequence of solves were obtained.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub struct ReuseCounts {
    /// Full builds (first solve, interval, growth, renumbering, failure).
    pub builds: u64,
    /// Solves with a reused hierarchy.
    pub reuses: u64,
    /// Builds forced by the iteration growth.
    pub growth_rebuilds: u64,
    /// Reused solves that failed and were repeated with a new hierarchy.
    pub failed_reuses: u64,
}

/// Preconditioner state kept between pressure solves, owned by the simulation (one per
/// simulation, so that runs do not share it) and handed to [`super::solve_reusing`].
/// Because the preconditioner of a step depends on earlier steps, the iterates (not the
/// converged accuracy) depend on the history; a simulation is still deterministic.
#[derive(Default, serde::Serialize, serde::Deserialize)]
pub struct SolverCache {
    hierarchy: Option<Hierarchy>,
    /// The key (particle index) of each fine row of `hierarchy`.
    keys: Vec<u32>,
    /// Number of keys (particles) when the hierarchy was built or last remapped.
    key_space: usize,
    /// Solves done with the current hierarchy.
    age: usize,
    iterations_after_build: usize,
    last_iterations: usize,
    counts: ReuseCounts,
    /// CG's work vectors, reused by every solve.
    #[serde(skip)]
    vectors: CgVectors,
}

impl std::fmt::Debug for SolverCache {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SolverCache")
            .field("has_hierarchy", &self.hierarchy.is_some())
            .field("rows", &self.keys.len())
            .field("age", &self.age)
            .field("iterations_after_build", &self.iterations_after_build)
            .field("counts", &self.counts)
            .finish()
    }
}

impl SolverCache {
    /// Forget the hierarchy: the next solve builds a new one. Call when the keys change
    /// meaning (particles removed and renumbered).
    pub fn invalidate(&mut self) {
        self.hierarchy = None;
        self.keys.clear();
    }

    /// z = M⁻¹ r with the cached hierarchy (one V-cycle on the fine matrix `a`, the
    /// matrix it was built or refitted for); false when there is none.
    pub fn precondition(&mut self, a: &CsrMatrix, r: &[Real], z: &mut [Real]) -> bool {
        match self.hierarchy.as_mut() {
            Some(h) if self.keys.len() == a.n => {
                h.apply(a, r, z);
                true
            }
            _ => false,
        }
    }

    pub fn counts(&self) -> ReuseCounts {
        self.counts
    }

    fn build(&mut self, a: &CsrMatrix, keys: &[u32], key_space: usize) {
        // the old hierarchy and CG's vectors go first: alive during the build they would
        // raise the memory peak (CG's by 32 B a row: 1116-1127 against 1036-1065 B a
        // particle at 160k, bench --scaling)
        self.hierarchy = None;
        self.vectors = CgVectors::default();
        self.hierarchy = Some(Hierarchy::new(a));
        self.keys.clear();
        self.keys.extend_from_slice(keys);
        self.key_space = key_space;
        self.age = 0;
        self.counts.builds += 1;
    }

    /// Fit the kept hierarchy to the matrix `a` with row keys `keys`; false when it
    /// cannot serve it (then build).
    fn refit(&mut self, a: &CsrMatrix, keys: &[u32], coarse: CoarseUpdate) -> bool {
        let Some(h) = self.hierarchy.as_mut() else {
            return false;
        };
        // a hierarchy without coarse levels is the fine matrix itself, factorised
        if h.coarsened_levels() == 0 {
            return false;
        }
        if self.keys != keys {
            let mut row_of_key = vec![u32::MAX; self.key_space];
            for (row, &k) in keys.iter().enumerate() {
                row_of_key[k as usize] = row as u32;
            }
            let new_row: Vec<u32> = self.keys.iter().map(|&k| row_of_key[k as usize]).collect();
            // the old row of each new key, through the same table
            row_of_key.iter_mut().for_each(|v| *v = u32::MAX);
            for (row, &k) in self.keys.iter().enumerate() {
                row_of_key[k as usize] = row as u32;
            }
            let old_row: Vec<u32> = keys.iter().map(|&k| row_of_key[k as usize]).collect();
            h.remap_fine_rows(&old_row, &new_row);
            self.keys.clear();
            self.keys.extend_from_slice(keys);
        }
        match coarse {
            CoarseUpdate::Keep => {
                h.refresh_fine_smoother(a);
                true
            }
            CoarseUpdate::Galerkin => h.refresh_operators(a),
        }
    }
}

/// What a solve may carry over from earlier solves: the cache, the key of each row
/// (`keys[row]` identifies the unknown across solves: the particle index, below
/// `key_space`) and when to rebuild.
pub struct Reuse<'a> {
    pub cache: &'a mut SolverCache,
    pub keys: &'a [u32],
    pub key_space: usize,
    pub policy: ReusePolicy,
}

/// CG preconditioned by an AMG hierarchy taken from the cache when the policy allows,
/// else built (and kept there); `x` holds the initial guess.
pub fn solve_amg_reusing(
    a: &CsrMatrix,
    b: &[Real],
    x: &mut [Real],
    params: SolveParams,
    reuse: Reuse,
) -> Result<SolveInfo, SolveError> {
    let Reuse {
        cache,
        keys,
        key_space,
        policy,
    } = reuse;
    assert_eq!(keys.len(), a.n, "one key per row");
    if a.n == 0 || b.iter().all(|&v| v == 0.0) {
        return pcg_with(a, b, x, params, |r, z| z.copy_from_slice(r));
    }
    let clock = std::time::Instant::now();
    let stale = cache.hierarchy.is_none()
        || key_space != cache.key_space
        || cache.age >= policy.rebuild_interval.max(1);
    let grown = !stale && cache.last_iterations > growth_limit(cache.iterations_after_build);
    let reused = !stale && !grown && cache.refit(a, keys, policy.coarse);
    if !reused {
        cache.counts.growth_rebuilds += grown as u64;
        cache.build(a, keys, key_space);
    }
    count_setup(clock);
    let guess = reused.then(|| x.to_vec());
    let mut result = {
        let h = cache.hierarchy.as_mut().expect("built above");
        pcg_in(a, b, x, params, &mut cache.vectors, |r, z| {
            h.apply_dot(a, r, z)
        })
    };
    if let (Err(_), Some(guess)) = (&result, guess) {
        // the reused hierarchy did not do: a new one, from the same initial guess
        cache.counts.failed_reuses += 1;
        let clock = std::time::Instant::now();
        cache.build(a, keys, key_space);
        count_setup(clock);
        x.copy_from_slice(&guess);
        let h = cache.hierarchy.as_mut().expect("built above");
        result = pcg_in(a, b, x, params, &mut cache.vectors, |r, z| {
            h.apply_dot(a, r, z)
        });
    } else if reused {
        cache.counts.reuses += 1;
    }
    let info = result?;
    if cache.age == 0 {
        cache.iterations_after_build = info.iterations;
    }
    cache.age += 1;
    cache.last_iterations = info.iterations;
    Ok(info)
}
