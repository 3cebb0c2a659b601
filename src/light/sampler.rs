//! Choosing a light: in proportion to its luminous power (PBR 4ed §12.6.2,
//! PowerLightSampler), or for next-event estimation in scenes of a few bounded lights by its
//! importance at the receiver (`spatial.rs`). A scene with a single light needs no table: it is
//! chosen with probability 1 without a lookup (the table would give the same index and pmf,
//! exactly: its CDF is [0, 1]).

use super::spatial::SpatialSampler;
use super::{Light, LightSampleContext};
use crate::sampling::Distribution1D;

#[derive(Clone, Debug, Default)]
pub enum LightSampler {
    /// No lights.
    #[default]
    Empty,
    /// One light: index 0, probability 1.
    Single,
    /// A table of the lights' luminous powers.
    Power(Distribution1D),
    /// Next-event estimation by the lights' importance at the receiver (`spatial.rs`), light
    /// subpaths by power.
    Spatial(Box<SpatialSampler>),
}

impl LightSampler {
    /// The sampler of `lights`: none for one light, the spatial one for 2 to
    /// `spatial::MAX_GROUPS` prims of bounded lights, else the power table.
    pub fn new(lights: &[Light], scene_radius: f32) -> LightSampler {
        match lights.len() {
            0 => LightSampler::Empty,
            1 => LightSampler::Single,
            _ => match SpatialSampler::new(lights, scene_radius) {
                Some(s) => LightSampler::Spatial(Box::new(s)),
                None => LightSampler::table(lights, scene_radius),
            },
        }
    }

    /// The power table whatever the number of lights (a single light's too).
    pub fn table(lights: &[Light], scene_radius: f32) -> LightSampler {
        if lights.is_empty() {
            return LightSampler::Empty;
        }
        let weights: Vec<f32> = lights
            .iter()
            .map(|l| l.luminous_power(scene_radius))
            .collect();
        LightSampler::Power(Distribution1D::new(&weights))
    }

    /// (light index, probability) by power, without a receiver (the origin of a light
    /// subpath), or None when there are no lights.
    #[inline]
    pub fn sample(&self, u: f32) -> Option<(usize, f32)> {
        match self {
            LightSampler::Empty => None,
            LightSampler::Single => Some((0, 1.0)),
            LightSampler::Power(d) => {
                let (i, pmf, _) = d.sample_discrete(u);
                (pmf > 0.0).then_some((i, pmf))
            }
            LightSampler::Spatial(s) => s.sample_by_power(u),
        }
    }

    /// The probability that [`sample`](Self::sample) chooses `light`.
    #[inline]
    pub fn pmf(&self, light: usize) -> f32 {
        match self {
            LightSampler::Empty => 0.0,
            LightSampler::Single => 1.0,
            LightSampler::Power(d) => d.discrete_pmf(light),
            LightSampler::Spatial(s) => s.pmf_by_power(light),
        }
    }

    /// (light index, probability) for next-event estimation at the receiver `ctx`.
    #[inline]
    pub fn sample_at(&self, ctx: &LightSampleContext, u: f32) -> Option<(usize, f32)> {
        match self {
            LightSampler::Spatial(s) => s.sample(ctx, u),
            _ => self.sample(u),
        }
    }

    /// The probability that [`sample_at`](Self::sample_at) chooses `light` at `ctx`.
    #[inline]
    pub fn pmf_at(&self, ctx: &LightSampleContext, light: usize) -> f32 {
        match self {
            LightSampler::Spatial(s) => s.pmf(ctx, light),
            _ => self.pmf(light),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::light::{DistantLight, Light};
    use crate::spectral::Spectrum;
    use glam::Vec3;

    #[test]
    fn a_single_light_is_chosen_as_its_table_would_choose_it() {
        let sun = Light::Distant(DistantLight {
            prim_path: "/Sun".into(),
            to_light: Vec3::Y,
            cos_theta_max: 1.0,
            one_minus_cos: 0.0,
            radiance: Spectrum::Constant(1.0),
        });
        let (single, table) = (
            LightSampler::new(std::slice::from_ref(&sun), 1.0),
            LightSampler::table(std::slice::from_ref(&sun), 1.0),
        );
        assert!(matches!(single, LightSampler::Single));
        for u in [0.0, 0.3, 0.999_999] {
            assert_eq!(single.sample(u), table.sample(u));
        }
        assert_eq!(single.pmf(0), table.pmf(0));
    }
}
