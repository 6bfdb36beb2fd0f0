//! Rigid bodies. PLACEHOLDER until the rapier2d coupling lands: bodies move at their
//! initial velocity (kinematic); free bodies are not yet integrated.

use crate::case::Case;
use crate::engine::Simulation;
use crate::output::BodySample;

pub struct Coupling;

impl Coupling {
    /// None when the case has no bodies: nothing is built or stepped.
    pub fn new(case: &Case, _sim: &Simulation) -> Option<Self> {
        if case.bodies.is_empty() { None } else { Some(Self) }
    }

    pub fn before_step(&mut self, _sim: &mut Simulation, _dt: f64) {}

    pub fn after_step(&mut self, _sim: &mut Simulation, _dt: f64) {}

    pub fn samples(&self, sim: &Simulation) -> Vec<BodySample> {
        sim.walls
            .iter()
            .filter(|w| w.body.is_some())
            .map(|w| BodySample {
                name: w.name.clone(),
                x: w.state.center_of_mass.x,
                y: w.state.center_of_mass.y,
                angle: w.state.angle,
                vx: w.state.velocity.x,
                vy: w.state.velocity.y,
                omega: w.state.angular_velocity,
            })
            .collect()
    }
}
