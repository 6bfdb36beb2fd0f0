//! Rigid bodies and fluid–structure coupling: the rapier coupling, the
//! added-mass stabilisation, body walls in the number density, buoyancy, flotation
//! and the slamming load of a wedge against the similarity solution.

mod acceleration_reaction;
mod apex;
mod circle;
mod common;
mod coupling;
mod drop_tests;
mod gauges;
mod hydrostatics;
mod impact;
mod plate_impulse;
mod probe;
mod replay;
mod uncertainty;
mod wedge;
