//! Warps from [0,1)² to shapes and directions, with their pdfs.

use crate::math::octant::sin_cos_octant;
use crate::math::{safe_sqrt, INV_4PI, INV_PI};
use glam::{Vec2, Vec3};
use std::f32::consts::{FRAC_PI_4, PI};

/// Concentric map of the square to the unit disk (Shirley & Chiu 1997; PBR 4ed §A.5.1).
#[inline]
pub fn concentric_disk(u: [f32; 2]) -> Vec2 {
    let o = Vec2::new(2.0 * u[0] - 1.0, 2.0 * u[1] - 1.0);
    if o.x == 0.0 && o.y == 0.0 {
        return Vec2::ZERO;
    }
    // θ = (π/4)(y/x) within the octant about the x axis, or π/2 − (π/4)(x/y) about the y
    // axis, whose cosine and sine are the sine and cosine of (π/4)(x/y).
    if o.x.abs() > o.y.abs() {
        let (s, c) = sin_cos_octant(FRAC_PI_4 * (o.y / o.x));
        o.x * Vec2::new(c, s)
    } else {
        let (s, c) = sin_cos_octant(FRAC_PI_4 * (o.x / o.y));
        o.y * Vec2::new(s, c)
    }
}

/// Cosine-weighted hemisphere around +Z by Malley's method (PBR 4ed §A.5.3).
#[inline]
pub fn cosine_hemisphere(u: [f32; 2]) -> Vec3 {
    let d = concentric_disk(u);
    Vec3::new(d.x, d.y, safe_sqrt(1.0 - d.x * d.x - d.y * d.y))
}

/// pdf of [`cosine_hemisphere`] per solid angle: cos θ / π.
#[inline]
pub fn cosine_hemisphere_pdf(cos_theta: f32) -> f32 {
    cos_theta.max(0.0) * INV_PI
}

/// Uniform direction on the unit sphere (PBR 4ed §A.5.2).
#[inline]
pub fn uniform_sphere(u: [f32; 2]) -> Vec3 {
    let z = 1.0 - 2.0 * u[0];
    let r = safe_sqrt(1.0 - z * z);
    let phi = 2.0 * PI * u[1];
    Vec3::new(r * phi.cos(), r * phi.sin(), z)
}

pub const UNIFORM_SPHERE_PDF: f32 = INV_4PI;

/// Uniform direction in the cone of half-angle θmax around +Z (PBR 4ed §A.5.4); the lights
/// use [`uniform_cone_gap`], this form is for the χ² tests.
#[cfg(any(test, feature = "testing"))]
#[inline]
pub fn uniform_cone(u: [f32; 2], cos_theta_max: f32) -> Vec3 {
    // 1 − cos θmax is exact in f32 for cos θmax ≥ 1/2 (Sterbenz).
    uniform_cone_gap(u, 1.0 - cos_theta_max)
}

/// [`uniform_cone`] given the gap 1 − cos θmax instead of cos θmax: 1 − cos θ = u₀ (1 − cos θmax)
/// and sin θ = √((1 − cos θ)(1 + cos θ)) never subtract numbers near 1, so tiny cones (the sun,
/// a far sphere light) are sampled smoothly; `(1 − u₀) + u₀ cos θmax` would round cos θ to a
/// few hundred rings and pile samples on the axis.
#[inline]
pub fn uniform_cone_gap(u: [f32; 2], one_minus_cos_max: f32) -> Vec3 {
    let one_minus_cos = u[0] * one_minus_cos_max;
    let sin_theta = safe_sqrt(one_minus_cos * (2.0 - one_minus_cos));
    let phi = u[1] * 2.0 * PI;
    Vec3::new(
        sin_theta * phi.cos(),
        sin_theta * phi.sin(),
        1.0 - one_minus_cos,
    )
}

/// pdf of [`uniform_cone`]: 1 / (2π (1 − cos θmax)).
#[cfg(any(test, feature = "testing"))]
#[inline]
pub fn uniform_cone_pdf(cos_theta_max: f32) -> f32 {
    crate::math::INV_2PI / (1.0 - cos_theta_max)
}

/// Uniform barycentrics on a triangle (PBR 4ed §A.5.5, the square-root parameterisation of
/// Turk 1990): returns (b0, b1, b2).
#[inline]
pub fn uniform_triangle(u: [f32; 2]) -> [f32; 3] {
    let su0 = u[0].sqrt();
    let b0 = 1.0 - su0;
    let b1 = u[1] * su0;
    [b0, b1, 1.0 - b0 - b1]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::Sampler;

    #[test]
    fn warps_stay_on_their_domains() {
        let mut s = Sampler::new(3, 0, 0);
        for _ in 0..10_000 {
            let u = s.get_2d();
            assert!(concentric_disk(u).length() <= 1.0 + 1e-6);
            let d = cosine_hemisphere(u);
            assert!((d.length() - 1.0).abs() < 1e-5 && d.z >= 0.0);
            assert!((uniform_sphere(u).length() - 1.0).abs() < 1e-5);
            assert!(uniform_cone(u, 0.9).z >= 0.9 - 1e-6);
            let b = uniform_triangle(u);
            assert!(b.iter().all(|&x| x >= -1e-6) && (b.iter().sum::<f32>() - 1.0).abs() < 1e-6);
        }
    }

    /// The map is Shirley and Chiu's definition, evaluated in f64, up to round-off: both
    /// octant cases, the diagonals between them, the axes and the square's corners.
    #[test]
    fn the_concentric_map_is_the_definition_up_to_round_off() {
        let exact = |u: [f32; 2]| {
            let (x, y) = (2.0 * f64::from(u[0]) - 1.0, 2.0 * f64::from(u[1]) - 1.0);
            if x == 0.0 && y == 0.0 {
                return (0.0, 0.0);
            }
            let q = std::f64::consts::FRAC_PI_4;
            let (r, theta) = if x.abs() > y.abs() {
                (x, q * (y / x))
            } else {
                (y, 2.0 * q - q * (x / y))
            };
            (r * theta.cos(), r * theta.sin())
        };
        let n = 512;
        let mut worst = 0f64;
        for i in 0..=n {
            for j in 0..=n {
                let u = [i as f32 / n as f32, j as f32 / n as f32];
                let (d, e) = (concentric_disk(u), exact(u));
                worst = worst.max(
                    (f64::from(d.x) - e.0)
                        .abs()
                        .max((f64::from(d.y) - e.1).abs()),
                );
            }
        }
        assert!(worst < 3e-7, "{worst:e}");
    }

    #[test]
    fn cosine_hemisphere_has_the_right_mean_cosine() {
        // E[cos θ] under p = cos θ/π is 2/3; standard deviation of cos θ is sqrt(1/2 - 4/9).
        let mut s = Sampler::new(5, 0, 0);
        let n = 100_000;
        let mean: f64 = (0..n)
            .map(|_| cosine_hemisphere(s.get_2d()).z as f64)
            .sum::<f64>()
            / n as f64;
        let sigma = (0.5f64 - 4.0 / 9.0).sqrt() / (n as f64).sqrt();
        assert!((mean - 2.0 / 3.0).abs() < 5.0 * sigma, "{mean}");
    }
}
