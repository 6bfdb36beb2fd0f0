//! Validation before any work: every rejection names the field path and the reason.
//! (Skeleton: the full rule set is being written.)

use super::{Case, CaseError};

/// Limits configured by the operator of the tool (CLI flags, service config).
#[derive(Debug, Clone)]
pub struct Limits {
    /// Largest number of fluid particles a case may create.
    pub max_particles: usize,
}

impl Default for Limits {
    fn default() -> Self {
        Self { max_particles: 2_000_000 }
    }
}

/// Check a case; `Ok` means the engine may build it.
pub fn validate(case: &Case, _limits: &Limits) -> Result<(), CaseError> {
    if !(case.particle_spacing.is_finite() && case.particle_spacing > 0.0) {
        return Err(CaseError::new("particle_spacing", "must be a positive finite number"));
    }
    Ok(())
}
