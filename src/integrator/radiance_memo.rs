//! A light's radiance at a path's wavelengths, kept from one vertex to the next: next event
//! estimation at every vertex of a path samples the same lights at the same wavelength tuple,
//! and an untextured mesh light emits one spectrum everywhere (`Light::uniform_radiance`), so
//! its evaluation (a tabulated spectrum at four wavelengths) is needed once per path and
//! mesh, not once per light sample. One entry, keyed by the light's radiance class
//! (`light::radiance_class`: the triangles of one emissive mesh share it). The value is the
//! light's own evaluation (its class's lights evaluate to the same bits), so light samples
//! carry the same bits as without the memo.

use crate::light::Light;
use crate::spectral::{SampledSpectrum, SampledWavelengths};

#[derive(Clone, Copy, Debug)]
pub(crate) struct RadianceMemo {
    /// The radiance class the entry holds (`u32::MAX`: none).
    class: u32,
    /// The wavelengths' bits it was evaluated at.
    lambda: [u32; 4],
    le: Option<SampledSpectrum>,
}

impl RadianceMemo {
    pub const EMPTY: RadianceMemo = RadianceMemo {
        class: u32::MAX,
        lambda: [0; 4],
        le: None,
    };

    /// `lights[light].uniform_radiance(lambda)`, evaluated when the entry holds another class
    /// (`classes[light]`, `light::radiance_class::radiance_classes` of `lights`) or other
    /// wavelengths. The test is inlined at the caller and the evaluation is not (`fill`): left
    /// to LLVM, the whole was a call at every light sample in some builds (design.md §8,
    /// "The per-sample cost, seventh pass").
    #[inline(always)]
    pub fn get(
        &mut self,
        (lights, classes): (&[Light], &[u32]),
        light: usize,
        lambda: &SampledWavelengths,
    ) -> Option<SampledSpectrum> {
        let bits = lambda.lambda.map(f32::to_bits);
        let class = classes[light];
        if self.class != class || self.lambda != bits {
            self.fill(&lights[light], class, lambda);
        }
        self.le
    }

    /// Evaluates `light` (of radiance class `class`) at `lambda` into the entry.
    #[inline]
    fn fill(&mut self, light: &Light, class: u32, lambda: &SampledWavelengths) {
        *self = RadianceMemo {
            class,
            lambda: lambda.lambda.map(f32::to_bits),
            le: light.uniform_radiance(lambda),
        };
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::light::TriangleLight;
    use crate::spectral::Spectrum;
    use glam::Vec3;

    fn triangle(kelvin: f32) -> Light {
        let p = [Vec3::ZERO, Vec3::X, Vec3::Y];
        let radiance = Spectrum::Blackbody { kelvin, scale: 1.0 };
        Light::Triangle(TriangleLight::new("/L".into(), p, radiance, false))
    }

    #[test]
    fn the_memo_is_the_lights_radiance_per_light_and_tuple() {
        let lights = [triangle(3000.0), triangle(6500.0)];
        let classes = crate::light::radiance_class::radiance_classes(&lights);
        let (a, b) = (
            SampledWavelengths::sample_visible(0.25),
            SampledWavelengths::sample_visible(0.75),
        );
        let mut memo = RadianceMemo::EMPTY;
        for (light, lambda) in [(0, &a), (0, &a), (1, &a), (1, &b), (0, &b), (0, &a)] {
            let want = lights[light].uniform_radiance(lambda);
            assert!(want.is_some());
            assert_eq!(memo.get((&lights, &classes), light, lambda), want);
        }
        // The four (light, tuple) pairs give four different spectra: a stale entry would show.
        let all = [(0, &a), (1, &a), (0, &b), (1, &b)].map(|(l, w)| lights[l].uniform_radiance(w));
        for i in 0..4 {
            for j in 0..i {
                assert_ne!(all[i], all[j]);
            }
        }
    }
}
