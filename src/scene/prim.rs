//! Per BVH primitive, what a hit on it needs that does not depend on where the ray met it:
//! which mesh triangle it is and its unit geometric normal. The normal is found once when the
//! scene is built instead of at every closest hit (a cross product, a square root and a
//! division on the hit's dependency chain: docs/design.md §8, session 38); it is the same
//! expression of the same vertices, so its bits are those the hit computed.

use super::render_scene::{Mesh, TriRef};
use glam::Vec3;

/// A BVH primitive: its triangle and that triangle's unit geometric normal (of the authored
/// front face, `(p1 − p0) × (p2 − p0)` normalised; zero where that product underflows).
#[derive(Clone, Copy, Debug)]
pub struct Prim {
    pub ng: Vec3,
    pub tri: TriRef,
}

/// The unit geometric normal of the triangle `[p0, p1, p2]`, zero when the cross product's
/// length is zero or not finite.
#[inline]
pub fn geometric_normal([p0, p1, p2]: [Vec3; 3]) -> Vec3 {
    (p1 - p0).cross(p2 - p0).normalize_or_zero()
}

/// The primitives of `meshes`, mesh by mesh and triangle by triangle, with their vertices:
/// what `Bvh::build` is given, in its input order.
pub fn flatten(meshes: &[Mesh]) -> (Vec<Prim>, Vec<[Vec3; 3]>) {
    let mut prims = Vec::new();
    let mut tris = Vec::new();
    for (mi, m) in meshes.iter().enumerate() {
        for (ti, t) in m.indices.iter().enumerate() {
            let vertices = t.map(|i| m.positions[i as usize]);
            prims.push(Prim {
                ng: geometric_normal(vertices),
                tri: TriRef {
                    mesh: mi as u32,
                    tri: ti as u32,
                },
            });
            tris.push(vertices);
        }
    }
    (prims, tris)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::material::normal_map::Tangents;

    fn mesh(positions: Vec<Vec3>, indices: Vec<[u32; 3]>) -> Mesh {
        Mesh {
            prim_path: "/m".into(),
            positions,
            indices,
            normals: None,
            uvs: None,
            tangents: Tangents::Unused,
            material: 0,
            light_offset: None,
        }
    }

    /// Primitives come mesh by mesh in triangle order, each with its triangle's vertices and
    /// unit normal (the authored front face's), zero for a degenerate triangle.
    #[test]
    fn flatten_orders_and_normals() {
        let quad = mesh(
            vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 0.0, 1.0), Vec3::Z],
            vec![[0, 2, 1], [0, 3, 2]],
        );
        let sliver = mesh(vec![Vec3::ZERO, Vec3::Y, 2.0 * Vec3::Y], vec![[0, 1, 2]]);
        let (prims, tris) = flatten(&[quad, sliver]);
        let refs: Vec<(u32, u32)> = prims.iter().map(|p| (p.tri.mesh, p.tri.tri)).collect();
        assert_eq!(refs, [(0, 0), (0, 1), (1, 0)]);
        assert_eq!(tris[1], [Vec3::ZERO, Vec3::Z, Vec3::new(1.0, 0.0, 1.0)]);
        assert_eq!(prims[0].ng, Vec3::Y);
        assert_eq!(prims[1].ng, Vec3::Y);
        assert_eq!(prims[2].ng, Vec3::ZERO);
        for (p, t) in prims.iter().zip(&tris) {
            assert_eq!(p.ng.to_array(), geometric_normal(*t).to_array());
        }
    }
}
