//! The emitter mask: pixels in which the camera sees a light source directly. Lamps seen
//! directly are bright, nearly noise-free for some integrators and noisy for others (light
//! tracing), and their relative error says nothing about the lighting of the scene, so the
//! masked metrics leave them out (`metrics.rs`).
//!
//! A pixel is masked when any of [`SUBPIXELS`]² stratified camera rays through it (at the
//! lens centre) first hits an emitter: an analytic light shape, an emissive triangle, or
//! nothing at all while the scene has an infinite light (a dome or distant light seen
//! directly). The mask is the true first-hit mask of the scene's geometry, not a threshold on
//! the reference's brightness, so it holds for any reference (ours or another renderer's).

use crate::scene::analysis::sees_emitter_at;
use crate::scene::Scene;
use rayon::prelude::*;

/// Rays per pixel side (4 × 4 per pixel).
pub const SUBPIXELS: usize = 4;

/// One flag per pixel (row-major, top row first): true where an emitter is seen directly.
pub fn emitter_mask(scene: &Scene) -> Vec<bool> {
    let (w, h) = (scene.camera.width as usize, scene.camera.height as usize);
    (0..w * h)
        .into_par_iter()
        .map(|i| sees_emitter(scene, i % w, i / w))
        .collect()
}

fn sees_emitter(scene: &Scene, x: usize, y: usize) -> bool {
    let step = 1.0 / SUBPIXELS as f32;
    (0..SUBPIXELS * SUBPIXELS).any(|k| {
        let (i, j) = (k % SUBPIXELS, k / SUBPIXELS);
        let film = [
            x as f32 + (i as f32 + 0.5) * step,
            y as f32 + (j as f32 + 0.5) * step,
        ];
        sees_emitter_at(scene, film)
    })
}
