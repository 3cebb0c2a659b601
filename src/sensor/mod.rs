//! Sensors: the camera and the film it exposes, the light meters (no film), and the sensor
//! end of a path (`endpoint.rs`: the camera or a meter, as the bidirectional integrators see
//! either).

pub mod camera;
pub mod endpoint;
pub mod film;
pub mod film_state;
pub mod grid_sum;
pub mod meter;
pub mod raw_bytes;
pub mod replicates;
pub mod spectral_film;

pub use camera::Camera;
pub use endpoint::{Sensor, SensorRay, SensorSample};
