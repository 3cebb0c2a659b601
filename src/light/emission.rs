//! From the UsdLux inputs of a light to its emitted spectral radiance (docs/design.md §2, §3).
//!
//! - The *shape* of the spectrum is the uplifted `inputs:color` (× the UsdLux colour
//!   temperature tint when enabled) as an RGB illuminant (D65 × sigmoid, so colour (1,1,1)
//!   is exactly D65), or the SPD named by `spectral:emission*`, which replaces the colour.
//!   Every shape is normalised so that white (or the named SPD) has a luminance of 1 cd/m².
//! - The luminance is `intensity · 2^exposure` nits, divided by the world-space area when
//!   `normalize` is on (OpenUSD UsdLux "Quantities and Units"); `spectral:luminousFlux` or
//!   `spectral:luminousIntensity`, when given, set it from the light's geometry instead
//!   (and from its ShapingAPI distribution: the scene builder integrates the shaping factor
//!   over directions, `light::shaping`).

use crate::desc::{EmissionDesc, SpdDesc};
use crate::error::Reason;
use crate::spectral::uplift::RgbIlluminantSpectrum;
use crate::spectral::{blackbody, color, data, xyz, DenseSpectrum, Spectrum};
use std::sync::Arc;

/// How a light's luminance relates to its photometric output, for `spectral:luminousFlux`
/// and `spectral:luminousIntensity`. "Luminance" is the base luminance L₀ before shaping; a
/// shaped light's factors include its shaping distribution s_v(ω):
/// flux = L₀ ∫ s_v(ω) P(ω) dω, peak intensity = L₀ max_ω s_v(ω) P(ω), P the projected area.
#[derive(Clone, Copy, Debug)]
pub struct Photometric {
    /// World-space emitting area (m²) for `normalize`; None for lights without one.
    pub area: Option<f32>,
    /// Luminous flux (lm) per cd/m² of luminance: π·A for a one-sided flat Lambertian emitter
    /// (∫ cos θ dω = π), π·4πr² for a sphere, π·2πrℓ for a cylinder's side.
    pub flux_per_nit: Option<f32>,
    /// Peak luminous intensity (cd) per cd/m² of luminance: the largest projected area
    /// (A for a flat emitter, πr² for a sphere, 2rℓ for a cylinder seen broadside).
    pub intensity_per_nit: Option<f32>,
}

/// The emitted radiance, or an error message (the caller adds file and prim).
pub fn radiance(e: &EmissionDesc, geometry: Photometric) -> Reason<Spectrum> {
    let shape = unit_shape(e)?;
    let luminance = luminance_nits(e, geometry)?;
    if !luminance.is_finite() || luminance < 0.0 {
        return Err(format!(
            "the light's luminance ({luminance} cd/m²) is not a finite non-negative number: \
             its intensity, exposure or photometric quantity is too large"
        ));
    }
    Ok(shape.scaled(luminance))
}

/// The luminance in nits set by intensity/exposure/normalize or the photometric overrides.
fn luminance_nits(e: &EmissionDesc, g: Photometric) -> Reason<f32> {
    if let Some(flux) = e.luminous_flux {
        let per = g
            .flux_per_nit
            .ok_or("spectral:luminousFlux is not defined for this light type")?;
        return Ok(flux / per);
    }
    if let Some(cd) = e.luminous_intensity {
        let per = g
            .intensity_per_nit
            .ok_or("spectral:luminousIntensity is not defined for this light type")?;
        return Ok(cd / per);
    }
    let mut l = e.intensity * e.exposure.exp2();
    if e.normalize {
        if let Some(area) = g.area {
            if area <= 0.0 {
                return Err("normalize is on but the light has zero area".into());
            }
            l /= area;
        }
    }
    Ok(l)
}

/// The spectral shape with a luminance of 1 cd/m² for white (or the named SPD); an RGB colour
/// as an RGB illuminant tabulated at 1 nm for rendering (`Spectrum::tabulated`).
pub fn unit_shape(e: &EmissionDesc) -> Reason<Spectrum> {
    match &e.spd {
        Some(spd) => normalized_spd(spd),
        None => {
            let mut rgb = e.color;
            if let Some(k) = e.color_temperature {
                let t = color_temperature_rgb(k);
                rgb = [rgb[0] * t[0], rgb[1] * t[1], rgb[2] * t[2]];
            }
            if rgb.iter().any(|c| !c.is_finite() || *c < 0.0) {
                return Err(format!(
                    "inputs:color {rgb:?} must be finite and non-negative"
                ));
            }
            Ok(Spectrum::RgbIlluminant(RgbIlluminantSpectrum::new(rgb)).tabulated())
        }
    }
}

/// A named, blackbody or sampled SPD scaled to a luminance of 1 cd/m².
pub fn normalized_spd(spd: &SpdDesc) -> Reason<Spectrum> {
    let dense = match spd {
        SpdDesc::Named(name) => data::illuminant(name).cloned().ok_or_else(|| {
            format!(
                "unknown spectral:emission '{name}' (known: {}, blackbody)",
                data::illuminant_names().join(", ")
            )
        })?,
        SpdDesc::Blackbody(k) => {
            if !(k.is_finite() && *k > 0.0) {
                return Err(format!("spectral:temperature {k} K must be positive"));
            }
            DenseSpectrum::from_fn(|l| blackbody::planck(l, *k))
        }
        SpdDesc::Samples(s) => DenseSpectrum::from_samples(s).ok_or(
            "spectral:emission:samples must be finite (nm, value) pairs sorted by wavelength",
        )?,
    };
    let lum = xyz::luminance(&dense);
    if lum.is_nan() || lum <= 0.0 {
        return Err("the emission spectrum has zero luminance".into());
    }
    Ok(Spectrum::Dense {
        data: Arc::new(dense),
        scale: (1.0 / lum) as f32,
    })
}

/// The colour temperatures (K) a tint is computed for; others are clamped to it (and the
/// scene builder says so).
pub const COLOR_TEMPERATURE_RANGE: (f32, f32) = (1000.0, 10000.0);

/// UsdLux colour temperature as a linear Rec.709 tint: the blackbody's chromaticity
/// converted to RGB, divided by that of 6500 K so that the default is exactly white
/// (the normalisation `UsdLuxBlackbodyTemperatureAsRgb` specifies), scaled to luminance 1.
pub fn color_temperature_rgb(kelvin: f32) -> [f32; 3] {
    let rgb_of = |k: f32| {
        let xyz = xyz::dense_to_xyz(&DenseSpectrum::from_fn(|l| blackbody::planck(l, k)));
        color::xyz_to_rgb(xyz)
    };
    let (lo, hi) = COLOR_TEMPERATURE_RANGE;
    let t = rgb_of(kelvin.clamp(lo, hi));
    let w = rgb_of(6500.0);
    let rel = [t[0] / w[0], t[1] / w[1], t[2] / w[2]];
    let y = color::rgb_to_xyz(rel)[1];
    rel.map(|c| (c / y).max(0.0) as f32)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lum(s: &Spectrum) -> f64 {
        xyz::luminance(&s.to_dense())
    }

    const FLAT: Photometric = Photometric {
        area: Some(2.0),
        flux_per_nit: Some(std::f32::consts::PI * 2.0),
        intensity_per_nit: Some(2.0),
    };

    #[test]
    fn intensity_exposure_and_normalize_set_the_luminance() {
        let e = EmissionDesc {
            intensity: 10.0,
            exposure: 2.0,
            ..Default::default()
        };
        assert!((lum(&radiance(&e, FLAT).unwrap()) / 40.0 - 1.0).abs() < 1e-3);
        let n = EmissionDesc {
            normalize: true,
            ..e.clone()
        };
        assert!((lum(&radiance(&n, FLAT).unwrap()) / 20.0 - 1.0).abs() < 1e-3);
    }

    #[test]
    fn named_spd_and_blackbody_are_normalised() {
        for spd in [
            SpdDesc::Named("CIE-A".into()),
            SpdDesc::Blackbody(3000.0),
            SpdDesc::Samples(vec![(400.0, 1.0), (700.0, 2.0)]),
        ] {
            let e = EmissionDesc {
                intensity: 5.0,
                spd: Some(spd),
                ..Default::default()
            };
            assert!((lum(&radiance(&e, FLAT).unwrap()) / 5.0 - 1.0).abs() < 1e-4);
        }
        let bad = EmissionDesc {
            spd: Some(SpdDesc::Named("CIE-Z9".into())),
            ..Default::default()
        };
        assert!(radiance(&bad, FLAT).unwrap_err().contains("CIE-Z9"));
    }

    #[test]
    fn photometric_overrides() {
        let e = EmissionDesc {
            luminous_flux: Some(1000.0),
            ..Default::default()
        };
        let l = lum(&radiance(&e, FLAT).unwrap());
        assert!((l * std::f64::consts::PI * 2.0 / 1000.0 - 1.0).abs() < 1e-3);
        let none = Photometric {
            area: None,
            flux_per_nit: None,
            intensity_per_nit: None,
        };
        assert!(radiance(&e, none).is_err());
    }

    #[test]
    fn color_temperature_6500_is_white() {
        let t = color_temperature_rgb(6500.0);
        for c in t {
            assert!((c - 1.0).abs() < 1e-4, "{t:?}");
        }
        let warm = color_temperature_rgb(2700.0);
        assert!(warm[0] > warm[2]);
    }
}
