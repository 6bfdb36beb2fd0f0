//! Estimators and reference answers shared by `mpsfsi bench` and the tests: the pure
//! functions that turn a run's outputs into an error against a published or analytic
//! reference, and the envelope in which the defaults' slamming loads are validated.
//! Analysis reads outputs and cases; it runs nothing, so it imports nothing from the
//! benchmark.

pub mod envelope;
pub mod measure;
pub mod reference;
pub mod similarity;
pub mod uncertainty;
