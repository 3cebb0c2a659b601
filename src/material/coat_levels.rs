//! Coat albedos precomputed for textured inputs: the layered models scale their base by the
//! coat's directional albedo E(μ) and average transmittance T̄ (`bxdf::coat`), which cost a
//! quadrature per roughness. A textured roughness (or clearcoat roughness) therefore uses the
//! nearest of [`ROUGHNESS_LEVELS`] roughnesses precomputed when the scene is built, while the
//! GGX α of the lobe itself stays exact per lookup.
//!
//! Levels are uniform in the perceptual roughness r = √α (UsdPreviewSurface roughness;
//! Δr = 1/32), where E changes most evenly. A Schlick coat whose F0 is textured needs no
//! extra levels: E and T̄ are linear in F0 (Schlick: F = F0 + (1 − F0)(1 − cos)⁵, and E is an
//! integral of F), so the values at F0 = 0 and F0 = 1 give every other one exactly
//! ([`CoatAlbedo::lerp`]).

use crate::bxdf::coat::ScalarFresnel;
use crate::bxdf::{CoatAlbedo, TrowbridgeReitz};

/// Roughness levels of a textured roughness: r = k / (N − 1).
pub const ROUGHNESS_LEVELS: usize = 33;

/// E(μ) and T̄ of one coat Fresnel at one roughness (constant input) or at every level.
#[derive(Clone, Debug)]
pub struct CoatLevels {
    albedo: Vec<CoatAlbedo>,
    t_avg: Vec<f32>,
}

impl CoatLevels {
    /// The coat at every level r_k = k / (N − 1), α = r_k².
    pub fn levels(fresnel: ScalarFresnel) -> CoatLevels {
        let last = (ROUGHNESS_LEVELS - 1) as f32;
        Self::at_roughnesses((0..ROUGHNESS_LEVELS).map(|k| k as f32 / last), fresnel)
    }

    /// The coat at one perceptual roughness `r` (α = r²).
    pub fn single(r: f32, fresnel: ScalarFresnel) -> CoatLevels {
        Self::at_roughnesses(std::iter::once(r), fresnel)
    }

    fn at_roughnesses(r: impl Iterator<Item = f32>, fresnel: ScalarFresnel) -> CoatLevels {
        let albedo: Vec<CoatAlbedo> = r
            .map(|r| CoatAlbedo::new(TrowbridgeReitz::isotropic(r * r), fresnel))
            .collect();
        let t_avg = albedo
            .iter()
            .map(CoatAlbedo::average_transmittance)
            .collect();
        CoatLevels { albedo, t_avg }
    }

    /// The level nearest to perceptual roughness `r` ∈ [0, 1] (the only one when single).
    #[inline]
    pub fn level(&self, r: f32) -> usize {
        let last = self.albedo.len() - 1;
        ((r * last as f32).round().max(0.0) as usize).min(last)
    }

    /// E and T̄ at level `k`.
    #[inline]
    pub fn get(&self, k: usize) -> (CoatAlbedo, f32) {
        (self.albedo[k], self.t_avg[k])
    }
}

/// A Schlick coat with a textured F0: its albedo at F0 = 0 and at F0 = 1.
#[derive(Clone, Debug)]
pub struct SchlickLevels {
    pub f0_zero: CoatLevels,
    pub f0_one: CoatLevels,
}

impl SchlickLevels {
    /// At every roughness level (`textured_roughness`) or at the one roughness `r`.
    pub fn new(textured_roughness: bool, r: f32) -> SchlickLevels {
        let make = |f0: f32| {
            let f = ScalarFresnel::Schlick { f0 };
            if textured_roughness {
                CoatLevels::levels(f)
            } else {
                CoatLevels::single(r, f)
            }
        };
        SchlickLevels {
            f0_zero: make(0.0),
            f0_one: make(1.0),
        }
    }

    /// E and T̄ at level `k` for Schlick F0 = `f0` (exact: both are linear in F0).
    #[inline]
    pub fn get(&self, k: usize, f0: f32) -> (CoatAlbedo, f32) {
        let ((e0, t0), (e1, t1)) = (self.f0_zero.get(k), self.f0_one.get(k));
        (CoatAlbedo::lerp(&e0, &e1, f0), t0 + f0 * (t1 - t0))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn levels_are_nearest_and_clamped() {
        let l = CoatLevels::levels(ScalarFresnel::Dielectric { eta: 1.5 });
        assert_eq!(l.level(0.0), 0);
        assert_eq!(l.level(0.5), 16);
        assert_eq!(l.level(0.51), 16);
        assert_eq!(l.level(1.7), ROUGHNESS_LEVELS - 1);
        assert_eq!(l.level(-0.3), 0);
        let one = CoatLevels::single(0.37, ScalarFresnel::Dielectric { eta: 1.5 });
        assert_eq!(one.level(0.9), 0);
        let direct = CoatAlbedo::new(
            TrowbridgeReitz::isotropic(0.37 * 0.37),
            ScalarFresnel::Dielectric { eta: 1.5 },
        );
        assert_eq!(one.get(0).0, direct);
    }

    /// The albedo interpolated between F0 = 0 and 1 is the albedo computed at F0.
    #[test]
    fn schlick_albedo_is_linear_in_f0() {
        for (textured, r) in [(false, 0.0), (false, 0.45), (true, 0.0)] {
            let s = SchlickLevels::new(textured, r);
            let k = if textured { 20 } else { 0 };
            let r = if textured { 20.0 / 32.0 } else { r };
            for f0 in [0.04f32, 0.3, 0.8] {
                let (e, t) = s.get(k, f0);
                let direct = CoatLevels::single(r, ScalarFresnel::Schlick { f0 });
                let (de, dt) = direct.get(0);
                assert!((t - dt).abs() < 1e-5, "{t} vs {dt}");
                for mu in [0.05f32, 0.3, 0.7, 1.0] {
                    assert!((e.eval(mu) - de.eval(mu)).abs() < 1e-5, "{f0} {mu}");
                }
            }
        }
    }
}
