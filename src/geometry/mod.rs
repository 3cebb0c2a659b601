//! Rays, triangles and robust ray spawning.

pub mod offset;
pub mod ray;
pub mod triangle;

pub use ray::Ray;
