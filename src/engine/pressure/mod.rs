//! The pressure Poisson equation: a sparse system over the particles that are not on
//! the free surface (those carry the Dirichlet value p = 0), and its linear solvers.
//!
//! Sign convention: the engine assembles A p = b with A = -(discrete Laplacian) (+ the
//! quasi-compressibility diagonal), which is symmetric positive definite for the
//! symmetric Laplacians, so conjugate gradients apply.

mod amg;
mod csr;
mod gmres;
mod pcg;
mod reuse;

pub use amg::Amg;
pub use csr::{concat_into, CsrMatrix, Entries, RowChunk};
pub use gmres::gmres;
pub use pcg::{bicgstab, conjugate_gradient, Preconditioner};
pub use reuse::{
    growth_limit, solve_amg_reusing, CoarseUpdate, Reuse, ReuseCounts, ReusePolicy, SolverCache,
};

use crate::case::SolverKind;
use crate::math::Real;

/// Process-wide seconds spent building preconditioners (IC(0) factor, AMG hierarchy),
/// for benchmarks that split a solve into setup and iterations.
pub fn preconditioner_setup_seconds() -> f64 {
    pcg::SETUP_NANOS.load(std::sync::atomic::Ordering::Relaxed) as f64 * 1e-9
}

/// Convergence report of an iterative solve (faer style: `Params -> Result<Info, Error>`).
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SolveInfo {
    pub iterations: usize,
    /// ||b - A x|| / ||b|| at exit.
    pub relative_residual: Real,
}

/// Settings of a solve.
#[derive(Debug, Clone, Copy)]
pub struct SolveParams {
    pub tolerance: Real,
    pub max_iterations: usize,
    /// Conjugate gradients only: the relative error in the energy norm,
    /// ||x* - x||_A / ||x||_A, at which the solve stops even above `tolerance` (0: none;
    /// `Scheme::solver_energy_tolerance`).
    pub energy: Real,
}

impl SolveParams {
    /// Stops at the relative residual `tolerance` alone.
    pub const fn relative(tolerance: Real, max_iterations: usize) -> Self {
        Self {
            tolerance,
            max_iterations,
            energy: 0.0,
        }
    }
}

#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SolveError {
    #[error("linear solver did not converge: relative residual {relative_residual:.3e} after {iterations} iterations")]
    NotConverged {
        iterations: usize,
        relative_residual: Real,
    },
    #[error("linear solver broke down (non-finite value)")]
    Breakdown,
    #[error("direct factorisation failed: {0}")]
    Factorization(String),
}

/// Solve A x = b with the chosen solver; `x` holds the initial guess on entry.
pub fn solve(
    kind: SolverKind,
    a: &CsrMatrix,
    b: &[Real],
    x: &mut [Real],
    params: SolveParams,
) -> Result<SolveInfo, SolveError> {
    match kind {
        SolverKind::PcgJacobi => conjugate_gradient(a, b, x, params, Preconditioner::Jacobi),
        SolverKind::PcgIc0 => {
            conjugate_gradient(a, b, x, params, Preconditioner::IncompleteCholesky)
        }
        SolverKind::PcgAmg => conjugate_gradient(a, b, x, params, Preconditioner::Amg),
        SolverKind::Bicgstab => bicgstab(a, b, x, params),
        SolverKind::Direct => csr::solve_direct(a, b, x),
    }
}

/// [`solve`], with the AMG hierarchy of [`SolverCache`] reused across solves as the
/// policy allows (the other solvers keep nothing).
pub fn solve_reusing(
    kind: SolverKind,
    a: &CsrMatrix,
    b: &[Real],
    x: &mut [Real],
    params: SolveParams,
    reuse: Reuse,
) -> Result<SolveInfo, SolveError> {
    match kind {
        SolverKind::PcgAmg => solve_amg_reusing(a, b, x, params, reuse),
        _ => solve(kind, a, b, x, params),
    }
}
