//! Which kinds of lobe a material scatters light with, as pbrt-v4's `BxDFFlags` (PBR 4ed
//! §9.1.2: reflection, transmission, diffuse, glossy, specular), read from the built
//! [`Material`]. A glossy lobe narrower than [`NEAR_SPECULAR_ALPHA`] is also
//! `NEAR_SPECULAR`: for the path classes of the analysis (caustics, SDS) it behaves as a
//! mirror, since a small light seen in it is found by BSDF sampling about as rarely as in a
//! mirror.

use crate::bxdf::TrowbridgeReitz;
use crate::material::{AlphaTexture, Material};

/// GGX α below which a glossy lobe counts as near-specular for path classes. The GGX
/// distribution (Walter et al. 2007 eq. 33) falls to half its peak at tan θ_h ≈ 0.64 α, so at
/// α = 0.1 reflected directions spread over about ±7°: such a surface images a light of a few
/// centimetres at a metre nearly as a mirror does (docs/design.md §9).
pub const NEAR_SPECULAR_ALPHA: f32 = 0.1;

/// A set of lobe kinds.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Lobes(u8);

impl Lobes {
    pub const REFLECTION: Lobes = Lobes(1);
    pub const TRANSMISSION: Lobes = Lobes(2);
    pub const DIFFUSE: Lobes = Lobes(4);
    pub const GLOSSY: Lobes = Lobes(8);
    /// A Dirac delta lobe (smooth mirror or interface).
    pub const SPECULAR: Lobes = Lobes(16);
    /// A glossy lobe of α < [`NEAR_SPECULAR_ALPHA`].
    pub const NEAR_SPECULAR: Lobes = Lobes(32);

    const NAMES: [(Lobes, &'static str); 6] = [
        (Lobes::REFLECTION, "reflection"),
        (Lobes::TRANSMISSION, "transmission"),
        (Lobes::DIFFUSE, "diffuse"),
        (Lobes::GLOSSY, "glossy"),
        (Lobes::SPECULAR, "specular"),
        (Lobes::NEAR_SPECULAR, "near-specular"),
    ];

    pub fn contains(self, other: Lobes) -> bool {
        self.0 & other.0 == other.0
    }

    pub fn intersects(self, other: Lobes) -> bool {
        self.0 & other.0 != 0
    }

    /// Specular or near-specular: an S vertex of the path classes.
    pub fn specular_like(self) -> bool {
        self.intersects(Lobes::SPECULAR | Lobes::NEAR_SPECULAR)
    }

    /// Diffuse, or glossy and wider than [`NEAR_SPECULAR_ALPHA`]: a D vertex.
    pub fn diffuse_like(self) -> bool {
        self.contains(Lobes::DIFFUSE)
            || (self.contains(Lobes::GLOSSY) && !self.contains(Lobes::NEAR_SPECULAR))
    }

    /// The names of the kinds, e.g. "reflection, diffuse, specular".
    pub fn names(self) -> String {
        let names: Vec<&str> = Lobes::NAMES
            .iter()
            .filter(|(l, _)| self.contains(*l))
            .map(|(_, n)| *n)
            .collect();
        names.join(", ")
    }
}

impl std::ops::BitOr for Lobes {
    type Output = Lobes;
    fn bitor(self, o: Lobes) -> Lobes {
        Lobes(self.0 | o.0)
    }
}

impl std::ops::BitOrAssign for Lobes {
    fn bitor_assign(&mut self, o: Lobes) {
        self.0 |= o.0;
    }
}

/// A microfacet lobe of GGX α (`distrib`, or a texture, whose α varies: glossy).
fn microfacet(distrib: &TrowbridgeReitz, texture: Option<&AlphaTexture>) -> Lobes {
    if texture.is_some() {
        return Lobes::GLOSSY;
    }
    if distrib.effectively_smooth() {
        return Lobes::SPECULAR;
    }
    if distrib.alpha_x.max(distrib.alpha_y) < NEAR_SPECULAR_ALPHA {
        return Lobes::GLOSSY | Lobes::NEAR_SPECULAR;
    }
    Lobes::GLOSSY
}

/// The lobes `m` scatters with (an upper set: a lobe whose weight is a texture is included).
pub fn lobes(m: &Material) -> Lobes {
    let r = Lobes::REFLECTION;
    let rt = Lobes::REFLECTION | Lobes::TRANSMISSION;
    match m {
        Material::Diffuse { .. } | Material::OrenNayar { .. } => r | Lobes::DIFFUSE,
        Material::Conductor {
            distrib, roughness, ..
        } => r | microfacet(distrib, roughness.as_ref()),
        Material::Dielectric {
            distrib, roughness, ..
        } => rt | microfacet(distrib, roughness.as_ref()),
        Material::ThinDielectric { .. } => rt | Lobes::SPECULAR,
        Material::Plastic(p) => r | Lobes::DIFFUSE | microfacet(&p.distrib, p.roughness.as_ref()),
        Material::Preview(p) => {
            let t = &p.textures;
            let base = match &t.roughness {
                Some(_) => Lobes::GLOSSY,
                None => microfacet(&p.distrib, None),
            };
            let mut out = r | base;
            if p.metallic < 1.0 || t.metallic.is_some() {
                out |= Lobes::DIFFUSE;
            }
            if p.clearcoat > 0.0 || t.clearcoat.is_some() {
                out |= match &t.clearcoat_roughness {
                    Some(_) => Lobes::GLOSSY,
                    None => microfacet(&p.clearcoat_distrib, None),
                };
            }
            out
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::PlasticMaterial;
    use crate::spectral::sellmeier::Sellmeier;
    use crate::spectral::Spectrum;

    fn dielectric(alpha: f32) -> Material {
        Material::Dielectric {
            ior: Sellmeier::constant(1.5),
            distrib: TrowbridgeReitz::isotropic(alpha),
            roughness: None,
        }
    }

    #[test]
    fn smooth_glass_is_specular_both_ways_and_rough_glass_is_glossy() {
        let l = lobes(&dielectric(0.0));
        assert!(l.contains(Lobes::SPECULAR | Lobes::TRANSMISSION) && l.specular_like());
        assert!(!l.diffuse_like());
        let l = lobes(&dielectric(0.05));
        assert!(l.contains(Lobes::NEAR_SPECULAR) && l.specular_like() && !l.diffuse_like());
        let l = lobes(&dielectric(0.3));
        assert!(l.contains(Lobes::GLOSSY) && !l.specular_like() && l.diffuse_like());
        assert_eq!(l.names(), "reflection, transmission, glossy");
    }

    #[test]
    fn a_smooth_plastic_is_both_diffuse_and_specular() {
        let p = Material::Plastic(PlasticMaterial::new(Spectrum::Constant(0.5), 1.5, 0.0));
        let l = lobes(&p);
        assert!(l.specular_like() && l.diffuse_like());
    }
}
