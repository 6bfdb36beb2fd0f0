//! Verification of the operator family against the papers in shared/papers (issue 5).

mod convergence;
