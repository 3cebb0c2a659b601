//! Emission-weighted layers (`--illuminants`, `--light-groups`): extra images of the same
//! paths, each weighting them by its own emission. A path's throughput, its MIS weights and
//! the light selection do not depend on the emission *spectrum* (hero wavelength sampling,
//! Wilkie et al. 2014; the light sampler's weights are the lights' luminous powers, which a
//! replacement at the same luminance keeps, and which every layer shares), so a layer that
//! evaluates its own emission wherever the path tracer evaluates the scene's is the render
//! of the scene with that emission, from the same samples.
//!
//! - **Illuminant layers** replace every light's spectrum by an illuminant of
//!   `spectra/illuminants/` normalised to the same luminance: the replacement's base
//!   radiance L₀ (cd/m², the light's own normalisation of `intensity`, `exposure`,
//!   `normalize`, `spectral:luminousFlux`/`luminousIntensity`, before shaping) equals the
//!   original's, so its luminance, luminous intensity distribution and luminous flux are
//!   the original's too (for an untinted light; a `shaping:focusTint` filters the new
//!   spectrum as it filtered the old). Lights with a textured emission (a rect light's
//!   `inputs:texture:file`, a dome map, a textured `emissiveColor`) are refused: their
//!   chroma varies over the light and a single illuminant does not define it.
//! - **Light groups** keep the scene's emission of the group's lights and none of the
//!   others': the groups' layers sum to the image.

use super::emission::normalized_spd;
use super::Light;
use crate::desc::SpdDesc;
use crate::error::Reason;
use crate::spectral::{data, xyz, Spectrum};

/// The extra layers of a render; empty for none.
#[derive(Clone, Debug, Default)]
pub struct EmissionLayers {
    pub layers: Vec<EmissionLayer>,
}

/// One layer: its name (the EXR layer, `<name>.R`) and the emission it weights paths by.
#[derive(Clone, Debug)]
pub struct EmissionLayer {
    pub name: String,
    pub source: LayerSource,
}

/// What a layer's emitters are.
#[derive(Clone, Debug)]
pub enum LayerSource {
    /// Every light replaced (index for index the scene's lights, the same geometry).
    Replaced(Vec<Light>),
    /// The scene's own lights, those with `true` only.
    Group(Vec<bool>),
}

impl EmissionLayers {
    pub fn is_empty(&self) -> bool {
        self.layers.is_empty()
    }

    pub fn len(&self) -> usize {
        self.layers.len()
    }

    /// The layers' names, in order.
    pub fn names(&self) -> Vec<String> {
        self.layers.iter().map(|l| l.name.clone()).collect()
    }
}

/// The full name of an illuminant in `spectra/illuminants/`: `CIE-A`, or its short form `A`.
pub fn illuminant_name(name: &str) -> Reason<&'static str> {
    let names = data::illuminant_names();
    let prefixed = format!("CIE-{name}");
    names
        .iter()
        .find(|n| n.eq_ignore_ascii_case(name) || n.eq_ignore_ascii_case(&prefixed))
        .copied()
        .ok_or_else(|| {
            format!(
                "unknown illuminant '{name}' (known: {}; CIE-X may be written X)",
                names.join(", ")
            )
        })
}

/// The illuminant `name` (full name) normalised to a luminance of 1 cd/m².
pub fn unit_illuminant(name: &str) -> Reason<Spectrum> {
    normalized_spd(&SpdDesc::Named(name.to_string()))
}

/// `light` with its spectrum replaced by `unit` (luminance 1 cd/m²) at the same base
/// luminance L₀ (see the module docs); an error for a textured emission.
pub fn replaced(light: &Light, unit: &Spectrum) -> Reason<Light> {
    const TEXTURED: &str = "the light's emission is textured: its colour varies over the \
                            light and an illuminant does not replace it (render it without \
                            --illuminants)";
    let mut l = light.clone();
    let radiance = match &mut l {
        Light::Triangle(t) if t.texture.is_some() => return Err(TEXTURED.into()),
        Light::Rect(r) if r.texture.is_some() => return Err(TEXTURED.into()),
        Light::Dome(d) if d.map.is_some() => return Err(TEXTURED.into()),
        Light::Triangle(t) => &mut t.radiance,
        Light::Rect(r) => &mut r.radiance,
        Light::Disk(d) => &mut d.radiance,
        Light::Sphere(s) => &mut s.radiance,
        Light::Point(p) => &mut p.sphere.radiance,
        Light::Cylinder(c) => &mut c.radiance,
        Light::Line(l) => &mut l.cylinder.radiance,
        Light::Distant(d) => &mut d.radiance,
        Light::Dome(d) => &mut d.radiance,
    };
    let luminance = xyz::luminance(&radiance.to_dense());
    *radiance = unit.scaled(luminance as f32);
    Ok(l)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::light::DistantLight;
    use glam::Vec3;

    #[test]
    fn short_and_full_illuminant_names() {
        assert_eq!(illuminant_name("A").unwrap(), "CIE-A");
        assert_eq!(illuminant_name("d65").unwrap(), "CIE-D65");
        assert_eq!(illuminant_name("LED-B3").unwrap(), "LED-B3");
        assert!(illuminant_name("Z9").unwrap_err().contains("CIE-F11"));
    }

    #[test]
    fn a_replacement_keeps_the_luminance() {
        let sun = Light::Distant(DistantLight {
            prim_path: "/Sun".into(),
            to_light: Vec3::Y,
            cos_theta_max: 1.0,
            one_minus_cos: 0.0,
            radiance: unit_illuminant("CIE-D65").unwrap().scaled(1234.0),
        });
        for name in ["CIE-A", "CIE-F11", "LED-B3"] {
            let r = replaced(&sun, &unit_illuminant(name).unwrap()).unwrap();
            let Light::Distant(d) = r else { unreachable!() };
            let y = xyz::luminance(&d.radiance.to_dense());
            assert!((y / 1234.0 - 1.0).abs() < 1e-5, "{name}: {y}");
        }
    }
}
