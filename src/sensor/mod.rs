//! Sensors: the camera and the film it exposes (light meters come in a later issue).

pub mod camera;
pub mod film;

pub use camera::Camera;
pub use film::Film;
