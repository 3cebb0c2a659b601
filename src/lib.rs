//! spectral-render: a spectral, physically based renderer for USD stages whose images and
//! light-meter readings are in absolute photometric units. See `ARCHITECTURE.md`.

pub mod accel;
pub mod bxdf;
pub mod cli;
pub mod error;
pub mod geometry;
pub mod imageio;
pub mod integrator;
pub mod light;
pub mod material;
pub mod math;
pub mod output;
pub mod render;
pub mod sampling;
pub mod scene;
pub mod sensor;
pub mod spectral;

pub use error::{Error, Result};
