//! Choosing a light: in proportion to its luminous power (PBR 4ed §12.6.2,
//! PowerLightSampler), or for next-event estimation by the lights' importance at the receiver:
//! exhaustively over a few prims of bounded lights (`spatial.rs`), through a tree over many
//! (`tree.rs`). A scene with a single light needs no table: it is
//! chosen with probability 1 without a lookup (the table would give the same index and pmf,
//! exactly: its CDF is [0, 1]).

use super::spatial::{SpatialSampler, MAX_GROUPS};
use super::tree::LightTree;
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
    /// Next-event estimation down a tree of the bounded lights (`tree.rs`), light subpaths by
    /// power.
    Tree(Box<LightTree>),
}

impl LightSampler {
    /// The sampler of `lights`: none for one light, the spatial one for 2 to [`MAX_GROUPS`]
    /// prims of bounded lights, the tree for more than [`MAX_GROUPS`] bounded lights otherwise
    /// (more prims, or one emissive mesh of many triangles), else the power table.
    pub fn new(lights: &[Light], scene_radius: f32) -> LightSampler {
        if lights.len() < 2 {
            return match lights.len() {
                0 => LightSampler::Empty,
                _ => LightSampler::Single,
            };
        }
        if let Some(s) = SpatialSampler::new(lights, scene_radius) {
            return LightSampler::Spatial(Box::new(s));
        }
        match LightTree::new(lights, scene_radius, MAX_GROUPS) {
            Some(t) => LightSampler::Tree(Box::new(t)),
            None => LightSampler::table(lights, scene_radius),
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
            LightSampler::Tree(t) => t.sample_by_power(u),
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
            LightSampler::Tree(t) => t.pmf_by_power(light),
        }
    }

    /// (light index, probability) for next-event estimation at the receiver `ctx`.
    #[inline]
    pub fn sample_at(&self, ctx: &LightSampleContext, u: f32) -> Option<(usize, f32)> {
        match self {
            LightSampler::Spatial(s) => s.sample(ctx, u),
            LightSampler::Tree(t) => t.sample(ctx, u),
            _ => self.sample(u),
        }
    }

    /// The probability that [`sample_at`](Self::sample_at) chooses `light` at `ctx`.
    #[inline]
    pub fn pmf_at(&self, ctx: &LightSampleContext, light: usize) -> f32 {
        match self {
            LightSampler::Spatial(s) => s.pmf(ctx, light),
            LightSampler::Tree(t) => t.pmf(ctx, light),
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
