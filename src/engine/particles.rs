//! Struct-of-arrays particle storage: one array per quantity, indexed by particle.

use crate::math::{Real, Vec2};

#[derive(Debug, Clone, Default, serde::Serialize, serde::Deserialize)]
pub struct Particles {
    pub position: Vec<Vec2>,
    pub velocity: Vec<Vec2>,
    pub pressure: Vec<Real>,
    /// Particle number density n (fluid neighbours plus wall contribution).
    pub number_density: Vec<Real>,
    /// Rate of change of n (HS form), kept for the error-compensating source.
    pub number_density_rate: Vec<Real>,
    /// Dirichlet (free-surface) flag of the last pressure solve.
    pub free_surface: Vec<bool>,
    /// Spacing as a multiple of l0 (1 everywhere in a uniform layout; see `resolution`).
    pub scale: Vec<Real>,
}

impl Particles {
    pub fn with_positions(position: Vec<Vec2>, velocity: Vec<Vec2>) -> Self {
        let n = position.len();
        Self {
            position,
            velocity,
            pressure: vec![0.0; n],
            number_density: vec![0.0; n],
            number_density_rate: vec![0.0; n],
            free_surface: vec![false; n],
            scale: vec![1.0; n],
        }
    }

    pub fn len(&self) -> usize {
        self.position.len()
    }

    pub fn is_empty(&self) -> bool {
        self.position.is_empty()
    }

    /// The number of particles of spacing `scale` l0.
    pub fn count_of_scale(&self, scale: Real) -> usize {
        self.scale.iter().filter(|&&s| s == scale).count()
    }

    /// Keep the particles for which `keep[i]` is true, preserving order.
    pub fn retain(&mut self, keep: &[bool]) {
        fn filter<T: Copy>(v: &mut Vec<T>, keep: &[bool]) {
            let mut k = 0;
            for i in 0..v.len() {
                if keep[i] {
                    v[k] = v[i];
                    k += 1;
                }
            }
            v.truncate(k);
        }
        filter(&mut self.position, keep);
        filter(&mut self.velocity, keep);
        filter(&mut self.pressure, keep);
        filter(&mut self.number_density, keep);
        filter(&mut self.number_density_rate, keep);
        filter(&mut self.free_surface, keep);
        filter(&mut self.scale, keep);
    }
}
