//! The sensor end of a path ("camera vertex" z_0). Today the camera; a light meter is another
//! variant of [`Sensor`] with its own importance, so light tracing and BDPT estimate meters
//! through the same connections (`bin` then names the meter instead of a pixel).

use crate::sensor::Camera;
use glam::Vec3;

#[derive(Clone, Copy, Debug)]
pub enum Sensor<'a> {
    Camera(&'a Camera),
}

/// A sensor point sampled from a reference point (t = 1 connections).
#[derive(Clone, Copy, Debug)]
pub struct SensorSample {
    /// The sampled point on the sensor (lens point).
    pub p: Vec3,
    /// Unit direction from the reference point towards `p`.
    pub wi: Vec3,
    /// We / pdf_w: importance arriving at the reference point over the density of `wi`.
    pub we_over_pdf: f32,
    /// Density per solid angle with which the sensor's own rays leave `p` towards the
    /// reference point (the camera subpath's first direction, for MIS).
    pub pdf_dir_w: f32,
    /// Which accumulator receives the splat: a pixel index for the camera.
    pub bin: u32,
    /// Fraction of the segment reference → sensor in which occluders count.
    pub visible_fraction: f32,
}

impl Sensor<'_> {
    /// Samples a point on the sensor as seen from `p_ref` (PBR 4ed §5.4.1, `SampleWi`).
    #[inline]
    pub fn sample_wi(&self, p_ref: Vec3, u: [f32; 2]) -> Option<SensorSample> {
        match self {
            Sensor::Camera(cam) => {
                let s = cam.sample_wi(p_ref, u)?;
                let bin = cam.pixel_index(s.raster)?;
                if !(s.pdf_w > 0.0 && s.we > 0.0) {
                    return None;
                }
                Some(SensorSample {
                    p: s.p_lens,
                    wi: s.wi,
                    we_over_pdf: s.we / s.pdf_w,
                    pdf_dir_w: s.pdf_dir_w,
                    bin,
                    visible_fraction: s.visible_fraction,
                })
            }
        }
    }

    /// Density per solid angle of the direction of a ray the sensor generated itself
    /// (PDF_We without the bounds test).
    #[inline]
    pub fn ray_pdf_dir_w(&self, w: Vec3) -> f32 {
        match self {
            Sensor::Camera(cam) => cam.ray_pdf_dir(w),
        }
    }
}
