//! Choosing a light for next-event estimation by its importance at the receiver, for scenes
//! of a few bounded lights (PBR 4ed §12.6.3's exhaustive sampler, `ExhaustiveLightSampler`,
//! over the lights' prims; the importance of Conty Estevez and Kulla 2018, `bounds.rs`).
//!
//! The power sampler (`sampler.rs`, PBR 4ed §12.6.2) gives a panel across the room the same
//! share of the light samples as the one above the receiver. Here:
//! - the infinite lights keep their share of the luminous power, P∞ = Σ∞ φ / Σ φ, and are
//!   chosen among themselves by power, as before;
//! - the bounded lights are grouped by prim (an emissive mesh is a light per triangle, a
//!   UsdLux light is one light), and the groups share 1 − P∞ in proportion to their
//!   importance I_g(p, n) at the receiver; within a group a light is chosen by power:
//!   p(i | p, n) = (1 − P∞) · I_g / Σ_h I_h · φᵢ / φ_g.
//!
//! A group's bounds are its lights' box, power and normal cone together (the cone's axis is
//! its first light's, its half-angle the largest angle to another's, every direction if one
//! emits everywhere). A group of importance 0 cannot reach the receiver (the bounds are
//! conservative) and is never chosen, so the estimate stays unbiased; where every group's
//! importance is 0 no bounded light is chosen. Each choice evaluates every group's
//! importance, so the sampler serves 2 to [`MAX_GROUPS`] groups; a scene with one group (a
//! mesh light, the peers' Cornell box) or more keeps the power sampler. The probability of a
//! choice (`pmf`) repeats the same sums in the same order, so it is exactly the one `sample`
//! returned.

use super::bounds::Bounds4;
use super::power_share::PowerShare;
use super::{Light, LightBounds, LightSampleContext};
use crate::sampling::Distribution1D;

/// The most groups (bounded prims) a scene may have for the spatial sampler.
pub const MAX_GROUPS: usize = 32;

/// The lights of one prim.
#[derive(Clone, Debug)]
struct Group {
    bounds: LightBounds,
    /// The lights' indices among the scene's lights.
    lights: Vec<usize>,
    /// Their powers' table (None for a single light).
    table: Option<Distribution1D>,
}

#[derive(Clone, Debug)]
pub struct SpatialSampler {
    groups: Vec<Group>,
    /// The groups' bounds, four to a chunk, for their importances four at a time.
    chunks: Vec<Bounds4>,
    /// Per scene light: (its group, its position in the group); `u32::MAX` for an infinite one.
    member: Vec<(u32, u32)>,
    /// Every light's power, and the infinite lights' share P∞.
    share: PowerShare,
}

impl SpatialSampler {
    /// The sampler of `lights`, or None when the spatial choice is not taken: fewer than two
    /// or more than [`MAX_GROUPS`] groups of bounded lights, or no power at all.
    pub fn new(lights: &[Light], scene_radius: f32) -> Option<SpatialSampler> {
        let (groups, member) = group(lights)?;
        let share = PowerShare::new(lights, scene_radius)?;
        let bounds: Vec<LightBounds> = groups.iter().map(|g| g.bounds).collect();
        let chunks = bounds.chunks(4).map(Bounds4::new).collect();
        Some(SpatialSampler {
            groups,
            chunks,
            member,
            share,
        })
    }

    /// The groups' importances at `ctx` and their sum.
    #[inline]
    fn importances(&self, ctx: &LightSampleContext) -> ([f32; MAX_GROUPS], f32) {
        let mut imp = [0.0f32; MAX_GROUPS];
        for (c, chunk) in self.chunks.iter().enumerate() {
            imp[4 * c..4 * c + 4].copy_from_slice(&chunk.importance(ctx.p, ctx.n));
        }
        let sum = imp[..self.groups.len()].iter().sum();
        (imp, sum)
    }

    /// (light index, probability) for the receiver `ctx`, or None when no light is chosen.
    pub fn sample(&self, ctx: &LightSampleContext, u: f32) -> Option<(usize, f32)> {
        let p_infinite = self.share.p_infinite;
        if u < p_infinite {
            return self.share.sample_infinite(u);
        }
        let (imp, sum) = self.importances(ctx);
        if sum <= 0.0 {
            return None;
        }
        let share = 1.0 - p_infinite;
        let target = ((u - p_infinite) / share).min(1.0) * sum;
        let (k, below) = pick(&imp[..self.groups.len()], target)?;
        let p_group = share * (imp[k] / sum);
        let g = &self.groups[k];
        match &g.table {
            None => Some((g.lights[0], p_group)),
            Some(t) => {
                let v = ((target - below) / imp[k]).clamp(0.0, 1.0 - f32::EPSILON / 2.0);
                let (m, pm, _) = t.sample_discrete(v);
                (pm > 0.0).then_some((g.lights[m], p_group * pm))
            }
        }
    }

    /// The probability that `sample` chooses `light` at `ctx`.
    pub fn pmf(&self, ctx: &LightSampleContext, light: usize) -> f32 {
        let (k, m) = self.member[light];
        if k == u32::MAX {
            // An infinite light: its power's share, as the power sampler gives it.
            return self.share.pmf(light);
        }
        let (imp, sum) = self.importances(ctx);
        if sum <= 0.0 {
            return 0.0;
        }
        let g = &self.groups[k as usize];
        let p_group = (1.0 - self.share.p_infinite) * (imp[k as usize] / sum);
        match &g.table {
            None => p_group,
            Some(t) => p_group * t.discrete_pmf(m as usize),
        }
    }

    /// The power sampler's choice, for light subpaths (they start without a receiver).
    pub fn sample_by_power(&self, u: f32) -> Option<(usize, f32)> {
        self.share.sample(u)
    }

    /// The power sampler's probability of `light`.
    pub fn pmf_by_power(&self, light: usize) -> f32 {
        self.share.pmf(light)
    }
}

/// The first index k of a nonzero weight with `target` < Σ_{j≤k} wⱼ (the last nonzero one if
/// `target` reaches the sum), and Σ_{j<k} wⱼ; None when every weight is 0. Zero weights are
/// skipped, so they are never chosen.
#[inline]
pub(super) fn pick(weights: &[f32], target: f32) -> Option<(usize, f32)> {
    let (mut below, mut chosen) = (0.0f32, None);
    for (k, &w) in weights.iter().enumerate() {
        if w == 0.0 {
            continue;
        }
        chosen = Some((k, below));
        if target < below + w {
            break;
        }
        below += w;
    }
    chosen
}

/// The bounded lights grouped by prim path (in order of first appearance), and each light's
/// (group, position); None unless there are 2 to [`MAX_GROUPS`] groups.
#[allow(clippy::type_complexity)]
fn group(lights: &[Light]) -> Option<(Vec<Group>, Vec<(u32, u32)>)> {
    let mut groups: Vec<Group> = Vec::new();
    let mut member = vec![(u32::MAX, u32::MAX); lights.len()];
    let mut by_path: std::collections::HashMap<&str, usize> = std::collections::HashMap::new();
    for (i, light) in lights.iter().enumerate() {
        let Some(b) = light.bounds() else { continue };
        let k = *by_path.entry(light.prim_path()).or_insert_with(|| {
            groups.push(Group {
                bounds: b,
                lights: Vec::new(),
                table: None,
            });
            groups.len() - 1
        });
        let g = &mut groups[k];
        if !g.lights.is_empty() {
            g.bounds = g.bounds.union(&b);
        }
        member[i] = (k as u32, g.lights.len() as u32);
        g.lights.push(i);
        if groups.len() > MAX_GROUPS {
            return None;
        }
    }
    if groups.len() < 2 {
        return None;
    }
    for g in &mut groups {
        if g.lights.len() > 1 {
            let w: Vec<f32> = g
                .lights
                .iter()
                .map(|&i| lights[i].luminous_power(0.0))
                .collect();
            g.table = Some(Distribution1D::new(&w));
        }
    }
    Some((groups, member))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::light::{DistantLight, LightSampler, RectLight, TriangleLight};
    use crate::spectral::Spectrum;
    use glam::Vec3;

    /// Three ceiling panels of different sizes and radiances, a lamp of two triangles (one
    /// prim), and a sun.
    fn lights() -> Vec<Light> {
        let panel = |path: &str, c: Vec3, w: f32, l: f32| {
            Light::Rect(RectLight::new(
                path.into(),
                c,
                Vec3::new(w, 0.0, 0.0),
                Vec3::new(0.0, 0.0, -w),
                -Vec3::Y,
                Spectrum::Constant(l),
            ))
        };
        let tri = |a: Vec3, b: Vec3, c: Vec3| {
            Light::Triangle(TriangleLight::new(
                "/Lamp".into(),
                [a, b, c],
                Spectrum::Constant(5.0),
                false,
            ))
        };
        let (a, b, c, d) = (
            Vec3::new(4.0, 1.0, 0.0),
            Vec3::new(4.0, 1.0, 1.0),
            Vec3::new(4.0, 2.0, 1.0),
            Vec3::new(4.0, 2.0, 0.0),
        );
        vec![
            panel("/P0", Vec3::new(0.0, 3.0, 0.0), 0.6, 10.0),
            tri(a, c, b),
            panel("/P1", Vec3::new(3.0, 3.0, 0.0), 1.2, 2.0),
            Light::Distant(DistantLight {
                prim_path: "/Sun".into(),
                to_light: Vec3::new(0.3, 1.0, 0.2).normalize(),
                cos_theta_max: 1.0,
                one_minus_cos: 0.0,
                radiance: Spectrum::Constant(1e-3),
            }),
            panel("/P2", Vec3::new(-6.0, 3.0, 4.0), 0.3, 50.0),
            tri(a, d, c),
        ]
    }

    fn receivers() -> Vec<LightSampleContext> {
        let mut out = Vec::new();
        for (i, p) in [
            Vec3::new(0.3, 0.0, -0.3),
            Vec3::new(0.3, 2.9, -0.3),
            Vec3::new(3.5, 1.5, 0.5),
            Vec3::new(-5.0, 1.0, 3.0),
            Vec3::new(0.0, 5.0, 0.0),
            Vec3::new(10.0, 1.5, 0.5),
        ]
        .into_iter()
        .enumerate()
        {
            out.push(LightSampleContext { p, n: Vec3::ZERO });
            let n = [
                Vec3::Y,
                -Vec3::Y,
                Vec3::X,
                -Vec3::X,
                Vec3::Z,
                Vec3::ONE.normalize(),
            ][i];
            out.push(LightSampleContext { p, n });
        }
        out
    }

    #[test]
    fn groups_by_prim_and_keeps_power_where_it_does_not_apply() {
        let all = lights();
        assert!(matches!(
            LightSampler::new(&all, 10.0),
            LightSampler::Spatial(_)
        ));
        // The lamp alone is one prim of two triangles: the power table.
        let lamp = vec![all[1].clone(), all[5].clone()];
        assert!(matches!(
            LightSampler::new(&lamp, 10.0),
            LightSampler::Power(_)
        ));
        let s = SpatialSampler::new(&all, 10.0).unwrap();
        assert_eq!(s.groups.len(), 4);
        assert_eq!(s.groups[1].lights, vec![1, 5]);
    }

    /// The probabilities sum to 1 over the lights; `sample` returns exactly `pmf`; with u on a
    /// stratified grid of N points each light is chosen pmf · N times up to the grid's
    /// resolution at each end of its interval; a light of importance 0 is never chosen.
    #[test]
    fn choices_follow_their_probabilities() {
        let all = lights();
        let s = SpatialSampler::new(&all, 10.0).unwrap();
        const N: usize = 1 << 16;
        for ctx in receivers() {
            let pmf: Vec<f32> = (0..all.len()).map(|i| s.pmf(&ctx, i)).collect();
            let total: f32 = pmf.iter().sum();
            // Where no bounded light can reach the receiver only the sun is ever chosen.
            let reached = s.importances(&ctx).1 > 0.0;
            let expected = if reached { 1.0 } else { s.share.p_infinite };
            assert!((total - expected).abs() < 1e-5, "{ctx:?}: Σ pmf = {total}");
            let mut count = vec![0usize; all.len()];
            for k in 0..N {
                let u = (k as f32 + 0.5) / N as f32;
                match s.sample(&ctx, u) {
                    Some((i, p)) => {
                        assert_eq!(p.to_bits(), pmf[i].to_bits(), "{ctx:?}: light {i}");
                        count[i] += 1;
                    }
                    None => assert!(!reached && u >= s.share.p_infinite, "{ctx:?}: u {u}"),
                }
            }
            for i in 0..all.len() {
                let freq = count[i] as f64 / N as f64;
                assert!(
                    (freq - f64::from(pmf[i])).abs() <= 4.0 / N as f64 + 1e-6,
                    "{ctx:?}: light {i} chosen {freq}, pmf {}",
                    pmf[i]
                );
                if pmf[i] == 0.0 {
                    assert_eq!(count[i], 0);
                }
            }
        }
        // Under a panel it is preferred to its power's share; right above it (behind it, and
        // the box's cone from there does not reach its front) it is never chosen. (Above the
        // plane but off to the side, the bounding cone from the box's sphere reaches past the
        // plane: there the importance is small but not 0, as bounds must err.)
        let under_p0 = LightSampleContext {
            p: Vec3::new(0.3, 0.0, -0.3),
            n: Vec3::Y,
        };
        assert!(s.pmf(&under_p0, 0) > 2.0 * s.pmf_by_power(0));
        let above = LightSampleContext {
            p: Vec3::new(0.3, 3.5, -0.3),
            n: Vec3::ZERO,
        };
        assert_eq!(s.pmf(&above, 0), 0.0);
    }
}
