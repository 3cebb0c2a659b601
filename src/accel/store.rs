//! The BVH's store: one array of f32 words in which every node's record is followed by the
//! triangles of its leaf children, so a ray that tests a node's leaves reads their rows from the
//! lines and the 4 KiB page right after the node's own (Embree keeps a node's Triangle4 blocks
//! beside it in the same way). Records are laid out in the collapse's node order (obvhs's
//! depth-first `bvh2_to_cwbvh`: a node's children one after the other, each followed by its
//! triangles here, then the first child's subtree), each at a multiple of [`NODE_ALIGN`] words.
//!
//! A record is [`NODE_FLOATS`] words: the child boxes' 48 planes (half h's row r in words
//! 24h + 4r … 24h + 4r + 3, as [`WideNode::planes`]), then eight child words (the bits of a u32:
//! an inner child's record offset, a leaf's first triangle's offset), two words of leaf counts
//! (a byte per slot), and the masks of the slots that hold a child and of those that hold a
//! leaf or nothing (a word each; an empty slot is a leaf of no triangles whose box, min +∞ and
//! max −∞, no ray meets, so the traversal reads the second mask only). A triangle is [`TRI_FLOATS`] words: its rows
//! ([`PackedTriangle::push_rows`]) and the bits of its index into the slice given to
//! `Bvh::build`, which is the fourth lane its last row's load reads and ignores.

use glam::{Vec3, Vec4};

use super::bvh::WideNode;
use crate::geometry::triangle::{PackedTriangle, ROW_FLOATS, ROW_PADDING};

/// Words of a node's record (240 bytes).
pub(super) const NODE_FLOATS: usize = 60;
/// Words of a triangle: rows, then its input index.
pub(super) const TRI_FLOATS: usize = ROW_FLOATS + ROW_PADDING;
/// Records start at multiples of this many words (16 bytes), so no plane's four-lane load
/// straddles a cache line.
const NODE_ALIGN: usize = 4;

const CHILD: usize = 48;
const COUNT: usize = 56;
const PRESENT: usize = 58;
const LEAVES: usize = 59;

/// A node's record in the store.
#[derive(Clone, Copy, Debug)]
pub(super) struct Record<'a>(&'a [f32; NODE_FLOATS]);

impl<'a> Record<'a> {
    /// A record of no child.
    #[cfg(test)]
    pub const EMPTY: Record<'static> = Record(&[0.0; NODE_FLOATS]);

    /// The record at word `offset` (None beyond the store: not built so).
    #[inline(always)]
    pub fn at(store: &'a [f32], offset: usize) -> Option<Record<'a>> {
        let words = store.get(offset..offset + NODE_FLOATS)?;
        words.try_into().ok().map(Record)
    }

    /// Half `h`'s six planes of four lanes (see the module docs).
    #[inline(always)]
    pub fn half(&self, h: usize) -> &'a [f32; 24] {
        let (lo, hi) = self.0.split_at(24);
        let half = if h == 0 { lo } else { &hi[..24] };
        half.try_into().expect("24 words")
    }

    /// The child word of `slot` (an inner child's record offset, a leaf's first triangle's).
    #[inline(always)]
    pub fn child(&self, slot: usize) -> u32 {
        self.0[CHILD + (slot & 7)].to_bits()
    }

    /// Triangles of the leaf in `slot` (0 for inner children and empty slots).
    #[inline(always)]
    pub fn count(&self, slot: usize) -> usize {
        let word = self.0[COUNT + (slot >> 2 & 1)].to_bits();
        (word >> (8 * (slot & 3)) & 0xff) as usize
    }

    /// Bit `s`: slot s holds a child.
    #[inline(always)]
    pub fn present(&self) -> u32 {
        self.0[PRESENT].to_bits()
    }

    /// Bit `s`: slot s holds a leaf, or nothing (a leaf of no triangles, its box the empty one).
    #[inline(always)]
    pub fn leaves(&self) -> u32 {
        self.0[LEAVES].to_bits()
    }

    /// Slot `slot`'s box `(min, max)`.
    pub fn child_box(&self, slot: usize) -> (Vec3, Vec3) {
        let (half, lane) = (self.half(slot / 4), slot % 4);
        let plane = |row: usize| half[4 * row + lane];
        (
            Vec3::new(plane(0), plane(2), plane(4)),
            Vec3::new(plane(1), plane(3), plane(5)),
        )
    }
}

/// Plane `row` (0–5) of a half, four lanes.
#[inline(always)]
pub(super) fn plane(half: &[f32; 24], row: usize) -> Vec4 {
    Vec4::from_slice(&half[4 * row..4 * row + 4])
}

/// The store of `nodes` (node 0 the root, a node's inner children after it; a leaf child's
/// `child` indexes `ordered`) and of the triangles `ordered` with their input indices: the
/// root's record at word 0. Panics beyond 2³² words (16 GiB), which the u32 child words
/// cannot address.
pub(super) fn build(nodes: &[WideNode], ordered: &[[Vec3; 3]], input_index: &[u32]) -> Vec<f32> {
    let offsets = record_offsets(nodes);
    let mut store = Vec::with_capacity(offsets.last().map_or(0, |&(_, end)| end));
    for (node, &(offset, _)) in nodes.iter().zip(&offsets) {
        store.resize(offset, 0.0);
        let mut words = [0.0; NODE_FLOATS];
        for (h, half) in node.planes.iter().enumerate() {
            for (r, row) in half.iter().enumerate() {
                words[24 * h + 4 * r..24 * h + 4 * r + 4].copy_from_slice(&row.to_array());
            }
        }
        // An empty slot is a leaf of no triangles (its box is the empty one, `WideNode::EMPTY`):
        // the traversal needs no mask of the present slots.
        let leaves = node.leaves | !node.present;
        let mut counts = [0u32; 2];
        let mut row = offset + NODE_FLOATS;
        for slot in 0..8 {
            let word = if leaves & (1 << slot) != 0 {
                counts[slot / 4] |= (node.count[slot] as u32) << (8 * (slot % 4));
                let first = row;
                row += TRI_FLOATS * node.count[slot] as usize;
                first
            } else {
                offsets[node.child[slot] as usize].0
            };
            words[CHILD + slot] = f32::from_bits(u32::try_from(word).expect("a 32-bit offset"));
        }
        words[COUNT..COUNT + 2].copy_from_slice(&counts.map(f32::from_bits));
        words[PRESENT] = f32::from_bits(node.present as u32);
        words[LEAVES] = f32::from_bits(leaves as u32);
        store.extend(words);
        for slot in (0..8).filter(|&s| node.leaves & (1 << s) != 0) {
            let first = node.child[slot] as usize;
            for k in first..first + node.count[slot] as usize {
                PackedTriangle::push_rows(&mut store, ordered[k]);
                store.push(f32::from_bits(input_index[k]));
            }
        }
    }
    store
}

/// Each node's record offset and the end of its triangles, in node order.
fn record_offsets(nodes: &[WideNode]) -> Vec<(usize, usize)> {
    let mut next = 0usize;
    let offsets: Vec<(usize, usize)> = nodes
        .iter()
        .map(|node| {
            let triangles: usize = (0..8)
                .filter(|&s| node.leaves & (1 << s) != 0)
                .map(|s| node.count[s] as usize)
                .sum();
            let offset = next.next_multiple_of(NODE_ALIGN);
            next = offset + NODE_FLOATS + TRI_FLOATS * triangles;
            (offset, next)
        })
        .collect();
    assert!(next <= u32::MAX as usize, "a BVH store beyond 2^32 words");
    offsets
}

/// The records reachable from the root (all of them) with their offsets, depth first.
pub(super) fn records(store: &[f32]) -> Vec<(usize, Record<'_>)> {
    let mut found = Vec::new();
    let mut pending = vec![0];
    while let Some(offset) = pending.pop() {
        let Some(node) = Record::at(store, offset) else {
            continue;
        };
        found.push((offset, node));
        let inner = node.present() & !node.leaves();
        let children = (0..8).filter(|&s| inner & (1 << s) != 0);
        pending.extend(children.map(|s| node.child(s) as usize));
    }
    found
}
