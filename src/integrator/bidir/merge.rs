//! Vertex merging (Georgiev, Křivánek, Davidovič, Slusallek 2012, "Light transport simulation
//! with vertex connection and merging", §4–5; the tech. rep. "Implementing Vertex Connection
//! and Merging", §4): a camera vertex z within radius r of a stored light vertex y completes
//! the path x_0 … y ≈ z … camera, estimated as a photon-density kernel
//!
//!   β_z · f_z(ω_z, ω_y) · β_y / (π r² N_L)
//!
//! (tech. rep. eq. (19)–(21): the merge's density is the connection's times π r² N_L), with
//! ω_y the direction back along y's light subpath and N_L the light subpaths stored this
//! iteration. No cosine: the density of the light subpath's arrival per area carries it.
//!
//! The store ([`LightVertexStore`], `store.rs`) keeps what merging needs of every non-specular
//! light vertex of the iteration in [`MergeVertex`] (76 bytes), in the slot order of a hash
//! grid over them: a cell's candidates are contiguous.
//!
//! **No merges through walls.** A light vertex on another mesh than the camera vertex merges
//! only when the segment between the two points, each lifted off its surface by r/100 to the
//! side its path arrived from, is unoccluded. Without it, a zero-thickness wall lets every
//! camera vertex within r of it merge the light vertices on its far side: on `scenes/gap.usda`
//! at 80 × 60 (r_0 = 82 mm) the lit closet leaked into the room, +33 % in the image's mean
//! luminance. The kernel estimate near an edge then counts the vertices the camera vertex
//! sees, a bias within r of the edge that vanishes with r as the blur does; vertices on the
//! camera vertex's own mesh are not tested (a shadow ray per merge would double VCM's cost on
//! the Cornell box), so a single mesh running under a wall still leaks.

use super::mis::{Mis, SubpathMis};
use super::{LightVertexStore, PathVertex};
use crate::bxdf::{BsdfEval, TransportMode};
use crate::geometry::offset::SHADOW_EPSILON;
use crate::geometry::Ray;
use crate::scene::Scene;
use crate::sensor::meter::MeterSensor;
use crate::spectral::SampledSpectrum;
use glam::Vec3;

/// A light vertex y_i (i ≥ 1) as merging needs it.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct MergeVertex {
    pub p: Vec3,
    /// Unit direction from y_i back towards y_{i−1}.
    pub wo: Vec3,
    /// The light subpath's throughput at y_i.
    pub beta: SampledSpectrum,
    /// y_i's dVCM and dVM [tech. rep. (31)–(36)].
    pub dvcm: f32,
    pub dvm: f32,
    /// |cos| between ω_y and the geometric normal of the surface the vertex lies on.
    pub cos_ng: f32,
    /// i: segments from the light.
    pub depth: u32,
    /// The mesh the vertex lies on, and its geometric normal turned to the side the light
    /// subpath arrived from.
    pub mesh: u32,
    pub n: Vec3,
    /// The light subpath terminated its secondary wavelengths (dispersion): only the hero
    /// lane of `beta` is meaningful.
    pub hero_only: bool,
}

impl MergeVertex {
    pub fn new(y: &PathVertex, mesh: u32, hero_only: bool) -> MergeVertex {
        MergeVertex {
            mesh,
            n: arrival_normal(y),
            p: y.p,
            wo: y.wo,
            beta: y.beta,
            dvcm: y.mis.dvcm,
            dvm: y.mis.dvm,
            cos_ng: y.ng.dot(y.wo).abs(),
            depth: y.depth,
            hero_only,
        }
    }
}

/// What one merge search found: contributions relative to the camera subpath's wavelengths,
/// and those that may only count on the hero wavelength (light vertices whose subpath
/// terminated the secondary wavelengths, met by a camera subpath that has not).
#[derive(Clone, Copy, Debug, Default)]
pub struct Merged {
    pub all: SampledSpectrum,
    pub hero_only: SampledSpectrum,
}

/// What merging at a camera vertex needs to know about the iteration.
#[derive(Clone, Copy, Debug)]
pub struct MergeParams {
    /// m(1/η_VCM) and the heuristic (the `Mis` of the iteration).
    pub mis: Mis,
    /// 1 / η_VCM: 1 / (π r² N_L) [tech. rep. (21)], or with per-sample wavelength tuples
    /// B / (π r² N_L), only the N_L / B light subpaths of the camera's bin merging (`vcm.rs`).
    pub normalization: f32,
    pub max_depth: u32,
    /// The camera sample's hero-wavelength bin: merges use light vertices of this key only.
    pub key: u32,
}

impl LightVertexStore {
    /// Merges camera vertex `z` (non-specular, on mesh `mesh` of `scene`; its walk's MIS in
    /// `cam`) with every stored light vertex within the radius whose full path stays within
    /// the depth limit (i + j − 1 scattering events for y_i ≈ z_j) and that `z` sees (module
    /// docs), weighted by MIS [tech. rep. (38), (39); SmallVCM's merging weights].
    pub fn merge(
        &self,
        scene: &Scene,
        z: &PathVertex,
        mesh: u32,
        cam: &SubpathMis,
        camera_hero_only: bool,
        params: &MergeParams,
    ) -> Merged {
        let mut out = Merged::default();
        if self.vertices.is_empty() {
            return out;
        }
        // Most camera vertices lie far from every stored vertex: the query stops at once
        // (`reach.rs`), so nothing is computed for them before it.
        self.grid.query(z.p, params.key, |s| {
            let y = &self.vertices[s];
            if y.depth + z.depth > params.max_depth + 1 {
                return;
            }
            let e = z.bsdf.eval(z.wo, y.wo, TransportMode::Radiance);
            if e.f.is_black() {
                return;
            }
            let w = merge_weight(&params.mis, cam, y, &e);
            let c = z.beta * e.f * y.beta * (w * params.normalization);
            // The light-leak guard last: most candidates lie on z's own mesh, and the rest
            // need a shadow ray only when they would count.
            if y.mesh != mesh && !c.is_black() {
                let lift = MERGE_LIFT * self.grid.radius();
                let z_lifted = z.p + arrival_normal(z) * lift;
                if !unoccluded(scene, z_lifted, y.p + y.n * lift) {
                    return;
                }
            }
            if y.hero_only && !camera_hero_only {
                out.hero_only += c;
            } else {
                out.all += c;
            }
        });
        out
    }
}

impl LightVertexStore {
    /// Merges the light vertices within the radius of irradiance meter `m`'s point, weighted
    /// by MIS against every other technique (`Mis::merge_at_sensor`); `hero_only` as
    /// [`LightVertexStore::merge`].
    pub fn merge_at_sensor(
        &self,
        m: &MeterSensor,
        camera_hero_only: bool,
        params: &MergeParams,
    ) -> Merged {
        let mut out = Merged::default();
        self.grid.query(m.p, params.key, |s| {
            let y = &self.vertices[s];
            let cos = m.dir.dot(y.wo);
            if cos <= 0.0 || y.cos_ng <= 0.0 || y.depth < 2 || y.depth > params.max_depth + 1 {
                return;
            }
            let w = sensor_merge_weight(&params.mis, m, y);
            let c = y.beta * (cos / y.cos_ng * w * params.normalization);
            if y.hero_only && !camera_hero_only {
                out.hero_only += c;
            } else {
                out.all += c;
            }
        });
        out
    }
}

/// How far, in radii, merge visibility tests lift both ends off their surfaces: far above
/// the points' rounding error, so that the segment between two floors meets the wall standing
/// between them rather than grazing its edge, and a wall's own vertex on its far side is a
/// finite step behind it.
const MERGE_LIFT: f32 = 0.01;

/// `v`'s geometric normal turned to the side its subpath arrived from.
fn arrival_normal(v: &PathVertex) -> Vec3 {
    if v.ng.dot(v.wo) < 0.0 {
        -v.ng
    } else {
        v.ng
    }
}

/// Nothing in `scene` blocks the segment between two points off surfaces.
fn unoccluded(scene: &Scene, from: Vec3, to: Vec3) -> bool {
    !scene.occluded(&Ray::new(from, to - from), 1.0 - SHADOW_EPSILON, None)
}

/// The MIS weight of merging light vertex `y` at irradiance meter `m`'s point: the meter's ray
/// density towards y_{i−1} (cos θ / π) takes the place of a camera BSDF's.
pub fn sensor_merge_weight(mis: &Mis, m: &MeterSensor, y: &MergeVertex) -> f32 {
    mis.merge_at_sensor(y.dvcm, y.dvm, m.pdf_dir_w(y.wo))
}

/// The MIS weight of merging camera vertex z (its walk's MIS `cam`, its BSDF evaluated at
/// (ω_z, ω_y) in `e`) with light vertex `y` [tech. rep. (38), (39)]: the camera BSDF's
/// density of ω_y (the light side's technique one vertex longer) and of ω_z from ω_y (the
/// camera side's) enter `Mis::merge`, each only where its dVM factor is not 0 (the camera's
/// first vertex has none: no merge precedes it).
pub fn merge_weight(mis: &Mis, cam: &SubpathMis, y: &MergeVertex, e: &BsdfEval) -> f32 {
    let pdf_dir = if y.dvm == 0.0 { 0.0 } else { e.pdf_fwd };
    let pdf_rev = if cam.dvm == 0.0 { 0.0 } else { e.pdf_rev };
    mis.merge(y.dvcm, y.dvm, cam, pdf_dir, pdf_rev)
}
