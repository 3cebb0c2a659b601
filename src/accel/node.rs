//! The BVH's 8-wide node in 80 bytes: child boxes quantised to 8 bits per plane relative to the
//! node's origin and a power-of-two scale per axis, as in the compressed wide BVH (Ylitie,
//! Karras, Laine 2017, "Efficient Incoherent Ray Traversal on GPUs Through Compressed Wide
//! BVHs", §3.1), with the children's indices as a base plus a 5-bit offset per slot (their
//! §3.1 "meta" byte).
//!
//! **Conservative decoding.** A plane is decoded as fl(origin + q·2^e): q·2^e is exact (q ≤ 255,
//! 2^e a normal float, the product far from overflow), so the decoded plane is one f32 addition,
//! the same at build and at traversal (Rust never contracts it into an FMA). The build picks,
//! for each lower plane, the largest q whose *decoded* value is ≤ the exact plane and, for each
//! upper plane, the smallest q whose decoded value is ≥ it (raising e when 255 is not enough),
//! checking the decoded values themselves rather than a rounding argument. A decoded box
//! therefore contains the exact box of its child, and the slab test on it is at least as
//! conservative as on the exact box (the BVH's watertightness at box faces is kept).
//!
//! Coordinates are bounded by [`MAX_COORDINATE`] (2^64), so extents stay below 2^65, scales
//! below 2^58 and decoded planes finite; the BVH leaves triangles beyond it out.

use glam::{Vec3, Vec4};

/// Largest coordinate magnitude the BVH holds (2^64; the scene limits coordinates to 1e9 m).
pub(super) const MAX_COORDINATE: f32 = 18_446_744_073_709_551_616.0;

/// Smallest scale exponent: 2^−126, the smallest normal float (finer is never needed for
/// conservative boxes, it only tightens boxes below 255·2^−126 across).
const MIN_EXPONENT: i32 = -126;

/// A node with up to eight children; slot `s` is lane `s % 4` of half `s / 4`.
#[derive(Clone, Copy, Debug)]
pub(super) struct Node {
    /// `q[h][2k]` / `q[h][2k + 1]`: quantised min / max along axis k of the children of half h.
    q: [[[u8; 4]; 6]; 2],
    /// The planes' origin per axis (the node's exact lower corner).
    origin: [f32; 3],
    /// Biased exponent per axis (the f32 exponent field): scale = 2^(exp − 127).
    exp: [u8; 3],
    /// Bit `s`: slot s holds a child.
    present: u8,
    /// First inner child's node index; inner children follow it in slot order.
    node_base: u32,
    /// First triangle (BVH order) of the leaf children.
    prim_base: u32,
    /// Per slot: bits 0–4 the offset from `node_base` (inner) or `prim_base` (leaf); bits 5–6 the
    /// leaf's triangle count (1–3), 0 for an inner child.
    meta: [u8; 8],
}

/// A child as the builder gives it: its exact box and what it holds.
#[derive(Clone, Copy, Debug)]
pub(super) enum Child {
    Inner { node: u32 },
    Leaf { first: u32, count: u32 },
}

impl Node {
    pub const EMPTY: Node = Node {
        q: [[[0; 4]; 6]; 2],
        origin: [0.0; 3],
        exp: [127; 3],
        present: 0,
        node_base: 0,
        prim_base: 0,
        meta: [0; 8],
    };

    /// A node over `children[s] = Some((exact box, child))` in slot `s`. Inner children must be
    /// consecutive nodes in slot order and leaves' triangles within 31 of the first one (the
    /// CWBVH's layout, which obvhs produces); every box within ±[`MAX_COORDINATE`].
    pub fn new(children: &[Option<((Vec3, Vec3), Child)>; 8]) -> Node {
        let mut node = Node::EMPTY;
        let boxes = children.iter().flatten().map(|(b, _)| *b);
        let (lo, hi) = boxes.fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), (a, b)| {
            (lo.min(a), hi.max(b))
        });
        if lo.x > hi.x {
            return node;
        }
        for axis in 0..3 {
            node.origin[axis] = lo[axis];
            node.exp[axis] = node.quantise_axis(axis, children, hi[axis]);
        }
        let first_of = |inner: bool| {
            let indices = children.iter().flatten().map(|(_, c)| match *c {
                Child::Inner { node } => (inner, node),
                Child::Leaf { first, .. } => (!inner, first),
            });
            indices.filter(|&(keep, _)| keep).map(|(_, i)| i).min()
        };
        node.node_base = first_of(true).unwrap_or(0);
        node.prim_base = first_of(false).unwrap_or(0);
        for (slot, child) in children.iter().enumerate() {
            let Some((_, child)) = child else { continue };
            node.present |= 1 << slot;
            node.meta[slot] = match *child {
                Child::Inner { node: index } => offset(index - node.node_base),
                Child::Leaf { first, count } => {
                    assert!((1..=3).contains(&count), "leaves hold 1 to 3 triangles");
                    offset(first - node.prim_base) | (count as u8) << 5
                }
            };
        }
        node
    }

    /// Quantises the planes of `axis` for the node whose upper corner there is `hi`; returns the
    /// biased exponent.
    fn quantise_axis(
        &mut self,
        axis: usize,
        children: &[Option<((Vec3, Vec3), Child)>; 8],
        hi: f32,
    ) -> u8 {
        let origin = self.origin[axis];
        let extent = hi as f64 - origin as f64;
        // The smallest e with 255·2^e ≥ extent; raised below when rounding needs more.
        let mut e = ((extent / 255.0).log2().ceil() as i32).max(MIN_EXPONENT);
        loop {
            let scale = exp2(e);
            let mut fits = true;
            for (slot, child) in children.iter().enumerate() {
                let Some(((lo_c, hi_c), _)) = child else {
                    continue;
                };
                let (q_lo, q_hi) = (
                    lower_q(origin, scale, lo_c[axis]),
                    upper_q(origin, scale, hi_c[axis]),
                );
                let Some(q_hi) = q_hi else {
                    fits = false;
                    break;
                };
                self.q[slot / 4][2 * axis][slot % 4] = q_lo;
                self.q[slot / 4][2 * axis + 1][slot % 4] = q_hi;
            }
            if fits {
                return (e + 127) as u8;
            }
            e += 1;
        }
    }

    /// Bit `s`: slot s holds a child.
    #[inline(always)]
    pub fn present(&self) -> u32 {
        self.present as u32
    }

    /// Bit `s`: slot s holds a leaf (bits 5–6 of its meta byte set, gathered by one multiply).
    #[inline(always)]
    pub fn leaves(&self) -> u32 {
        let m = u64::from_le_bytes(self.meta) >> 5 & 0x0303_0303_0303_0303;
        let bits = (m | m >> 1) & 0x0101_0101_0101_0101;
        (bits.wrapping_mul(0x0102_0408_1020_4080) >> 56) as u32
    }

    /// Inner child in `slot`: its node index.
    #[inline(always)]
    pub fn inner(&self, slot: usize) -> u32 {
        self.node_base + (self.meta[slot] & 31) as u32
    }

    /// Leaf child in `slot`: its first triangle and count.
    #[inline(always)]
    pub fn leaf(&self, slot: usize) -> (usize, usize) {
        let meta = self.meta[slot];
        (
            self.prim_base as usize + (meta & 31) as usize,
            (meta >> 5) as usize,
        )
    }

    /// The decoded plane rows of half `h` (see [`Node::q`]): min / max per axis of four children.
    #[inline(always)]
    pub fn planes(&self, h: usize) -> [Vec4; 6] {
        let scale = self.exp.map(|e| Vec4::splat(f32::from_bits((e as u32) << 23)));
        let origin = self.origin.map(Vec4::splat);
        let row = |r: usize| {
            let q = self.q[h][r];
            let q = Vec4::new(q[0] as f32, q[1] as f32, q[2] as f32, q[3] as f32);
            q * scale[r / 2] + origin[r / 2]
        };
        [row(0), row(1), row(2), row(3), row(4), row(5)]
    }
}

/// The meta byte's offset field.
fn offset(value: u32) -> u8 {
    assert!(value < 32, "CWBVH child offsets fit in 5 bits");
    value as u8
}

/// 2^e for a normal exponent.
fn exp2(e: i32) -> f32 {
    f32::from_bits(((e + 127) as u32) << 23)
}

/// The decoded plane fl(origin + q·scale), exactly as [`Node::planes`] computes it.
fn decode(origin: f32, scale: f32, q: u8) -> f32 {
    q as f32 * scale + origin
}

/// The largest q whose decoded plane is ≤ `lo` (q = 0 decodes to the origin ≤ lo).
fn lower_q(origin: f32, scale: f32, lo: f32) -> u8 {
    let estimate = ((lo as f64 - origin as f64) / scale as f64).floor();
    let mut q = estimate.clamp(0.0, 255.0) as u8;
    while q > 0 && decode(origin, scale, q) > lo {
        q -= 1;
    }
    while q < 255 && decode(origin, scale, q + 1) <= lo {
        q += 1;
    }
    q
}

/// The smallest q whose decoded plane is ≥ `hi`, if one ≤ 255 is.
fn upper_q(origin: f32, scale: f32, hi: f32) -> Option<u8> {
    let estimate = ((hi as f64 - origin as f64) / scale as f64).ceil();
    let mut q = estimate.clamp(0.0, 255.0) as u8;
    while q > 0 && decode(origin, scale, q - 1) >= hi {
        q -= 1;
    }
    while decode(origin, scale, q) < hi {
        q = q.checked_add(1)?;
    }
    Some(q)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::rng::Rng;

    fn decoded_box(node: &Node, slot: usize) -> (Vec3, Vec3) {
        let rows = node.planes(slot / 4).map(|r| r[slot % 4]);
        (
            Vec3::new(rows[0], rows[2], rows[4]),
            Vec3::new(rows[1], rows[3], rows[5]),
        )
    }

    /// Random child boxes at every scale and offset: each decoded box contains its exact box,
    /// and exceeds it by at most one quantisation step per plane (2^−7 of the node's extent,
    /// or the float spacing at the plane); slots, leaves and indices come back.
    #[test]
    fn decoded_boxes_contain_and_hug_the_exact_ones() {
        let mut rng = Rng::new(11);
        for k in 0..20_000 {
            let scale = [1e-30f32, 1e-6, 1.0, 1e5, 1e15][k % 5];
            let shift = rng.vec3(-1.0, 1.0) * scale * [0.0, 1.0, 1e3, 1e7][k / 5 % 4];
            let mut children = [None; 8];
            let mut inner = 0;
            for (slot, child) in children.iter_mut().enumerate() {
                if rng.below(4) == 0 {
                    continue;
                }
                let a = shift + rng.vec3(-1.0, 1.0) * scale;
                let mut b = a + rng.vec3(0.0, 1.0) * scale * [1.0, 1e-3, 0.0][rng.below(3)];
                if rng.below(5) == 0 {
                    b.y = a.y; // flat along y, as a floor's leaf
                }
                *child = Some((
                    (a, b),
                    if slot % 2 == 0 {
                        inner += 1;
                        Child::Inner { node: 40 + inner }
                    } else {
                        Child::Leaf {
                            first: 7 + 3 * slot as u32,
                            count: 1 + slot as u32 % 3,
                        }
                    },
                ));
            }
            let node = Node::new(&children);
            let mut leaves = 0;
            for (slot, child) in children.iter().enumerate() {
                let Some(((lo, hi), c)) = child else {
                    assert_eq!(node.present() >> slot & 1, 0);
                    continue;
                };
                assert_eq!(node.present() >> slot & 1, 1);
                let (dlo, dhi) = decoded_box(&node, slot);
                assert!(dlo.cmple(*lo).all() && dhi.cmpge(*hi).all(), "{lo} {hi}: {dlo} {dhi}");
                assert!(dlo.is_finite() && dhi.is_finite());
                for axis in 0..3 {
                    let step = f32::from_bits((node.exp[axis] as u32) << 23);
                    let ulp = |x: f32| (f32::from_bits(x.abs().to_bits() + 1) - x.abs()).abs();
                    let slack = step + 2.0 * ulp(lo[axis]).max(ulp(hi[axis]));
                    assert!(lo[axis] - dlo[axis] <= slack && dhi[axis] - hi[axis] <= slack);
                    let node_extent = children
                        .iter()
                        .flatten()
                        .map(|((_, h), _)| h[axis])
                        .fold(f32::NEG_INFINITY, f32::max)
                        - node.origin[axis];
                    assert!(step <= (node_extent / 127.0).max(exp2(MIN_EXPONENT)));
                }
                match *c {
                    Child::Inner { node: index } => assert_eq!(node.inner(slot), index),
                    Child::Leaf { first, count } => {
                        leaves |= 1 << slot;
                        assert_eq!(node.leaf(slot), (first as usize, count as usize));
                    }
                }
            }
            assert_eq!(node.leaves(), leaves);
        }
    }
}
