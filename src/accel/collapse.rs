//! The collapse of a binary BVH into the 8-wide tree the traversal walks, with leaves of up to
//! four triangles (one four-lane block, [`super::leaf4`]).
//!
//! The wide tree is the one of least SAH cost (Goldsmith, Salmon 1987; MacDonald, Booth 1990;
//! PBR 4ed §7.3.2) among those made by keeping a subset of the binary nodes, found by the dynamic
//! programme of Ylitie, Karras, Laine 2017 ("Efficient Incoherent Ray Traversal on GPUs Through
//! Compressed Wide BVHs", §4.1, equations 1–3): C(n, i) is the least cost of the subtree at n
//! spread over at most i slots of its wide parent,
//! - C(n, 1) = min(leaf: [`LEAF_COST`]·A(n) if n holds ≤ 4 triangles,
//!   wide node: [`NODE_COST`]·A(n) + D(n, 8)),
//! - C(n, i) = min(C(n, i − 1), D(n, i)) for i = 2..8,
//! - D(n, j) = min over k = 1..j − 1 of C(left, k) + C(right, j − k),
//!
//! with A(n) the surface area of n's box. The leaf cost is Embree's: one intersection cost per
//! block of four triangles, whatever its fill (Wald et al. 2014, "Embree: A Kernel Framework
//! for Efficient CPU Ray Tracing", §4.1, `sahBlockSize` 4), where Ylitie et al. count each
//! triangle; a leaf of 1 to 4 costs one four-lane pass here.

/// A node of the binary BVH: its box's half surface area, and its children or its triangle.
#[derive(Clone, Copy, Debug)]
pub(super) struct BinaryNode {
    pub half_area: f32,
    pub kind: BinaryKind,
}

#[derive(Clone, Copy, Debug)]
pub(super) enum BinaryKind {
    /// Indices of the two children.
    Inner([u32; 2]),
    /// One triangle (an index the caller chose).
    Prim(u32),
}

/// A child slot of a wide node.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Child {
    /// Index into [`Collapsed::nodes`] (always after its parent's).
    Node(u32),
    /// Index into [`Collapsed::leaves`].
    Leaf(u32),
}

/// The wide tree's shape: node 0 is the root.
pub(super) struct Collapsed {
    /// Each node's children (1 to 8).
    pub nodes: Vec<Vec<Child>>,
    /// Each leaf's triangles (1 to 4), as given in [`BinaryKind::Prim`].
    pub leaves: Vec<Vec<u32>>,
}

/// Children per wide node.
const WIDTH: usize = 8;
/// Triangles per leaf (one four-lane block).
const LEAF_MAX: u32 = 4;
/// SAH cost of one leaf block test (a four-lane watertight pass).
const LEAF_COST: f32 = 1.0;
/// SAH cost of one wide node (an 8-child box test, the entry sort and a stack entry), taken
/// equal to a leaf pass: both are about the same number of SSE instructions.
const NODE_COST: f32 = 1.0;

/// The best choice for each binary node and each number of slots (see the module docs).
#[derive(Clone, Copy)]
struct Choice {
    /// `cost[i − 1]` = C(n, i).
    cost: [f32; WIDTH],
    /// `take[0]`: 0 for a leaf, 1 for a wide node. `take[i − 1]` for i ≥ 2: 0 to use i − 1
    /// slots, else the k of D(n, i) (slots given to the left child).
    take: [u8; WIDTH],
    /// The k of D(n, 8): how a wide node made of n shares its slots between its children.
    wide_k: u8,
}

/// Collapses the binary BVH rooted at node 0 (which must not be empty).
pub(super) fn collapse(binary: &[BinaryNode]) -> Collapsed {
    let choice = choices(binary);
    let mut out = Collapsed {
        nodes: vec![Vec::new()],
        leaves: Vec::new(),
    };
    let mut pending = vec![(0u32, slots(binary, &choice, 0, WIDTH))];
    while let Some((wide, children)) = pending.pop() {
        for c in children {
            let child = match binary[c as usize].kind {
                BinaryKind::Inner([l, r]) if choice[c as usize].take[0] != 0 => {
                    out.nodes.push(Vec::new());
                    let index = out.nodes.len() as u32 - 1;
                    let k = choice[c as usize].wide_k as usize;
                    let mut grand = slots(binary, &choice, l, k);
                    grand.extend(slots(binary, &choice, r, WIDTH - k));
                    pending.push((index, grand));
                    Child::Node(index)
                }
                _ => {
                    out.leaves.push(gather(binary, c));
                    Child::Leaf(out.leaves.len() as u32 - 1)
                }
            };
            out.nodes[wide as usize].push(child);
        }
    }
    out
}

/// The binary nodes that fill at most `i` slots for the subtree at `n` (C(n, i)'s choice).
fn slots(binary: &[BinaryNode], choice: &[Choice], n: u32, i: usize) -> Vec<u32> {
    let (mut out, mut pending) = (Vec::new(), vec![(n, i)]);
    while let Some((n, i)) = pending.pop() {
        let take = choice[n as usize].take[i - 1] as usize;
        match binary[n as usize].kind {
            BinaryKind::Inner([l, r]) if i > 1 && take > 0 => {
                pending.extend([(r, i - take), (l, take)]);
            }
            _ if i > 1 => pending.push((n, i - 1)),
            _ => out.push(n),
        }
    }
    out
}

/// C(n, i) for every node, children before parents, areas relative to the root's.
fn choices(binary: &[BinaryNode]) -> Vec<Choice> {
    let empty = Choice {
        cost: [0.0; WIDTH],
        take: [0; WIDTH],
        wide_k: 0,
    };
    let mut choice = vec![empty; binary.len()];
    let mut count = vec![0u32; binary.len()];
    let root_area = binary[0].half_area;
    let scale = if root_area > 0.0 {
        1.0 / root_area
    } else {
        1.0
    };
    for n in post_order(binary) {
        let area = binary[n].half_area * scale;
        let leaf = LEAF_COST * area;
        (count[n], choice[n]) = match binary[n].kind {
            BinaryKind::Prim(_) => (
                1,
                Choice {
                    cost: [leaf; WIDTH],
                    ..empty
                },
            ),
            BinaryKind::Inner([l, r]) => {
                let (l, r) = (l as usize, r as usize);
                let n_count = count[l] + count[r];
                (
                    n_count,
                    choose(&choice[l], &choice[r], area, n_count <= LEAF_MAX),
                )
            }
        };
    }
    choice
}

/// C(n, ·) of an inner node from its children's.
fn choose(left: &Choice, right: &Choice, area: f32, leaf_ok: bool) -> Choice {
    let distribute = |j: usize| {
        (1..j)
            .map(|k| (left.cost[k - 1] + right.cost[j - k - 1], k as u8))
            .fold(
                (f32::INFINITY, 0),
                |best, c| if c.0 < best.0 { c } else { best },
            )
    };
    let (wide_cost, wide_k) = distribute(WIDTH);
    let wide_cost = NODE_COST * area + wide_cost;
    let leaf_cost = LEAF_COST * area;
    let mut c = Choice {
        cost: [0.0; WIDTH],
        take: [0; WIDTH],
        wide_k,
    };
    (c.cost[0], c.take[0]) = if leaf_ok && leaf_cost <= wide_cost {
        (leaf_cost, 0)
    } else {
        (wide_cost, 1)
    };
    for i in 2..=WIDTH {
        let (d, k) = distribute(i);
        (c.cost[i - 1], c.take[i - 1]) = if c.cost[i - 2] <= d {
            (c.cost[i - 2], 0)
        } else {
            (d, k)
        };
    }
    c
}

/// Node indices in post order (children before parents) from the root 0.
fn post_order(binary: &[BinaryNode]) -> Vec<usize> {
    let mut order = Vec::with_capacity(binary.len());
    let mut pending = vec![0usize];
    while let Some(n) = pending.pop() {
        order.push(n);
        if let BinaryKind::Inner([l, r]) = binary[n].kind {
            pending.extend([l as usize, r as usize]);
        }
    }
    order.reverse();
    order
}

/// The triangles of the subtree at `n`, left to right.
fn gather(binary: &[BinaryNode], n: u32) -> Vec<u32> {
    let (mut prims, mut pending) = (Vec::new(), vec![n]);
    while let Some(n) = pending.pop() {
        match binary[n as usize].kind {
            BinaryKind::Prim(p) => prims.push(p),
            BinaryKind::Inner([l, r]) => pending.extend([r, l]),
        }
    }
    prims
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A balanced binary tree over `n` triangles, areas halving with depth.
    fn balanced(n: u32) -> Vec<BinaryNode> {
        fn build(nodes: &mut Vec<BinaryNode>, prims: std::ops::Range<u32>, area: f32) -> u32 {
            let index = nodes.len() as u32;
            nodes.push(BinaryNode {
                half_area: area,
                kind: BinaryKind::Prim(prims.start),
            });
            if prims.len() > 1 {
                let mid = prims.start + prims.len() as u32 / 2;
                let l = build(nodes, prims.start..mid, area * 0.5);
                let r = build(nodes, mid..prims.end, area * 0.5);
                nodes[index as usize].kind = BinaryKind::Inner([l, r]);
            }
            index
        }
        let mut nodes = Vec::new();
        build(&mut nodes, 0..n, 1.0);
        nodes
    }

    /// Every triangle in exactly one leaf, leaves of 1–4, nodes of 1–8 children, children
    /// after their parents, every node reachable once.
    fn check(c: &Collapsed, n: u32) {
        let mut seen = vec![0; n as usize];
        c.leaves
            .iter()
            .flatten()
            .for_each(|&p| seen[p as usize] += 1);
        assert!(seen.iter().all(|&s| s == 1), "{seen:?}");
        assert!(c.leaves.iter().all(|l| (1..=4).contains(&l.len())));
        let mut parents = vec![0; c.nodes.len()];
        let mut leaf_parents = vec![0; c.leaves.len()];
        for (i, node) in c.nodes.iter().enumerate() {
            assert!((1..=WIDTH).contains(&node.len()));
            for &child in node {
                match child {
                    Child::Node(k) => {
                        assert!(k as usize > i);
                        parents[k as usize] += 1;
                    }
                    Child::Leaf(k) => leaf_parents[k as usize] += 1,
                }
            }
        }
        assert!(parents[1..].iter().all(|&p| p == 1) && parents[0] == 0);
        assert!(leaf_parents.iter().all(|&p| p == 1));
    }

    #[test]
    fn shapes_of_balanced_trees() {
        for n in [1, 2, 3, 4, 5, 7, 8, 9, 31, 32, 33, 100, 1000] {
            let c = collapse(&balanced(n));
            check(&c, n);
            if n <= 4 {
                assert_eq!(c.nodes, vec![vec![Child::Leaf(0)]]);
            }
        }
        // 32 triangles whose areas halve per level: eight leaves of four under the root.
        let c = collapse(&balanced(32));
        assert_eq!(c.nodes.len(), 1);
        assert_eq!(c.leaves.len(), 8);
        // 64: sixteen leaves of four, under the root and at most two more nodes.
        let c = collapse(&balanced(64));
        assert!(c.nodes.len() <= 3, "{}", c.nodes.len());
    }

    /// Children much smaller than their parent are split off rather than merged into one leaf.
    #[test]
    fn sah_splits_distant_children() {
        let mut nodes = balanced(4);
        // The two halves of the root are tiny next to the root's box (far apart).
        nodes[0].half_area = 100.0;
        let c = collapse(&nodes);
        check(&c, 4);
        assert!(c.leaves.len() >= 2);
    }

    /// A chain (each inner node with one triangle and one subtree) 500 deep.
    #[test]
    fn deep_chains() {
        let n = 500u32;
        let mut nodes = Vec::new();
        for k in 0..n - 1 {
            let next = nodes.len() as u32 + 2;
            nodes.push(BinaryNode {
                half_area: (n - k) as f32,
                kind: BinaryKind::Inner([nodes.len() as u32 + 1, next]),
            });
            nodes.push(BinaryNode {
                half_area: 0.5,
                kind: BinaryKind::Prim(k),
            });
        }
        nodes.push(BinaryNode {
            half_area: 0.5,
            kind: BinaryKind::Prim(n - 1),
        });
        check(&collapse(&nodes), n);
    }
}
