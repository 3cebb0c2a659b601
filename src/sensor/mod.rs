//! Sensors: the camera and the film it exposes, and the light meters (no film).

pub mod camera;
pub mod film;
pub mod meter;

pub use camera::Camera;
pub use film::Film;
