//! The MPS core: pure, synchronous and deterministic. It imports neither rapier nor
//! tokio; bodies are wall objects whose pose the coupling sets between steps.

pub mod config;
pub mod kernel;
pub mod neighbors;
pub mod operators;
pub mod params;
pub mod particles;
pub mod pressure;
pub mod refinement;
pub mod resolution;
pub mod scene;
pub mod simulation;
mod state;
pub mod step;
pub mod walls;
mod workspace;

pub use simulation::{Attempt, SimError, Simulation, StageTimes, StepInfo, WallLoad};
