//! The image's extra layers as EXR channels and attributes (`session::layers`).
//!
//! **Spectral radiance** follows Fichet, Pacanowski and Wilkie 2021, "An OpenEXR Layout for
//! Spectral Images" (JCGT 10(3)), §3: one float32 channel per bin named `S0.<λ>nm`, the
//! Stokes component S0 (unpolarised emissive data) and the bin's centre wavelength with a
//! comma as its decimal separator (`S0.367,343750nm`), and the string attributes
//! `spectralLayoutVersion` = `1.0` and `emissiveUnits` = `W.m^-2.sr^-1` (the channels hold
//! spectral radiance per nm of the wavelength unit in their names). The values are the
//! bin-averaged spectral radiance × 2^exposure, on the scale of the RGB and XYZ layers
//! (`whiteLuminance` gives it back as absolute). `spectralRender:spectralBins` records the
//! bins as `MIN,MAX,COUNT` (nm).
//!
//! **AOVs.** `variance.Y`: per pixel, the estimated variance of the pixel's mean luminance
//! (cd/m²)², × 2^(2·exposure), from the film's even and odd halves (`sensor::film`); −1 where
//! a pixel has fewer than 2 samples. `P.X/Y/Z`, `N.X/Y/Z`, `Z` (`--aov position`, `normal` or
//! `depth`: the three come together): the mean over the pixel's samples of the first surface
//! its camera ray meets (pbrt-v4's GBufferFilm conventions): position and geometric normal in
//! OpenEXR's camera space (`worldToCamera`: x right, y up, z along the view, metres), and the
//! depth Z = P.z; 0 where no sample hit anything. `albedo.R/G/B` (`--aov albedo`): pbrt-v4's
//! GBufferFilm albedo, the mean over the pixel's samples of the directional-hemispherical
//! reflectance ρ_hd(ωo) of the BSDF at the first hit, whatever its lobes (0 for samples that
//! escaped or met a light's shape), converted to RGB with each sample's wavelengths as the
//! reflectance under the working space's white at Y = 1 (a white Lambertian is (1, 1, 1); not
//! scaled by the exposure).
//!
//! **Samples per pixel** (an adaptive render, `--adaptive`): the channel `samples` holds each
//! pixel's sample count, and the string attribute `spectralRender:adaptive` the allocation's
//! settings and the counts' range (`session::adaptive`).
//!
//! **Emission layers** (`--illuminants`, `--light-groups`): per layer `<name>.R/G/B` in the
//! EXR's working space (as `R`, `G`, `B`) and `<name>.XYZ.X/Y/Z`, absolute, × 2^exposure like
//! the image's; with `--spectral`, its spectral radiance `<name>.S0.<λ>nm` in the bins of the
//! image's own spectral channels.

use super::exr::ExrLayers;
use crate::sensor::spectral_film::SpectralImage;
use crate::session::emission_layers::EmissionImage;
use crate::session::layers::LayerImages;
use crate::spectral::working_space::WorkingSpace;

/// The layout version the spectral channels follow (Fichet et al. 2021).
pub const SPECTRAL_LAYOUT_VERSION: &str = "1.0";
/// The unit of the emissive spectral channels (Fichet et al. 2021, §3.2).
pub const EMISSIVE_UNITS: &str = "W.m^-2.sr^-1";
/// The variance of the pixel's mean luminance (`--aov variance`).
pub const VARIANCE_CHANNEL: &str = "variance.Y";
pub const SPECTRAL_BINS_ATTRIBUTE: &str = "spectralRender:spectralBins";
/// An adaptive render's samples per pixel.
pub const SAMPLES_CHANNEL: &str = "samples";
/// An adaptive render's settings and counts.
pub const ADAPTIVE_ATTRIBUTE: &str = "spectralRender:adaptive";
/// The first hit's albedo (`--aov albedo`), RGB in the EXR's working space.
pub const ALBEDO_CHANNELS: [&str; 3] = ["albedo.R", "albedo.G", "albedo.B"];

/// The channels and attributes of `layers`, RGB in `space`.
pub fn exr_layers(layers: &LayerImages, space: WorkingSpace) -> ExrLayers {
    let mut out = ExrLayers::default();
    for e in &layers.emission {
        emission(e, space, &mut out);
    }
    if let Some(s) = &layers.spectral {
        spectral(s, &mut out);
    }
    if let Some(v) = &layers.variance {
        out.channels.push((VARIANCE_CHANNEL.to_string(), v.clone()));
    }
    if let Some(a) = &layers.adaptive {
        out.channels
            .push((SAMPLES_CHANNEL.to_string(), a.samples.clone()));
        out.strings
            .push((ADAPTIVE_ATTRIBUTE.to_string(), a.summary.clone()));
    }
    if let Some(f) = &layers.first_hit {
        for (c, axis) in ["X", "Y", "Z"].iter().enumerate() {
            let p = f.position.iter().map(|v| v[c]).collect();
            out.channels.push((format!("P.{axis}"), p));
            let n = f.normal.iter().map(|v| v[c]).collect();
            out.channels.push((format!("N.{axis}"), n));
        }
        out.channels
            .push(("Z".into(), f.position.iter().map(|v| v[2]).collect()));
    }
    if let Some(a) = &layers.albedo {
        let rgb = space.convert(a);
        for (c, name) in ALBEDO_CHANNELS.iter().enumerate() {
            out.channels
                .push((name.to_string(), rgb.iter().map(|p| p[c]).collect()));
        }
    }
    out
}

/// The channel name of an emissive, unpolarised bin centred on `nm`.
pub fn spectral_channel(nm: f64) -> String {
    format!("S0.{}nm", format!("{nm:.6}").replace('.', ","))
}

/// An emission layer's RGB (the image's own conversion in linear Rec.709), XYZ and bins.
fn emission(e: &EmissionImage, space: WorkingSpace, out: &mut ExrLayers) {
    let converted;
    let rgb = match space {
        WorkingSpace::LinRec709 => &e.rgb,
        space => {
            converted = space.convert(&e.xyz);
            &converted
        }
    };
    for (c, name) in ["R", "G", "B"].iter().enumerate() {
        let v = rgb.iter().map(|p| p[c]).collect();
        out.channels.push((format!("{}.{name}", e.name), v));
    }
    for (c, name) in ["X", "Y", "Z"].iter().enumerate() {
        let v = e.xyz.iter().map(|p| p[c]).collect();
        out.channels.push((format!("{}.XYZ.{name}", e.name), v));
    }
    if let Some(s) = &e.spectral {
        for (i, image) in s.images.iter().enumerate() {
            let name = format!("{}.{}", e.name, spectral_channel(s.bins.centre(i)));
            out.channels.push((name, image.clone()));
        }
    }
}

fn spectral(s: &SpectralImage, out: &mut ExrLayers) {
    for (i, image) in s.images.iter().enumerate() {
        out.channels
            .push((spectral_channel(s.bins.centre(i)), image.clone()));
    }
    let strings = [
        ("spectralLayoutVersion", SPECTRAL_LAYOUT_VERSION.to_string()),
        ("emissiveUnits", EMISSIVE_UNITS.to_string()),
        (
            SPECTRAL_BINS_ATTRIBUTE,
            format!("{},{},{}", s.bins.min, s.bins.max, s.bins.count),
        ),
    ];
    out.strings
        .extend(strings.into_iter().map(|(k, v)| (k.to_string(), v)));
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn channel_names_follow_the_layout() {
        assert_eq!(spectral_channel(560.0), "S0.560,000000nm");
        assert_eq!(spectral_channel(367.34375), "S0.367,343750nm");
    }
}
