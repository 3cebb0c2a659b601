//! The photometric report of `spectral-render lights`: per light (by prim path) its luminous
//! flux, peak luminous intensity, luminance, illuminance (infinite lights), the chromaticity
//! and CCT of its spectrum and the spectrum's luminous efficacy — all computed from the built
//! light's spectral radiance and geometry, not from the authored numbers.
//!
//! | light | flux Φ (lm) | peak intensity (cd) | luminance (cd/m²) |
//! |---|---|---|---|
//! | rect, disk (one-sided, area A) | π A L | A L (on the normal) | L |
//! | sphere (radius r) | π · 4πr² · L | πr² L (any direction) | L |
//! | cylinder (r, ℓ; side only) | π · 2πrℓ · L | 2rℓ L (broadside) | L |
//! | mesh light (area A, sides k) | k π A L | max over directions of Σ Aᵢ L max(0, nᵢ·ω) | L |
//! | shaped (ShapingAPI) | L ∫ s_v(ω) P(ω) dω | L max s_v(ω) P(ω) | L max s_v(ω) |
//! | distant | — | — | L (none for angle 0); illuminance on a facing plane π L sin²θmax (L for angle 0) |
//! | dome | — | — | mean over the sphere; illuminance on an open upward (+Y) plane: π L if constant |
//!
//! L = K_m ∫ L(λ) ȳ(λ) dλ is the light's luminance, P(ω) its projected area towards ω and
//! s_v the luminous shaping factor (`shaping.rs`). Chromaticity, CCT and efficacy are those of
//! the emitted spectral radiance (for a shaped light with a focusTint, the on-axis spectrum;
//! for a textured dome, the sin θ-weighted mean spectrum of up to 128 × 64 of its texels); the
//! radiant flux is Φ / efficacy over 360–830 nm. Flux and intensity are not defined for
//! distant and dome lights (null in JSON).

use super::dome::{uv_to_dir, DomeLight};
use super::{DistantLight, Light, TriangleLight};
use crate::spectral::photometry::{self, SpectrumPhotometry};
use crate::spectral::DenseSpectrum;
use glam::Vec3;
use std::f32::consts::PI;

/// One light's report.
#[derive(Clone, Debug, PartialEq)]
pub struct LightReport {
    pub prim_path: String,
    /// The UsdLux type, or "MeshLight" for MeshLightAPI and emissive meshes.
    pub kind: &'static str,
    /// lm.
    pub luminous_flux: Option<f64>,
    /// cd.
    pub peak_intensity: Option<f64>,
    /// cd/m² (the largest over emission directions for a shaped light).
    pub luminance: Option<f64>,
    /// lx, for distant and dome lights (on a facing / upward plane).
    pub illuminance: Option<f64>,
    /// Emitting area in m² (world space).
    pub area: Option<f64>,
    /// W over 360–830 nm.
    pub radiant_flux: Option<f64>,
    /// Chromaticity, CCT and luminous efficacy of the emitted spectrum.
    pub spectrum: SpectrumPhotometry,
    pub shaped: bool,
    /// What a null or unusual value means for this light.
    pub note: Option<&'static str>,
}

/// The report of every light, in scene order; a mesh light's triangles form one entry.
pub fn report(lights: &[Light]) -> Vec<LightReport> {
    let mut out: Vec<LightReport> = Vec::new();
    let mut i = 0;
    while i < lights.len() {
        if let Light::Triangle(t) = &lights[i] {
            let n = lights[i..]
                .iter()
                .take_while(|l| matches!(l, Light::Triangle(u) if u.prim_path == t.prim_path))
                .count();
            let tris: Vec<&TriangleLight> = lights[i..i + n]
                .iter()
                .filter_map(|l| match l {
                    Light::Triangle(t) => Some(t),
                    _ => None,
                })
                .collect();
            out.push(mesh(&tris));
            i += n;
        } else {
            out.push(single(&lights[i]));
            i += 1;
        }
    }
    out
}

/// A finite area light: flux, peak intensity and luminance per nit, unshaped or shaped.
struct Finite {
    kind: &'static str,
    area: f32,
    flux_per_nit: f32,
    peak_per_nit: f32,
}

fn single(light: &Light) -> LightReport {
    let (finite, spectrum, shaping) = match light {
        Light::Rect(l) => (
            Finite {
                kind: "RectLight",
                area: l.area,
                flux_per_nit: PI * l.area * l.texture_mean(),
                peak_per_nit: l.area * l.texture_mean(),
            },
            &l.radiance,
            &l.shaping,
        ),
        Light::Disk(l) => (
            Finite {
                kind: "DiskLight",
                area: l.area(),
                flux_per_nit: PI * l.area(),
                peak_per_nit: l.area(),
            },
            &l.radiance,
            &l.shaping,
        ),
        Light::Sphere(l) => (
            Finite {
                kind: "SphereLight",
                area: l.area(),
                flux_per_nit: PI * l.area(),
                peak_per_nit: l
                    .ellipsoid
                    .as_ref()
                    .map_or(PI * l.radius * l.radius, |e| e.peak_projected_area()),
            },
            &l.radiance,
            &l.shaping,
        ),
        Light::Cylinder(l) => (
            Finite {
                kind: "CylinderLight",
                area: l.area(),
                flux_per_nit: PI * l.area(),
                peak_per_nit: 2.0 * l.radius * l.length,
            },
            &l.radiance,
            &l.shaping,
        ),
        Light::Distant(l) => return distant(l),
        Light::Dome(l) => return dome(l),
        // The far field of the shape they stand for: its flux and intensities, no area and no
        // luminance (nothing can see them).
        Light::Point(l) => {
            return delta_position(
                single(&Light::Sphere(l.sphere.clone())),
                "SphereLight (point)",
            )
        }
        Light::Line(l) => {
            let r = single(&Light::Cylinder(l.cylinder.clone()));
            return delta_position(r, "CylinderLight (line)");
        }
        Light::Triangle(t) => return mesh(&[t]),
    };
    let sp = photometry::summarize(&spectrum.to_dense());
    let lv = sp.luminous;
    let (flux, peak, max_factor) = match shaping {
        Some(s) => {
            let d = s.photometry;
            (d.flux_per_nit, d.peak_per_nit, d.max_factor)
        }
        None => (finite.flux_per_nit, finite.peak_per_nit, 1.0),
    };
    finite_report(
        light.prim_path(),
        finite.kind,
        finite.area,
        [flux as f64 * lv, peak as f64 * lv, max_factor as f64 * lv],
        sp,
        shaping.is_some(),
    )
}

fn delta_position(shape: LightReport, kind: &'static str) -> LightReport {
    LightReport {
        kind,
        area: None,
        luminance: None,
        ..shape
    }
}

fn finite_report(
    prim_path: &str,
    kind: &'static str,
    area: f32,
    [flux, peak, luminance]: [f64; 3],
    spectrum: SpectrumPhotometry,
    shaped: bool,
) -> LightReport {
    LightReport {
        prim_path: prim_path.to_string(),
        kind,
        luminous_flux: Some(flux),
        peak_intensity: Some(peak),
        luminance: Some(luminance),
        illuminance: None,
        area: Some(area as f64),
        radiant_flux: spectrum.efficacy.map(|eta| flux / eta),
        spectrum,
        shaped,
        note: shaped.then_some(
            "ShapingAPI: luminance is the peak over directions; the spectrum is the on-axis one",
        ),
    }
}

/// One mesh light from its triangles (all of the same prim and sidedness; GeomSubset pieces of
/// one prim may differ in radiance, so every triangle counts with its own luminance).
fn mesh(tris: &[&TriangleLight]) -> LightReport {
    let first = tris[0];
    let sides = if first.two_sided { 2.0 } else { 1.0 };
    let mut last: Option<(&crate::spectral::Spectrum, f64)> = None;
    let (mut area, mut flux, mut luminance) = (0.0f64, 0.0f64, 0.0f64);
    let mut patches = Vec::with_capacity(tris.len());
    for t in tris {
        let lv = match last {
            Some((r, lv)) if *r == t.radiance => lv,
            _ => xyz_luminance(&t.radiance),
        };
        last = Some((&t.radiance, lv));
        area += t.area as f64;
        flux += sides * std::f64::consts::PI * t.area as f64 * lv;
        luminance = luminance.max(lv);
        patches.push((t.n, (t.area as f64 * lv) as f32));
    }
    let peak = peak_projected_area(&patches, first.two_sided) as f64;
    let sp = photometry::summarize(&first.radiance.to_dense());
    finite_report(
        &first.prim_path,
        "MeshLight",
        area as f32,
        [flux, peak, luminance],
        sp,
        false,
    )
}

fn xyz_luminance(s: &crate::spectral::Spectrum) -> f64 {
    crate::spectral::xyz::luminance(&s.to_dense())
}

/// max over directions ω of Σ wᵢ max(0, nᵢ·ω) (|nᵢ·ω| when two-sided) for flat patches of unit
/// normal nᵢ and weight wᵢ (area, or area × luminance): the largest projected area (or
/// intensity). The candidates are the patches' own normals (at most 1024 distinct ones), their
/// weighted mean and up to 4096 directions of a Fibonacci sphere (fewer for meshes of more than
/// 1000 triangles, to bound the cost); exact for a planar mesh.
pub fn peak_projected_area(patches: &[(Vec3, f32)], two_sided: bool) -> f32 {
    let projected = |w: Vec3| -> f32 {
        patches
            .iter()
            .map(|(n, a)| {
                let c = n.dot(w);
                a * if two_sided { c.abs() } else { c.max(0.0) }
            })
            .sum()
    };
    let mut candidates: Vec<Vec3> = Vec::new();
    for (n, _) in patches {
        if candidates.len() >= 1024 {
            break;
        }
        if !candidates.iter().any(|c| c.dot(*n) > 0.99999) {
            candidates.push(*n);
        }
    }
    let mean: Vec3 = patches.iter().map(|(n, a)| *n * *a).sum();
    candidates.push(mean.normalize_or_zero());
    candidates.extend(fibonacci_sphere(
        (4_000_000 / patches.len().max(1)).clamp(256, 4096),
    ));
    candidates.into_iter().map(projected).fold(0.0, f32::max)
}

/// `n` nearly uniform unit directions (the spherical Fibonacci lattice).
fn fibonacci_sphere(n: usize) -> impl Iterator<Item = Vec3> {
    let golden = PI * (3.0 - 5f32.sqrt());
    (0..n).map(move |i| {
        let z = 1.0 - (2.0 * i as f32 + 1.0) / n as f32;
        let r = (1.0 - z * z).max(0.0).sqrt();
        let phi = golden * i as f32;
        Vec3::new(r * phi.cos(), r * phi.sin(), z)
    })
}

fn distant(l: &DistantLight) -> LightReport {
    let sp = photometry::summarize(&l.radiance.to_dense());
    let lv = sp.luminous;
    // A facing plane sees the cone only up to its horizon (θ ≤ π/2).
    let facing = if l.cos_theta_max < 0.0 {
        1.0
    } else {
        l.sin2_theta_max() as f64
    };
    let (luminance, illuminance) = if l.is_delta() {
        (None, lv)
    } else {
        (Some(lv), lv * std::f64::consts::PI * facing)
    };
    LightReport {
        prim_path: l.prim_path.clone(),
        kind: "DistantLight",
        luminous_flux: None,
        peak_intensity: None,
        luminance,
        illuminance: Some(illuminance),
        area: None,
        radiant_flux: None,
        spectrum: sp,
        shaped: false,
        note: Some(
            "flux and intensity are not defined for a distant light; illuminance is on a plane \
             facing it (luminance is null for angle 0, a delta light)",
        ),
    }
}

fn dome(l: &DomeLight) -> LightReport {
    let (spectrum, luminance, illuminance) = match &l.map {
        None => {
            let sp = photometry::summarize(&l.radiance.to_dense());
            (sp, sp.luminous, std::f64::consts::PI * sp.luminous)
        }
        Some(map) => textured_dome(l, map),
    };
    LightReport {
        prim_path: l.prim_path.clone(),
        kind: "DomeLight",
        luminous_flux: None,
        peak_intensity: None,
        luminance: Some(luminance),
        illuminance: Some(illuminance),
        area: None,
        radiant_flux: None,
        spectrum,
        shaped: false,
        note: Some(
            "flux and intensity are not defined for a dome light; luminance is the mean over \
             the sphere, illuminance is on an unoccluded upward-facing (+Y) plane",
        ),
    }
}

/// (spectrum summary, mean luminance, upward illuminance) of a lat-long dome: texel (x, y)
/// covers the solid angle (2π/W)(π/H) sin θ.
fn textured_dome(l: &DomeLight, map: &super::dome::LatLong) -> (SpectrumPhotometry, f64, f64) {
    let scale = crate::spectral::xyz::luminance(&l.radiance.to_dense())
        / crate::spectral::xyz::luminance(&DenseSpectrum::constant(1.0));
    let to_world = l.world_to_local.transpose();
    let (w, h) = (map.width, map.height);
    let d_omega = 2.0 * std::f64::consts::PI / w as f64 * std::f64::consts::PI / h as f64;
    let (mut lum_sum, mut weight_sum, mut e_up) = (0.0f64, 0.0f64, 0.0f64);
    for y in 0..h {
        let v = (y as f32 + 0.5) / h as f32;
        let sin_theta = (v * PI).sin() as f64;
        for x in 0..w {
            let u = (x as f32 + 0.5) / w as f32;
            let lum = map.luminance[y * w + x] as f64 * scale;
            lum_sum += lum * sin_theta;
            weight_sum += sin_theta;
            let up = (to_world * uv_to_dir([u, v])).y.max(0.0) as f64;
            e_up += lum * up * sin_theta * d_omega;
        }
    }
    // Mean spectrum of a sub-grid of texels, sin θ weighted.
    let (sx, sy) = (w.div_ceil(128).max(1), h.div_ceil(64).max(1));
    let mut acc = vec![0.0f64; crate::spectral::dense::DENSE_LEN];
    for y in (0..h).step_by(sy) {
        let sin_theta = ((y as f32 + 0.5) / h as f32 * PI).sin() as f64;
        for x in (0..w).step_by(sx) {
            let t = &map.texels[y * w + x];
            for (i, a) in acc.iter_mut().enumerate() {
                *a += sin_theta * t.eval(crate::spectral::LAMBDA_MIN + i as f32) as f64;
            }
        }
    }
    let mean = DenseSpectrum::from_fn(|lambda| {
        acc[(lambda - crate::spectral::LAMBDA_MIN) as usize] as f32
    });
    let sp = photometry::summarize(&mean);
    (sp, lum_sum / weight_sum.max(1e-300), e_up)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::light::{RectLight, SphereLight};
    use crate::spectral::{data, xyz, Spectrum};
    use std::sync::Arc;

    fn d65(nits: f32) -> Spectrum {
        let d = data::illuminant("CIE-D65").unwrap().clone();
        let lum = xyz::luminance(&d) as f32;
        Spectrum::Dense {
            data: Arc::new(d),
            scale: nits / lum,
        }
    }

    #[test]
    fn flat_and_round_lights() {
        let rect = Light::Rect(RectLight::new(
            "/R".into(),
            Vec3::ZERO,
            Vec3::X * 2.0,
            Vec3::Y * 0.5,
            Vec3::NEG_Z,
            d65(100.0),
        ));
        let sphere = Light::Sphere(SphereLight {
            ellipsoid: None,
            prim_path: "/S".into(),
            center: Vec3::ZERO,
            radius: 0.5,
            radiance: d65(10.0),
            shaping: None,
        });
        let r = report(&[rect, sphere]);
        let close = |a: f64, b: f64| (a / b - 1.0).abs() < 1e-5;
        assert!(close(
            r[0].luminous_flux.unwrap(),
            std::f64::consts::PI * 100.0
        ));
        assert!(close(r[0].peak_intensity.unwrap(), 100.0));
        assert!(close(r[0].luminance.unwrap(), 100.0));
        let pi = std::f64::consts::PI;
        assert!(close(r[1].luminous_flux.unwrap(), pi * pi * 10.0));
        assert!(close(r[1].peak_intensity.unwrap(), pi * 0.25 * 10.0));
        let cct = r[1].spectrum.cct.unwrap().kelvin;
        assert!((cct - 6504.0).abs() < 3.0, "{cct}");
        let eta = r[0].spectrum.efficacy.unwrap();
        assert!(close(
            r[0].radiant_flux.unwrap(),
            r[0].luminous_flux.unwrap() / eta
        ));
    }

    #[test]
    fn peak_projected_area_of_a_folded_sheet() {
        // Two unit patches at ±45° about Z: the peak is along Z, 2 cos 45°.
        let a = Vec3::new(1.0, 0.0, 1.0).normalize();
        let b = Vec3::new(-1.0, 0.0, 1.0).normalize();
        let p = peak_projected_area(&[(a, 1.0), (b, 1.0)], false);
        assert!((p - 2f32.sqrt()).abs() < 1e-5, "{p}");
        let flat = peak_projected_area(&[(Vec3::Y, 3.0)], true);
        assert!((flat - 3.0).abs() < 1e-6);
    }
}
