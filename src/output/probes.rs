//! Pressure probes: the MPS weighted average of particle pressures around a point,
//! p = Σ w(|x_j - x|) p_j / Σ w (kernel of the scheme at r_e; with multi-resolution each
//! particle at its own radius, w(d; r_e s_j) = w(d/s_j; r_e)).

use crate::engine::kernel::weight;
use crate::engine::Simulation;
use crate::math::{Real, Vec2};

#[derive(Debug, Clone)]
pub struct ProbePoint {
    pub name: String,
    pub position: Vec2,
}

/// Pressure at every probe (0 where no particle is within r_e: a dry probe).
pub fn sample(sim: &Simulation, probes: &[ProbePoint]) -> Vec<(String, Real)> {
    let re = sim.config.params.re;
    let kind = sim.config.method.kernel;
    let scales = sim.scales();
    probes
        .iter()
        .map(|probe| {
            let (mut sw, mut swp) = (0.0, 0.0);
            let particles = sim.particles.position.iter().zip(&sim.particles.pressure);
            for (j, (x, p)) in particles.enumerate() {
                let s = scales.of(j);
                let r = (x - probe.position).norm() / s;
                if r < re {
                    let w = weight(kind, r.max(0.05 * sim.config.params.l0), re);
                    sw += w;
                    swp += w * p;
                }
            }
            (probe.name.clone(), if sw > 0.0 { swp / sw } else { 0.0 })
        })
        .collect()
}
