//! Choosing a light for next-event estimation from many bounded lights: a tree over the
//! lights' bounds, descended by importance at the receiver (PBR 4ed §12.6.3, "BVH Light
//! Sampling", after Conty Estevez and Kulla 2018; the importance is `bounds.rs`'s).
//!
//! The exhaustive sampler (`spatial.rs`) evaluates every prim's importance per choice, so it
//! serves at most `spatial::MAX_GROUPS` prims. Beyond that — an office of 48 luminaires, a
//! façade of lit windows, an emissive mesh of many triangles — the bounded lights go into
//! this tree, one light per leaf:
//! - the infinite lights keep their share of the luminous power, P∞, and are chosen among
//!   themselves by power, as in `spatial.rs`;
//! - from the root down, each node's up to four children are weighed by the importance
//!   I(p, n) of their bounds, and one is chosen in proportion (four importances per SSE pass,
//!   `Bounds4`); the light's probability is (1 − P∞) times the product of the ratios
//!   I_k / Σ I on its way down;
//! - a child of importance 0 cannot send light to the receiver (the bounds are conservative)
//!   and is never chosen, so the estimate stays unbiased.
//!
//! The tree is built top-down as a binary tree whose splits minimise the book's cost
//! (`split_cost`: power × the normal cone's orientation measure M_Ω × the box's area, with
//! its aspect regularisation), over 12 buckets of box centres per axis; each 4-wide node then
//! takes its binary node's grandchildren. Each light keeps its trail from the root, two bits a
//! level, so that `pmf` repeats `sample`'s ratios in the same order and returns exactly the
//! probability `sample` did.

use super::bounds::Bounds4;
use super::power_share::PowerShare;
use super::spatial::pick;
use super::{Light, LightBounds, LightSampleContext};
use std::f32::consts::PI;

/// Buckets of box centres per axis when a node's lights are split (PBR 4ed §12.6.3 uses 12).
const BUCKETS: usize = 12;
/// Levels of the 4-wide tree a trail can hold (two bits each in a u64).
const MAX_LEVELS: usize = 32;

/// A 4-wide node: its children's bounds as lanes, and per child a node or a light.
#[derive(Clone, Copy, Debug)]
struct Node {
    bounds: Bounds4,
    /// Child k: a node index, or a light index where bit k of `leaves` is set.
    child: [u32; 4],
    leaves: u8,
    /// Children in use (the rest have importance 0: φ = 0 in `bounds`).
    count: u8,
}

impl Node {
    /// The importances of the children at `ctx` and their sum (in lane order, the same sum in
    /// `sample` and `pmf`).
    #[inline]
    fn weights(&self, ctx: &LightSampleContext) -> ([f32; 4], f32) {
        let imp = self.bounds.importance(ctx.p, ctx.n);
        (imp, imp[0] + imp[1] + imp[2] + imp[3])
    }
}

/// Where a light sits: its trail of child slots from the root (two bits a level, the root's
/// first) and the number of levels; `levels` 0 for a light outside the tree (an infinite one,
/// or one without power).
#[derive(Clone, Copy, Debug, Default)]
struct Trail {
    slots: u64,
    levels: u8,
    infinite: bool,
}

#[derive(Clone, Debug)]
pub struct LightTree {
    nodes: Vec<Node>,
    trail: Vec<Trail>,
    /// Every light's power, and the infinite lights' share P∞.
    share: PowerShare,
}

/// The binary tree the 4-wide one is made from.
enum Binary {
    /// A light and its bounds.
    Leaf(usize, LightBounds),
    /// Two subtrees and the union of their bounds.
    Inner(Box<Binary>, Box<Binary>, LightBounds),
}

impl Binary {
    fn bounds(&self) -> &LightBounds {
        match self {
            Binary::Leaf(_, b) | Binary::Inner(_, _, b) => b,
        }
    }
}

impl LightTree {
    /// The tree of `lights`' bounded lights of positive power, or None when there are no more
    /// than `min_lights` of them (fewer are better served by `spatial.rs` or the power table),
    /// or no power at all.
    pub fn new(lights: &[Light], scene_radius: f32, min_lights: usize) -> Option<LightTree> {
        let bounded: Vec<(usize, LightBounds)> = lights
            .iter()
            .enumerate()
            .filter_map(|(i, l)| Some((i, l.bounds()?)))
            .filter(|(_, b)| usable(b))
            .collect();
        if bounded.len() <= min_lights {
            return None;
        }
        let share = PowerShare::new(lights, scene_radius)?;
        let mut items = bounded;
        let root = build(&mut items, 0);
        let mut tree = LightTree {
            nodes: Vec::new(),
            trail: lights
                .iter()
                .map(|l| Trail {
                    infinite: l.is_infinite(),
                    ..Trail::default()
                })
                .collect(),
            share,
        };
        tree.flatten(&root, Trail::default());
        Some(tree)
    }

    /// Appends the 4-wide node of binary node `b` (and its subtree) at trail `at`; returns its
    /// index.
    fn flatten(&mut self, b: &Binary, at: Trail) -> u32 {
        let index = self.nodes.len();
        self.nodes.push(Node {
            bounds: Bounds4::default(),
            child: [0; 4],
            leaves: 0,
            count: 0,
        });
        let kids: Vec<&Binary> = match b {
            Binary::Leaf(..) => vec![b],
            Binary::Inner(l, r, _) => [l, r]
                .into_iter()
                .flat_map(|c| match c.as_ref() {
                    Binary::Leaf(..) => vec![c.as_ref()],
                    Binary::Inner(a, z, _) => vec![a.as_ref(), z.as_ref()],
                })
                .collect(),
        };
        let mut bounds = Vec::with_capacity(4);
        let (mut child, mut leaves) = ([0u32; 4], 0u8);
        for (k, kid) in kids.iter().enumerate() {
            let here = Trail {
                slots: at.slots | (k as u64) << (2 * at.levels),
                levels: at.levels + 1,
                infinite: false,
            };
            match kid {
                Binary::Leaf(i, _) => {
                    child[k] = *i as u32;
                    leaves |= 1 << k;
                    self.trail[*i] = here;
                }
                Binary::Inner(..) => child[k] = self.flatten(kid, here),
            }
            bounds.push(*kid.bounds());
        }
        self.nodes[index] = Node {
            bounds: Bounds4::new(&bounds),
            child,
            leaves,
            count: kids.len() as u8,
        };
        index as u32
    }

    /// (light index, probability) for the receiver `ctx`, or None when no light is chosen.
    pub fn sample(&self, ctx: &LightSampleContext, u: f32) -> Option<(usize, f32)> {
        let p_infinite = self.share.p_infinite;
        if u < p_infinite {
            return self.share.sample_infinite(u);
        }
        let share = 1.0 - p_infinite;
        let mut u = ((u - p_infinite) / share).min(ONE_MINUS_EPSILON);
        let mut p = share;
        let mut node = &self.nodes[0];
        loop {
            let (imp, sum) = node.weights(ctx);
            if sum <= 0.0 {
                return None;
            }
            let target = u * sum;
            let (k, below) = pick(&imp[..node.count as usize], target)?;
            p *= imp[k] / sum;
            u = ((target - below) / imp[k]).clamp(0.0, ONE_MINUS_EPSILON);
            if node.leaves & (1 << k) != 0 {
                return Some((node.child[k] as usize, p));
            }
            node = &self.nodes[node.child[k] as usize];
        }
    }

    /// The probability that `sample` chooses `light` at `ctx`.
    pub fn pmf(&self, ctx: &LightSampleContext, light: usize) -> f32 {
        let Some(t) = self.trail.get(light) else {
            return 0.0;
        };
        if t.levels == 0 {
            // An infinite light (its power's share), or one outside the tree (no power).
            return if t.infinite {
                self.share.pmf(light)
            } else {
                0.0
            };
        }
        let mut p = 1.0 - self.share.p_infinite;
        let mut node = &self.nodes[0];
        for level in 0..t.levels {
            let k = (t.slots >> (2 * level) & 3) as usize;
            let (imp, sum) = node.weights(ctx);
            if sum <= 0.0 || imp[k] == 0.0 {
                return 0.0;
            }
            p *= imp[k] / sum;
            if node.leaves & (1 << k) == 0 {
                node = &self.nodes[node.child[k] as usize];
            }
        }
        p
    }

    /// The power sampler's choice, for light subpaths (they start without a receiver).
    pub fn sample_by_power(&self, u: f32) -> Option<(usize, f32)> {
        self.share.sample(u)
    }

    /// The power sampler's probability of `light`.
    pub fn pmf_by_power(&self, light: usize) -> f32 {
        self.share.pmf(light)
    }

    /// Nodes and bytes held.
    #[cfg(test)]
    fn memory(&self) -> (usize, usize) {
        (
            self.nodes.len(),
            self.nodes.len() * std::mem::size_of::<Node>()
                + self.trail.len() * std::mem::size_of::<Trail>(),
        )
    }
}

/// The largest f32 below 1.
const ONE_MINUS_EPSILON: f32 = 1.0 - f32::EPSILON / 2.0;

/// Bounds a tree can weigh: positive, finite power and a finite box.
fn usable(b: &LightBounds) -> bool {
    b.phi > 0.0 && b.phi.is_finite() && b.lo.is_finite() && b.hi.is_finite()
}

/// The binary tree over `items` (light index, bounds), at binary depth `depth`.
fn build(items: &mut [(usize, LightBounds)], depth: usize) -> Binary {
    if items.len() == 1 {
        return Binary::Leaf(items[0].0, items[0].1);
    }
    let mid = split(items, depth);
    let (l, r) = items.split_at_mut(mid);
    let (l, r) = (build(l, depth + 1), build(r, depth + 1));
    let bounds = l.bounds().union(r.bounds());
    Binary::Inner(Box::new(l), Box::new(r), bounds)
}

/// Reorders `items` and returns where its two halves meet (1 ≤ mid < len): at the bucket
/// boundary of least `split_cost`, or at the median centre along the box's longest axis where
/// no boundary separates the centres or the trail would run out of levels.
fn split(items: &mut [(usize, LightBounds)], depth: usize) -> usize {
    let n = items.len();
    let centre = |b: &LightBounds| 0.5 * (b.lo + b.hi);
    let (lo, hi) = items.iter().fold(
        (glam::Vec3::INFINITY, glam::Vec3::NEG_INFINITY),
        |(lo, hi), (_, b)| (lo.min(centre(b)), hi.max(centre(b))),
    );
    let all = items
        .iter()
        .skip(1)
        .fold(items[0].1, |acc, (_, b)| acc.union(b));
    let extent = all.hi - all.lo;
    // A split by count halves the lights, so a binary depth of `depth + ⌈log₂ n⌉` stays within
    // the trail's 2 · MAX_LEVELS levels whatever the later splits do.
    let levels_left = 2 * MAX_LEVELS - 2 - depth;
    let balanced = (usize::BITS - (n - 1).leading_zeros()) as usize >= levels_left;
    let mut best: Option<(f32, usize, usize)> = None; // (cost, axis, bucket boundary)
    if !balanced {
        for axis in 0..3 {
            if hi[axis] <= lo[axis] {
                continue;
            }
            let bucket = |b: &LightBounds| {
                let t = (centre(b)[axis] - lo[axis]) / (hi[axis] - lo[axis]);
                ((t * BUCKETS as f32) as usize).min(BUCKETS - 1)
            };
            let mut bins: [Option<LightBounds>; BUCKETS] = [None; BUCKETS];
            for (_, b) in items.iter() {
                let k = bucket(b);
                bins[k] = Some(bins[k].map_or(*b, |a| a.union(b)));
            }
            let regular = extent.max_element() / extent[axis].max(f32::MIN_POSITIVE);
            let pad = 1e-3 * extent.max_element();
            for cut in 1..BUCKETS {
                let side = |r: std::ops::Range<usize>| {
                    bins[r]
                        .iter()
                        .flatten()
                        .fold(None, |acc: Option<LightBounds>, b| {
                            Some(acc.map_or(*b, |a| a.union(b)))
                        })
                };
                let (Some(a), Some(z)) = (side(0..cut), side(cut..BUCKETS)) else {
                    continue;
                };
                let cost = regular * (split_cost(&a, pad) + split_cost(&z, pad));
                if cost.is_finite() && best.is_none_or(|(c, _, _)| cost < c) {
                    best = Some((cost, axis, cut));
                }
            }
        }
    }
    match best {
        Some((_, axis, cut)) => {
            let t = |b: &LightBounds| (centre(b)[axis] - lo[axis]) / (hi[axis] - lo[axis]);
            let mut mid = 0;
            for i in 0..n {
                let k = ((t(&items[i].1) * BUCKETS as f32) as usize).min(BUCKETS - 1);
                if k < cut {
                    items.swap(i, mid);
                    mid += 1;
                }
            }
            mid.clamp(1, n - 1)
        }
        None => {
            let axis = (hi - lo).max_position();
            items.sort_unstable_by(|a, b| centre(&a.1)[axis].total_cmp(&centre(&b.1)[axis]));
            n / 2
        }
    }
}

/// PBR 4ed §12.6.3's cost of a side of a split, without the parent's constant factors: power
/// × the orientation measure M_Ω of the normal cone widened by the emission spread × the
/// box's surface area. With θw = min(θo + θe, π),
/// M_Ω = 2π (1 − cos θo) + π/2 (2 θw sin θo − cos(θo − 2θw) − 2 θo sin θo + cos θo)
/// (the solid angle of the cone, plus the cosine-weighted solid angle of the band θo..θw).
/// The box's sides count as at least `pad`, so that point-like and flat sides are still
/// ordered by their power and spread.
fn split_cost(b: &LightBounds, pad: f32) -> f32 {
    let theta_o = b.cos_theta_o.clamp(-1.0, 1.0).acos();
    let theta_e = b.cos_theta_e.clamp(-1.0, 1.0).acos();
    let theta_w = (theta_o + theta_e).min(PI);
    let (sin_o, cos_o) = theta_o.sin_cos();
    let m_omega = 2.0 * PI * (1.0 - cos_o)
        + PI / 2.0
            * (2.0 * theta_w * sin_o - (theta_o - 2.0 * theta_w).cos() - 2.0 * theta_o * sin_o
                + cos_o);
    let d = (b.hi - b.lo).max(glam::Vec3::splat(pad));
    let area = 2.0 * (d.x * d.y + d.y * d.z + d.z * d.x);
    b.phi * m_omega * area
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::light::{DistantLight, LightSampler, RectLight, SphereLight, TriangleLight};
    use crate::spectral::Spectrum;
    use crate::testing::rng::Rng;
    use glam::Vec3;

    /// A ceiling of 6 × 8 downward panels of varied radiance, five sphere lamps on the walls,
    /// an emissive mesh of 12 triangles facing −x, and a sun: 65 lights in 55 prims.
    fn office() -> Vec<Light> {
        let mut out = Vec::new();
        for i in 0..6 {
            for j in 0..8 {
                let c = Vec3::new(1.5 * i as f32, 3.0, -1.5 * j as f32);
                out.push(Light::Rect(RectLight::new(
                    format!("/P{i}_{j}"),
                    c,
                    Vec3::new(0.6, 0.0, 0.0),
                    Vec3::new(0.0, 0.0, -0.6),
                    -Vec3::Y,
                    Spectrum::Constant(1.0 + ((i * 8 + j) % 5) as f32),
                )));
            }
        }
        for k in 0..5 {
            out.push(Light::Sphere(SphereLight {
                prim_path: format!("/Lamp{k}"),
                center: Vec3::new(-0.5, 1.5, -2.5 * k as f32),
                radius: 0.1,
                radiance: Spectrum::Constant(20.0),
                shaping: None,
                ellipsoid: None,
            }));
        }
        for k in 0..12 {
            let (y, z) = (0.5 + 0.2 * (k / 4) as f32, -2.0 - 0.5 * (k % 4) as f32);
            out.push(Light::Triangle(TriangleLight::new(
                "/Sign".into(),
                [
                    Vec3::new(9.0, y, z),
                    Vec3::new(9.0, y + 0.2, z),
                    Vec3::new(9.0, y, z - 0.5),
                ],
                Spectrum::Constant(3.0),
                false,
            )));
        }
        out.push(Light::Distant(DistantLight {
            prim_path: "/Sun".into(),
            to_light: Vec3::new(0.3, 1.0, 0.2).normalize(),
            cos_theta_max: 1.0,
            one_minus_cos: 0.0,
            radiance: Spectrum::Constant(1e-3),
        }));
        out
    }

    fn receivers() -> Vec<LightSampleContext> {
        let points = [
            (Vec3::new(0.3, 0.0, -0.3), Vec3::Y),
            (Vec3::new(4.0, 0.75, -5.0), Vec3::Y),
            (Vec3::new(8.0, 1.0, -2.5), Vec3::X),
            (Vec3::new(0.0, 1.5, -5.0), -Vec3::X),
            (Vec3::new(3.0, 3.5, -3.0), Vec3::Y),
            (Vec3::new(3.0, 1.0, -20.0), Vec3::ZERO),
            (Vec3::new(30.0, 1.0, 0.0), Vec3::ONE.normalize()),
        ];
        points
            .into_iter()
            .flat_map(|(p, n)| {
                [
                    LightSampleContext { p, n },
                    LightSampleContext { p, n: Vec3::ZERO },
                ]
            })
            .collect()
    }

    #[test]
    fn many_prims_take_the_tree_and_few_do_not() {
        let all = office();
        assert!(matches!(
            LightSampler::new(&all, 20.0),
            LightSampler::Tree(_)
        ));
        // Ten panels: the exhaustive sampler; one mesh of twelve triangles: the power table.
        assert!(matches!(
            LightSampler::new(&all[..10], 20.0),
            LightSampler::Spatial(_)
        ));
        assert!(matches!(
            LightSampler::new(&all[53..65], 20.0),
            LightSampler::Power(_)
        ));
        let t = LightTree::new(&all, 20.0, MAX_GROUPS_FOR_TESTS).unwrap();
        // 64 bounded lights in 4-wide nodes: a few dozen nodes at most.
        let (nodes, bytes) = t.memory();
        assert!((21..=63).contains(&nodes), "{nodes} nodes");
        assert!(bytes < 64 * 1024);
    }

    const MAX_GROUPS_FOR_TESTS: usize = super::super::spatial::MAX_GROUPS;

    /// The probabilities sum to at most 1 over the lights, and to 1 where no subtree that the
    /// bounds admit turns out empty further down (below the ceiling); `sample` returns exactly
    /// `pmf`, and nothing with probability 1 − Σ pmf; on a stratified grid of N numbers each
    /// light is chosen pmf · N times up to the grid's resolution at each end of its interval
    /// at each level; a light of probability 0 is never chosen.
    #[test]
    fn choices_follow_their_probabilities() {
        let all = office();
        let t = LightTree::new(&all, 20.0, MAX_GROUPS_FOR_TESTS).unwrap();
        const N: usize = 1 << 16;
        for (r, ctx) in receivers().into_iter().enumerate() {
            let pmf: Vec<f32> = (0..all.len()).map(|i| t.pmf(&ctx, i)).collect();
            let total: f32 = pmf.iter().sum();
            assert!(total <= 1.0 + 1e-5, "{ctx:?}: Σ pmf = {total}");
            if r < 4 {
                assert!((total - 1.0).abs() < 1e-5, "{ctx:?}: Σ pmf = {total}");
            }
            let mut count = vec![0usize; all.len()];
            let mut none = 0usize;
            for k in 0..N {
                let u = (k as f32 + 0.5) / N as f32;
                match t.sample(&ctx, u) {
                    Some((i, p)) => {
                        assert_eq!(p.to_bits(), pmf[i].to_bits(), "{ctx:?}: light {i}");
                        count[i] += 1;
                    }
                    None => {
                        assert!(u >= t.share.p_infinite, "{ctx:?}: u {u}");
                        none += 1;
                    }
                }
            }
            // Each level's remapping of u costs a little resolution: a few grid points per
            // level of the light's trail.
            let tol = 16.0 / N as f64 + 1e-6;
            let missed = none as f64 / N as f64;
            assert!(
                (missed - (1.0 - f64::from(total))).abs() <= 4.0 * tol,
                "{ctx:?}"
            );
            for i in 0..all.len() {
                let freq = count[i] as f64 / N as f64;
                assert!(
                    (freq - f64::from(pmf[i])).abs() <= tol,
                    "{ctx:?}: light {i} chosen {freq}, pmf {}",
                    pmf[i]
                );
                if pmf[i] == 0.0 {
                    assert_eq!(count[i], 0);
                }
            }
        }
        // Under a panel it gets more than its power's share (the lamp on the wall beside it
        // takes most); above the ceiling, no panel.
        let under = receivers()[0];
        assert!(t.pmf(&under, 0) > 3.0 * t.pmf_by_power(0));
        let above = receivers()[8];
        assert!((0..48).all(|i| t.pmf(&above, i) == 0.0));
    }

    /// Conservative: at random receivers, every light that sends light there (a point of it
    /// in front of its emitting side and, for a receiver with a normal, off its plane) has a
    /// probability above 0.
    #[test]
    fn a_light_that_reaches_the_receiver_can_be_chosen() {
        let all = office();
        let t = LightTree::new(&all, 20.0, MAX_GROUPS_FOR_TESTS).unwrap();
        let mut rng = Rng::new(7);
        for _ in 0..2000 {
            let p = rng.vec3(-3.0, 12.0);
            let n = if rng.f32() < 0.2 {
                Vec3::ZERO
            } else {
                rng.vec3(-1.0, 1.0).normalize_or_zero()
            };
            let ctx = LightSampleContext { p, n };
            for (i, light) in all.iter().enumerate() {
                let reaches = match light {
                    Light::Rect(r) => {
                        let c = r.corner + 0.5 * (r.edge_u + r.edge_v);
                        r.n.dot(p - c) > 0.0 && (n == Vec3::ZERO || n.dot(c - p) != 0.0)
                    }
                    Light::Triangle(tl) => {
                        let c = (tl.p[0] + tl.p[1] + tl.p[2]) / 3.0;
                        tl.n.dot(p - c) > 0.0 && (n == Vec3::ZERO || n.dot(c - p) != 0.0)
                    }
                    Light::Sphere(_) => true,
                    _ => continue,
                };
                if reaches {
                    assert!(t.pmf(&ctx, i) > 0.0, "light {i} at {p} n {n}");
                }
            }
        }
    }

    /// Lights stacked at one point, and a long row: the trail's levels suffice (the splits
    /// fall back to halving by count) and every light keeps its probability.
    #[test]
    fn degenerate_and_deep_layouts_build() {
        let mut rng = Rng::new(3);
        let stacked: Vec<Light> = (0..5000)
            .map(|k| {
                Light::Sphere(SphereLight {
                    prim_path: format!("/S{k}"),
                    center: Vec3::ONE,
                    radius: 0.01,
                    radiance: Spectrum::Constant(1.0 + rng.f32()),
                    shaping: None,
                    ellipsoid: None,
                })
            })
            .collect();
        let row: Vec<Light> = (0..5000)
            .map(|k| {
                Light::Sphere(SphereLight {
                    prim_path: format!("/S{k}"),
                    center: Vec3::new(1.5f32.powi(k % 60), 0.0, 0.0),
                    radius: 0.01,
                    radiance: Spectrum::Constant(1.0),
                    shaping: None,
                    ellipsoid: None,
                })
            })
            .collect();
        for lights in [stacked, row] {
            let t = LightTree::new(&lights, 1e9, MAX_GROUPS_FOR_TESTS).unwrap();
            assert!(t
                .trail
                .iter()
                .all(|tr| (1..=MAX_LEVELS as u8).contains(&tr.levels)));
            let ctx = LightSampleContext {
                p: Vec3::new(0.5, -2.0, 0.5),
                n: Vec3::Y,
            };
            let total: f64 = (0..lights.len()).map(|i| f64::from(t.pmf(&ctx, i))).sum();
            assert!((total - 1.0).abs() < 1e-4, "Σ pmf = {total}");
        }
    }
}
