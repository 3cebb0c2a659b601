//! Lights that emit the same spectrum everywhere and the same as each other: the triangles of
//! one emissive mesh. Found once per scene, so that a path that keeps a light's radiance at
//! its wavelengths (`integrator::radiance_memo`) keeps it for the whole mesh, whichever of
//! its triangles next event estimation picks.

use super::Light;

/// Per light, the first light of its run of consecutive lights whose
/// [`Light::uniform_radiance`] is the same function of λ, bit for bit (the same spectrum:
/// the same variant and the same bits); a light without a uniform radiance is its own class.
/// Consecutive only: a mesh's triangles are consecutive lights, and the scan stays linear.
pub fn radiance_classes(lights: &[Light]) -> Vec<u32> {
    let mut classes = Vec::with_capacity(lights.len());
    for (i, light) in lights.iter().enumerate() {
        let same = i > 0 && same_uniform_radiance(&lights[i - 1], light);
        classes.push(if same { classes[i - 1] } else { i as u32 });
    }
    classes
}

/// True when both lights have a uniform radiance and it is the same spectrum bit for bit.
fn same_uniform_radiance(a: &Light, b: &Light) -> bool {
    match (a, b) {
        (Light::Triangle(s), Light::Triangle(t)) => {
            s.texture.is_none() && t.texture.is_none() && s.radiance.same_bits(&t.radiance)
        }
        _ => false,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::light::{DistantLight, TriangleLight};
    use crate::spectral::Spectrum;
    use glam::Vec3;

    fn triangle(radiance: Spectrum) -> Light {
        let p = [Vec3::ZERO, Vec3::X, Vec3::Y];
        Light::Triangle(TriangleLight::new("/L".into(), p, radiance, false))
    }

    #[test]
    fn consecutive_triangles_of_one_spectrum_share_a_class() {
        let warm = Spectrum::Blackbody {
            kelvin: 3000.0,
            scale: 1.0,
        };
        let lights = [
            triangle(warm.clone()),
            triangle(warm.clone()),
            triangle(Spectrum::Constant(0.0)),
            triangle(Spectrum::Constant(-0.0)),
            triangle(Spectrum::Constant(-0.0)),
            triangle(warm.clone()),
        ];
        assert_eq!(radiance_classes(&lights), vec![0, 0, 2, 3, 3, 5]);
        // Shared classes evaluate to the same bits at any wavelengths.
        let lambda = crate::spectral::SampledWavelengths::sample_visible(0.3);
        let le = |i: usize| lights[i].uniform_radiance(&lambda).unwrap();
        assert_eq!(le(0).0.map(f32::to_bits), le(1).0.map(f32::to_bits));
    }

    #[test]
    fn lights_without_a_uniform_radiance_are_their_own_class() {
        let sun = || {
            Light::Distant(DistantLight {
                prim_path: "/Sun".into(),
                to_light: Vec3::Y,
                cos_theta_max: 1.0,
                one_minus_cos: 0.0,
                radiance: Spectrum::Constant(1.0),
            })
        };
        assert_eq!(radiance_classes(&[sun(), sun()]), vec![0, 1]);
        let t = triangle(Spectrum::Constant(1.0));
        assert_eq!(
            radiance_classes(&[sun(), t.clone(), sun(), t]),
            vec![0, 1, 2, 3]
        );
        assert!(radiance_classes(&[]).is_empty());
    }
}
