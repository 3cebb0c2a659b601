//! The sensor end of a path ("camera vertex" z_0): the camera, or a light meter
//! (`sensor::meter::point`). Light tracing and BDPT (`integrator::bidir`) reach either
//! through the same techniques;
//! `bin` names the pixel for the camera and is 0 for a meter (one reading per sample).
//!
//! MIS treats both alike (Georgiev 2012 tech. rep. (31)–(33)): the sensor point is a delta in
//! position, its rays have a density per solid angle (the camera's 1/(A cos³θ), an irradiance
//! meter's cos θ/π), except for a luminance meter, whose direction is a delta as well, so that
//! no technique with t ≤ 1 can produce its paths (see `integrator::bidir::mis::SubpathMis::delta_sensor_start`).

use super::meter::MeterSensor;
use super::Camera;
use crate::geometry::offset::spawn_ray_to_point;
use crate::geometry::Ray;
use glam::Vec3;

#[derive(Clone, Copy, Debug)]
pub enum Sensor<'a> {
    Camera(&'a Camera),
    Meter(MeterSensor),
}

/// A sensor point sampled from a reference point (t = 1 connections).
#[derive(Clone, Copy, Debug)]
pub struct SensorSample {
    /// The sampled point on the sensor (lens point, meter point).
    pub p: Vec3,
    /// Unit direction from the reference point towards `p`.
    pub wi: Vec3,
    /// We / pdf_w: importance arriving at the reference point over the density of `wi`.
    pub we_over_pdf: f32,
    /// Density per solid angle with which the sensor's own rays leave `p` towards the
    /// reference point (the camera subpath's first direction, for MIS).
    pub pdf_dir_w: f32,
    /// Which accumulator receives the splat: a pixel index for the camera, 0 for a meter.
    pub bin: u32,
    /// Fraction of the segment reference → sensor in which occluders count (camera: beyond
    /// the near clipping plane; 1 for a meter).
    pub visible_fraction: f32,
}

/// A ray the sensor generated itself: the start of a camera subpath.
#[derive(Clone, Copy, Debug)]
pub struct SensorRay {
    pub ray: Ray,
    pub t_max: f32,
    /// The sensor point z_0 (lens point, meter point).
    pub p: Vec3,
}

impl Sensor<'_> {
    /// The sensor's ray for raster position `film` (camera only) and the 2D sample `u`
    /// (the lens point of the camera, the direction of an irradiance meter).
    #[inline]
    pub fn generate_ray(&self, film: [f32; 2], u: [f32; 2]) -> Option<SensorRay> {
        match self {
            Sensor::Camera(cam) => {
                let (ray, t_max) = cam.generate_ray(film, u);
                Some(SensorRay {
                    ray,
                    t_max,
                    p: cam.lens_point(u),
                })
            }
            Sensor::Meter(m) => m.generate_ray(u).map(|r| SensorRay {
                ray: r.ray,
                t_max: f32::INFINITY,
                p: m.p,
            }),
        }
    }

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
            Sensor::Meter(m) => {
                let s = m.sample_wi(p_ref)?;
                Some(SensorSample {
                    p: m.p,
                    wi: s.wi,
                    we_over_pdf: s.we_over_pdf,
                    pdf_dir_w: s.pdf_dir_w,
                    bin: 0,
                    visible_fraction: 1.0,
                })
            }
        }
    }

    /// Density per solid angle of the direction of a ray the sensor generated itself
    /// (PDF_We without the bounds test); 0 for a delta direction.
    #[inline]
    pub fn ray_pdf_dir_w(&self, w: Vec3) -> f32 {
        match self {
            Sensor::Camera(cam) => cam.ray_pdf_dir(w),
            Sensor::Meter(m) => m.pdf_dir_w(w),
        }
    }

    /// W |cos θ| / (p_pos p_dir) of the sensor's own ray along `w`: the throughput a camera
    /// subpath starts with (1 for the camera, whose importance is normalised so).
    #[inline]
    pub fn ray_weight(&self, w: Vec3) -> f32 {
        match self {
            Sensor::Camera(_) => 1.0,
            Sensor::Meter(m) => m.ray_weight(w),
        }
    }

    /// True when the sensor's rays have a delta direction (a luminance meter).
    #[inline]
    pub fn delta_direction(&self) -> bool {
        match self {
            Sensor::Camera(_) => false,
            Sensor::Meter(m) => m.delta_direction(),
        }
    }

    /// The irradiance meter, which estimates direct light from infinite lights by connecting
    /// to the light's sampled direction (s = 1, t = 1; `connect::infinite_to_sensor`); None for
    /// the camera (pbrt-v4 and SmallVCM do not connect infinite lights to it either) and for a
    /// luminance meter.
    #[inline]
    pub fn infinite_light_meter(&self) -> Option<&MeterSensor> {
        match self {
            Sensor::Meter(m) if !m.delta_direction() => Some(m),
            _ => None,
        }
    }

    /// The shadow ray from surface point `p` (error `p_error`, geometric normal `n`) to the
    /// sensor sample `ss`, and the distance up to which occluders count.
    pub fn shadow_ray(&self, p: Vec3, p_error: Vec3, n: Vec3, ss: &SensorSample) -> (Ray, f32) {
        let (ray, t) = match self {
            Sensor::Camera(_) => spawn_ray_to_point(p, p_error, n, ss.p),
            Sensor::Meter(m) => m.ray_to(p, p_error, n),
        };
        (ray, t * ss.visible_fraction)
    }
}
