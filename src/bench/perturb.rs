//! Seeded lattice disorder: the same offsets on every machine, so that a perturbed
//! scene is a reproducible benchmark input.

use crate::math::{Real, Vec2};

/// Seed of the lattice perturbations of the stress and scaling scenes.
pub const PERTURBATION_SEED: u64 = 20_240_601;

/// A small seeded generator (SplitMix64), so the studies need no random-number crate.
#[derive(Debug, Clone)]
pub struct SplitMix64(u64);

impl SplitMix64 {
    pub fn new(seed: u64) -> Self {
        Self(seed)
    }
    pub fn next_u64(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in [0, 1).
    pub fn unit(&mut self) -> Real {
        (self.next_u64() >> 11) as Real / (1u64 << 53) as Real
    }
    /// Uniform in [-1, 1).
    pub fn symmetric(&mut self) -> Real {
        self.unit() * 2.0 - 1.0
    }
}

/// Move every position by an independent uniform offset in [-amplitude, amplitude) per
/// axis, from `seed`.
pub fn perturb_positions(positions: &mut [Vec2], amplitude: Real, seed: u64) {
    let mut rng = SplitMix64::new(seed);
    for p in positions {
        p.x += amplitude * rng.symmetric();
        p.y += amplitude * rng.symmetric();
    }
}
