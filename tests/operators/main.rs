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
