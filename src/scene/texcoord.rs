//! Texture coordinates with their footprint at a surface hit, for textured materials only.

use super::render_scene::{Scene, SurfaceHit, TriRef};
use crate::material::normal_map::{triangle_dpduv, Tangents};
use crate::texture::{TexCoord, TextureFilter};
use glam::{Vec2, Vec3};

impl Scene {
    /// What the material at `si` looks its textures up with: st and, when the BSDF is
    /// textured and `filter` is the camera's, st's derivatives per pixel from the camera's
    /// approximate ∂p/∂x, ∂p/∂y at the hit (geometric normal) and the triangle's ∂p/∂u, ∂p/∂v
    /// (PBR 4ed §10.1.1). The derivatives depend on the point only, not on the ray that found
    /// it, so the filtered BSDF is the same for every path through the point (camera and light
    /// subpaths, all BDPT techniques).
    #[inline(always)]
    pub fn tex_coord(&self, si: &SurfaceHit, filter: TextureFilter) -> TexCoord {
        // A scene without textured materials (found once at build) skips the per-hit test;
        // the test and the footprint are a call of their own, this check is the caller's.
        match filter {
            TextureFilter::Camera { spp_scale } if self.any_textured => {
                self.filtered_tex_coord(si, spp_scale)
            }
            _ => TexCoord::point(si.uv),
        }
    }

    /// [`Self::tex_coord`] with the camera's filter in a scene with textured materials.
    #[inline(never)]
    fn filtered_tex_coord(&self, si: &SurfaceHit, spp_scale: f32) -> TexCoord {
        if !self.materials[si.material as usize].is_textured() {
            return TexCoord::point(si.uv);
        }
        let dpdxy = self.camera.approximate_dp_dxy(si.p, si.ng, spp_scale);
        TexCoord::from_differentials(si.uv, self.dpduv(si.tri), dpdxy)
    }

    /// ∂p/∂u, ∂p/∂v of a triangle for its mesh's st, or for the barycentric st a mesh without
    /// texture coordinates uses (PBR 4ed §6.5.3); zeros where st is degenerate.
    pub fn dpduv(&self, r: TriRef) -> [Vec3; 2] {
        let mesh = &self.meshes[r.mesh as usize];
        if let Tangents::PerTriangle(d) = &mesh.tangents {
            return d[r.tri as usize];
        }
        let p = mesh.indices[r.tri as usize].map(|i| mesh.positions[i as usize]);
        let uv = mesh
            .uvs
            .as_ref()
            .map_or([Vec2::ZERO, Vec2::X, Vec2::Y], |uv| uv[r.tri as usize]);
        triangle_dpduv(p, uv)
    }
}
