//! Subpath vertices: plain `Copy` records that refer to the scene by id (docs/design.md §4) and
//! carry what connections and, later, merges need: position, normals, BSDF, throughput and
//! the partial MIS quantities.

use super::mis::SubpathMis;
use crate::bxdf::{Bsdf, TransportMode};
use crate::light::LightHit;
use crate::material::{Material, SpectraCache};
use crate::scene::{Scene, SurfaceHit};
use crate::spectral::{SampledSpectrum, SampledWavelengths};
use crate::texture::TextureFilter;
use glam::Vec3;

/// A scattering vertex of a light (y_i) or camera (z_i) subpath, i ≥ 1.
#[derive(Clone, Copy, Debug)]
pub struct PathVertex {
    pub p: Vec3,
    /// Absolute error bound of `p` (for spawning connection rays).
    pub p_error: Vec3,
    /// Unit geometric normal.
    pub ng: Vec3,
    /// Unit shading normal.
    pub ns: Vec3,
    /// Unit direction back towards the previous vertex of the same subpath.
    pub wo: Vec3,
    pub bsdf: Bsdf,
    /// Throughput of the subpath up to this vertex (a light subpath's includes the emission
    /// divided by its sampling densities; a camera subpath's starts at We / pdf = 1).
    pub beta: SampledSpectrum,
    pub mis: SubpathMis,
    /// Segments from the subpath's origin: i for y_i or z_i.
    pub depth: u32,
    /// Merging at this vertex is available (`merge_rule.rs`): always under
    /// [`super::MergeRule::All`]; under the caustic rule, for a light vertex, when its
    /// predecessor on its subpath is near-specular (camera vertices: unused).
    pub merges: bool,
    /// The vertex is near-specular (`merge_rule::near_specular`), which decides merging at
    /// the vertex after it in light order; false where no rule asks.
    pub near_specular: bool,
}

impl PathVertex {
    pub fn new(
        si: &SurfaceHit,
        wo: Vec3,
        bsdf: Bsdf,
        beta: SampledSpectrum,
        mis: SubpathMis,
        depth: u32,
    ) -> PathVertex {
        PathVertex {
            p: si.p,
            p_error: si.p_error,
            ng: si.ng,
            ns: si.ns,
            wo,
            bsdf,
            beta,
            mis,
            depth,
            merges: true,
            near_specular: false,
        }
    }

    /// The BSDF for radiance leaving towards `wo` from `wi` (camera subpaths).
    #[inline]
    pub fn f_radiance(&self, wi: Vec3) -> SampledSpectrum {
        self.bsdf.f(self.wo, wi, TransportMode::Radiance)
    }

    /// The adjoint BSDF for importance carried from `wo` on to `wi` (light subpaths),
    /// including the shading-normal correction.
    #[inline]
    pub fn f_importance(&self, wi: Vec3) -> SampledSpectrum {
        self.bsdf.f(self.wo, wi, TransportMode::Importance)
            * shading_correction(self.ns, self.ng, self.wo, wi)
    }

    /// The density with which the *other* subpath would sample `self.wo` at this vertex,
    /// arriving from `wi` (the vertex's own subpath transports in `mode`).
    #[inline]
    pub fn reverse_pdf(&self, wi: Vec3, mode: TransportMode) -> f32 {
        let other = match mode {
            TransportMode::Importance => TransportMode::Radiance,
            TransportMode::Radiance => TransportMode::Importance,
        };
        self.bsdf.pdf(wi, self.wo, other)
    }

    /// |cos θ| against the shading normal (the cosine of the rendering equation).
    #[inline]
    pub fn cos_shading(&self, w: Vec3) -> f32 {
        self.ns.dot(w).abs()
    }

    /// |cos θ| against the geometric normal (area-measure conversions).
    #[inline]
    pub fn cos_geo(&self, w: Vec3) -> f32 {
        self.ng.dot(w).abs()
    }
}

/// The first vertex y_0 of a light subpath: where on which light it started.
#[derive(Clone, Copy, Debug)]
pub struct LightOrigin {
    pub light: u32,
    pub p: Vec3,
    pub p_error: Vec3,
    /// Emitting-side geometric normal (for infinite lights: the direction of travel).
    pub n: Vec3,
    /// Probability of choosing this light.
    pub pmf: f32,
    pub pdf_pos_a: f32,
    /// Density per solid angle of the emitted direction (1 relative to a delta).
    pub pdf_dir_w: f32,
    /// Radiance carried by the emitted ray (for a delta distant light: its irradiance). An
    /// infinite light's connection to a meter reuses it, the direction being the same.
    pub le: SampledSpectrum,
    pub infinite: bool,
    pub delta_dir: bool,
    /// A point or line light: no surface at y_0, no ray can hit it, and the carried `le` is an
    /// intensity (per unit length for a line) with no cosine at y_0.
    pub delta_pos: bool,
}

impl LightOrigin {
    /// The light-shape description of y_0 for `Light::l` and `Light::pdf_li`.
    pub fn hit(&self, t: f32) -> LightHit {
        LightHit {
            p: self.p,
            n: self.n,
            t,
        }
    }
}

/// Shading-normal correction of the adjoint BSDF for importance transport,
/// |wo·ns| |wi·ng| / (|wo·ng| |wi·ns|) (Veach 1997 §5.3.2; PBR 3ed §16.1.3), so that light
/// tracing agrees with path tracing on surfaces with interpolated normals. The caller then
/// multiplies by the shading cosine |wi·ns|, as the camera side does.
#[inline]
pub fn shading_correction(ns: Vec3, ng: Vec3, wo: Vec3, wi: Vec3) -> f32 {
    let num = wo.dot(ns).abs() * wi.dot(ng).abs();
    let den = wo.dot(ng).abs() * wi.dot(ns).abs();
    if den == 0.0 {
        0.0
    } else {
        num / den
    }
}

/// The BSDF at a surface hit for the path's wavelengths: the one place subpaths build one.
/// `lambda` is the tuple shared by both subpaths of a sample, mutable so that a dispersive
/// material can terminate the secondary wavelengths here, for the whole path. Textures are
/// filtered per `filter` with the camera's footprint at the point, on light subpaths too
/// (as pbrt-v4's BDPT), so both subpaths see the same filtered surface. The material's
/// constant spectra come from `spectra`, which the walk has begun at `lambda`
/// ([`SpectraCache::begin`]).
#[inline]
pub fn cached_bsdf_at(
    scene: &Scene,
    si: &SurfaceHit,
    filter: TextureFilter,
    lambda: &mut SampledWavelengths,
    spectra: &mut SpectraCache,
) -> Bsdf {
    let (index, material) = material_at(scene, si, lambda);
    spectra.bsdf(material, index, scene.tex_coord(si, filter), si.ns, lambda)
}

/// [`cached_bsdf_at`] with the material's spectra sampled here (one-off BSDFs: VCM's
/// radius probe, tests).
#[inline]
pub fn bsdf_at(
    scene: &Scene,
    si: &SurfaceHit,
    filter: TextureFilter,
    lambda: &mut SampledWavelengths,
) -> Bsdf {
    let (_, material) = material_at(scene, si, lambda);
    material.bsdf(scene.tex_coord(si, filter), si.ns, lambda)
}

/// The material at `si` (its index and itself), the secondary wavelengths of `lambda`
/// terminated first if it is dispersive.
#[inline]
fn material_at<'s>(
    scene: &'s Scene,
    si: &SurfaceHit,
    lambda: &mut SampledWavelengths,
) -> (usize, &'s Material) {
    let index = si.material as usize;
    let material = &scene.materials[index];
    if scene.dispersive && material.is_dispersive() {
        lambda.terminate_secondary();
    }
    (index, material)
}

/// Area density at `p_to` (geometric normal `n_to`) of a direction density `pdf_w` at
/// `p_from`: pdf_w · |cos θ_to| / d² (PBR 4ed eq. 4.9 inverted). The walks convert
/// incrementally (`mis.rs`); this closed form checks them.
#[cfg(test)]
#[inline]
pub fn solid_angle_to_area(pdf_w: f32, p_from: Vec3, p_to: Vec3, n_to: Vec3) -> f32 {
    let d = p_to - p_from;
    let dist2 = d.length_squared();
    if dist2 == 0.0 {
        return 0.0;
    }
    pdf_w * n_to.dot(d).abs() / (dist2 * dist2.sqrt())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn correction_is_one_without_shading_normals() {
        let n = Vec3::new(0.0, 0.6, 0.8);
        let (wo, wi) = (Vec3::Z, Vec3::new(0.6, 0.0, 0.8));
        assert!((shading_correction(n, n, wo, wi) - 1.0).abs() < 1e-6);
        let ns = Vec3::new(0.0, 0.0, 1.0);
        let c = shading_correction(ns, n, wo, wi);
        let expected = (1.0 * wi.dot(n)) / (wo.dot(n) * 0.8);
        assert!((c - expected).abs() < 1e-5);
    }

    #[test]
    fn area_conversion() {
        let a = solid_angle_to_area(2.0, Vec3::ZERO, Vec3::new(0.0, 0.0, 2.0), -Vec3::Z);
        assert!((a - 2.0 / 4.0).abs() < 1e-6);
    }
}
