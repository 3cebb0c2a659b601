//! The albedo of a material: the share of uniformly diffuse incident light it scatters
//! (reflected plus transmitted), the bi-hemispherical or "white-sky" albedo
//! ρ = (1/π) ∫∫ f(ωo, ωi) |cos θi| |cos θo| dωi dωo, weighted by luminous efficiency over an
//! equal-energy spectrum: ρ_Y = ∫ ρ(λ) ȳ(λ) dλ / ∫ ȳ(λ) dλ, the luminous reflectance
//! lighting designers quote for walls ("ρ = 0.8"). (The largest ρ(λ) would be useless: the
//! uplifted spectrum of a saturated red reflects almost everything beyond 700 nm.)
//!
//! An estimate by sampling the BSDF, as pbrt-v4's `BxDF::rho` estimates ρ_hh (PBR 4ed
//! §4.3.1 and §9.1.2): ωo cosine-distributed on a stratified grid, ωi from `sample_f`, in
//! the importance transport mode (flux, without the 1/η² of radiance crossing an interface,
//! PBR 4ed §9.5.2), so that a lossless dielectric scatters exactly 1; wavelengths are
//! stratified hero tuples weighted by ȳ/p (`spectral::xyz::sampled_to_xyz`). Textured inputs
//! are averaged over st ∈ [0, 1)². Spectrally flat Lambertian surfaces come out exact.
//! Deterministic: the random numbers come from fixed `Sampler` streams.

use crate::bxdf::TransportMode;
use crate::material::Material;
use crate::sampling::warp::cosine_hemisphere;
use crate::sampling::Sampler;
use crate::spectral::xyz::sampled_to_xyz;
use crate::spectral::{SampledSpectrum, SampledWavelengths};
use crate::texture::TexCoord;
use glam::{Vec2, Vec3};

/// Wavelength tuples (4 wavelengths each, stratified over the visible range).
const TUPLES: u32 = 16;
/// Directions per side of the stratified grid of ωo (per tuple).
const GRID: u32 = 16;

/// The material's luminous white-sky albedo, in [0, 1] (clamped against sampling noise).
pub fn albedo(m: &Material) -> f32 {
    let (mut scattered, mut incident) = (0.0f64, 0.0f64);
    for t in 0..TUPLES {
        let lambda = SampledWavelengths::sample_visible((t as f32 + 0.5) / TUPLES as f32);
        let y_in = f64::from(sampled_to_xyz(SampledSpectrum::ONE, &lambda)[1]);
        let mut sampler = Sampler::new(0x00a1_bed0, u64::from(t), 0);
        for k in 0..GRID * GRID {
            let j = [sampler.get_1d(), sampler.get_1d()];
            let u = [
                ((k % GRID) as f32 + j[0]) / GRID as f32,
                ((k / GRID) as f32 + j[1]) / GRID as f32,
            ];
            let wo = cosine_hemisphere(u);
            let st = Vec2::from(sampler.get_2d());
            let bsdf = m.bsdf(TexCoord::point(st), Vec3::Z, &lambda);
            let (uc, u2) = (sampler.get_1d(), sampler.get_2d());
            incident += y_in;
            let Some(s) = bsdf.sample_f(wo, uc, u2, TransportMode::Importance) else {
                continue;
            };
            let y = f64::from(sampled_to_xyz(s.f * (s.wi.z.abs() / s.pdf_w), &lambda)[1]);
            if y.is_finite() {
                scattered += y;
            }
        }
    }
    if incident > 0.0 {
        (scattered / incident).clamp(0.0, 1.0) as f32
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::bxdf::TrowbridgeReitz;
    use crate::material::ColorInput;
    use crate::spectral::sellmeier::Sellmeier;
    use crate::spectral::Spectrum;

    #[test]
    fn lambert_is_exact_and_glass_keeps_everything() {
        let lambert = Material::Diffuse {
            reflectance: ColorInput::Constant(Spectrum::Constant(0.7)),
        };
        assert!((albedo(&lambert) - 0.7).abs() < 1e-5);
        for alpha in [0.0, 0.3] {
            let glass = Material::Dielectric {
                ior: Sellmeier::constant(1.5),
                distrib: TrowbridgeReitz::isotropic(alpha),
                roughness: None,
            };
            // Smooth: every sample weighs 1. Rough: GGX without multiple scattering loses a
            // little energy (Heitz et al. 2016), still close to 1.
            let a = albedo(&glass);
            assert!(a > 0.9 && a <= 1.0, "α {alpha}: {a}");
        }
    }
}
