//! The collapse of a binary BVH into the 8-wide tree the traversal walks, with leaves of up to
//! four triangles (one four-lane block, [`super::leaf4`]).
//!
//! Which subtrees become leaves is decided bottom-up by the surface area heuristic (Goldsmith,
//! Salmon 1987; MacDonald, Booth 1990; PBR 4ed §7.3.2), with Embree's cost of a leaf: one
//! intersection cost per block of four triangles, whatever its fill (Wald et al. 2014, "Embree:
//! A Kernel Framework for Efficient CPU Ray Tracing", §4.1, `sahBlockSize` 4). For a subtree n
//! with surface area A(n), cost(n) = min(leaf: [`LEAF_COST`]·A(n) if n holds ≤ 4 triangles,
//! inner: [`STEP_COST`]·A(n) + cost(left) + cost(right)); the ratio of the two costs is all
//! that matters. The 8-wide nodes are then formed top-down as Wald, Benthin, Boulos 2008
//! ("Getting Rid of Packets", §3.2) and Embree's BVH8 builder do: starting from a node's two
//! children, the inner child of largest surface area is replaced by its two children until
//! there are eight or only leaves are left.

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
/// SAH cost of testing one leaf block (the unit).
const LEAF_COST: f32 = 1.0;
/// SAH cost of one binary level inside a wide node: an 8-wide node test (two four-lane slab
/// passes, about two leaf passes) shared by the about seven binary nodes it absorbs.
const STEP_COST: f32 = 0.3;

/// Collapses the binary BVH rooted at node 0 (which must not be empty).
pub(super) fn collapse(binary: &[BinaryNode]) -> Collapsed {
    let is_leaf = leaf_decisions(binary);
    let mut out = Collapsed {
        nodes: vec![Vec::new()],
        leaves: Vec::new(),
    };
    if is_leaf[0] {
        out.nodes[0].push(Child::Leaf(0));
        out.leaves.push(gather(binary, 0));
        return out;
    }
    let mut pending = vec![(0u32, 0u32)];
    while let Some((wide, n)) = pending.pop() {
        for c in widen(binary, &is_leaf, n) {
            let child = if is_leaf[c as usize] {
                out.leaves.push(gather(binary, c));
                Child::Leaf(out.leaves.len() as u32 - 1)
            } else {
                out.nodes.push(Vec::new());
                let index = out.nodes.len() as u32 - 1;
                pending.push((index, c));
                Child::Node(index)
            };
            out.nodes[wide as usize].push(child);
        }
    }
    out
}

/// Per binary node: whether the SAH makes its subtree one leaf (see the module docs).
fn leaf_decisions(binary: &[BinaryNode]) -> Vec<bool> {
    let mut count = vec![0u32; binary.len()];
    let mut cost = vec![0f32; binary.len()];
    let mut is_leaf = vec![false; binary.len()];
    for n in post_order(binary) {
        let area = binary[n].half_area;
        let leaf_cost = LEAF_COST * area;
        (count[n], cost[n], is_leaf[n]) = match binary[n].kind {
            BinaryKind::Prim(_) => (1, leaf_cost, true),
            BinaryKind::Inner([l, r]) => {
                let (l, r) = (l as usize, r as usize);
                let n_count = count[l] + count[r];
                let split = STEP_COST * area + cost[l] + cost[r];
                let leaf = n_count <= LEAF_MAX && leaf_cost <= split;
                (n_count, if leaf { leaf_cost } else { split }, leaf)
            }
        };
    }
    is_leaf
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

/// The children of a wide node made from inner binary node `n`: its two children, then the
/// inner one of largest area opened until there are [`WIDTH`].
fn widen(binary: &[BinaryNode], is_leaf: &[bool], n: u32) -> Vec<u32> {
    let mut children = match binary[n as usize].kind {
        BinaryKind::Inner([l, r]) => vec![l, r],
        BinaryKind::Prim(_) => vec![n],
    };
    while children.len() < WIDTH {
        let largest = (0..children.len())
            .filter(|&i| !is_leaf[children[i] as usize])
            .max_by(|&i, &j| {
                let area = |k: usize| binary[children[k] as usize].half_area;
                area(i).total_cmp(&area(j))
            });
        let Some(i) = largest else { break };
        let BinaryKind::Inner([l, r]) = binary[children[i] as usize].kind else {
            break;
        };
        children[i] = l;
        children.insert(i + 1, r);
    }
    children
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
        // 32 triangles whose areas halve per level: eight leaves of four under the root (a
        // leaf of 4 costs 1·A, its two halves 0.3·A + 2·(A/2)).
        let c = collapse(&balanced(32));
        assert_eq!(c.nodes.len(), 1);
        assert_eq!(c.leaves.len(), 8);
    }

    /// Children much smaller than their parent are split off rather than merged into one leaf.
    #[test]
    fn sah_splits_distant_children() {
        let mut nodes = balanced(4);
        // The two halves of the root are tiny next to the root's box (far apart).
        nodes[0].half_area = 100.0;
        let c = collapse(&nodes);
        check(&c, 4);
        assert_eq!(c.leaves.len(), 2);
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
