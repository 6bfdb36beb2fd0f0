//! Added-mass stabilisation of the explicit (staggered) fluid–body coupling.
//!
//! With an incompressible fluid the force of step n+1 contains -m_a a^n, the reaction
//! to the body acceleration of the step before, so the explicit update
//! M a^{n+1} = F^{n+1} + M g has the amplification -m_a / M: it oscillates and grows
//! whenever the added mass m_a exceeds the body mass M, whatever the time step
//! (Causin, Gerbeau & Nobile 2005; Förster, Wall & Ramm 2007).
//!
//! Söding-type stabilisation adds an estimate m~ of the added mass to both sides,
//!
//!   (M + m~) a^{n+1} = F^{n+1} + M g + m~ a^n,
//!
//! which is exact when the acceleration is steady and has the amplification
//! (m~ - m_a) / (M + m~): stable for any m~ > (m_a - M) / 2, in particular for every
//! overestimate (which only adds a lag of about (m~ / M) dt). The rotational
//! counterpart uses I~ and the angular acceleration.
//!
//! The estimate here is Wagner's flat-plate added mass of the wetted width, m~ =
//! rho pi c² / 2 with c half the horizontal extent of the wetted surface, for
//! vertical motion (and the vertical extent for horizontal motion); the rotational
//! one is the half-space flat plate, I~ = rho pi c⁴ / 16. The wetted surface is the
//! set of wall contacts of the last step closer than one spacing to the body.

use crate::engine::Simulation;
use crate::math::{Real, Vec2};

/// How the coupling estimates the added mass it puts on both sides of the body equation.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum AddedMass {
    /// Plain explicit coupling: unstable for bodies lighter than their added mass.
    Off,
    /// A fixed estimate (kg/m, kg·m²/m).
    Constant { mass: Real, inertia: Real },
    /// Wagner's flat-plate added mass of the wetted width, times `factor`.
    WettedWidth { factor: Real },
}

impl Default for AddedMass {
    fn default() -> Self {
        Self::WettedWidth { factor: 1.0 }
    }
}

/// Horizontal and vertical extent of the wetted surface of wall object `wall`:
/// contacts of the last step within one spacing of its surface (or inside it).
pub fn wetted_extent(sim: &Simulation, wall: usize) -> Option<(Vec2, Vec2)> {
    let reach = sim.config.params.l0;
    let mut lo = Vec2::repeat(Real::INFINITY);
    let mut hi = Vec2::repeat(Real::NEG_INFINITY);
    let mut any = false;
    for c in &sim.workspace.contacts.contacts {
        if c.object as usize == wall && (c.penetrated || c.distance < reach) {
            lo = lo.inf(&c.point);
            hi = hi.sup(&c.point);
            any = true;
        }
    }
    any.then_some((lo, hi))
}

/// The estimate (mass, rotational inertia) for one body given its free degrees of freedom.
pub fn estimate(
    model: AddedMass,
    sim: &Simulation,
    wall: usize,
    free_x: bool,
    free_y: bool,
    free_rotation: bool,
) -> (Real, Real) {
    match model {
        AddedMass::Off => (0.0, 0.0),
        AddedMass::Constant { mass, inertia } => (mass, if free_rotation { inertia } else { 0.0 }),
        AddedMass::WettedWidth { factor } => {
            let Some((lo, hi)) = wetted_extent(sim, wall) else {
                return (0.0, 0.0);
            };
            let rho = sim.config.params.density;
            let l0 = sim.config.params.l0;
            // the first layer sits l0/2 off the surface: its projections span the wetted
            // surface up to about one spacing short
            let cx = 0.5 * (hi.x - lo.x + l0);
            let cy = 0.5 * (hi.y - lo.y + l0);
            let plate = |c: Real| 0.5 * std::f64::consts::PI * rho * c * c;
            let mut m: Real = 0.0;
            if free_y {
                m = m.max(plate(cx));
            }
            if free_x {
                m = m.max(plate(cy));
            }
            let c = cx.max(cy);
            let inertia = if free_rotation {
                std::f64::consts::PI * rho * c.powi(4) / 16.0
            } else {
                0.0
            };
            (factor * m, factor * inertia)
        }
    }
}
