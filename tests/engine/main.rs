//! Engine suite: kernels, lattice operators, neighbour search, the polygon-wall
//! lattice sums, and determinism. Each test compares with an exact value.

mod amg;
mod amg_reuse;
mod determinism;
mod impact_defaults;
mod kernels;
mod lattice;
mod multi_resolution;
mod neighbors;
mod resume;
mod statistics;
mod wall_pressure;
mod walls;
