//! Small math helpers on top of glam: orthonormal frames and spherical geometry.
//!
//! Naming conventions used throughout the crate (stated once here, as in SmallVCM):
//! - `wo` points back along the path (towards the camera for camera paths), `wi` is the
//!   sampled or connecting direction; both point away from the surface (pbrt semantics).
//! - `_local` marks a vector in a shading frame where the normal is +Z.
//! - `_w` marks a pdf per unit solid angle, `_a` per unit area.
//! - `lambda: &SampledWavelengths` is the wavelength tuple a path carries.

pub mod frame;

pub use frame::Frame;

use glam::Vec3;
use std::f32::consts::PI;

/// sqrt that returns 0 for tiny negative arguments caused by rounding.
#[inline]
pub fn safe_sqrt(x: f32) -> f32 {
    x.max(0.0).sqrt()
}

/// Unit vector from spherical angles around +Z (PBR 4ed §3.8.1).
#[inline]
pub fn spherical_direction(sin_theta: f32, cos_theta: f32, phi: f32) -> Vec3 {
    let s = sin_theta.clamp(-1.0, 1.0);
    Vec3::new(s * phi.cos(), s * phi.sin(), cos_theta.clamp(-1.0, 1.0))
}

/// Reflection of `wo` about `n` (both pointing away from the surface).
#[inline]
pub fn reflect(wo: Vec3, n: Vec3) -> Vec3 {
    -wo + 2.0 * wo.dot(n) * n
}

/// Flips `v` to lie in the hemisphere of `reference`.
#[inline]
pub fn face_forward(v: Vec3, reference: Vec3) -> Vec3 {
    if v.dot(reference) < 0.0 {
        -v
    } else {
        v
    }
}

pub const INV_PI: f32 = 1.0 / PI;
pub const INV_2PI: f32 = 0.5 / PI;
pub const INV_4PI: f32 = 0.25 / PI;
