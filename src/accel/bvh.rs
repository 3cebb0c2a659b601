//! Triangle BVH: obvhs collapses a binary BVH into a compressed 8-wide one (CWBVH; Ylitie,
//! Karras, Laine 2017, "Efficient Incoherent Ray Traversal on GPUs Through Compressed Wide
//! BVHs"). The binary tree is built top-down by our binned SAH ([`Builder::Sah`],
//! `accel/sah.rs`, the default) or bottom-up by obvhs's PLOC (Meister, Bittner 2018, "Parallel
//! Locally-Ordered Clustering for Bounding Volume Hierarchy Construction") plus reinsertion
//! (Meister, Bittner 2017, "Parallel Reinsertion for Bounding Volume Hierarchy Optimization").
//! We keep the collapse's topology and child slots, store every node with the exact f32 boxes
//! of its children, and traverse with our own loop.
//! This module and `sah.rs` are the only ones that name obvhs.
//!
//! **Traversal.** A node holds its eight child boxes in SIMD lanes (two halves of four), so a
//! node test is two 4-wide slab tests (Kay, Kajiya 1986; PBR 4ed §6.1.2). The children met are
//! ordered by entry distance (integer keys of the distance's bits and the slot, picked one at a
//! time: a node meets one to three children, mostly): leaves are tested at once, near to far;
//! the nearest inner child is visited next, and the others are pushed with their entry distance,
//! far to near, so they are popped nearest first (and their records touched as they are
//! pushed, a prefetch by a plain load); a leaf or a subtree that starts beyond the
//! closest hit found so far is skipped. (The ray-octant order of the CWBVH's child slots,
//! Ylitie et al. 2017, §3.2, costs 3% more instructions per closest hit on the Cornell box and
//! 7% on a 100k-triangle sphere.) Shadow rays (`occluded`) stop at the first hit and compute
//! nothing else.
//!
//! **Robustness.**
//! - Triangles: the watertight test of [`crate::geometry::triangle`], on triangles stored
//!   right after the record of the node whose leaves hold them (`accel/store.rs`), 40 bytes
//!   each: 36 of coordinates and the triangle's input index, which a hit reads from the line
//!   it was tested in (no index indirection per test; a leaf of three triangles is 120
//!   contiguous bytes).
//! - Child boxes are the exact bounds of their triangles (the CWBVH's 8-bit quantised boxes are
//!   not used), and the box test is conservative in the spirit of PBR 4ed §6.8.2
//!   ("Conservative Ray–Bounds Intersections"; see `RayBoxes` in the source). A box the exact
//!   ray meets within t ∈ [0, t_max] is never culled, in particular not one whose face holds a
//!   triangle (every axis-aligned floor), and nothing is clipped at t = 1e-4 as in obvhs's own
//!   node test.
//!
//! Degenerate triangles (zero area, or a non-finite vertex) are left out of the tree: they can
//! never be hit. `Bvh` is plain data (`Send + Sync`); queries allocate nothing (the traversal
//! stack's first [`STACK_PLACES`] entries live on the call stack), except on pathologically
//! deep trees (see [`super::stack`]).
//!
//! ```
//! use glam::Vec3;
//! use spectral_render::accel::bvh::Bvh;
//! use spectral_render::geometry::Ray;
//!
//! let floor = [[Vec3::ZERO, Vec3::X, Vec3::Z], [Vec3::X, Vec3::new(1.0, 0.0, 1.0), Vec3::Z]];
//! let bvh = Bvh::build(&floor);
//! let ray = Ray::new(Vec3::new(0.8, 1.0, 0.7), Vec3::NEG_Y);
//! let hit = bvh.intersect(&ray, f32::INFINITY).expect("the ray hits the floor");
//! assert_eq!(hit.prim, 1);
//! assert!((hit.hit.t - 1.0).abs() < 1e-6);
//! assert!(!bvh.occluded(&ray, 0.5));
//! ```

use std::cell::Cell;

use glam::{Vec3, Vec3A, Vec4};
use obvhs::bvh2::reinsertion::ReinsertionOptimizer;
use obvhs::cwbvh::bvh2_to_cwbvh::bvh2_to_cwbvh;
use obvhs::cwbvh::node::CwBvhNode;
use obvhs::cwbvh::CwBvh;
use obvhs::ploc::{PlocBuilder, PlocSearchDistance, SortPrecision};
use obvhs::triangle::Triangle;

use super::sah;
use super::stack::Stack;
use super::store::{self, Record, TRI_FLOATS};
use crate::geometry::offset::gamma;
use crate::geometry::ray::Ray;
use crate::geometry::triangle::{
    intersect_packed, is_degenerate, PackedTriangle, TriangleHit, WatertightRay, ROW_FLOATS,
};

/// A hit found by the BVH: `prim` indexes the slice given to [`Bvh::build`]; `slot` is the
/// triangle's place in the BVH's own store, where [`Bvh::vertices`] reads its vertices.
#[derive(Clone, Copy, Debug)]
pub struct BvhHit {
    pub prim: u32,
    pub slot: u32,
    pub hit: TriangleHit,
}

/// An 8-wide BVH over triangles, with the triangles stored in BVH primitive order.
pub struct Bvh {
    /// The nodes' records, each followed by its leaves' triangles (`accel/store.rs`); the
    /// root's at word 0; empty for a BVH without hittable triangles.
    store: Vec<f32>,
    /// Hittable triangles (those in the store).
    hittable: usize,
    input_count: usize,
    bounds: (Vec3, Vec3),
}

/// A node with up to eight children as built, before `accel/store.rs` lays it out. Slot `s` is
/// lane `s % 4` of half `s / 4`.
#[derive(Clone, Copy, Debug)]
pub(super) struct WideNode {
    /// `planes[h][2k]` / `planes[h][2k + 1]`: min / max along axis k of the children of half h.
    pub planes: [[Vec4; 6]; 2],
    /// Inner child: its node index; leaf child: its first triangle (BVH order).
    pub child: [u32; 8],
    /// Triangles of each leaf child (0 for inner children and empty slots).
    pub count: [u8; 8],
    /// Bit `s`: slot s holds a child.
    pub present: u8,
    /// Bit `s`: slot s holds a leaf.
    pub leaves: u8,
}

/// A subtree waiting on the traversal stack: the bits of the (widened) distance where the ray
/// enters it above its record's offset in the store, one 8-byte word to push and pop.
#[derive(Clone, Copy, Debug, Default)]
struct Entry(u64);

impl Entry {
    /// The child of `node` in the slot of `key` (see [`order_key`]), entered at the key's distance.
    #[inline(always)]
    fn child(node: &Record, key: u64) -> Entry {
        Entry(key & !0xffff_ffff | node.child(key as usize) as u64)
    }

    #[inline(always)]
    fn node(self) -> usize {
        self.0 as u32 as usize
    }
}

/// Traversal stack entries kept on the call stack (128 bytes, eight 16-byte stores to clear per
/// query; 32 places made the clear a `memset` call of ~35 instructions); deeper traversals
/// spill to the heap. The worst case 7·depth − 6 (each ancestor of the visited node leaves at
/// most 7 of its ≤ 8 children on the stack, the node pushes at most 8) is far above what rays
/// meet: none of the primary, diffuse and shadow rays of `../shared/limit`'s box and 100k- and
/// 1M-triangle spheres needed more than 16 (docs/design.md §8).
const STACK_PLACES: usize = 16;

/// Triangles per leaf (the CWBVH maximum).
const LEAF_SIZE: u32 = 3;

/// Nodes reinserted at least (all of them in smaller trees): see [`build_cwbvh`].
const REINSERTION_NODES: f32 = 4096.0;

/// How the binary BVH that the 8-wide one is collapsed from is built.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Builder {
    /// obvhs's PLOC, bottom up (see `build_cwbvh` in the source).
    Ploc,
    /// Our top-down binned SAH (`accel/sah.rs`), the default: a tree of 5–6 % lower SAH than
    /// PLOC's on the spheres of `../shared/limit`, 3–4 % fewer query instructions, 1.0–1.08×
    /// the one-ray rate, for a 1.2× build (docs/design.md §8).
    Sah,
}

impl Builder {
    /// The builder of [`Bvh::build`].
    pub const DEFAULT: Builder = Builder::Sah;
}

/// The SAH of a built tree: the expected number of 8-wide node tests and of triangle tests for
/// a ray that meets the root box, with rays distributed uniformly over lines (so a box is met
/// with probability area / root area; MacDonald, Booth 1990, "Heuristics for ray tracing using
/// space subdivision"; PBR 4ed §7.3.2). The SAH cost is c_node·nodes + c_tri·triangles.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SahCost {
    pub nodes: f64,
    pub triangles: f64,
}

/// Builds the CWBVH from the given builder's binary tree. [`Builder::Ploc`] has the settings
/// of obvhs's `medium_build` preset: PLOC with search radius
/// 14 (`PlocSearchDistance::Medium`, `search_depth_threshold` 3, 64-bit Morton codes), then
/// reinsertion over 5% of the nodes but at least [`REINSERTION_NODES`] (on small scenes the full
/// pass costs little and the tree shape matters most: on the Cornell box it saves 12% of the
/// traversal instructions, while 20% instead of 5% on 50k-triangle scenes saves nothing and
/// costs 37% more build). [`Builder::Sah`]'s tree is not reinserted: 5% changed its SAH by
/// less than 0.3% on the spheres of `../shared/limit` (`Bvh::sah_cost`). Then both are
/// collapsed to 8-wide nodes with up to [`LEAF_SIZE`]
/// triangles per leaf. No spatial pre-splits: a leaf's box must
/// bound its whole triangles, which the conservative box test relies on for watertightness at
/// leaf boundaries.
/// (The body of obvhs's `build_cwbvh_from_tris`, minus its debug-build validation, which asserts
/// a depth below 32 and absolute 1e-5 box tolerances that large scenes exceed.)
fn build_cwbvh(triangles: &[Triangle], builder: Builder) -> CwBvh {
    let mut bvh2 = match builder {
        Builder::Ploc => PlocBuilder::with_capacity(triangles.len()).build(
            PlocSearchDistance::Medium,
            triangles,
            (0..triangles.len() as u32).collect(),
            SortPrecision::U64,
            3,
        ),
        Builder::Sah => sah::build_bvh2(triangles),
    };
    if builder == Builder::Ploc {
        let ratio = (REINSERTION_NODES / bvh2.nodes.len() as f32).clamp(0.05, 1.0);
        ReinsertionOptimizer::default().run(&mut bvh2, ratio, None);
    }
    bvh2_to_cwbvh(&bvh2, LEAF_SIZE, false, false)
}

impl Bvh {
    /// Builds a BVH over the triangles (each `[p0, p1, p2]`). Degenerate triangles are allowed
    /// and never hit; an empty slice gives a BVH that never hits.
    pub fn build(triangles: &[[Vec3; 3]]) -> Bvh {
        Bvh::build_with(triangles, Builder::DEFAULT)
    }

    /// [`Bvh::build`] with the given builder of the binary BVH.
    pub fn build_with(triangles: &[[Vec3; 3]], builder: Builder) -> Bvh {
        let kept: Vec<u32> = (0..triangles.len() as u32)
            .filter(|&i| {
                let [p0, p1, p2] = triangles[i as usize];
                !is_degenerate(p0, p1, p2)
            })
            .collect();
        if kept.is_empty() {
            return Bvh::empty(triangles.len());
        }
        let prims: Vec<Triangle> = kept
            .iter()
            .map(|&i| {
                let [v0, v1, v2] = triangles[i as usize].map(Vec3A::from);
                Triangle { v0, v1, v2 }
            })
            .collect();
        let cwbvh = build_cwbvh(&prims, builder);
        let input_index: Vec<u32> = cwbvh
            .primitive_indices
            .iter()
            .map(|&k| kept[k as usize])
            .collect();
        let ordered: Vec<[Vec3; 3]> = input_index.iter().map(|&i| triangles[i as usize]).collect();
        let nodes = wide_nodes(&cwbvh.nodes, &ordered);
        Bvh {
            store: store::build(&nodes, &ordered, &input_index),
            hittable: ordered.len(),
            bounds: bounds_of(&ordered),
            input_count: triangles.len(),
        }
    }

    fn empty(input_count: usize) -> Bvh {
        Bvh {
            store: Vec::new(),
            hittable: 0,
            input_count,
            bounds: (Vec3::ZERO, Vec3::ZERO),
        }
    }

    /// Closest hit with t in (0, t_max).
    #[inline(always)]
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<BvhHit> {
        if !self.may_hit(t_max) {
            return None;
        }
        let query = (&WatertightRay::new(ray)?, &RayBoxes::new(ray));
        self.closest(&mut Stack::<Entry, STACK_PLACES>::new(), query, t_max, &())
    }

    /// The vertices of the triangle `hit` met, as given to [`Bvh::build`] (bit for bit), read
    /// from the BVH's triangle store: a hit's point and normal need no other copy of them.
    #[inline]
    pub fn vertices(&self, hit: &BvhHit) -> [Vec3; 3] {
        PackedTriangle::at(&self.store, hit.slot as usize).vertices()
    }

    /// [`Bvh::intersect`], adding the nodes and triangles it tests to `count` (for benchmarks;
    /// the queries above count nothing).
    pub fn count_closest(&self, ray: &Ray, t_max: f32, count: &TraversalCount) -> Option<BvhHit> {
        self.may_hit(t_max).then_some(())?;
        let query = (&WatertightRay::new(ray)?, &RayBoxes::new(ray));
        self.closest(
            &mut Stack::<Entry, STACK_PLACES>::new(),
            query,
            t_max,
            count,
        )
    }

    /// [`Bvh::occluded`], adding the nodes and triangles it tests to `count`.
    pub fn count_any(&self, ray: &Ray, t_max: f32, count: &TraversalCount) -> bool {
        let Some(triangle) = WatertightRay::new(ray).filter(|_| self.may_hit(t_max)) else {
            return false;
        };
        let query = (&triangle, &RayBoxes::new(ray));
        self.any(
            &mut Stack::<Entry, STACK_PLACES>::new(),
            query,
            t_max,
            count,
        )
    }

    /// Whether anything is hit with t in (0, t_max) (shadow rays; stops at the first hit).
    #[inline(always)]
    pub fn occluded(&self, ray: &Ray, t_max: f32) -> bool {
        if !self.may_hit(t_max) {
            return false;
        }
        let Some(triangle) = WatertightRay::new(ray) else {
            return false;
        };
        let query = (&triangle, &RayBoxes::new(ray));
        self.any(&mut Stack::<Entry, STACK_PLACES>::new(), query, t_max, &())
    }

    /// Number of triangles given to [`Bvh::build`] (degenerate ones included).
    pub fn triangle_count(&self) -> usize {
        self.input_count
    }

    /// Bytes held: `(nodes, triangles)`, the nodes with the store's alignment padding, the
    /// triangles with their index into the input.
    pub fn memory_bytes(&self) -> (usize, usize) {
        (
            (self.store.len() - TRI_FLOATS * self.hittable) * std::mem::size_of::<f32>(),
            TRI_FLOATS * self.hittable * std::mem::size_of::<f32>(),
        )
    }

    /// The tree's [`SahCost`]; zero for a BVH without hittable triangles, and counted per
    /// node when the root box has no area.
    pub fn sah_cost(&self) -> SahCost {
        let area = |(lo, hi): (Vec3, Vec3)| {
            let d = (hi.as_dvec3() - lo.as_dvec3()).max(glam::DVec3::ZERO);
            d.x * d.y + d.y * d.z + d.z * d.x
        };
        let mut cost = SahCost {
            nodes: 0.0,
            triangles: 0.0,
        };
        let records = store::records(&self.store);
        for (_, node) in &records {
            let boxes = (0..8).filter(|&s| node.present() & (1 << s) != 0);
            let node_box = boxes.clone().map(|s| node.child_box(s));
            let node_box = node_box.fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |b, c| {
                (b.0.min(c.0), b.1.max(c.1))
            });
            cost.nodes += area(node_box);
            for s in boxes.filter(|&s| node.leaves() & (1 << s) != 0) {
                cost.triangles += area(node.child_box(s)) * node.count(s) as f64;
            }
        }
        let root = area(self.bounds);
        if root > 0.0 {
            cost.nodes /= root;
            cost.triangles /= root;
        } else {
            cost.nodes = records.len() as f64;
            cost.triangles = self.hittable as f64;
        }
        cost
    }

    /// World-space AABB `(min, max)` of the hittable triangles; both zero when there are none.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        self.bounds
    }

    /// False when nothing can be hit (no triangles, or an empty interval (0, t_max)).
    #[inline(always)]
    fn may_hit(&self, t_max: f32) -> bool {
        !self.store.is_empty() && t_max > 0.0
    }

    /// Per-ray setup, or None when nothing can be hit.
    #[cfg(test)]
    fn query(&self, ray: &Ray, t_max: f32) -> Option<(WatertightRay, RayBoxes)> {
        self.may_hit(t_max).then_some(())?;
        Some((WatertightRay::new(ray)?, RayBoxes::new(ray)))
    }

    /// Closest-hit traversal: the hit, with its input index and its slot (the triangle's offset
    /// in the store).
    #[inline(always)]
    fn closest<const N: usize>(
        &self,
        stack: &mut Stack<Entry, N>,
        (triangle, boxes): (&WatertightRay, &RayBoxes),
        mut t_max: f32,
        tally: &impl Tally,
    ) -> Option<BvhHit> {
        let mut best: Option<(usize, TriangleHit)> = None;
        self.traverse(stack, boxes, &mut t_max, tally, |first, count, t_max| {
            tally.triangles(count);
            for at in (0..count).map(|k| first + TRI_FLOATS * k) {
                let tri = PackedTriangle::at(&self.store, at);
                if let Some(hit) = intersect_packed(triangle, tri, *t_max) {
                    *t_max = hit.t;
                    best = Some((at, hit));
                }
            }
            false
        });
        let (at, hit) = best?;
        Some(BvhHit {
            prim: self.store.get(at + ROW_FLOATS)?.to_bits(),
            slot: at as u32,
            hit,
        })
    }

    /// Any-hit traversal with early exit.
    #[inline(always)]
    fn any<const N: usize>(
        &self,
        stack: &mut Stack<Entry, N>,
        (triangle, boxes): (&WatertightRay, &RayBoxes),
        mut t_max: f32,
        tally: &impl Tally,
    ) -> bool {
        let mut hit = false;
        self.traverse(stack, boxes, &mut t_max, tally, |first, count, t_max| {
            hit = (0..count).map(|k| first + TRI_FLOATS * k).any(|at| {
                tally.triangles(1);
                let tri = PackedTriangle::at(&self.store, at);
                intersect_packed(triangle, tri, *t_max).is_some()
            });
            hit
        });
        hit
    }

    /// Calls `leaf(first, count, t_max)` (`first` the store offset of the leaf's first
    /// triangle) for the leaves whose boxes the ray meets before `t_max`, near to far within
    /// each node; `leaf` may lower `t_max` and returns true to stop.
    #[inline(always)]
    fn traverse<const N: usize>(
        &self,
        stack: &mut Stack<Entry, N>,
        ray: &RayBoxes,
        t_max: &mut f32,
        tally: &impl Tally,
        mut leaf: impl FnMut(usize, usize, &mut f32) -> bool,
    ) {
        // The root, then the nearest inner child met by each node, is visited without a push
        // and a pop; the other inner children wait on the stack. The visiting order is the
        // stack's: nearest first, then the rest near to far.
        let mut entry = Entry::default();
        let mut limit = key_limit(*t_max);
        loop {
            if entry.0 <= limit {
                let Some(node) = Record::at(&self.store, entry.node()) else {
                    return;
                };
                tally.node();
                let (hits, t_enter) = node.intersect(ray, *t_max);
                let leaves = hits & node.leaves();
                if leaves != 0
                    && node.leaves_near_to_far(leaves, &t_enter, (t_max, &mut limit), &mut leaf)
                {
                    return;
                }
                let inner = hits & !node.leaves();
                if let Some(next) = node.push_inner(inner, &t_enter, (stack, &self.store)) {
                    entry = next;
                    continue;
                }
            }
            match stack.pop() {
                Some(next) => entry = next,
                None => return,
            }
        }
    }
}

/// The sort key of a met child: its entry distance's bits above its slot. Entry distances are
/// ≥ 0 (clamped; +∞ at most, never NaN), and the bits of non-negative floats order as the floats
/// do, so keys order children by entry distance, ties in slot order.
#[inline(always)]
fn order_key(t_enter: &[f32; 8], slot: u32) -> u64 {
    (t_enter[slot as usize & 7].to_bits() as u64) << 32 | slot as u64
}

/// The largest key (an [`Entry`]'s word or an [`order_key`]) of a child that may hold a hit
/// before `t_max` (> 0; leaves lower it): entered at t_enter ≤ fl(t_max + `f32::MIN_POSITIVE`).
/// The margin is the one the node test adds to the exit (see [`RayBoxes`]): a product that
/// underflows has an absolute, not a relative, error; above 2⁻¹⁰⁰ the sum is t_max itself. Keys
/// hold the entry distance's bits above 32 low bits, and the bits of non-negative floats order
/// as the floats, so one integer comparison per pop and per leaf tells; the limit is recomputed
/// only when t_max falls.
#[inline(always)]
fn key_limit(t_max: f32) -> u64 {
    ((t_max + f32::MIN_POSITIVE).to_bits() as u64) << 32 | 0xffff_ffff
}

/// The smallest (`pick` = `u64::min`) or largest key among the slots set in `mask` (not empty).
/// Picking children one at a time orders the few a node meets (one to three, mostly) without
/// an array of keys in memory: a node meeting k children costs k(k − 1)/2 comparisons.
#[inline(always)]
fn pick_key(mut mask: u32, t_enter: &[f32; 8], pick: impl Fn(u64, u64) -> u64) -> u64 {
    let mut best = order_key(t_enter, mask.trailing_zeros());
    mask &= mask - 1;
    while mask != 0 {
        best = pick(best, order_key(t_enter, mask.trailing_zeros()));
        mask &= mask - 1;
    }
    best
}

impl Record<'_> {
    /// Calls `leaf` on the leaf children in `leaves` (not empty), near to far, skipping those
    /// that start beyond `t_max` (keys above `limit`, [`key_limit`]) as `leaf` lowers it; true
    /// when `leaf` asks to stop.
    #[inline(always)]
    fn leaves_near_to_far(
        &self,
        mut leaves: u32,
        t_enter: &[f32; 8],
        (t_max, limit): (&mut f32, &mut u64),
        leaf: &mut impl FnMut(usize, usize, &mut f32) -> bool,
    ) -> bool {
        while leaves != 0 {
            let key = pick_key(leaves, t_enter, u64::min);
            let slot = key as usize & 7;
            leaves &= !(1 << slot);
            let (first, count) = (self.child(slot) as usize, self.count(slot));
            if key <= *limit {
                if leaf(first, count, t_max) {
                    return true;
                }
                *limit = key_limit(*t_max);
            }
        }
        false
    }

    /// Pushes the inner children in `inner` but the nearest far to near, so they pop near to
    /// far, and returns the nearest (None when `inner` is empty). Each pushed child's record
    /// is touched ([`touch`]) as it is pushed.
    #[inline(always)]
    fn push_inner<const N: usize>(
        &self,
        mut inner: u32,
        t_enter: &[f32; 8],
        (stack, store): (&mut Stack<Entry, N>, &[f32]),
    ) -> Option<Entry> {
        if inner == 0 {
            return None;
        }
        while inner & (inner - 1) != 0 {
            let key = pick_key(inner, t_enter, u64::max);
            inner &= !(1 << (key & 7));
            let entry = Entry::child(self, key);
            touch(store, entry.node());
            stack.push(entry);
        }
        Some(Entry::child(
            self,
            order_key(t_enter, inner.trailing_zeros()),
        ))
    }

    /// Mask of the children (bit = slot) whose boxes the ray meets within [0, t_max], and the
    /// widened entry distance of each slot.
    #[inline(always)]
    fn intersect(&self, ray: &RayBoxes, t_max: f32) -> (u32, [f32; 8]) {
        let t_max = Vec4::splat(t_max);
        let (m0, t0) = slab_half(self.half(0), ray, t_max);
        let (m1, t1) = slab_half(self.half(1), ray, t_max);
        let (t0, t1) = (t0.to_array(), t1.to_array());
        let t_enter = [t0[0], t0[1], t0[2], t0[3], t1[0], t1[1], t1[2], t1[3]];
        // No mask of the slots that hold a child: an empty slot's box is the empty one, whose
        // entry (+∞ on an axis the ray is not parallel to) never precedes its exit (−∞), and
        // it counts as a leaf of no triangles, so a ray parallel to all three axes' slabs
        // (|d| < 2⁻¹²⁷ on each), which meets every box, tests nothing there (`store::build`).
        ((m0 | m1 << 4), t_enter)
    }
}

/// Loads the first word of the record at `offset`: a subtree left on the stack starts on its
/// way into the cache while the nearer one is traversed, a prefetch without `unsafe`
/// (`_mm_prefetch` needs it: docs/design.md §8, session 35). The word is a plane, never this
/// NaN, so the call is never made, but the compiler cannot drop the load (and the call would
/// be harmless).
#[inline(always)]
fn touch(store: &[f32], offset: usize) {
    if store
        .get(offset)
        .is_some_and(|w| w.to_bits() == 0x7fc0_dead)
    {
        never_a_plane();
    }
}

/// [`touch`]'s branch target, which no store reaches: it only keeps the branch (and so the
/// load) in the code.
#[cold]
#[inline(never)]
fn never_a_plane() {
    std::hint::black_box(());
}

/// Nodes and triangles tested by the queries given it ([`Bvh::count_closest`],
/// [`Bvh::count_any`]).
#[derive(Debug, Default)]
pub struct TraversalCount {
    pub nodes: Cell<u64>,
    pub triangles: Cell<u64>,
}

/// What a traversal reports of its work: nothing for the queries (`()`, which compiles to no
/// code), counts for [`TraversalCount`].
trait Tally {
    fn node(&self);
    fn triangles(&self, n: usize);
}

impl Tally for () {
    #[inline(always)]
    fn node(&self) {}
    #[inline(always)]
    fn triangles(&self, _: usize) {}
}

impl Tally for TraversalCount {
    fn node(&self) {
        self.nodes.set(self.nodes.get() + 1);
    }
    fn triangles(&self, n: usize) {
        self.triangles.set(self.triangles.get() + n as u64);
    }
}

/// Per-ray part of the box test. A plane's distance is r = fl(fl(p − o)·fl(1/d)); a child's
/// entry is fl(max(0, r_near…)·s) with s = 1 − 2γ(4), its exit fl(min(t_max, r_far…)·s′) with
/// s′ = 1 + 2γ(4): four roundings, so each is within γ(4) (relative) of the exact (p − o)·s/d
/// and of the same sign (standard model, PBR 4ed §6.8.1; max, min and the clamps at 0 and t_max
/// are exact and commute with the positive scale), and the widening by 2γ(4) makes the interval
/// contain the exact one (PBR 4ed §6.8.2 scales the exit only; we also compare the entry with
/// t_max). The scale is applied once to the nearest exit and the farthest entry, not per plane,
/// so the node test keeps six splatted vectors (o and 1/d per axis) in registers instead of
/// twelve. The exit is moved out by twice the smallest normal float as well, which covers
/// products that underflow.
/// An axis with a non-finite 1/d·s′ (the ray is parallel to its slabs, or |d| < 2⁻¹²⁷ there)
/// constrains nothing: its splatted origin is NaN, so its planes' distances are NaN, which
/// [`max_or_acc`] and [`min_or_acc`] skip. No other distance is NaN: p − o is finite or ±∞ and
/// 1/d finite and non-zero elsewhere (a non-finite d never reaches the BVH).
struct RayBoxes {
    /// Per axis: the plane row (see [`WideNode::planes`], the store's layout) of the near
    /// slab; the far one is `near ^ 1`.
    near: [usize; 3],
    /// Per axis, splatted: a plane's distance is (plane − o)·inv.
    o: [Vec4; 3],
    inv: [Vec4; 3],
}

/// Widening factors of the slab distances (see [`RayBoxes`]).
const ENTER_SCALE: f32 = 1.0 - 2.0 * gamma(4);
const EXIT_SCALE: f32 = 1.0 + 2.0 * gamma(4);

impl RayBoxes {
    #[inline(always)]
    fn new(ray: &Ray) -> RayBoxes {
        let inv = Vec4::ONE / Vec4::from((ray.d, 1.0));
        // |1/d·s′| ≥ |1/d·s|: where the exit's factor is finite, so is the entry's.
        let finite = (inv * EXIT_SCALE).is_finite_mask();
        let o = Vec4::select(finite, Vec4::from((ray.o, 0.0)), Vec4::NAN);
        let neg = inv.cmplt(Vec4::ZERO).bitmask() as usize;
        let splats = |v: Vec4| [Vec4::splat(v.x), Vec4::splat(v.y), Vec4::splat(v.z)];
        RayBoxes {
            near: [neg & 1, 2 | (neg >> 1 & 1), 4 | (neg >> 2 & 1)],
            o: splats(o),
            // A non-finite axis's 1/d (±∞ or huge) needs no replacing: (p − NaN)·anything is NaN.
            inv: splats(inv),
        }
    }
}

/// max(a, acc) per lane, and acc where a is NaN (`acc` is never NaN). SSE's `maxps`, which
/// glam's `max` is on x86, returns its second operand when either is NaN (Intel SDM, MAXPS);
/// elsewhere (NEON's `vmaxq_f32` propagates NaN) a compare and select says the same.
#[inline(always)]
fn max_or_acc(a: Vec4, acc: Vec4) -> Vec4 {
    if cfg!(any(target_arch = "x86", target_arch = "x86_64")) {
        a.max(acc)
    } else {
        Vec4::select(a.cmpgt(acc), a, acc)
    }
}

/// min(a, acc) per lane, and acc where a is NaN (see [`max_or_acc`]; SSE's `minps` likewise).
#[inline(always)]
fn min_or_acc(a: Vec4, acc: Vec4) -> Vec4 {
    if cfg!(any(target_arch = "x86", target_arch = "x86_64")) {
        a.min(acc)
    } else {
        Vec4::select(a.cmplt(acc), a, acc)
    }
}

/// The planes of slots without a child: the empty box, min +∞ and max −∞ on every axis.
const EMPTY_MIN: Vec4 = Vec4::splat(f32::INFINITY);
const EMPTY_MAX: Vec4 = Vec4::splat(f32::NEG_INFINITY);

impl WideNode {
    /// No child; each slot's box the empty box (min +∞, max −∞), which no ray meets (see
    /// `store::build`).
    const EMPTY: WideNode = WideNode {
        planes: [[
            EMPTY_MIN, EMPTY_MAX, EMPTY_MIN, EMPTY_MAX, EMPTY_MIN, EMPTY_MAX,
        ]; 2],
        child: [0; 8],
        count: [0; 8],
        present: 0,
        leaves: 0,
    };

    fn set_box(&mut self, slot: usize, (lo, hi): (Vec3, Vec3)) {
        let (half, lane) = (slot / 4, slot % 4);
        for k in 0..3 {
            self.planes[half][2 * k][lane] = lo[k];
            self.planes[half][2 * k + 1][lane] = hi[k];
        }
        self.present |= 1 << slot;
    }
}

/// The slab test of four children (PBR 4ed §6.1.2, widened as described at [`RayBoxes`]):
/// the overlap mask (4 bits) and the entry distances (≥ +0, never NaN).
#[inline(always)]
fn slab_half(planes: &[f32; 24], ray: &RayBoxes, t_max: Vec4) -> (u32, Vec4) {
    let distance = |row: usize, k: usize| (store::plane(planes, row) - ray.o[k]) * ray.inv[k];
    let (mut enter, mut exit) = (Vec4::ZERO, t_max);
    for k in 0..3 {
        enter = max_or_acc(distance(ray.near[k], k), enter);
        exit = min_or_acc(distance(ray.near[k] ^ 1, k), exit);
    }
    let t_enter = enter * ENTER_SCALE;
    let t_exit = exit * EXIT_SCALE + Vec4::splat(2.0 * f32::MIN_POSITIVE);
    (t_enter.cmple(t_exit).bitmask(), t_enter)
}

/// Our nodes from obvhs's: same indices and slots, exact child boxes. obvhs appends a node's
/// children after it, so one pass from the back sees every child's box before its parent's.
fn wide_nodes(cw: &[CwBvhNode], triangles: &[[Vec3; 3]]) -> Vec<WideNode> {
    let mut nodes = vec![WideNode::EMPTY; cw.len()];
    let mut boxes = vec![(Vec3::INFINITY, Vec3::NEG_INFINITY); cw.len()];
    for n in (0..cw.len()).rev() {
        let mut node = WideNode::EMPTY;
        let mut node_box = (Vec3::INFINITY, Vec3::NEG_INFINITY);
        for slot in (0..8).filter(|&s| !cw[n].is_child_empty(s)) {
            let child_box = if cw[n].is_leaf(slot) {
                let (first, count) = cw[n].child_primitives(slot);
                node.child[slot] = first;
                node.count[slot] = count as u8;
                node.leaves |= 1 << slot;
                bounds_of(&triangles[first as usize..(first + count) as usize])
            } else {
                let child = cw[n].child_node_index(slot);
                assert!(
                    child as usize > n,
                    "obvhs stores children after their parent"
                );
                node.child[slot] = child;
                boxes[child as usize]
            };
            node.set_box(slot, child_box);
            node_box = (node_box.0.min(child_box.0), node_box.1.max(child_box.1));
        }
        (nodes[n], boxes[n]) = (node, node_box);
    }
    nodes
}

/// Number of nodes on the longest root-to-leaf path.
#[cfg(test)]
fn tree_depth(store: &[f32]) -> usize {
    let mut deepest = 0;
    let mut pending = vec![(0u32, 1usize)];
    while let Some((offset, depth)) = pending.pop() {
        deepest = deepest.max(depth);
        let node = Record::at(store, offset as usize).expect("a record");
        for slot in 0..8 {
            if (node.present() & !node.leaves()) & (1 << slot) != 0 {
                pending.push((node.child(slot), depth + 1));
            }
        }
    }
    deepest
}

fn bounds_of(triangles: &[[Vec3; 3]]) -> (Vec3, Vec3) {
    let init = (Vec3::INFINITY, Vec3::NEG_INFINITY);
    triangles
        .iter()
        .flatten()
        .fold(init, |(lo, hi), &p| (lo.min(p), hi.max(p)))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::triangle::intersect;
    use crate::testing::rng::Rng;

    const _: () = {
        const fn assert_send_sync<T: Send + Sync>() {}
        assert_send_sync::<Bvh>();
    };

    /// Closest hit over all triangles in input order (the first of equal t wins).
    fn brute_closest(tris: &[[Vec3; 3]], ray: &Ray, t_max: f32) -> Option<BvhHit> {
        let mut best: Option<BvhHit> = None;
        let mut t_max = t_max;
        for (i, t) in tris.iter().enumerate() {
            if let Some(hit) = intersect(ray, t[0], t[1], t[2], t_max) {
                t_max = hit.t;
                best = Some(BvhHit {
                    prim: i as u32,
                    slot: u32::MAX,
                    hit,
                });
            }
        }
        best
    }

    fn brute_occluded(tris: &[[Vec3; 3]], ray: &Ray, t_max: f32) -> bool {
        tris.iter()
            .any(|t| intersect(ray, t[0], t[1], t[2], t_max).is_some())
    }

    /// Asserts the BVH answers exactly as brute force: same t bit for bit, and the same
    /// triangle unless another one is hit at exactly that t (shared edges, duplicates).
    fn assert_agrees(bvh: &Bvh, tris: &[[Vec3; 3]], ray: &Ray, t_max: f32) {
        let expected = brute_closest(tris, ray, t_max);
        let got = bvh.intersect(ray, t_max);
        match (expected, got) {
            (None, None) => {}
            (Some(e), Some(g)) => {
                assert_eq!(e.hit.t, g.hit.t, "{ray:?} t_max {t_max}: {e:?} vs {g:?}");
                if e.prim != g.prim {
                    let t = tris[g.prim as usize];
                    let again = intersect(ray, t[0], t[1], t[2], f32::INFINITY).unwrap();
                    assert_eq!(again.t, e.hit.t, "{ray:?}: {e:?} vs {g:?}");
                }
                assert!(g.hit.t.is_finite() && g.hit.b0.is_finite());
                assert_eq!(
                    bvh.vertices(&g),
                    tris[g.prim as usize],
                    "the hit's vertices"
                );
            }
            (e, g) => panic!("{ray:?} t_max {t_max}: brute force {e:?}, BVH {g:?}"),
        }
        assert_eq!(
            bvh.occluded(ray, t_max),
            brute_occluded(tris, ray, t_max),
            "{ray:?} t_max {t_max}"
        );
    }

    fn random_soup(rng: &mut Rng, n: usize, scale: f32) -> Vec<[Vec3; 3]> {
        let center = rng.vec3(-3.0, 3.0) * scale;
        (0..n)
            .map(|k| {
                let c = center + rng.vec3(-1.0, 1.0) * scale;
                let size = scale * if k % 10 == 0 { 0.5 } else { 0.05 };
                [0, 1, 2].map(|_| c + rng.vec3(-1.0, 1.0) * size)
            })
            .collect()
    }

    /// Axis-aligned quads (floors, walls, box faces) on a coarse lattice: triangles lying in
    /// child-box faces, shared edges on box boundaries, exactly axis-parallel rays.
    fn axis_aligned_scene(rng: &mut Rng, n_quads: usize, scale: f32) -> Vec<[Vec3; 3]> {
        let mut tris = Vec::new();
        for _ in 0..n_quads {
            let axis = rng.below(3);
            let (u, v) = ((axis + 1) % 3, (axis + 2) % 3);
            let mut base = Vec3::ZERO;
            base[axis] = rng.below(5) as f32 * 0.25 * scale;
            base[u] = rng.below(8) as f32 * 0.125 * scale;
            base[v] = rng.below(8) as f32 * 0.125 * scale;
            let (mut du, mut dv) = (Vec3::ZERO, Vec3::ZERO);
            du[u] = 0.125 * scale;
            dv[v] = 0.125 * scale;
            tris.push([base, base + du, base + du + dv]);
            tris.push([base, base + du + dv, base + dv]);
        }
        tris
    }

    fn random_ray(rng: &mut Rng, center: Vec3, extent: f32) -> Ray {
        let o = center + rng.vec3(-1.5, 1.5) * extent;
        let mut d = match rng.below(4) {
            0 => (center + rng.vec3(-0.5, 0.5) * extent) - o, // unnormalised, towards the scene
            _ => rng.unit_vector(),
        };
        // Exactly axis-parallel directions and zero components.
        match rng.below(8) {
            0 => d = Vec3::ZERO.with_x(d.x.signum()),
            1 => d.y = 0.0,
            2 => d.z = -0.0,
            _ => {}
        }
        Ray::new(o, d)
    }

    fn random_t_max(rng: &mut Rng, extent: f32) -> f32 {
        match rng.below(3) {
            0 => f32::INFINITY,
            _ => rng.range(0.0, 3.0) * extent,
        }
    }

    #[test]
    fn empty_and_all_degenerate_never_hit() {
        let mut rng = Rng::new(1);
        let empty = Bvh::build(&[]);
        assert_eq!(empty.triangle_count(), 0);
        assert_eq!(empty.bounds(), (Vec3::ZERO, Vec3::ZERO));
        let a = Vec3::new(0.5, 0.25, 0.125);
        let degenerate = vec![
            [a, a, a],
            [a, a * 2.0, a * 3.0],
            [Vec3::NAN, Vec3::X, Vec3::Y],
            [Vec3::ZERO, Vec3::INFINITY, Vec3::Y],
        ];
        let all_degenerate = Bvh::build(&degenerate);
        assert_eq!(all_degenerate.triangle_count(), 4);
        assert_eq!(all_degenerate.bounds(), (Vec3::ZERO, Vec3::ZERO));
        for _ in 0..1000 {
            let r = random_ray(&mut rng, a, 2.0);
            for bvh in [&empty, &all_degenerate] {
                assert!(bvh.intersect(&r, f32::INFINITY).is_none());
                assert!(!bvh.occluded(&r, f32::INFINITY));
            }
        }
    }

    /// The store holds every hittable triangle once, right after the record of the node whose
    /// leaf holds it, with its input index and its vertices bit for bit.
    #[test]
    fn leaves_follow_their_node_in_the_store() {
        let mut rng = Rng::new(11);
        let mut tris = random_soup(&mut rng, 2000, 1.0);
        tris[7] = [Vec3::ZERO; 3];
        let bvh = Bvh::build(&tris);
        let mut seen = vec![0; tris.len()];
        for (offset, node) in store::records(&bvh.store) {
            let mut next = offset + store::NODE_FLOATS;
            for slot in (0..8).filter(|&s| node.leaves() & (1 << s) != 0) {
                let first = node.child(slot) as usize;
                assert_eq!(first, next);
                for k in 0..node.count(slot) {
                    let at = first + TRI_FLOATS * k;
                    let prim = bvh.store[at + ROW_FLOATS].to_bits() as usize;
                    seen[prim] += 1;
                    let stored = PackedTriangle::at(&bvh.store, at).vertices();
                    assert_eq!(
                        stored.map(|p| p.to_array()),
                        tris[prim].map(|p| p.to_array())
                    );
                }
                next += TRI_FLOATS * node.count(slot);
            }
        }
        let expected: Vec<u32> = (0..tris.len()).map(|i| (i != 7) as u32).collect();
        assert_eq!(seen, expected);
        assert_eq!(bvh.memory_bytes().1, 4 * TRI_FLOATS * (tris.len() - 1));
    }

    #[test]
    fn single_triangle() {
        let mut rng = Rng::new(2);
        let tri = [[
            Vec3::new(0.3, -0.2, 0.1),
            Vec3::new(1.7, 0.4, -0.3),
            Vec3::new(0.1, 1.3, 0.9),
        ]];
        let bvh = Bvh::build(&tri);
        assert_eq!(bvh.triangle_count(), 1);
        assert_eq!(
            bvh.bounds(),
            (Vec3::new(0.1, -0.2, -0.3), Vec3::new(1.7, 1.3, 0.9))
        );
        let mut hits = 0;
        for _ in 0..20_000 {
            let target = tri[0][0]
                .lerp(tri[0][1], rng.f32())
                .lerp(tri[0][2], rng.f32());
            let o = target + rng.unit_vector() * rng.range(0.01, 5.0);
            for r in [
                Ray::new(o, target - o),
                random_ray(&mut rng, Vec3::splat(0.5), 1.0),
            ] {
                let t_max = random_t_max(&mut rng, 2.0);
                assert_agrees(&bvh, &tri, &r, t_max);
                hits += bvh.intersect(&r, t_max).is_some() as usize;
            }
        }
        assert!(hits > 10_000, "{hits}");
    }

    #[test]
    fn matches_brute_force_on_random_soups() {
        let mut rng = Rng::new(3);
        for (scale, n) in [(1.0, 3000), (1e-4, 2000), (1e5, 2000), (1.0, 40)] {
            let mut tris = random_soup(&mut rng, n, scale);
            // A few degenerate triangles and exact duplicates mixed in.
            tris[7] = [tris[3][0]; 3];
            tris[11] = tris[12];
            let bvh = Bvh::build(&tris);
            assert_eq!(bvh.triangle_count(), n);
            let (lo, hi) = bvh.bounds();
            let (center, extent) = (0.5 * (lo + hi), (hi - lo).max_element());
            let mut hits = 0;
            for k in 0..8000 {
                let r = if k % 2 == 0 {
                    // Aimed at a random point of a random triangle.
                    let t = tris[rng.below(n)];
                    let target = t[0].lerp(t[1], rng.f32()).lerp(t[2], rng.f32());
                    let o = center + rng.vec3(-1.5, 1.5) * extent;
                    Ray::new(o, (target - o).normalize())
                } else {
                    random_ray(&mut rng, center, extent)
                };
                let t_max = random_t_max(&mut rng, extent);
                assert_agrees(&bvh, &tris, &r, t_max);
                hits += bvh.intersect(&r, t_max).is_some() as usize;
            }
            assert!(hits > 2500, "scale {scale}: only {hits} hits");
        }
    }

    /// A direction below 2⁻¹²⁷ on every axis constrains no slab, so the ray meets every box,
    /// the empty slots' empty boxes too (leaves of no triangles, `store::build`): the queries
    /// still end and agree with brute force, on trees with partly filled nodes.
    #[test]
    fn rays_meeting_every_box_agree() {
        let mut rng = Rng::new(12);
        for n in [1, 5, 40, 300] {
            let tris = random_soup(&mut rng, n, 1.0);
            let bvh = Bvh::build(&tris);
            for _ in 0..200 {
                let o = rng.vec3(-2.0, 2.0);
                let d = rng.vec3(-1.0, 1.0) * 1e-39;
                assert_agrees(&bvh, &tris, &Ray::new(o, d), f32::INFINITY);
            }
        }
    }

    #[test]
    fn matches_brute_force_on_axis_aligned_scenes() {
        let mut rng = Rng::new(4);
        for scale in [1e-4, 1.0, 1e5] {
            let mut tris = axis_aligned_scene(&mut rng, 600, scale);
            // Offset far from the origin: coarse ulps relative to the geometry.
            let shift = Vec3::new(3.0, -7.0, 5.0) * scale;
            tris.iter_mut().flatten().for_each(|p| *p += shift);
            let bvh = Bvh::build(&tris);
            let (lo, hi) = bvh.bounds();
            let (center, extent) = (0.5 * (lo + hi), (hi - lo).max_element());
            let mut hits = 0;
            for k in 0..10_000 {
                let r = if k % 2 == 0 {
                    // Aim at a lattice point: vertices and shared edges of the quads.
                    let mut target = lo;
                    for a in 0..3 {
                        target[a] += rng.below(9) as f32 * 0.125 * scale;
                    }
                    let o = center + rng.vec3(-1.5, 1.5) * extent;
                    Ray::new(o, (target - o).normalize())
                } else {
                    random_ray(&mut rng, center, extent)
                };
                let t_max = random_t_max(&mut rng, extent);
                assert_agrees(&bvh, &tris, &r, t_max);
                hits += bvh.intersect(&r, t_max).is_some() as usize;
            }
            assert!(hits > 2000, "scale {scale}: only {hits} hits");
        }
    }

    /// The SAH builder's trees answer as brute force does, on soups (with degenerate triangles
    /// and duplicates), axis-aligned scenes far from the origin, and a floor hit through its
    /// shared vertices and edges; and, on a soup with a few large triangles around many small
    /// ones, their SAH is below PLOC's.
    #[test]
    fn sah_builder_matches_brute_force() {
        let mut rng = Rng::new(9);
        let mut soup = random_soup(&mut rng, 3000, 1.0);
        soup[7] = [soup[3][0]; 3];
        soup[11] = soup[12];
        let mut boxes = axis_aligned_scene(&mut rng, 600, 1e3);
        boxes
            .iter_mut()
            .flatten()
            .for_each(|p| *p += Vec3::splat(-7e3));
        let floor: Vec<[Vec3; 3]> = (0..40 * 40)
            .flat_map(|k| {
                let at = |i: usize, j: usize| Vec3::new(i as f32 * 0.1, 0.0, j as f32 * 0.07);
                let (i, j) = (k % 40, k / 40);
                [
                    [at(i, j), at(i + 1, j), at(i + 1, j + 1)],
                    [at(i, j), at(i + 1, j + 1), at(i, j + 1)],
                ]
            })
            .collect();
        for tris in [&soup, &boxes, &floor] {
            let bvh = Bvh::build_with(tris, Builder::Sah);
            let (lo, hi) = bvh.bounds();
            let (center, extent) = (0.5 * (lo + hi), (hi - lo).max_element());
            let mut hits = 0;
            for k in 0..6000 {
                let r = if k % 2 == 0 {
                    let t = tris[rng.below(tris.len())];
                    let target = t[0].lerp(t[1], [0.0, 1.0, rng.f32()][k % 3]);
                    let o = center + rng.vec3(-1.5, 1.5) * extent;
                    Ray::new(o, target - o)
                } else {
                    random_ray(&mut rng, center, extent)
                };
                let t_max = random_t_max(&mut rng, extent);
                assert_agrees(&bvh, tris, &r, t_max);
                hits += bvh.intersect(&r, t_max).is_some() as usize;
            }
            assert!(hits > 2000, "only {hits} hits");
        }
        // Many small triangles inside a room of twelve large ones (the limit scenes' shape).
        let mut walls: Vec<[Vec3; 3]> = (0..20_000)
            .map(|_| {
                let c = rng.vec3(-0.5, 0.5);
                [0, 1, 2].map(|_| c + rng.vec3(-0.01, 0.01))
            })
            .collect();
        for axis in 0..3 {
            for side in [-1.0, 1.0] {
                let corner = |u: f32, v: f32| {
                    let mut p = Vec3::splat(side);
                    (p[(axis + 1) % 3], p[(axis + 2) % 3]) = (u, v);
                    p
                };
                let (a, b) = (corner(-1.0, -1.0), corner(1.0, 1.0));
                walls.push([a, corner(1.0, -1.0), b]);
                walls.push([a, b, corner(-1.0, 1.0)]);
            }
        }
        let [ploc, sah] =
            [Builder::Ploc, Builder::Sah].map(|b| Bvh::build_with(&walls, b).sah_cost());
        assert!(sah.nodes < ploc.nodes, "{sah:?} vs {ploc:?}");
    }

    /// A tessellated axis-aligned floor seen through the BVH: rays through shared vertices and
    /// edges (which lie on child-box faces) never fall through.
    #[test]
    fn watertight_through_the_bvh() {
        let mut rng = Rng::new(5);
        for (scale, offset) in [(1.0, 0.0), (1e-4, 1e-2), (1e5, 3e5)] {
            let n = 48;
            let at = |i: usize, j: usize| {
                Vec3::new(
                    i as f32 * 0.1 * scale + offset,
                    offset,
                    j as f32 * 0.07 * scale - offset,
                )
            };
            let mut tris = Vec::new();
            for j in 0..n {
                for i in 0..n {
                    tris.push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
                    tris.push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
                }
            }
            let bvh = Bvh::build(&tris);
            let mut misses = 0;
            for k in 0..30_000 {
                let (i, j) = (1 + rng.below(n - 1), 1 + rng.below(n - 1));
                let target = match k % 3 {
                    0 => at(i, j),
                    1 => at(i, j).lerp(at(i + 1, j), rng.f32()),
                    _ => at(i, j).lerp(at(i + 1, j + 1), rng.f32()),
                };
                let mut dir = rng.unit_vector();
                dir.y = dir.y.abs().max(0.05) * if k % 2 == 0 { 1.0 } else { -1.0 };
                let o = target + dir * rng.range(0.01, 10.0) * scale;
                let r = Ray::new(o, target - o);
                if bvh.intersect(&r, f32::INFINITY).is_none() || !bvh.occluded(&r, f32::INFINITY) {
                    misses += 1;
                }
            }
            assert_eq!(misses, 0, "scale {scale}");
        }
    }

    /// Rays parallel to an axis whose origin lies exactly in box planes of that axis (where a
    /// naive slab test computes 0·∞ = NaN): walls standing on y = 0 hit at their bottom edge
    /// by rays running along y = 0, and boxes the ray only touches.
    #[test]
    fn axis_parallel_rays_in_box_planes() {
        let mut rng = Rng::new(8);
        // Unit quads in the planes x = 2, 3, ..., 9, spanning y in [0, 1] and z in [0, 1].
        let mut tris = Vec::new();
        for i in 2..10 {
            let x = i as f32;
            let (a, b) = (Vec3::new(x, 0.0, 0.0), Vec3::new(x, 1.0, 0.0));
            let (c, d) = (Vec3::new(x, 1.0, 1.0), Vec3::new(x, 0.0, 1.0));
            tris.extend([[a, b, c], [a, c, d]]);
        }
        let bvh = Bvh::build(&tris);
        let mut hits = 0;
        for k in 0..4000 {
            // y and z on the box planes 0 and 1 or inside; x before, between or after the walls.
            let on_plane = |rng: &mut Rng| [0.0, 1.0, rng.f32()][rng.below(3)];
            let o = Vec3::new(rng.range(0.0, 11.0), on_plane(&mut rng), on_plane(&mut rng));
            let d = [Vec3::X, Vec3::NEG_X, Vec3::Y, Vec3::NEG_Z][k % 4] * rng.range(0.5, 2.0);
            let r = Ray::new(o, d);
            let t_max = random_t_max(&mut rng, 10.0);
            assert_agrees(&bvh, &tris, &r, t_max);
            hits += bvh.intersect(&r, t_max).is_some() as usize;
        }
        assert!(hits > 1000, "{hits}");
    }

    /// obvhs's own node test ignores boxes left before t = 1e-4; ours must not.
    #[test]
    fn finds_hits_at_tiny_t() {
        for scale in [1e-6f32, 1e-4, 1e-2] {
            let tris = [[
                Vec3::new(0.0, 0.0, 0.0),
                Vec3::new(scale, 0.0, 0.0),
                Vec3::new(0.0, scale, 0.0),
            ]];
            let bvh = Bvh::build(&tris);
            let o = Vec3::new(0.25 * scale, 0.25 * scale, 0.01 * scale);
            let r = Ray::new(o, Vec3::new(0.0, 0.0, -1.0));
            let hit = bvh.intersect(&r, f32::INFINITY).expect("tiny-t hit");
            assert!((hit.hit.t - 0.01 * scale).abs() <= 1e-6 * scale);
            assert!(bvh.occluded(&r, 1.0));
        }
    }

    /// The node test's max and min skip a NaN distance (an axis that constrains nothing) on
    /// either side of the accumulator, and are max and min otherwise.
    #[test]
    fn nan_distances_are_skipped() {
        let acc = Vec4::new(0.0, 1.0, -2.0, f32::INFINITY);
        let a = Vec4::new(f32::NAN, 3.0, -5.0, f32::NAN);
        assert_eq!(
            max_or_acc(a, acc).to_array(),
            [0.0, 3.0, -2.0, f32::INFINITY]
        );
        assert_eq!(
            min_or_acc(a, acc).to_array(),
            [0.0, 1.0, -5.0, f32::INFINITY]
        );
    }

    /// `key_limit` admits every child entered at or before t_max + `f32::MIN_POSITIVE`, in
    /// every slot, from subnormal to infinite distances, and nothing entered beyond it.
    #[test]
    fn key_limit_admits_exactly_up_to_the_margin() {
        let t_maxes = [
            1e-44,
            f32::MIN_POSITIVE,
            3e-30,
            0.5,
            1.0,
            7.25e3,
            3e38,
            f32::INFINITY,
        ];
        for t_max in t_maxes {
            let limit = key_limit(t_max);
            let edge = t_max + f32::MIN_POSITIVE;
            let below = [0.0, t_max * 0.5, t_max, edge.next_down(), edge];
            for slot in 0..8 {
                for t_enter in below {
                    let key = order_key(&[t_enter; 8], slot);
                    assert!(key <= limit, "t_max {t_max}: {t_enter} in slot {slot}");
                    let entry = Entry::child(&Record::EMPTY, key);
                    assert!(entry.0 <= limit, "t_max {t_max}: entry at {t_enter}");
                }
                if edge < f32::INFINITY {
                    let key = order_key(&[edge.next_up(); 8], slot);
                    assert!(key > limit, "t_max {t_max}: {} admitted", edge.next_up());
                }
            }
        }
    }

    /// Triangles at geometrically growing distances give a deep tree, a random soup a bushy
    /// one. Traversals with 1, 2 and the default number of in-place stack entries (the first
    /// two spill to the heap) all find brute force's hit.
    #[test]
    fn deep_trees_and_stack_spills() {
        let mut rng = Rng::new(6);
        let deep: Vec<[Vec3; 3]> = (0..400)
            .map(|k| {
                let c = Vec3::splat(1.12f32.powi(k) * 1e-6);
                [c, c + Vec3::X * 1e-7, c + Vec3::Y * 1e-7]
            })
            .collect();
        let soup = random_soup(&mut rng, 3000, 1.0);
        let mut spills = 0;
        for (tris, k) in [(&deep, 0), (&soup, 1)] {
            let bvh = Bvh::build(tris);
            assert!(tree_depth(&bvh.store) >= 3);
            let (lo, hi) = bvh.bounds();
            let (center, extent) = (0.5 * (lo + hi), (hi - lo).max_element());
            for _ in 0..3000 {
                let r = if k == 0 {
                    let k = rng.below(tris.len());
                    let target = (tris[k][0] + tris[k][1] + tris[k][2]) / 3.0;
                    let o = target + Vec3::new(0.1, -0.2, 1.0) * 1.12f32.powi(k as i32) * 1e-6;
                    Ray::new(o, target - o)
                } else {
                    random_ray(&mut rng, center, extent)
                };
                let Some((tri, boxes)) = bvh.query(&r, f32::INFINITY) else {
                    continue;
                };
                let q = (&tri, &boxes);
                let (mut one, mut two) = (Stack::<Entry, 1>::new(), Stack::<Entry, 2>::new());
                let results = [
                    bvh.closest(&mut one, q, f32::INFINITY, &()),
                    bvh.closest(&mut two, q, f32::INFINITY, &()),
                    bvh.closest(
                        &mut Stack::<Entry, STACK_PLACES>::new(),
                        q,
                        f32::INFINITY,
                        &(),
                    ),
                ];
                spills += two.spilled() as usize;
                let expected = brute_closest(tris, &r, f32::INFINITY).map(|h| h.hit.t);
                for got in results {
                    assert_eq!(got.map(|h| h.hit.t), expected);
                }
            }
        }
        assert!(spills > 100, "{spills}");
    }

    /// Rays spawned from hit points on a tessellated, tilted planar mesh (PBR 4ed §6.8.6 offsets)
    /// re-hit neither their own triangle nor a neighbour, at every scene scale.
    #[test]
    fn spawned_rays_leave_a_planar_mesh() {
        use crate::geometry::offset::spawn_ray;
        use crate::geometry::triangle::hit_point_error;
        let mut rng = Rng::new(7);
        for scale in [1e-4f32, 1.0, 1e5] {
            let (u, v) = (
                Vec3::new(0.9, 0.3, -0.2).normalize() * 0.113 * scale,
                Vec3::new(-0.1, 0.4, 0.9).normalize() * 0.097 * scale,
            );
            let origin = Vec3::new(7.1, -3.3, 5.9) * scale;
            let at = |i: usize, j: usize| origin + u * i as f32 + v * j as f32;
            let n = 24;
            let mut tris = Vec::new();
            for j in 0..n {
                for i in 0..n {
                    tris.push([at(i, j), at(i + 1, j), at(i + 1, j + 1)]);
                    tris.push([at(i, j), at(i + 1, j + 1), at(i, j + 1)]);
                }
            }
            let bvh = Bvh::build(&tris);
            let normal = u.cross(v).normalize();
            let mut spawned = 0;
            for k in 0..20_000 {
                let target = at(1 + rng.below(n - 2), 1 + rng.below(n - 2))
                    + (u * rng.range(-0.5, 0.5) + v * rng.range(-0.5, 0.5))
                        * if k % 2 == 0 { 1.0 } else { 1e-3 };
                let o = target + rng.unit_vector() * rng.range(0.1, 5.0) * scale;
                let Some(h) = bvh.intersect(&Ray::new(o, target - o), f32::INFINITY) else {
                    continue;
                };
                let [p0, p1, p2] = tris[h.prim as usize];
                let p = h.hit.point(p0, p1, p2);
                let err = hit_point_error(&h.hit, p0, p1, p2);
                let n_geo = (p1 - p0).cross(p2 - p0);
                let w = rng.unit_vector();
                let w = if rng.below(8) == 0 {
                    (w - w.dot(normal) * normal + normal * 1e-4 * w.dot(normal).signum())
                        .normalize()
                } else {
                    w
                };
                let ray = spawn_ray(p, err, n_geo, w);
                spawned += 1;
                let rehit = bvh.intersect(&ray, f32::INFINITY);
                assert!(
                    rehit.is_none(),
                    "scale {scale}: {ray:?} from {:?} re-hit {rehit:?}",
                    h.prim
                );
            }
            assert!(spawned > 15_000, "{spawned}");
        }
    }
}
