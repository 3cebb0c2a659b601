//! The ranges a scene must stay within so that every sample stays finite. Transport runs in
//! `f32` (largest value 3.4e38): a radiance, times a path throughput divided by pdfs, times a
//! light's power or a scene's squared radius in the light sampler, must not overflow, and
//! the BVH builder squares extents. Rather than discover an overflow sample by sample (and
//! drop the samples), the builder refuses a scene outside these bounds, naming the prim:
//!
//! | quantity | bound | for comparison |
//! |---|---|---|
//! | a point, light position or light size | ±1e9 m | the Moon's orbit is 3.8e8 m |
//! | a light's peak luminance (after shaping) | 1e16 cd/m² | the Sun's is 1.6e9 cd/m² |
//! | a camera's exposure | ±64 stops | a camera spans about ±20 |
//!
//! With them the largest light power (π · area · luminance ≈ 1e35 lm) and the light sampler's
//! bound for infinite lights (4π² r² L) stay finite, with orders of magnitude to spare for
//! the throughputs and pdfs of a path.

use glam::{Mat4, Vec3};

use crate::error::Reason;
use crate::spectral::{xyz, Spectrum};

/// Largest absolute coordinate (m) of a point, a light's position or its size.
pub const MAX_COORDINATE: f32 = 1e9;

/// Largest peak luminance (cd/m²) of a light.
pub const MAX_LUMINANCE: f64 = 1e16;

/// Largest absolute camera exposure (stops).
pub const MAX_EXPOSURE: f32 = 64.0;

/// Points must be finite and within ±[`MAX_COORDINATE`].
pub fn check_points(points: &[Vec3]) -> Reason<()> {
    for (i, p) in points.iter().enumerate() {
        check_point(*p).map_err(|e| format!("point {i}: {e}"))?;
    }
    Ok(())
}

/// A point must be finite and within ±[`MAX_COORDINATE`].
pub fn check_point(p: Vec3) -> Reason<()> {
    let shown = format!("({}, {}, {})", number(p.x), number(p.y), number(p.z));
    if !p.is_finite() {
        return Err(format!("{shown} is not finite"));
    }
    if p.abs().max_element() > MAX_COORDINATE {
        return Err(format!(
            "{shown} m lies beyond ±{MAX_COORDINATE:e} m, the largest coordinate supported"
        ));
    }
    Ok(())
}

/// `x` plainly when it is of moderate size, in exponent form otherwise.
fn number(x: f32) -> String {
    if x == 0.0 || (1e-3..1e6).contains(&x.abs()) {
        format!("{x}")
    } else {
        format!("{x:e}")
    }
}

/// A light's or camera's transform: finite, invertible, its origin within bounds, and the
/// images of its unit axes scaled by `size` (the object's own extent) within bounds.
pub fn check_transform(m: &Mat4, size: f32) -> Reason<()> {
    if !m.is_finite() {
        return Err("the transform is not finite (NaN or Inf)".into());
    }
    let det = m.determinant();
    if !det.is_normal() {
        return Err("degenerate transform (zero scale)".into());
    }
    check_point(m.w_axis.truncate()).map_err(|e| format!("its origin {e}"))?;
    let extent = [m.x_axis, m.y_axis, m.z_axis]
        .iter()
        .map(|a| a.truncate().length() * size)
        .fold(0.0f32, f32::max);
    if extent.is_nan() || extent > MAX_COORDINATE {
        return Err(format!(
            "it is {extent:e} m large, beyond the {MAX_COORDINATE:e} m supported"
        ));
    }
    Ok(())
}

/// The luminance (cd/m²) of an emission spectrum, in f64.
pub fn luminance(s: &Spectrum) -> f64 {
    xyz::luminance(&s.to_dense())
}

/// A peak luminance must be finite and at most [`MAX_LUMINANCE`].
pub fn check_luminance(nits: f64) -> Reason<()> {
    if nits.is_finite() && nits <= MAX_LUMINANCE {
        return Ok(());
    }
    Err(format!(
        "its peak luminance {nits:.3e} cd/m² exceeds {MAX_LUMINANCE:e} cd/m², the largest \
         supported (the Sun's is 1.6e9)"
    ))
}

/// A camera exposure must lie within ±[`MAX_EXPOSURE`] stops.
pub fn check_exposure(stops: f32) -> Reason<()> {
    if stops.is_finite() && stops.abs() <= MAX_EXPOSURE {
        return Ok(());
    }
    Err(format!(
        "exposure {stops} is outside ±{MAX_EXPOSURE} stops (2^{MAX_EXPOSURE} ≈ 1.8e19)"
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn bounds() {
        assert!(check_points(&[Vec3::ZERO, Vec3::splat(1e8)]).is_ok());
        let far = check_points(&[Vec3::ZERO, Vec3::new(1e19, 0.0, 0.0)]).unwrap_err();
        assert!(far.starts_with("point 1:"), "{far}");
        assert!(check_point(Vec3::new(f32::NAN, 0.0, 0.0)).is_err());
        assert!(check_transform(&Mat4::ZERO, 1.0).is_err());
        assert!(check_transform(&Mat4::from_scale(Vec3::splat(2.0)), 1.0).is_ok());
        assert!(check_transform(&Mat4::from_scale(Vec3::splat(1e8)), 100.0).is_err());
        assert!(check_luminance(1e9).is_ok());
        assert!(check_luminance(1e38).is_err());
        assert!(check_luminance(f64::NAN).is_err());
        assert!(check_exposure(-8.0).is_ok());
        assert!(check_exposure(130.0).is_err());
    }
}
