//! Choosing a light for next-event estimation in proportion to its luminous power
//! (PBR 4ed §12.6.2, PowerLightSampler).

use super::Light;
use crate::sampling::Distribution1D;

#[derive(Clone, Debug, Default)]
pub struct LightSampler {
    distribution: Distribution1D,
}

impl LightSampler {
    pub fn new(lights: &[Light], scene_radius: f32) -> LightSampler {
        let weights: Vec<f32> = lights
            .iter()
            .map(|l| l.luminous_power(scene_radius))
            .collect();
        LightSampler {
            distribution: Distribution1D::new(&weights),
        }
    }

    /// (light index, probability), or None when there are no lights.
    #[inline]
    pub fn sample(&self, u: f32) -> Option<(usize, f32)> {
        if self.distribution.is_empty() {
            return None;
        }
        let (i, pmf, _) = self.distribution.sample_discrete(u);
        (pmf > 0.0).then_some((i, pmf))
    }

    #[inline]
    pub fn pmf(&self, light: usize) -> f32 {
        if self.distribution.is_empty() {
            return 0.0;
        }
        self.distribution.discrete_pmf(light)
    }
}
