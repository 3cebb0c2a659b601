//! Top-down binned-SAH build of a binary BVH (Wald 2007, "On fast construction of SAH-based
//! bounding volume hierarchies"; PBR 4ed §7.3.2, "The Surface Area Heuristic"), the builder
//! of [`super::bvh::Builder::Sah`]. The output is obvhs's `Bvh2` with one triangle per leaf,
//! which is what obvhs's CWBVH collapse expects (it chooses the leaves itself, by its own SAH;
//! Ylitie, Karras, Laine 2017, §4.1), so reinsertion and the collapse apply unchanged.
//!
//! A node over more than one triangle is always split. Its triangles are put into [`BINS`] bins
//! of equal width along each of four keys, and the split is the bin boundary of least SAH over
//! the four. With one-triangle leaves the SAH of a split (PBR 4ed §7.3.2, without its leaf
//! alternative) is
//!
//! c = c_trav + c_isect · (A_L·N_L + A_R·N_R) / A,
//!
//! so neither cost constant changes which split wins, and the comparison is on
//! A_L·N_L + A_R·N_R alone (areas in f64, so no product overflows for any finite f32 box).
//! The keys:
//! - the three coordinates of the triangle's box centre (Wald 2007's centroid binning);
//! - the log₂ of the box's half area (ours). A scene of large triangles around many small ones
//!   (the walls of `../shared/limit`'s box around its 100k- or 1M-triangle sphere) has no
//!   centroid plane between the two: each of the first splits carries wall triangles down both
//!   sides, whose boxes then span the room. Splitting by size lets the SAH put the walls apart
//!   at the top. On the spheres it cut the 8-wide tree's SAH node term by 8–19 % (4.81 → 4.41
//!   on 100k, 6.63 → 5.39 on 1M, `Bvh::sah_cost`), from above PLOC's to 5–6 % below it
//!   (docs/design.md §8, "BVH: a binned-SAH tree against PLOC's").
//!
//! Where every key coincides (copies of one triangle), there is no boundary to split at, and
//! the triangles are halved by count (an object-median split).
//!
//! The build runs on an explicit work list (no recursion: a tree of depth n, as a geometric
//! series of triangles gives, costs no call stack), and the two halves of a large node are
//! built on the two cores (`rayon::join`) down to [`PARALLEL_MIN`] triangles.

use glam::{Vec3A, Vec4};
use obvhs::aabb::Aabb;
use obvhs::bvh2::node::Bvh2Node;
use obvhs::bvh2::{Bvh2, DEFAULT_MAX_STACK_DEPTH};
use obvhs::triangle::Triangle;

/// Bins per key (Wald 2007 finds 16–32 bins close to the SAH of the full sweep over all
/// boundaries; 128 bins, on centroids alone, lowered the 100k sphere's binary-tree SAH by
/// 2 %). Nodes over
/// fewer triangles use one bin per triangle.
const BINS: usize = 32;

/// Keys split on: the three centroid coordinates, and the size (see the module's text).
const KEYS: usize = 4;

/// Nodes over at least this many triangles build their two halves in parallel.
const PARALLEL_MIN: usize = 1 << 14;

/// A triangle's box, the log₂ of its half area, and its index in the input.
#[derive(Clone, Copy, Debug)]
struct Prim {
    lo: Vec3A,
    hi: Vec3A,
    size: f32,
    index: u32,
}

impl Prim {
    fn new(lo: Vec3A, hi: Vec3A, index: u32) -> Prim {
        let size = (Bounds { lo, hi }.half_area().log2() as f32).max(f32::MIN);
        Prim {
            lo,
            hi,
            size,
            index,
        }
    }

    /// The keys a node is split on: the box's centre (halved before the sum so that no finite
    /// box overflows) and the size.
    fn keys(&self) -> Vec4 {
        (self.lo * 0.5 + self.hi * 0.5).extend(self.size)
    }
}

/// An axis-aligned box; [`Bounds::EMPTY`] is the identity of `grow`.
#[derive(Clone, Copy, Debug)]
struct Bounds {
    lo: Vec3A,
    hi: Vec3A,
}

impl Bounds {
    const EMPTY: Bounds = Bounds {
        lo: Vec3A::INFINITY,
        hi: Vec3A::NEG_INFINITY,
    };

    fn grow(self, lo: Vec3A, hi: Vec3A) -> Bounds {
        Bounds {
            lo: self.lo.min(lo),
            hi: self.hi.max(hi),
        }
    }

    fn union(self, other: Bounds) -> Bounds {
        self.grow(other.lo, other.hi)
    }

    /// Half the surface area, in f64 (0 for the empty box).
    fn half_area(self) -> f64 {
        let d = (self.hi.as_dvec3() - self.lo.as_dvec3()).max(glam::DVec3::ZERO);
        d.x * d.y + d.y * d.z + d.z * d.x
    }
}

/// One key's binning over a node's triangles: bin of key `c` = ⌊(c − lo)·scale⌋, clamped to the
/// last.
#[derive(Clone, Copy, Debug)]
struct Binning {
    axis: usize,
    lo: f64,
    scale: f64,
    bins: usize,
}

impl Binning {
    fn bin(&self, p: &Prim) -> usize {
        self.bin_of(p.keys())
    }

    fn bin_of(&self, keys: Vec4) -> usize {
        (((keys[self.axis] as f64 - self.lo) * self.scale) as usize).min(self.bins - 1)
    }
}

/// Builds the binary BVH over the triangles (none degenerate; no nodes for none).
pub(super) fn build_bvh2(triangles: &[Triangle]) -> Bvh2 {
    if triangles.is_empty() {
        return Bvh2::default();
    }
    let mut prims: Vec<Prim> = triangles
        .iter()
        .enumerate()
        .map(|(i, t)| Prim::new(t.v0.min(t.v1).min(t.v2), t.v0.max(t.v1).max(t.v2), i as u32))
        .collect();
    let (nodes, depth) = build_subtree(&mut prims, 0);
    Bvh2 {
        nodes,
        primitive_indices: prims.iter().map(|p| p.index).collect(),
        max_depth: (depth + 1).max(DEFAULT_MAX_STACK_DEPTH),
        ..Bvh2::default()
    }
}

/// A node waiting to be built: its slot and its triangles `prims[start..end]`.
struct Task {
    node: usize,
    start: usize,
    end: usize,
    depth: usize,
}

/// The subtree over `prims` (reordered into leaf order), root at index 0, leaves indexing
/// `first_prim + position in prims`; and its depth in nodes.
fn build_subtree(prims: &mut [Prim], first_prim: usize) -> (Vec<Bvh2Node>, usize) {
    let mut nodes = Vec::with_capacity(2 * prims.len() - 1);
    nodes.push(Bvh2Node::default());
    let mut tasks = vec![Task {
        node: 0,
        start: 0,
        end: prims.len(),
        depth: 1,
    }];
    let mut depth = 0;
    while let Some(task) = tasks.pop() {
        let range = &mut prims[task.start..task.end];
        let (bounds, keys) = bounds_of(range);
        let aabb = Aabb::new(bounds.lo, bounds.hi);
        if range.len() == 1 {
            nodes[task.node] = Bvh2Node::new(aabb, 1, (first_prim + task.start) as u32);
            depth = depth.max(task.depth);
            continue;
        }
        let mid = task.start + split(range, keys);
        let children = nodes.len();
        nodes[task.node] = Bvh2Node::new(aabb, 0, children as u32);
        if range.len() >= PARALLEL_MIN {
            let (left, right) = prims[task.start..task.end].split_at_mut(mid - task.start);
            let ((l, l_depth), (r, r_depth)) = rayon::join(
                || build_subtree(left, first_prim + task.start),
                || build_subtree(right, first_prim + mid),
            );
            graft(&mut nodes, l, r);
            depth = depth.max(task.depth + l_depth.max(r_depth));
            continue;
        }
        nodes.extend([Bvh2Node::default(); 2]);
        let (d, start, end) = (task.depth + 1, task.start, task.end);
        tasks.push(Task {
            node: children + 1,
            start: mid,
            end,
            depth: d,
        });
        tasks.push(Task {
            node: children,
            start,
            end: mid,
            depth: d,
        });
    }
    (nodes, depth)
}

/// Appends two separately built subtrees as the pair of children just allocated at
/// `nodes.len()`: their roots take the pair's two slots, the rest follows, inner nodes'
/// child indices moved to the new places (leaves' indices are already global).
fn graft(nodes: &mut Vec<Bvh2Node>, left: Vec<Bvh2Node>, right: Vec<Bvh2Node>) {
    let pair = nodes.len();
    let left_rest = pair + 2;
    let right_rest = left_rest + left.len() - 1;
    // Local index k ≥ 1 of a subtree whose other nodes start at `rest` goes to rest + k − 1.
    let moved = |node: Bvh2Node, rest: usize| -> Bvh2Node {
        let mut node = node;
        if node.prim_count == 0 {
            node.first_index += (rest - 1) as u32;
        }
        node
    };
    nodes.push(moved(left[0], left_rest));
    nodes.push(moved(right[0], right_rest));
    nodes.extend(left[1..].iter().map(|&n| moved(n, left_rest)));
    nodes.extend(right[1..].iter().map(|&n| moved(n, right_rest)));
}

/// The union of the triangles' boxes and the bounds of their keys.
fn bounds_of(prims: &[Prim]) -> (Bounds, Keys) {
    let keys = (Vec4::INFINITY, Vec4::NEG_INFINITY);
    prims
        .iter()
        .fold((Bounds::EMPTY, keys), |(b, (lo, hi)), p| {
            let k = p.keys();
            (b.grow(p.lo, p.hi), (lo.min(k), hi.max(k)))
        })
}

/// The bounds `(min, max)` of the keys of a node's triangles.
type Keys = (Vec4, Vec4);

/// Reorders `prims` (at least two) into the two children of the least-SAH bin boundary, or
/// halves them when every key coincides; returns the left child's count (in 1..len).
fn split(prims: &mut [Prim], keys: Keys) -> usize {
    let n = prims.len();
    let Some((binning, plane)) = best_split(prims, keys) else {
        return n / 2;
    };
    let (mut i, mut j) = (0, n);
    while i < j {
        if binning.bin(&prims[i]) < plane {
            i += 1;
        } else {
            j -= 1;
            prims.swap(i, j);
        }
    }
    if i == 0 || i == n {
        n / 2
    } else {
        i
    }
}

/// The binning and the boundary (bins below it go left) of least A_L·N_L + A_R·N_R over the
/// keys that spread; None when none does.
fn best_split(prims: &[Prim], keys: Keys) -> Option<(Binning, usize)> {
    let bins = prims.len().min(BINS);
    let binnings: [Option<Binning>; KEYS] = std::array::from_fn(|axis| {
        let (lo, hi) = (keys.0[axis] as f64, keys.1[axis] as f64);
        let scale = bins as f64 / (hi - lo);
        (hi > lo && scale.is_finite()).then_some(Binning {
            axis,
            lo,
            scale,
            bins,
        })
    });
    let mut filled = [[(Bounds::EMPTY, 0usize); BINS]; KEYS];
    for p in prims {
        let keys = p.keys();
        for (b, f) in binnings.iter().zip(&mut filled) {
            if let Some(b) = b {
                let (bin_box, count) = &mut f[b.bin_of(keys)];
                *bin_box = bin_box.grow(p.lo, p.hi);
                *count += 1;
            }
        }
    }
    let mut best: Option<(f64, Binning, usize)> = None;
    for (b, f) in binnings.iter().zip(&filled) {
        let Some(b) = *b else { continue };
        if let Some((cost, plane)) = sweep(&f[..bins]) {
            if best.is_none_or(|(c, _, _)| cost < c) {
                best = Some((cost, b, plane));
            }
        }
    }
    best.map(|(_, b, plane)| (b, plane))
}

/// The boundary of least A_L·N_L + A_R·N_R among those with triangles on both sides, and
/// that cost.
fn sweep(bins: &[(Bounds, usize)]) -> Option<(f64, usize)> {
    let mut right = [0.0; BINS];
    let (mut acc, mut count) = (Bounds::EMPTY, 0);
    for k in (1..bins.len()).rev() {
        acc = acc.union(bins[k].0);
        count += bins[k].1;
        right[k] = if count > 0 {
            acc.half_area() * count as f64
        } else {
            f64::NAN
        };
    }
    let (mut acc, mut count) = (Bounds::EMPTY, 0);
    let mut best: Option<(f64, usize)> = None;
    for plane in 1..bins.len() {
        acc = acc.union(bins[plane - 1].0);
        count += bins[plane - 1].1;
        let cost = acc.half_area() * count as f64 + right[plane];
        // NaN (an empty side) never compares less.
        if count > 0 && best.is_none_or(|(c, _)| cost < c) && !cost.is_nan() {
            best = Some((cost, plane));
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::rng::Rng;

    fn tri(a: Vec3A, b: Vec3A, c: Vec3A) -> Triangle {
        Triangle {
            v0: a,
            v1: b,
            v2: c,
        }
    }

    fn soup(rng: &mut Rng, n: usize) -> Vec<Triangle> {
        (0..n)
            .map(|_| {
                let c = Vec3A::from(rng.vec3(-1.0, 1.0));
                let e = |rng: &mut Rng| c + Vec3A::from(rng.vec3(-0.05, 0.05));
                tri(e(rng), e(rng), e(rng))
            })
            .collect()
    }

    /// Every triangle in exactly one leaf of one triangle, every box containing its children's
    /// (leaves: their triangle's), children stored as pairs after the root, depth within
    /// `max_depth`.
    fn check(bvh: &Bvh2, tris: &[Triangle]) {
        let n = tris.len();
        assert_eq!(bvh.nodes.len(), 2 * n - 1);
        let mut seen = vec![false; n];
        let mut pending = vec![(0usize, 1usize)];
        let mut visited = 0;
        while let Some((k, depth)) = pending.pop() {
            visited += 1;
            assert!(depth <= bvh.max_depth);
            let node = bvh.nodes[k];
            let b = node.aabb();
            if node.prim_count > 0 {
                assert_eq!(node.prim_count, 1);
                let i = bvh.primitive_indices[node.first_index as usize] as usize;
                assert!(!std::mem::replace(&mut seen[i], true));
                let t = &tris[i];
                assert_eq!(b.min, t.v0.min(t.v1).min(t.v2));
                assert_eq!(b.max, t.v0.max(t.v1).max(t.v2));
                continue;
            }
            let first = node.first_index as usize;
            assert!(first > k && first + 1 < bvh.nodes.len());
            for c in [first, first + 1] {
                let cb = bvh.nodes[c].aabb();
                assert!(b.min.cmple(cb.min).all() && b.max.cmpge(cb.max).all());
                pending.push((c, depth + 1));
            }
        }
        assert_eq!(visited, 2 * n - 1);
        assert!(seen.iter().all(|&s| s));
    }

    fn sah(bvh: &Bvh2) -> f64 {
        let area = |k: usize| {
            let b = bvh.nodes[k].aabb();
            let d = (b.max - b.min).as_dvec3();
            d.x * d.y + d.y * d.z + d.z * d.x
        };
        (0..bvh.nodes.len())
            .filter(|&k| bvh.nodes[k].prim_count == 0)
            .map(area)
            .sum::<f64>()
            / area(0)
    }

    #[test]
    fn valid_trees_on_soups_small_and_large() {
        let mut rng = Rng::new(11);
        assert!(build_bvh2(&[]).nodes.is_empty());
        for n in [1, 2, 3, 31, 33, 1000, PARALLEL_MIN + 5000] {
            let tris = soup(&mut rng, n);
            check(&build_bvh2(&tris), &tris);
        }
    }

    /// Copies of one triangle (every key equal) are halved by count, triangles sharing a
    /// centroid split by size; a geometric series gives a deep tree without recursion; boxes
    /// near the f32 limits give no NaN.
    #[test]
    fn coincident_centroids_and_deep_series() {
        let (a, b, c) = (Vec3A::ZERO, Vec3A::X, Vec3A::Y);
        let copies = vec![tri(a, b, c); 1000];
        let bvh = build_bvh2(&copies);
        check(&bvh, &copies);
        assert!(bvh.depth(0) <= 12, "{}", bvh.depth(0));
        let star: Vec<Triangle> = (1..200)
            .map(|k| {
                let s = k as f32 * 0.01;
                tri(
                    Vec3A::new(-s, -s, 0.0),
                    Vec3A::new(s, -s, 0.0),
                    Vec3A::new(0.0, s, 0.0),
                )
            })
            .collect();
        check(&build_bvh2(&star), &star);
        let series: Vec<Triangle> = (0..3000)
            .map(|k| {
                let p = Vec3A::splat(1.01f32.powi(k) * 1e-6);
                tri(p, p + Vec3A::X * 1e-7, p + Vec3A::Y * 1e-7)
            })
            .collect();
        check(&build_bvh2(&series), &series);
        let huge = vec![
            tri(
                Vec3A::splat(-3e38),
                Vec3A::splat(3e38),
                Vec3A::new(3e38, -3e38, 0.0),
            ),
            tri(Vec3A::splat(-3e38), Vec3A::ZERO, Vec3A::X),
            tri(Vec3A::ZERO, Vec3A::Y, Vec3A::Z),
        ];
        check(&build_bvh2(&huge), &huge);
    }

    /// The binned SAH beats a median split by index order on a soup in random order, whose
    /// index order carries no locality (the SAH of a tree is Σ inner areas / root area here,
    /// leaves all holding one triangle).
    #[test]
    fn lower_sah_than_an_index_median_tree() {
        let mut rng = Rng::new(12);
        let tris = soup(&mut rng, 4096);
        let bvh = build_bvh2(&tris);
        let mut median = Bvh2 {
            nodes: Vec::new(),
            primitive_indices: (0..4096).collect(),
            ..Bvh2::default()
        };
        median.nodes.push(Bvh2Node::default());
        let mut pending = vec![(0usize, 0usize, 4096usize)];
        while let Some((k, s, e)) = pending.pop() {
            let b = tris[s..e].iter().fold(Bounds::EMPTY, |b, t| {
                b.grow(t.v0.min(t.v1).min(t.v2), t.v0.max(t.v1).max(t.v2))
            });
            let aabb = Aabb::new(b.lo, b.hi);
            if e - s == 1 {
                median.nodes[k] = Bvh2Node::new(aabb, 1, s as u32);
                continue;
            }
            let c = median.nodes.len();
            median.nodes[k] = Bvh2Node::new(aabb, 0, c as u32);
            median.nodes.extend([Bvh2Node::default(); 2]);
            let m = (s + e) / 2;
            pending.extend([(c, s, m), (c + 1, m, e)]);
        }
        check(&median, &tris);
        let (ours, theirs) = (sah(&bvh), sah(&median));
        assert!(ours < 0.5 * theirs, "{ours} vs {theirs}");
    }
}
