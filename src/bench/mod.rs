//! Benchmarks and studies whose results are reported, not asserted here (the tests
//! assert them against the papers).

pub mod operators;
