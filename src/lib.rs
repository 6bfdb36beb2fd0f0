//! mpsfsi: a 2D moving-particle semi-implicit (MPS) engine with polygon walls and
//! rigid bodies, and a job service that returns the loads water puts on them.
//!
//! Data flows one way: [`case`] -> [`engine`] scene -> step pipeline -> [`output`].
//! [`math`] (scalar and vector types) and [`geometry`] (polygon predicates and wall
//! shapes) sit below both `case` and `engine`.
//!
//! Cargo features (both default): `service` ([`service`], the HTTP job service and its
//! database) and `bench` ([`bench`], the run-time-against-error study). Without them the
//! crate is the engine, the case format, the coupling and the outputs.

pub mod analysis;
#[cfg(feature = "bench")]
pub mod bench;
pub mod case;
pub mod coupling;
pub mod engine;
pub mod geometry;
pub mod math;
pub mod output;
pub mod run;
#[cfg(feature = "service")]
pub mod service;
pub mod state_io;
