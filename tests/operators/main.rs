//! Verification of the operator family against the papers of docs/references.md
//! Each module reproduces one paper's test and asserts the paper's stated behaviour, or
//! checks an operator that the step calls against analytic values (`vector_laplacian`,
//! `neighbourhood_sums`).

mod convergence;
mod diffusion;
mod dirichlet_1d;
mod engine_variants;
mod manufactured_ppe;
mod neighbourhood_sums;
mod rows;
mod spacing_1d;
mod vector_laplacian;

use mpsfsi::math::{Real, Vec2};
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;

/// An n × n square lattice of spacing `l0` from the origin.
pub fn square_lattice(n: usize, l0: Real) -> Vec<Vec2> {
    (0..n * n)
        .map(|k| Vec2::new((k % n) as Real, (k / n) as Real) * l0)
        .collect()
}

/// That lattice with each point moved by up to `amplitude` in x and y (seeded).
pub fn jittered_lattice(n: usize, l0: Real, amplitude: Real, seed: u64) -> Vec<Vec2> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    square_lattice(n, l0)
        .into_iter()
        .map(|p| {
            p + Vec2::new(
                rng.random_range(-amplitude..=amplitude),
                rng.random_range(-amplitude..=amplitude),
            )
        })
        .collect()
}
