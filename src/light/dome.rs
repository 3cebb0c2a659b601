//! UsdLux DomeLight: radiance arriving from every direction, constant or from a lat-long
//! texture in the OpenEXR convention the UsdLux text adopts (+Y pole; longitude 0 along +Z,
//! +π/2 along +X; the image's left column is longitude +π, its top row latitude +π/2).
//! Constant domes are sampled uniformly over the sphere; textured ones by a piecewise-constant
//! 2D distribution over luminance · sin θ (PBR 4ed §12.5.2, pdf_w = pdf_uv / (2π² sin θ)).
//! With UsdLux portals, a receiver facing one samples the mixture of `portal.rs`.

use super::portal::{self, Portal};
use super::{LightLiSample, LightSampleContext};
use crate::math::INV_PI;
use crate::sampling::distribution::Distribution2D;
use crate::sampling::warp::{uniform_sphere, UNIFORM_SPHERE_PDF};
use crate::spectral::uplift::RgbIlluminantSpectrum;
use crate::spectral::{SampledSpectrum, SampledWavelengths, Spectrum};
use glam::{Mat3, Vec3};
use std::f32::consts::PI;

/// A lat-long radiance map: per texel an RGB illuminant spectrum (already scaled).
#[derive(Clone, Debug)]
pub struct LatLong {
    pub width: usize,
    pub height: usize,
    pub texels: Vec<RgbIlluminantSpectrum>,
    /// Per-texel luminance in cd/m², row-major (for reports and the sampler).
    pub luminance: Vec<f32>,
    pub distribution: Distribution2D,
}

#[derive(Clone, Debug)]
pub struct DomeLight {
    pub prim_path: String,
    /// World → dome-local rotation.
    pub world_to_local: Mat3,
    /// Constant radiance (when `map` is None) or the scale of the map.
    pub radiance: Spectrum,
    pub map: Option<LatLong>,
    /// UsdLux PortalLights guiding the sampling (none: the dome's own distribution alone).
    pub portals: Vec<Portal>,
}

impl DomeLight {
    pub fn sample_li(
        &self,
        ctx: &LightSampleContext,
        u: [f32; 2],
        lambda: &SampledWavelengths,
    ) -> Option<LightLiSample> {
        if self.portals.is_empty() {
            return self.sample_dome(ctx, u, lambda);
        }
        let (facing, alpha) = portal::facing(&self.portals, ctx.p);
        let wi = if u[0] < alpha {
            // Reuse u₀ (PBR 4ed §2.2.1's remapping): first the portal, then a point on it.
            let x = u[0] / alpha * facing.len() as f32;
            let k = (x as usize).min(facing.len() - 1);
            let u0 = (x - k as f32).min(1.0 - f32::EPSILON);
            self.portals[facing[k]].sample(ctx.p, [u0, u[1]])?.0
        } else {
            let u0 = ((u[0] - alpha) / (1.0 - alpha)).min(1.0 - f32::EPSILON);
            self.sample_dome(ctx, [u0, u[1]], lambda)?.wi
        };
        let pdf_w = self.pdf_mixture(ctx.p, wi, &facing, alpha);
        if !(pdf_w > 0.0 && pdf_w.is_finite()) {
            return None;
        }
        Some(self.sample_towards(ctx, wi, pdf_w, lambda))
    }

    /// The light sample of direction `wi` drawn with density `pdf_w`.
    fn sample_towards(
        &self,
        ctx: &LightSampleContext,
        wi: Vec3,
        pdf_w: f32,
        lambda: &SampledWavelengths,
    ) -> LightLiSample {
        LightLiSample {
            l: self.le(wi, lambda),
            wi,
            pdf_w,
            p_light: ctx.p + 2.0e7 * wi,
            n_light: Vec3::ZERO,
            delta: false,
            infinite: true,
        }
    }

    /// The dome's own distribution (uniform, or the map's).
    fn sample_dome(
        &self,
        ctx: &LightSampleContext,
        u: [f32; 2],
        lambda: &SampledWavelengths,
    ) -> Option<LightLiSample> {
        let (wi, pdf_w) = match &self.map {
            None => (uniform_sphere(u), UNIFORM_SPHERE_PDF),
            Some(map) => {
                let (uv, pdf_uv) = map.distribution.sample(u);
                let d_local = uv_to_dir(uv);
                let sin_theta = pole_distance(d_local);
                if sin_theta == 0.0 || pdf_uv == 0.0 {
                    return None;
                }
                (self.to_world(d_local), pdf_uv / (2.0 * PI * PI * sin_theta))
            }
        };
        Some(self.sample_towards(ctx, wi, pdf_w, lambda))
    }

    /// The density of `sample_li` from `p` towards `wi`.
    pub fn pdf_li(&self, p: Vec3, wi: Vec3) -> f32 {
        if self.portals.is_empty() {
            return self.pdf_dome(wi);
        }
        let (facing, alpha) = portal::facing(&self.portals, p);
        self.pdf_mixture(p, wi, &facing, alpha)
    }

    fn pdf_mixture(&self, p: Vec3, wi: Vec3, facing: &[usize], alpha: f32) -> f32 {
        let guided = if alpha > 0.0 {
            alpha * portal::pdf(&self.portals, facing, p, wi)
        } else {
            0.0
        };
        guided + (1.0 - alpha) * self.pdf_dome(wi)
    }

    fn pdf_dome(&self, wi: Vec3) -> f32 {
        match &self.map {
            None => UNIFORM_SPHERE_PDF,
            Some(map) => {
                let d = self.to_local(wi);
                let sin_theta = pole_distance(d);
                if sin_theta == 0.0 {
                    return 0.0;
                }
                map.distribution.pdf(dir_to_uv(d)) / (2.0 * PI * PI * sin_theta)
            }
        }
    }

    pub fn le(&self, d: Vec3, lambda: &SampledWavelengths) -> SampledSpectrum {
        match &self.map {
            None => self.radiance.sample(lambda),
            Some(map) => {
                let [u, v] = dir_to_uv(self.to_local(d));
                let x = ((u * map.width as f32) as usize).min(map.width - 1);
                let y = ((v * map.height as f32) as usize).min(map.height - 1);
                let t = &map.texels[y * map.width + x];
                SampledSpectrum::from_fn(|i| t.eval(lambda.lambda[i]))
                    * self.radiance.sample(lambda)
            }
        }
    }

    /// World direction → unit dome-local direction. `world_to_local` is a rotation possibly
    /// times a uniform scale (`scene::build` inverts the light's to_world, which carries the
    /// stage's metersPerUnit), so directions are renormalised after the transform.
    #[inline]
    fn to_local(&self, w: Vec3) -> Vec3 {
        (self.world_to_local * w).normalize_or_zero()
    }

    /// Inverse of [`Self::to_local`] (the transpose is the inverse up to the uniform scale).
    #[inline]
    fn to_world(&self, d_local: Vec3) -> Vec3 {
        (self.world_to_local.transpose() * d_local).normalize_or_zero()
    }

    /// Φ ≈ π r² ∫ L dω (PBR 4ed §12.5.1's bound for infinite lights).
    pub fn luminous_power(&self, scene_radius: f32) -> f32 {
        let avg = match &self.map {
            None => crate::spectral::xyz::luminance(&self.radiance.to_dense()) as f32,
            Some(map) => {
                map_average(map) * crate::spectral::xyz::luminance(&self.radiance.to_dense()) as f32
            }
        };
        4.0 * PI * PI * scene_radius * scene_radius * avg
    }
}

/// Mean luminance over the sphere (sin θ weighted).
fn map_average(map: &LatLong) -> f32 {
    let mut sum = 0.0f64;
    let mut wsum = 0.0f64;
    for y in 0..map.height {
        let w = ((y as f64 + 0.5) / map.height as f64 * std::f64::consts::PI).sin();
        for x in 0..map.width {
            sum += w * map.luminance[y * map.width + x] as f64;
            wsum += w;
        }
    }
    (sum / wsum.max(1e-30)) as f32
}

/// Lat-long (u, v) in [0,1)² → dome-local unit direction.
#[inline]
pub fn uv_to_dir(uv: [f32; 2]) -> Vec3 {
    let lon = PI * (1.0 - 2.0 * uv[0]);
    let lat = PI * (0.5 - uv[1]);
    Vec3::new(lat.cos() * lon.sin(), lat.sin(), lat.cos() * lon.cos())
}

/// sin θ from the +Y pole of a unit dome-local direction, as the length of its horizontal
/// part: √(1 − y²) would cancel catastrophically near the poles, where the lat-long pdf
/// pdf_uv / (2π² sin θ) is largest.
#[inline]
fn pole_distance(d: Vec3) -> f32 {
    (d.x * d.x + d.z * d.z).sqrt()
}

/// Dome-local direction → lat-long (u, v); the latitude comes from atan2, which is accurate
/// near the poles (unlike asin of y) and indifferent to the length of `d`.
#[inline]
pub fn dir_to_uv(d: Vec3) -> [f32; 2] {
    let lon = d.x.atan2(d.z);
    let lat = d.y.atan2(pole_distance(d));
    let u = (1.0 - lon * INV_PI) * 0.5;
    let v = 0.5 - lat * INV_PI;
    [
        u.clamp(0.0, 1.0 - f32::EPSILON),
        v.clamp(0.0, 1.0 - f32::EPSILON),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn latlong_follows_the_openexr_convention() {
        let z = uv_to_dir([0.5, 0.5]);
        assert!((z - Vec3::Z).length() < 1e-5, "{z}");
        let x = uv_to_dir([0.25, 0.5]);
        assert!((x - Vec3::X).length() < 1e-5, "{x}");
        assert!((uv_to_dir([0.3, 0.0]) - Vec3::Y).length() < 1e-5);
        for uv in [[0.1, 0.2], [0.7, 0.9], [0.45, 0.5]] {
            let back = dir_to_uv(uv_to_dir(uv));
            assert!((back[0] - uv[0]).abs() < 1e-5 && (back[1] - uv[1]).abs() < 1e-5);
        }
    }
}
