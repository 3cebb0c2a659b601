//! The immutable, `Sync` scene the integrators read: triangles behind the BVH, materials,
//! lights with their sampler, the camera; plus closest-hit and shadow queries.

use super::analysis::SceneFeatures;
use super::prim::Prim;
use crate::accel::bvh::{Bvh, BvhHit};
use crate::desc::DataWindowDesc;
use crate::geometry::triangle::hit_point_error;
use crate::geometry::Ray;
use crate::light::emission_layers::EmissionLayers;
use crate::light::emit::SceneSphere;
use crate::light::{Light, LightHit, LightSampler};
use crate::material::normal_map::Tangents;
use crate::material::Material;
use crate::sensor::Camera;
use glam::{DMat4, Vec2, Vec3};
use std::path::PathBuf;

/// Error bound of a user-given point relative to the scene's extent ([`Scene::point_error`]):
/// 2⁻¹⁸ ≈ 3.8·10⁻⁶.
pub const POINT_ERROR_REL: f32 = 1.0 / 262_144.0;

/// A triangle mesh in world space.
#[derive(Clone, Debug)]
pub struct Mesh {
    pub prim_path: String,
    pub positions: Vec<Vec3>,
    pub indices: Vec<[u32; 3]>,
    pub normals: Option<Vec<[Vec3; 3]>>,
    pub uvs: Option<Vec<[Vec2; 3]>>,
    /// Per-triangle ∂p/∂u, ∂p/∂v when the material perturbs the shading normal.
    pub tangents: Tangents,
    pub material: u32,
    /// Index of the light of this mesh's triangle 0 (triangle i is light `offset + i`).
    pub light_offset: Option<u32>,
}

/// Which mesh and which of its triangles a BVH primitive is.
#[derive(Clone, Copy, Debug)]
pub struct TriRef {
    pub mesh: u32,
    pub tri: u32,
}

/// A ray's hit on a surface with a material.
#[derive(Clone, Copy, Debug)]
pub struct SurfaceHit {
    pub p: Vec3,
    /// Absolute error bound of `p` (for robust ray spawning).
    pub p_error: Vec3,
    /// Unit geometric normal of the authored front face.
    pub ng: Vec3,
    /// Unit shading normal, on the same side as `ng`, after the material's normal map.
    pub ns: Vec3,
    pub uv: Vec2,
    pub t: f32,
    pub material: u32,
    /// The triangle hit (for its ∂p/∂u, ∂p/∂v: `Scene::tex_coord`).
    pub tri: TriRef,
    /// The emissive triangle's light, if the surface is a mesh light.
    pub light: Option<u32>,
}

/// What a ray met first.
#[derive(Clone, Copy, Debug)]
pub enum Hit {
    Surface(SurfaceHit),
    /// An analytic light shape (rect, disk, sphere): it emits and absorbs.
    Light {
        light: u32,
        hit: LightHit,
    },
}

/// Counts and notes for the one-line load summary.
#[derive(Clone, Debug, Default)]
pub struct Summary {
    pub meshes: usize,
    pub triangles: usize,
    pub materials: usize,
    pub lights: usize,
    pub camera: String,
    pub warnings: Vec<String>,
    /// The time the stage was read at.
    pub time: crate::desc::TimeDesc,
}

pub struct Scene {
    pub source: PathBuf,
    pub meshes: Vec<Mesh>,
    /// Per BVH primitive (`BvhHit::prim`), its triangle and geometric normal (`scene/prim.rs`).
    pub prims: Vec<Prim>,
    pub bvh: Bvh,
    pub materials: Vec<Material>,
    pub lights: Vec<Light>,
    pub light_sampler: LightSampler,
    /// Per light, the first light of its run with the same uniform radiance
    /// (`light::radiance_class`): the key of a path's memo of a light's radiance.
    pub radiance_class: Vec<u32>,
    /// Indices of lights met by escaping rays.
    pub infinite_lights: Vec<u32>,
    /// Indices of lights that are analytic shapes.
    pub shape_lights: Vec<u32>,
    /// Indices of lights with `inputs:shadow:enable = 0`: next-event shadow rays towards them
    /// pass through occluders (`casts_shadows`).
    pub shadowless: Vec<u32>,
    pub camera: Camera,
    pub center: Vec3,
    pub radius: f32,
    pub summary: Summary,
    /// True when no material has an opacity below 1 (shadow rays then need no pass-through).
    pub all_opaque: bool,
    /// True when some material's BSDF is textured (`Material::is_textured`): only then does a
    /// hit's texture footprint need computing (`Scene::tex_coord`).
    pub any_textured: bool,
    /// True when a material refracts wavelengths apart (`Material::is_dispersive`): only then
    /// do the integrators check at each vertex whether to terminate the secondary
    /// wavelengths.
    pub dispersive: bool,
    /// Per material, whether it has a delta or near-specular lobe
    /// (`analysis::lobes::Lobes::specular_like`), found once here rather than at every vertex
    /// of VCM's walks (`integrator::bidir::merge_rule::near_specular`).
    pub specular_like: Vec<bool>,
    /// Stage space to world space (see `SceneDescription::stage_to_world`).
    pub stage_to_world: DMat4,
    /// The hash of the stage's layers (`SceneDescription::content_hash`).
    pub content_hash: u64,
    /// What the stage calls for (`scene::analysis`), found once when the scene is built.
    pub features: SceneFeatures,
    /// The RenderSettings' `dataWindowNDC`, when it is not the whole image: the part of the
    /// image a render renders (`session::crop`).
    pub data_window: Option<DataWindowDesc>,
    /// Per light, its group's name (`spectral:lightGroup`, else the light's prim): the
    /// layers of `--light-groups`.
    pub light_groups: Vec<String>,
    /// Extra layers weighting the paths by their own emission (`--illuminants`,
    /// `--light-groups`: `light::emission_layers`, `scene::emission_layers`).
    pub emission_layers: EmissionLayers,
}

impl Scene {
    /// False for a light with `inputs:shadow:enable = 0`. The path integrator and the meters
    /// then take its direct light from next event estimation alone, unoccluded and with
    /// weight 1, and give BSDF-sampled rays that find it weight 0 (so the two strategies
    /// still sum to one estimate: of the light's unshadowed direct illumination).
    #[inline]
    pub fn casts_shadows(&self, light: u32) -> bool {
        // Most scenes have no shadowless light: one test rather than `contains`'s loop setup
        // at every next-event estimate.
        self.shadowless.is_empty() || !self.shadowless.contains(&light)
    }

    /// Closest hit with t in (0, t_max).
    pub fn intersect(&self, ray: &Ray, t_max: f32) -> Option<Hit> {
        super::ray_count::count();
        let tri = self.bvh.intersect(ray, t_max);
        if !self.shape_lights.is_empty() {
            let limit = tri.as_ref().map_or(t_max, |h| h.hit.t);
            if let Some((light, hit)) = self.nearest_shape(ray, limit) {
                return Some(Hit::Light { light, hit });
            }
        }
        // The surface's hit is built only when it is the answer.
        tri.map(|h| Hit::Surface(self.surface_hit(&h)))
    }

    /// The nearest analytic light shape the ray meets before `limit` (the triangles' nearest
    /// hit or t_max), if any.
    fn nearest_shape(&self, ray: &Ray, mut limit: f32) -> Option<(u32, LightHit)> {
        let mut best = None;
        for &li in &self.shape_lights {
            if let Some(hit) = self.lights[li as usize].intersect(ray.o, ray.d, limit) {
                limit = hit.t;
                best = Some((li, hit));
            }
        }
        best
    }

    /// True when something blocks the ray before t_max; `skip` is the light being sampled
    /// (its own shape must not shadow the point sampled on it).
    pub fn occluded(&self, ray: &Ray, t_max: f32, skip: Option<u32>) -> bool {
        super::ray_count::count();
        if self.bvh.occluded(ray, t_max) {
            return true;
        }
        self.shape_lights.iter().any(|&li| {
            Some(li) != skip
                && self.lights[li as usize]
                    .intersect(ray.o, ray.d, t_max)
                    .is_some()
        })
    }

    /// The sphere light subpaths of infinite lights start from: the bounding sphere grown to
    /// contain the analytic light shapes (`SceneSphere::enclosing`).
    pub fn emission_sphere(&self) -> SceneSphere {
        let shapes = self.shape_lights.iter().map(|&i| &self.lights[i as usize]);
        SceneSphere::enclosing(self.center, self.radius, shapes)
    }

    /// The per-axis error bound given to a point typed in by the user (a light meter), which
    /// has none of its own: the rays it spawns leave from `p` moved along the normal (or view
    /// direction) by about this much (`geometry::offset`). 2⁻¹⁸ of the scene's extent
    /// (bounding sphere or |p|, whichever is larger) is 64 ulps of f32 at that magnitude: some
    /// 40 times the error bound of a ray hit on the scene's largest triangles (PBR 4ed §6.8.3,
    /// γ₇·Σ|bᵢpᵢ|), so a meter typed on a floor, a transformed wall or a surface converted
    /// from stage units starts above it, while the change of geometry stays negligible (4 mm
    /// for a 1 km ground plane, 20 µm in a 5 m room). The offset is along the meter's normal,
    /// so a meter lying on a surface must face away from it (as a real sensor would).
    pub fn point_error(&self, p: Vec3) -> Vec3 {
        let extent = self.center.abs().max_element() + self.radius;
        Vec3::splat(POINT_ERROR_REL * extent.max(p.abs().max_element()))
    }

    /// The surface's hit: its vertices are read from the BVH's triangle store, where the
    /// query just found them (`Bvh::vertices`, bit for bit the mesh's), with no hops through
    /// the mesh's indices and positions; its geometric normal is the primitive's, found when
    /// the scene was built (`scene/prim.rs`).
    fn surface_hit(&self, found: &BvhHit) -> SurfaceHit {
        let hit = &found.hit;
        let Prim { ng, tri: r } = self.prims[found.prim as usize];
        let mesh = &self.meshes[r.mesh as usize];
        let [p0, p1, p2] = self.bvh.vertices(found);
        let p = hit.b0 * p0 + hit.b1 * p1 + hit.b2 * p2;
        let uv = mesh.uvs.as_ref().map_or(Vec2::new(hit.b1, hit.b2), |uv| {
            let [a, b, c] = uv[r.tri as usize];
            hit.b0 * a + hit.b1 * b + hit.b2 * c
        });
        let ns = match &mesh.normals {
            Some(n) => {
                let [n0, n1, n2] = n[r.tri as usize];
                let ns = (hit.b0 * n0 + hit.b1 * n1 + hit.b2 * n2).normalize_or_zero();
                if ns == Vec3::ZERO {
                    ng
                } else if ns.dot(ng) < 0.0 {
                    -ns
                } else {
                    ns
                }
            }
            None => ng,
        };
        let ns = match mesh.tangents.at(r.tri) {
            Some(dpduv) => self.materials[mesh.material as usize].shading_normal(uv, ns, ng, dpduv),
            None => ns,
        };
        SurfaceHit {
            p,
            p_error: hit_point_error(hit, p0, p1, p2),
            ng,
            ns,
            uv,
            t: hit.t,
            material: mesh.material,
            tri: r,
            light: mesh.light_offset.map(|o| o + r.tri),
        }
    }
}
