//! Small math helpers on top of glam: orthonormal frames and spherical geometry.
//!
//! Naming conventions used throughout the crate (stated once here, as in SmallVCM):
//! - `wo` points back along the path (towards the camera for camera paths), `wi` is the
//!   sampled or connecting direction; both point away from the surface (pbrt semantics).
//! - `_local` marks a vector in a shading frame where the normal is +Z.
//! - `_w` marks a pdf per unit solid angle, `_a` per unit area.
//! - `lambda: &SampledWavelengths` is the wavelength tuple a path carries.

pub mod angle32;
pub mod frame;
pub mod octant;
pub mod ratio;

pub use frame::Frame;

use glam::Vec3;
use std::f32::consts::PI;

/// sqrt that returns 0 for tiny negative arguments caused by rounding.
#[inline]
pub fn safe_sqrt(x: f32) -> f32 {
    x.max(0.0).sqrt()
}

/// Reflection of `wo` about `n` (both pointing away from the surface).
#[inline]
pub fn reflect(wo: Vec3, n: Vec3) -> Vec3 {
    -wo + 2.0 * wo.dot(n) * n
}

/// The two-sided 95 % point of the standard normal distribution, Φ⁻¹(0.975) (any table, e.g.
/// Abramowitz & Stegun 26.2.23's tabulated value).
pub const Z95: f64 = 1.959_963_984_540_054;

pub const INV_PI: f32 = 1.0 / PI;
pub const INV_2PI: f32 = 0.5 / PI;
pub const INV_4PI: f32 = 0.25 / PI;
