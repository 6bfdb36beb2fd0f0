//! Verification of the operator family against the papers of docs/references.md
//! Each module reproduces one paper's test and asserts the paper's stated behaviour.

mod convergence;
mod diffusion;
mod dirichlet_1d;
mod engine_variants;
mod manufactured_ppe;
mod rows;
mod spacing_1d;
