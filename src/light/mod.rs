//! Lights. Every light's emitted spectral radiance is in W·m⁻²·sr⁻¹·nm⁻¹, set from the UsdLux
//! inputs exactly as docs/design.md §2 says (see `emission.rs`). One kind per file, dispatched
//! through the closed [`Light`] enum.
//!
//! Area-like lights (rect, disk, sphere, cylinder) are analytic shapes: visible to camera and
//! BSDF rays, opaque to shadow rays, and they do not reflect. Mesh lights are triangles of real
//! geometry (in the BVH) that also carry their material. UsdLux ShapingAPI (`shaping.rs`, with
//! IES profiles from `ies.rs`) scales the radiance of the analytic area lights per direction.
//! `report.rs` computes the photometric report of `spectral-render lights`.

pub mod bounds;
pub mod cylinder;
pub mod disk;
pub mod distant;
pub mod dome;
pub mod ellipsoid;
pub mod emission;
pub mod emission_layers;
pub mod emit;
pub mod ies;
pub mod line;
pub mod point;
pub mod portal;
pub mod power_share;
pub mod radiance_class;
pub mod rect;
pub mod report;
pub mod sampler;
pub mod shaping;
pub mod solid_angle;
pub mod spatial;
pub mod sphere;
pub mod tree;
pub mod triangle;

use crate::spectral::{SampledSpectrum, SampledWavelengths};
use glam::Vec3;

pub use bounds::LightBounds;
pub use cylinder::CylinderLight;
pub use disk::DiskLight;
pub use distant::DistantLight;
pub use dome::DomeLight;
pub use line::LineLight;
pub use point::PointLight;
pub use rect::RectLight;
pub use sampler::LightSampler;
pub use sphere::SphereLight;
pub use triangle::{EmissiveTexture, TriangleLight};

/// The receiving point of a light sample.
#[derive(Clone, Copy, Debug)]
pub struct LightSampleContext {
    pub p: Vec3,
    /// Geometric normal at `p`, or zero for a point in space (e.g. a meter).
    pub n: Vec3,
}

/// A sampled direction towards a light with the radiance arriving along it.
#[derive(Clone, Copy, Debug)]
pub struct LightLiSample {
    pub l: SampledSpectrum,
    /// Unit direction from the receiver towards the light.
    pub wi: Vec3,
    /// Solid-angle pdf at the receiver (for a delta light: 1, with `delta` set).
    pub pdf_w: f32,
    /// The sampled point on the light (for infinite lights a point far outside the scene).
    pub p_light: Vec3,
    /// Geometric normal at `p_light` (zero for infinite lights).
    pub n_light: Vec3,
    pub delta: bool,
    pub infinite: bool,
}

/// Where a ray met an area light: point, geometric normal, direction of the incoming ray.
#[derive(Clone, Copy, Debug)]
pub struct LightHit {
    pub p: Vec3,
    pub n: Vec3,
    /// Distance from the ray origin.
    pub t: f32,
}

#[derive(Clone, Debug)]
pub enum Light {
    Triangle(TriangleLight),
    Rect(RectLight),
    Disk(DiskLight),
    Sphere(SphereLight),
    Cylinder(CylinderLight),
    Distant(DistantLight),
    Dome(DomeLight),
    /// A SphereLight with `treatAsPoint`: a delta in position.
    Point(PointLight),
    /// A CylinderLight with `treatAsLine`: a delta across its axis.
    Line(LineLight),
}

impl Light {
    /// Samples incident radiance at `ctx` (PBR 4ed §12.2).
    #[inline]
    pub fn sample_li(
        &self,
        ctx: &LightSampleContext,
        u: [f32; 2],
        lambda: &SampledWavelengths,
    ) -> Option<LightLiSample> {
        match self {
            Light::Triangle(l) => l.sample_li(ctx, u, lambda),
            Light::Rect(l) => l.sample_li(ctx, u, lambda),
            Light::Disk(l) => l.sample_li(ctx, u, lambda),
            Light::Sphere(l) => l.sample_li(ctx, u, lambda),
            Light::Cylinder(l) => l.sample_li(ctx, u, lambda),
            Light::Distant(l) => l.sample_li(ctx, u, lambda),
            Light::Dome(l) => l.sample_li(ctx, u, lambda),
            Light::Point(l) => l.sample_li(ctx, lambda),
            Light::Line(l) => l.sample_li(ctx, u, lambda),
        }
    }

    /// The radiance the light emits at every point and towards every direction it emits in, at
    /// `lambda`, when that is one spectrum (an untextured triangle); None otherwise. What
    /// [`Self::sample_li_given`] takes.
    #[inline]
    pub fn uniform_radiance(&self, lambda: &SampledWavelengths) -> Option<SampledSpectrum> {
        match self {
            Light::Triangle(l) => l.uniform_radiance(lambda),
            _ => None,
        }
    }

    /// [`Self::sample_li`] given `le`, the light's [`Self::uniform_radiance`] at `lambda` (or
    /// None): a caller that keeps it per wavelength tuple spares its evaluation per sample,
    /// with the same result bit for bit.
    #[inline]
    pub fn sample_li_given(
        &self,
        ctx: &LightSampleContext,
        u: [f32; 2],
        lambda: &SampledWavelengths,
        le: Option<SampledSpectrum>,
    ) -> Option<LightLiSample> {
        match (self, le) {
            (Light::Triangle(l), le) => l.sample_li_given(ctx, u, lambda, le),
            _ => self.sample_li(ctx, u, lambda),
        }
    }

    /// Solid-angle pdf with which `sample_li` from `ctx` would produce direction `wi` hitting
    /// the light at `hit` (ignored for infinite lights).
    #[inline]
    pub fn pdf_li(&self, ctx: &LightSampleContext, wi: Vec3, hit: &LightHit) -> f32 {
        match self {
            Light::Triangle(l) => l.pdf_li(ctx, wi, hit),
            Light::Rect(l) => l.pdf_li(ctx, wi, hit),
            Light::Disk(l) => l.pdf_li(ctx, wi, hit),
            Light::Sphere(l) => l.pdf_li(ctx, wi, hit),
            Light::Cylinder(l) => l.pdf_li(ctx, wi, hit),
            Light::Distant(l) => l.pdf_li(wi),
            Light::Dome(l) => l.pdf_li(ctx.p, wi),
            // No direction finds a delta light (its density relative to the delta: `delta_pdf`).
            Light::Point(_) | Light::Line(_) => 0.0,
        }
    }

    /// Radiance leaving an area light at `hit` towards `w` (pointing away from the light); for
    /// a point light its intensity, for a line light its intensity per unit length (no ray
    /// hits them: this is what their emitted rays carry).
    #[inline]
    pub fn l(&self, hit: &LightHit, w: Vec3, lambda: &SampledWavelengths) -> SampledSpectrum {
        match self {
            Light::Triangle(l) => l.l(hit, w, lambda),
            Light::Rect(l) => l.l(hit.p, w, lambda),
            Light::Disk(l) => l.l(hit.n, w, lambda),
            Light::Sphere(l) => l.l(w, lambda),
            Light::Cylinder(l) => l.l(hit.n, w, lambda),
            Light::Point(l) => l.intensity(w, lambda),
            Light::Line(l) => l.intensity(w, lambda),
            Light::Distant(_) | Light::Dome(_) => SampledSpectrum::ZERO,
        }
    }

    /// Radiance arriving along an escaped ray of direction `d` (infinite lights only).
    #[inline]
    pub fn le(&self, d: Vec3, lambda: &SampledWavelengths) -> SampledSpectrum {
        match self {
            Light::Distant(l) => l.le(d, lambda),
            Light::Dome(l) => l.le(d, lambda),
            _ => SampledSpectrum::ZERO,
        }
    }

    /// Ray–shape intersection for analytic lights, t in (0, t_max).
    #[inline]
    pub fn intersect(&self, o: Vec3, d: Vec3, t_max: f32) -> Option<LightHit> {
        match self {
            Light::Rect(l) => l.intersect(o, d, t_max),
            Light::Disk(l) => l.intersect(o, d, t_max),
            Light::Sphere(l) => l.intersect(o, d, t_max),
            Light::Cylinder(l) => l.intersect(o, d, t_max),
            _ => None,
        }
    }

    pub fn is_infinite(&self) -> bool {
        matches!(self, Light::Distant(_) | Light::Dome(_))
    }

    pub fn is_analytic_shape(&self) -> bool {
        matches!(
            self,
            Light::Rect(_) | Light::Disk(_) | Light::Sphere(_) | Light::Cylinder(_)
        )
    }

    /// Luminous flux in lm, the light sampler's weight (PBR 4ed §12.6.1 uses power);
    /// infinite lights use the scene's bounding sphere of radius `scene_radius`.
    pub fn luminous_power(&self, scene_radius: f32) -> f32 {
        match self {
            Light::Triangle(l) => l.luminous_power(),
            Light::Rect(l) => l.luminous_power(),
            Light::Disk(l) => l.luminous_power(),
            Light::Sphere(l) => l.luminous_power(),
            Light::Cylinder(l) => l.luminous_power(),
            Light::Distant(l) => l.luminous_power(scene_radius),
            Light::Dome(l) => l.luminous_power(scene_radius),
            Light::Point(l) => l.luminous_power(),
            Light::Line(l) => l.luminous_power(),
        }
    }

    /// The USD prim this light came from.
    pub fn prim_path(&self) -> &str {
        match self {
            Light::Triangle(l) => &l.prim_path,
            Light::Rect(l) => &l.prim_path,
            Light::Disk(l) => &l.prim_path,
            Light::Sphere(l) => &l.prim_path,
            Light::Cylinder(l) => &l.prim_path,
            Light::Distant(l) => &l.prim_path,
            Light::Dome(l) => &l.prim_path,
            Light::Point(l) => &l.sphere.prim_path,
            Light::Line(l) => &l.cylinder.prim_path,
        }
    }
}

/// Converts an area-measure pdf at a light point into solid angle at the receiver:
/// p_w = p_a · d² / |cos θ_light| (PBR 4ed §4.2.3, eq. 4.9).
#[inline]
pub fn area_to_solid_angle(pdf_a: f32, receiver: Vec3, p_light: Vec3, n_light: Vec3) -> f32 {
    let d = p_light - receiver;
    let dist2 = d.length_squared();
    let cos_l = n_light.dot(d).abs() / dist2.sqrt();
    if cos_l == 0.0 || dist2 == 0.0 {
        return 0.0;
    }
    pdf_a * dist2 / cos_l
}

/// The common tail of sampling a point `p` (normal `n`) of an emitter of area `area` uniformly
/// by area: the direction from the receiver, the facing test, and the area pdf converted to
/// solid angle (eq. 4.9). `radiance(w)` is the radiance leaving `p` towards `w`. Always
/// inlined: left to the heuristics, the triangle light's next-event sample (`sample_area`)
/// took it as a call after an unrelated change, 28 instructions more a light sample
/// (design.md §8, session 41).
#[inline(always)]
pub fn sample_by_area(
    ctx: &LightSampleContext,
    p: Vec3,
    n: Vec3,
    area: f32,
    two_sided: bool,
    radiance: impl FnOnce(Vec3) -> SampledSpectrum,
) -> Option<LightLiSample> {
    let wi = (p - ctx.p).normalize_or_zero();
    if wi == Vec3::ZERO || area <= 0.0 || !emits_towards(n, -wi, two_sided) {
        return None;
    }
    let pdf_w = area_to_solid_angle(1.0 / area, ctx.p, p, n);
    if pdf_w == 0.0 || !pdf_w.is_finite() {
        return None;
    }
    Some(LightLiSample {
        l: radiance(-wi),
        wi,
        pdf_w,
        p_light: p,
        n_light: n,
        delta: false,
        infinite: false,
    })
}

/// One-sided (or two-sided) emission test for a flat emitter with normal `n`.
#[inline]
pub fn emits_towards(n: Vec3, w: Vec3, two_sided: bool) -> bool {
    two_sided || n.dot(w) > 0.0
}
