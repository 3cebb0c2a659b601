//! Every light's luminous power, and the infinite lights' share of it, P∞: what the samplers
//! that choose by importance at the receiver (`spatial.rs`, `tree.rs`) keep of the power
//! sampler (PBR 4ed §12.6.2). Light subpaths start without a receiver and choose by power; next
//! event estimation gives the infinite lights (which have no bounds) P∞ and chooses among them
//! by power, so an infinite light's probability is its power's share either way.

use super::Light;
use crate::sampling::Distribution1D;

#[derive(Clone, Debug)]
pub struct PowerShare {
    power: Distribution1D,
    infinite: Vec<usize>,
    /// P∞: the infinite lights' share of the power.
    pub p_infinite: f32,
}

impl PowerShare {
    /// The powers of `lights`, or None when they have no power at all.
    pub fn new(lights: &[Light], scene_radius: f32) -> Option<PowerShare> {
        let weights: Vec<f32> = lights
            .iter()
            .map(|l| l.luminous_power(scene_radius))
            .collect();
        let total: f64 = weights.iter().map(|&w| f64::from(w)).sum();
        if !(total > 0.0 && total.is_finite()) {
            return None;
        }
        let power = Distribution1D::new(&weights);
        let infinite: Vec<usize> = (0..lights.len())
            .filter(|&i| lights[i].is_infinite())
            .collect();
        let p_infinite = infinite.iter().map(|&i| power.discrete_pmf(i)).sum();
        Some(PowerShare {
            power,
            infinite,
            p_infinite,
        })
    }

    /// A light chosen by power (light subpaths).
    pub fn sample(&self, u: f32) -> Option<(usize, f32)> {
        let (i, pmf, _) = self.power.sample_discrete(u);
        (pmf > 0.0).then_some((i, pmf))
    }

    /// [`Self::sample`]'s probability of `light`: its share of the power.
    pub fn pmf(&self, light: usize) -> f32 {
        self.power.discrete_pmf(light)
    }

    /// An infinite light chosen by power among the infinite lights, for u in [0, P∞): its
    /// probability overall is its power's share.
    pub fn sample_infinite(&self, u: f32) -> Option<(usize, f32)> {
        let mut acc = 0.0;
        let mut last = None;
        for &i in &self.infinite {
            let p = self.power.discrete_pmf(i);
            if p == 0.0 {
                continue;
            }
            acc += p;
            last = Some((i, p));
            if u < acc {
                break;
            }
        }
        last
    }
}
