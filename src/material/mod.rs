//! Materials: what the scene stores per material prim, turned into a [`Bsdf`] at a hit for
//! the path's wavelengths.

use crate::bxdf::{Bsdf, Bxdf, DiffuseBxdf};
use crate::spectral::{SampledWavelengths, Spectrum};
use glam::Vec3;

#[derive(Clone, Debug)]
pub enum Material {
    /// Lambertian reflection with a spectral reflectance in [0, 1].
    Diffuse { reflectance: Spectrum },
}

impl Material {
    /// The BSDF at a surface point with shading normal `ns`.
    #[inline]
    pub fn bsdf(&self, ns: Vec3, lambda: &SampledWavelengths) -> Bsdf {
        match self {
            Material::Diffuse { reflectance } => {
                let r = reflectance.sample(lambda).map(|v| v.clamp(0.0, 1.0));
                Bsdf::new(Bxdf::Diffuse(DiffuseBxdf { r }), ns)
            }
        }
    }
}
