//! Triangle BVH: obvhs's compressed 8-wide BVH (CWBVH; Ylitie, Karras, Laine 2017, "Efficient
//! Incoherent Ray Traversal on GPUs Through Compressed Wide BVHs"), built bottom-up with PLOC
//! (Meister, Bittner 2018, "Parallel Locally-Ordered Clustering for Bounding Volume Hierarchy
//! Construction") plus reinsertion (Meister, Bittner 2017, "Parallel Reinsertion for Bounding
//! Volume Hierarchy Optimization"), traversed on the CPU with obvhs's `traverse!` loop.
//! This is the only module that names obvhs.
//!
//! Robustness. Two parts of the traversal are ours rather than obvhs's:
//! - **Triangles**: the watertight test of [`crate::geometry::triangle`], on triangles copied
//!   into BVH primitive order (no index indirection per test).
//! - **Child boxes**: obvhs's node test clips at t ≥ 1e-4 (which loses hits at small scene
//!   scales) and is not conservative under rounding (so a hit on a triangle lying in a box face —
//!   every axis-aligned floor — can be culled). Ours tests t ∈ [0, t_max] against boxes widened
//!   by 1/64 of a quantisation step (covering the builder's f32 quantisation) and slab
//!   distances widened by a forward error bound, in the spirit of PBR 4ed §6.8.2 ("Conservative
//!   Ray–Bounds Intersections"); see `slab_terms`.
//!
//! Degenerate triangles (zero area, or a non-finite vertex) are left out of the tree: they can
//! never be hit. `Bvh` is plain data (`Send + Sync`); queries allocate nothing (the traversal
//! stack lives on the call stack), except on pathologically deep trees (see `StackSize`).
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

use glam::{UVec2, Vec3, Vec3A, Vec4};
use obvhs::bvh2::reinsertion::ReinsertionOptimizer;
use obvhs::cwbvh::bvh2_to_cwbvh::bvh2_to_cwbvh;
use obvhs::cwbvh::node::{extract_byte64, CwBvhNode};
use obvhs::cwbvh::CwBvh;
use obvhs::faststack::{FastStack, HeapStack, StackStack};
use obvhs::ploc::{PlocBuilder, PlocSearchDistance, SortPrecision};
use obvhs::triangle::Triangle;

use crate::geometry::ray::Ray;
use crate::geometry::triangle::{
    intersect_non_degenerate, is_degenerate, TriangleHit, WatertightRay,
};

/// A hit found by the BVH: `prim` indexes the slice given to [`Bvh::build`].
#[derive(Clone, Copy, Debug)]
pub struct BvhHit {
    pub prim: u32,
    pub hit: TriangleHit,
}

/// A CWBVH over triangles, with the triangles stored in BVH primitive order.
pub struct Bvh {
    /// obvhs CWBVH nodes (80 bytes each); empty for a BVH without hittable triangles.
    nodes: Vec<CwBvhNode>,
    /// Triangles in BVH primitive order.
    triangles: Vec<[Vec3; 3]>,
    /// BVH primitive order → index into the slice given to `build`.
    input_index: Vec<u32>,
    /// Traversal stack needed by the deepest path of the tree.
    stack_size: StackSize,
    input_count: usize,
    bounds: (Vec3, Vec3),
}

/// Which traversal stack the tree needs. Wide BVHs are shallow (obvhs itself assumes depth < 32);
/// deeper trees only arise from adversarial inputs (e.g. geometrically spaced triangles).
#[derive(Clone, Copy, Debug, PartialEq)]
enum StackSize {
    /// 64 entries on the call stack (512 bytes).
    Small,
    /// 1024 entries on the call stack (8 KiB).
    Large,
    /// Heap-allocated per query, with this capacity.
    Heap(usize),
}

impl StackSize {
    /// obvhs's `StackStack<_, N>` holds N − 1 entries (a push on a full stack overwrites the top),
    /// and a traversal pushes at most one entry per level below the root.
    fn for_depth(depth: usize) -> StackSize {
        match depth + 2 {
            n if n < 64 => StackSize::Small,
            n if n < 1024 => StackSize::Large,
            n => StackSize::Heap(n),
        }
    }
}

/// Builds the CWBVH with the settings of obvhs's `medium_build` preset: PLOC with search radius
/// 14 (`PlocSearchDistance::Medium`, `search_depth_threshold` 3, 64-bit Morton codes),
/// reinsertion over 5% of the nodes, then collapse to 8-wide nodes with up to 3 triangles per
/// leaf (the CWBVH maximum), children ordered by octant. No spatial pre-splits: split boxes would
/// no longer bound whole triangles, which the conservative box test relies on for
/// watertightness at leaf boundaries.
/// (The body of obvhs's `build_cwbvh_from_tris`, minus its debug-build validation, which asserts
/// a depth below 32 and absolute 1e-5 box tolerances that large scenes exceed.)
/// Triangles per leaf.
const LEAF_SIZE: u32 = 3;

fn build_cwbvh(triangles: &[Triangle]) -> CwBvh {
    let indices = (0..triangles.len() as u32).collect();
    let mut bvh2 = PlocBuilder::with_capacity(triangles.len()).build(
        PlocSearchDistance::Medium,
        triangles,
        indices,
        SortPrecision::U64,
        3,
    );
    ReinsertionOptimizer::default().run(&mut bvh2, 0.05, None);
    bvh2_to_cwbvh(&bvh2, LEAF_SIZE, true, false)
}

impl Bvh {
    /// Builds a CWBVH over the triangles (each `[p0, p1, p2]`). Degenerate triangles are allowed
    /// and never hit; an empty slice gives a BVH that never hits.
    pub fn build(triangles: &[[Vec3; 3]]) -> Bvh {
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
        let cwbvh = build_cwbvh(&prims);
        let input_index: Vec<u32> = cwbvh
            .primitive_indices
            .iter()
            .map(|&k| kept[k as usize])
            .collect();
        let ordered: Vec<[Vec3; 3]> = input_index.iter().map(|&i| triangles[i as usize]).collect();
        Bvh {
            stack_size: StackSize::for_depth(tree_depth(&cwbvh.nodes)),
            nodes: cwbvh.nodes,
            bounds: bounds_of(&ordered),
            triangles: ordered,
            input_index,
            input_count: triangles.len(),
        }
    }

    fn empty(input_count: usize) -> Bvh {
        Bvh {
            nodes: Vec::new(),
            triangles: Vec::new(),
            input_index: Vec::new(),
            stack_size: StackSize::Small,
            input_count,
            bounds: (Vec3::ZERO, Vec3::ZERO),
        }
    }

    /// Closest hit with t in (0, t_max).
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<BvhHit> {
        let query = self.query(ray, t_max)?;
        let (i, hit) = match self.stack_size {
            StackSize::Small => self.closest(StackStack::<UVec2, 64>::default(), &query, t_max),
            StackSize::Large => self.closest(StackStack::<UVec2, 1024>::default(), &query, t_max),
            StackSize::Heap(n) => self.closest(HeapStack::new_with_capacity(n), &query, t_max),
        }?;
        Some(BvhHit {
            prim: self.input_index[i],
            hit,
        })
    }

    /// Whether anything is hit with t in (0, t_max) (shadow rays; stops at the first hit).
    pub fn occluded(&self, ray: &Ray, t_max: f32) -> bool {
        let Some(query) = self.query(ray, t_max) else {
            return false;
        };
        match self.stack_size {
            StackSize::Small => self.any(StackStack::<UVec2, 64>::default(), &query, t_max),
            StackSize::Large => self.any(StackStack::<UVec2, 1024>::default(), &query, t_max),
            StackSize::Heap(n) => self.any(HeapStack::new_with_capacity(n), &query, t_max),
        }
    }

    /// Number of triangles given to [`Bvh::build`] (degenerate ones included).
    pub fn triangle_count(&self) -> usize {
        self.input_count
    }

    /// World-space AABB `(min, max)` of the hittable triangles; both zero when there are none.
    pub fn bounds(&self) -> (Vec3, Vec3) {
        self.bounds
    }

    /// Per-ray setup, or None when nothing can be hit.
    fn query(&self, ray: &Ray, t_max: f32) -> Option<Query> {
        if self.nodes.is_empty() || t_max.is_nan() || t_max <= 0.0 {
            return None;
        }
        Some(Query {
            triangle: WatertightRay::new(ray)?,
            boxes: RayBoxes::new(ray),
        })
    }

    /// Closest-hit traversal: the BVH-order index and the hit.
    fn closest<S: FastStack<UVec2>>(
        &self,
        stack: S,
        query: &Query,
        mut t_max: f32,
    ) -> Option<(usize, TriangleHit)> {
        let mut state = TraversalState::new(stack, query.boxes.oct_inv4);
        let mut best = None;
        let mut node;
        obvhs::traverse!(
            self,
            node,
            state,
            node_hitmask(node, &query.boxes, t_max),
            {
                let i = state.primitive_id as usize;
                if let Some(hit) = self.hit_triangle(i, query, t_max) {
                    t_max = hit.t;
                    best = Some((i, hit));
                }
            }
        );
        best
    }

    /// Any-hit traversal with early exit.
    fn any<S: FastStack<UVec2>>(&self, stack: S, query: &Query, t_max: f32) -> bool {
        let mut state = TraversalState::new(stack, query.boxes.oct_inv4);
        let mut node;
        'traversal: {
            obvhs::traverse!(
                self,
                node,
                state,
                node_hitmask(node, &query.boxes, t_max),
                {
                    if self
                        .hit_triangle(state.primitive_id as usize, query, t_max)
                        .is_some()
                    {
                        break 'traversal true;
                    }
                }
            );
            false
        }
    }

    #[inline(always)]
    fn hit_triangle(&self, i: usize, query: &Query, t_max: f32) -> Option<TriangleHit> {
        let [p0, p1, p2] = self.triangles[i];
        intersect_non_degenerate(&query.triangle, p0, p1, p2, t_max)
    }
}

/// Traversal state in the shape obvhs's `traverse!` macro expects, with a stack of our choosing.
struct TraversalState<S> {
    stack: S,
    current_group: UVec2,
    primitive_group: UVec2,
    oct_inv4: u32,
    primitive_id: u32,
    hitmask: u32,
}

impl<S: FastStack<UVec2>> TraversalState<S> {
    /// Starts at the root: node 0 as the only member of the first node group (obvhs convention).
    fn new(stack: S, oct_inv4: u32) -> TraversalState<S> {
        TraversalState {
            stack,
            current_group: UVec2::new(0, 0x8000_0000),
            primitive_group: UVec2::ZERO,
            oct_inv4,
            primitive_id: 0,
            hitmask: 0,
        }
    }
}

/// Everything a query needs per ray.
struct Query {
    triangle: WatertightRay,
    boxes: RayBoxes,
}

/// Per-ray part of the child-box test.
struct RayBoxes {
    o: Vec3A,
    /// 1/d per axis (±∞ for a zero component).
    inv_d: Vec3A,
    negative: [bool; 3],
    /// Octant code for obvhs's child ordering (nearest children first).
    oct_inv4: u32,
}

impl RayBoxes {
    fn new(ray: &Ray) -> RayBoxes {
        let inv_d = Vec3A::ONE / Vec3A::from(ray.d);
        let code = |c: f32, bits: u32| if c < 0.0 { 0 } else { bits };
        RayBoxes {
            o: ray.o.into(),
            inv_d,
            negative: [inv_d.x < 0.0, inv_d.y < 0.0, inv_d.z < 0.0],
            // Same encoding as obvhs's (private) `ray_get_octant_inv4`.
            oct_inv4: code(ray.d.x, 0x0404_0404)
                | code(ray.d.y, 0x0202_0202)
                | code(ray.d.z, 0x0101_0101),
        }
    }
}

/// Margin, in quantisation steps, added on each side of every child box. The builder's
/// quantisation can shrink a box slightly: `floor`/`ceil` of a rounded f32 quotient (≤ 2e-5
/// step), and a scale e = 2^⌈log2(extent/255)⌉ whose f32 `log2` may round down to the integer,
/// so that the top plane is clamped to 255 steps while the box reaches up to 255·(1 + 8e-6)
/// steps (≤ 2.1e-3 step for any f32 exponent, allowing a 1-ulp `log2`). 1/64 step covers both
/// with a factor of 7 to spare and keeps q ± margin exact in f32 for every q ≤ 255.
const Q_MARGIN: f32 = 1.0 / 64.0;

/// γ(7) (PBR 4ed §6.8.1); see [`slab_terms`].
const SLAB_GAMMA: f32 = crate::geometry::offset::gamma(7);

/// Per-node, per-axis terms of the slab distances t(q) = q·a + b, with a = e/d, b = (p − o)/d
/// (node origin p, quantisation step e, a power of two). Evaluated in f32 as
/// fl(q·fl(e·fl(1/d))) + fl(fl(p − o)·fl(1/d)), t(q) has, by the standard model of PBR 4ed
/// §6.8.1, an absolute error below γ(5)·(|q a| + |b|) ≤ γ(5)·(256|a| + |b|) for |q| < 256;
/// widening by err = γ(7)·(256|a| + |b|) (the extra γ covers rounding the bound and adding it
/// to b) makes [t_near, t_far] contain the exact slab interval. Returns (a, b − err, b + err).
/// An axis whose terms are not finite (ray parallel to it, or overflow) is left unconstrained.
#[inline(always)]
fn slab_terms(node: &CwBvhNode, ray: &RayBoxes) -> (Vec3A, Vec3A, Vec3A) {
    let a = node.compute_extent() * ray.inv_d;
    let b = (Vec3A::from(node.p) - ray.o) * ray.inv_d;
    let err = SLAB_GAMMA * (256.0 * a.abs() + b.abs()) + Vec3A::splat(f32::MIN_POSITIVE);
    if err.is_finite() {
        return (a, b - err, b + err);
    }
    let (mut a, mut near, mut far) = (a, b - err, b + err);
    for k in 0..3 {
        if !err[k].is_finite() {
            (a[k], near[k], far[k]) = (0.0, f32::NEG_INFINITY, f32::INFINITY);
        }
    }
    (a, near, far)
}

/// Entry and exit distances of four children (`half` 0: children 0–3, 1: children 4–7) across
/// one axis's slabs, with the boxes widened by [`Q_MARGIN`].
#[inline(always)]
fn slab(
    lo: &[u8; 8],
    hi: &[u8; 8],
    half: usize,
    negative: bool,
    a: f32,
    near: f32,
    far: f32,
) -> (Vec4, Vec4) {
    let q = |v: &[u8; 8]| {
        let k = 4 * half;
        Vec4::new(
            v[k] as f32,
            v[k + 1] as f32,
            v[k + 2] as f32,
            v[k + 3] as f32,
        )
    };
    let (q_lo, q_hi) = (q(lo) - Q_MARGIN, q(hi) + Q_MARGIN);
    let (q_near, q_far) = if negative { (q_hi, q_lo) } else { (q_lo, q_hi) };
    (q_near * a + near, q_far * a + far)
}

/// obvhs-format hit mask of the children of `node` whose (conservative) boxes the ray overlaps
/// within t ∈ [0, t_max]: leaf children set their primitive bits (low 24), inner children their
/// traversal-order bit (high 8), exactly as obvhs's own node test does.
#[inline(always)]
fn node_hitmask(node: &CwBvhNode, ray: &RayBoxes, t_max: f32) -> u32 {
    let (a, near, far) = slab_terms(node, ray);
    let (child_bits8, bit_index8) = node.get_child_and_index_bits(ray.oct_inv4);
    let mut hit_mask = 0;
    for half in 0..2 {
        let (nx, fx) = slab(
            &node.child_min_x,
            &node.child_max_x,
            half,
            ray.negative[0],
            a.x,
            near.x,
            far.x,
        );
        let (ny, fy) = slab(
            &node.child_min_y,
            &node.child_max_y,
            half,
            ray.negative[1],
            a.y,
            near.y,
            far.y,
        );
        let (nz, fz) = slab(
            &node.child_min_z,
            &node.child_max_z,
            half,
            ray.negative[2],
            a.z,
            near.z,
            far.z,
        );
        let t_enter = nx.max(ny).max(nz).max(Vec4::ZERO);
        let t_exit = fx.min(fy).min(fz).min(Vec4::splat(t_max));
        let overlap = t_enter.cmple(t_exit).bitmask();
        for j in 0..4 {
            if overlap & (1 << j) != 0 {
                let child = 4 * half + j;
                hit_mask |= extract_byte64(child_bits8, child) << extract_byte64(bit_index8, child);
            }
        }
    }
    hit_mask
}

/// Number of nodes on the longest root-to-leaf path of the CWBVH.
fn tree_depth(nodes: &[CwBvhNode]) -> usize {
    let mut deepest = 0;
    let mut pending = vec![(0u32, 1usize)];
    while let Some((index, depth)) = pending.pop() {
        deepest = deepest.max(depth);
        let node = &nodes[index as usize];
        for child in 0..8 {
            if !node.is_child_empty(child) && !node.is_leaf(child) {
                pending.push((node.child_node_index(child), depth + 1));
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
    use crate::geometry::triangle::{intersect, test_rng::Rng};

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

    /// Triangles at geometrically growing distances give a deep tree; every stack size agrees.
    #[test]
    fn deep_trees_and_all_stack_sizes() {
        let mut rng = Rng::new(6);
        let tris: Vec<[Vec3; 3]> = (0..400)
            .map(|k| {
                let c = Vec3::splat(1.12f32.powi(k) * 1e-6);
                [c, c + Vec3::X * 1e-7, c + Vec3::Y * 1e-7]
            })
            .collect();
        let bvh = Bvh::build(&tris);
        let depth = tree_depth(&bvh.nodes);
        assert!(depth >= 3, "depth {depth}");
        assert_eq!(StackSize::for_depth(61), StackSize::Small);
        assert_eq!(StackSize::for_depth(62), StackSize::Large);
        assert_eq!(StackSize::for_depth(5000), StackSize::Heap(5002));
        for _ in 0..3000 {
            let k = rng.below(tris.len());
            let target = (tris[k][0] + tris[k][1] + tris[k][2]) / 3.0;
            let o = target + Vec3::new(0.1, -0.2, 1.0) * 1.12f32.powi(k as i32) * 1e-6;
            let r = Ray::new(o, target - o);
            let q = bvh.query(&r, f32::INFINITY).unwrap();
            let small = bvh.closest(StackStack::<UVec2, 64>::default(), &q, f32::INFINITY);
            let large = bvh.closest(StackStack::<UVec2, 1024>::default(), &q, f32::INFINITY);
            let heap = bvh.closest(HeapStack::new_with_capacity(depth + 2), &q, f32::INFINITY);
            let expected = brute_closest(&tris, &r, f32::INFINITY).map(|h| h.hit.t);
            for got in [small, large, heap] {
                assert_eq!(got.map(|(_, h)| h.t), expected);
            }
        }
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
