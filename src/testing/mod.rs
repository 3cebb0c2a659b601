//! Test machinery, compiled only for the project's own tests, benches and examples (the
//! `testing` feature, which the crate's self dev-dependency turns on) and for unit tests:
//!
//! - `chi2.rs`: the χ² goodness-of-fit harness for every sampling routine;
//! - `bxdf_examples.rs`: an instance of every BSDF model, including the hard corners;
//! - `rng.rs`: a small deterministic generator for geometry tests.

pub mod bxdf_examples;
pub mod chi2;
pub mod rng;

pub use bxdf_examples::{examples, Example};
