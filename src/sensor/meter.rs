//! Light meters as sensors: illuminance (lx) on a virtual surface and luminance (cd/m²)
//! along a ray, like Mitsuba 3's `irradiancemeter` and `radiancemeter`. A [`Meter`] is what
//! the user asked for (world space); [`MeterSensor`] (`point.rs`) is the meter as the sensor
//! vertex of the bidirectional integrators (importance, cos θ/π rays, connections); [`Stats`]
//! (`stats.rs`) are a reading's running mean and variance. The measurement driver, which turns
//! samples into readings with confidence intervals, is `session::meter`.

pub mod point;
pub mod stats;

pub use point::MeterSensor;
pub use stats::Stats;

use crate::error::{Error, Result};
use glam::{DMat4, DVec3, Vec3};

/// What a meter measures.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MeterKind {
    /// Illuminance in lx on a surface with the meter's normal.
    Illuminance,
    /// Luminance in cd/m² arriving from the meter's direction.
    Luminance,
}

impl MeterKind {
    pub fn name(&self) -> &'static str {
        match self {
            MeterKind::Illuminance => "illuminance",
            MeterKind::Luminance => "luminance",
        }
    }

    pub fn unit(&self) -> &'static str {
        match self {
            MeterKind::Illuminance => "lx",
            MeterKind::Luminance => "cd/m2",
        }
    }
}

/// One meter in world space (metres, Y up).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Meter {
    pub kind: MeterKind,
    pub p: Vec3,
    /// Unit normal of the receiving surface (illuminance) or the direction the meter looks
    /// along (luminance).
    pub dir: Vec3,
}

impl Meter {
    /// An illuminance meter at `p` on a surface facing `normal` (any non-zero length).
    pub fn illuminance(p: Vec3, normal: Vec3) -> Result<Meter> {
        Meter::new(MeterKind::Illuminance, p, normal)
    }

    /// A luminance meter at `p` looking along `dir` (any non-zero length).
    pub fn luminance(p: Vec3, dir: Vec3) -> Result<Meter> {
        Meter::new(MeterKind::Luminance, p, dir)
    }

    fn new(kind: MeterKind, p: Vec3, dir: Vec3) -> Result<Meter> {
        if !p.is_finite() {
            return Err(Error::option(format!(
                "the meter position {p} is not finite"
            )));
        }
        let unit = dir.normalize_or_zero();
        if unit == Vec3::ZERO || !unit.is_finite() {
            return Err(Error::option(format!(
                "the meter direction {dir} has no length"
            )));
        }
        Ok(Meter { kind, p, dir: unit })
    }
}

/// A point given in stage coordinates (stage units, stage up axis), in world space.
pub fn stage_point(stage_to_world: &DMat4, p: DVec3) -> Vec3 {
    stage_to_world.transform_point3(p).as_vec3()
}

/// A direction given in stage coordinates, in world space (not normalised).
pub fn stage_vector(stage_to_world: &DMat4, v: DVec3) -> Vec3 {
    stage_to_world.transform_vector3(v).as_vec3()
}

/// A surface normal given in stage coordinates, in world space: transformed by the inverse
/// transpose (PBR 4ed §3.10.3), which for the stage's scale·rotation is the rotation.
pub fn stage_normal(stage_to_world: &DMat4, n: DVec3) -> Vec3 {
    stage_to_world
        .inverse()
        .transpose()
        .transform_vector3(n)
        .as_vec3()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn stage_conversion_of_a_z_up_centimetre_stage() {
        // S(0.01) · R where R takes (x, y, z) to (x, z, −y).
        let m = DMat4::from_scale(DVec3::splat(0.01))
            * DMat4::from_cols(
                glam::DVec4::X,
                glam::DVec4::NEG_Z,
                glam::DVec4::Y,
                glam::DVec4::W,
            );
        let p = stage_point(&m, DVec3::new(100.0, 200.0, 300.0));
        assert!((p - Vec3::new(1.0, 3.0, -2.0)).length() < 1e-6, "{p}");
        let n = stage_normal(&m, DVec3::Z).normalize();
        assert!((n - Vec3::Y).length() < 1e-6, "{n}");
    }
}
