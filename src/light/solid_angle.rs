//! The rule for sampling flat emitters (triangles, rectangles) by solid angle rather than by
//! area, and the receiver's cos θ warp of the primary sample (PBR 4ed §6.5.4, `Triangle::Sample`
//! with a reference point; Hart et al. 2020, "Practical Product Sampling by Fitting and
//! Composing Warps", EGSR, §4.1: a bilinear fit of cos θ at the sample domain's corners).
//!
//! Uniform area sampling has density d²/(A |cos θ_light|) per solid angle, which near a light
//! (a ceiling above a wall's top, a meter under a luminaire) swings by orders of magnitude over
//! the light; sampling the subtended spherical triangle or rectangle uniformly removes both
//! factors, and the bilinear warp puts the receiver's |cos θ| (at the four corners of the
//! primary-sample square, floored at 0.01 so no direction of the light has density 0) back
//! in. Between pbrt-v4's thresholds below the estimator's variance falls; outside them area
//! sampling is used: tiny solid angles gain nothing from the costlier construction and lose
//! precision, and near-hemispherical ones (a receiver almost on the light's plane) are
//! numerically fragile. Lights far from the receiver ([`NEAR_MIN`]) keep area sampling too:
//! there the construction costs more than the variance it saves.

use crate::sampling::bilinear::{bilinear_pdf, sample_bilinear};
use glam::Vec3;

/// Sample triangles and rectangles by solid angle where the thresholds allow (true), or
/// always by area (false, the rule before; kept for measurement, docs/design.md §8
/// "Solid-angle sampling of flat lights").
pub const SOLID_ANGLE_SAMPLING: bool = true;

/// Solid-angle sampling only for a light near the receiver: its area over the squared distance
/// to its centre, A/d_c² (≈ Ω for a small light seen head-on, and an upper bound's order for one
/// seen edge-on), at least this (sr). Far lights subtend a nearly uniform area-sampling density
/// and would only pay for the construction: our rule, measured in docs/design.md §8
/// "Solid-angle sampling of flat lights" (pbrt-v4 samples every light above its thresholds).
pub const NEAR_MIN: f32 = 0.1;

/// True when a flat light of area `area` and centre `centre` is near the receiver `p` in the
/// sense of [`NEAR_MIN`].
#[inline]
pub fn is_near(area: f32, centre: Vec3, p: Vec3) -> bool {
    area >= NEAR_MIN * (centre - p).length_squared()
}

/// Triangles are sampled by solid angle when Ω lies in [3·10⁻⁴, 6.22] sr (pbrt-v4's
/// `Triangle::MinSphericalSampleArea` and `MaxSphericalSampleArea`, PBR 4ed §6.5.4).
pub const TRIANGLE_MIN_SOLID_ANGLE: f64 = 3e-4;
pub const TRIANGLE_MAX_SOLID_ANGLE: f64 = 6.22;

/// Rectangles are sampled by solid angle when Ω ≥ 10⁻⁴ sr (pbrt-v4's
/// `BilinearPatch::MinSphericalSampleArea`, PBR 4ed §6.6, sampling bilinear patches); a
/// rectangle never subtends more than 2π.
pub const RECT_MIN_SOLID_ANGLE: f64 = 1e-4;

/// The floor of the cos θ weights (pbrt-v4's 0.01, PBR 4ed §6.5.4).
const MIN_WEIGHT: f32 = 0.01;

/// The bilinear weights [w(0,0), w(1,0), w(0,1), w(1,1)] of the receiver with unit normal `n`
/// for the unit directions towards the primary-sample square's corners: max(0.01, |n·ω|);
/// None for a receiver without a normal (a point in space, a luminance meter), which is not
/// warped.
#[inline]
pub fn cos_weights(n: Vec3, corners: [Vec3; 4]) -> Option<[f32; 4]> {
    if n == Vec3::ZERO {
        return None;
    }
    Some(floor_weights(corners.map(|w| n.dot(w))))
}

/// The bilinear weights max(0.01, |cos|) of the receiver's cosines towards the four corners.
#[inline]
pub fn floor_weights(cos: [f32; 4]) -> [f32; 4] {
    cos.map(|c| c.abs().max(MIN_WEIGHT))
}

/// The primary sample `u` warped by the bilinear `weights` ([`cos_weights`]) and the warp's
/// density at the warped point (PBR 4ed §2.4.2, `SampleBilinear`, `BilinearPDF`); `u` and 1
/// without weights.
#[inline]
pub fn warp(u: [f32; 2], weights: Option<[f32; 4]>) -> ([f32; 2], f32) {
    match weights {
        Some(w) => {
            let u = sample_bilinear(u, w);
            (u, bilinear_pdf(u, w))
        }
        None => (u, 1.0),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::light::{LightHit, LightLiSample, LightSampleContext, RectLight, TriangleLight};
    use crate::spectral::{SampledWavelengths, Spectrum};
    use crate::testing::rng::Rng;
    use glam::DVec3;

    #[test]
    fn no_weights_without_a_normal_and_floored_otherwise() {
        assert!(cos_weights(Vec3::ZERO, [Vec3::Z; 4]).is_none());
        let w = cos_weights(Vec3::Z, [Vec3::Z, -Vec3::Z, Vec3::X, Vec3::Y]).unwrap();
        assert_eq!(w, [1.0, 1.0, MIN_WEIGHT, MIN_WEIGHT]);
    }

    fn triangle(p: [Vec3; 3]) -> TriangleLight {
        TriangleLight::new("/t".into(), p, Spectrum::Constant(1.0), false)
    }

    fn rect() -> RectLight {
        let (eu, ev) = (Vec3::new(1.2, 0.0, 0.0), Vec3::new(0.0, 0.0, 0.6));
        RectLight::new(
            "/r".into(),
            Vec3::new(-0.6, 2.0, -0.3),
            eu,
            ev,
            Vec3::NEG_Y,
            Spectrum::Constant(1.0),
        )
    }

    fn hit(p: Vec3, n: Vec3) -> LightHit {
        LightHit { p, n, t: 1.0 }
    }

    /// Irradiance at `p` (normal `n`) from a Lambertian polygon of unit radiance: Lambert's
    /// formula E = ½ |Σᵢ Θᵢ n·Γᵢ|, Θᵢ the angle subtended by edge i and Γᵢ the unit normal of
    /// the plane through p and that edge (Arvo 1995, "Applications of Irradiance Tensors", eq. 10),
    /// for a polygon wholly above p's tangent plane.
    fn lambert(p: DVec3, n: DVec3, v: &[DVec3]) -> f64 {
        let mut sum = 0.0;
        for i in 0..v.len() {
            let (a, b) = (
                (v[i] - p).normalize(),
                (v[(i + 1) % v.len()] - p).normalize(),
            );
            sum += a.dot(b).clamp(-1.0, 1.0).acos() * n.dot(a.cross(b).normalize());
        }
        0.5 * sum.abs()
    }

    /// Mean and standard error of L cos θ / p over `count` samples of `sample`.
    fn estimate(
        count: usize,
        n: Vec3,
        mut sample: impl FnMut([f32; 2]) -> Option<(f32, Vec3, f32)>,
    ) -> (f64, f64) {
        let mut rng = Rng::new(5);
        let (mut sum, mut sum2) = (0.0f64, 0.0f64);
        for _ in 0..count {
            let x = match sample([rng.f32(), rng.f32()]) {
                Some((l, wi, pdf)) => f64::from(l * n.dot(wi).max(0.0) / pdf),
                None => 0.0,
            };
            sum += x;
            sum2 += x * x;
        }
        let mean = sum / count as f64;
        let var = (sum2 / count as f64 - mean * mean).max(0.0);
        (mean, (var / count as f64).sqrt())
    }

    /// Solid-angle sampling (warped by cos θ, and not) and area sampling both estimate Lambert's
    /// closed form within 4.5 standard errors at receivers near and far, and near the light the
    /// solid-angle estimate has the smaller variance.
    #[test]
    fn irradiance_from_a_triangle_and_a_rectangle_matches_lamberts_formula() {
        let lambda = SampledWavelengths::sample_visible(0.5);
        let tri = triangle([
            Vec3::new(-0.5, 2.0, -0.3),
            Vec3::new(0.6, 2.0, -0.4),
            Vec3::new(0.1, 2.0, 0.7),
        ]);
        let r = rect();
        let rect_corners = [
            r.corner,
            r.corner + r.edge_u,
            r.corner + r.edge_u + r.edge_v,
            r.corner + r.edge_v,
        ];
        // Receivers facing up: just below the light, at a wall's top beside it, far below.
        let receivers = [
            (Vec3::new(0.0, 1.9, 0.0), Vec3::Y),
            (
                Vec3::new(0.9, 1.7, 0.0),
                Vec3::new(-1.0, 0.2, 0.0).normalize(),
            ),
            (Vec3::new(0.2, 0.0, 0.3), Vec3::Y),
        ];
        let count = 200_000;
        for (p, n) in receivers {
            for (name, corners) in [("triangle", &tri.p[..]), ("rect", &rect_corners[..])] {
                let exact = lambert(
                    p.as_dvec3(),
                    n.as_dvec3(),
                    &corners.iter().map(|c| c.as_dvec3()).collect::<Vec<_>>(),
                );
                for normal in [n, Vec3::ZERO] {
                    let ctx = LightSampleContext { p, n: normal };
                    let solid = estimate(count, n, |u| {
                        let ls = match name {
                            "triangle" => tri.sample_li(&ctx, u, &lambda)?,
                            _ => r.sample_li(&ctx, u, &lambda)?,
                        };
                        Some((ls.l[0], ls.wi, ls.pdf_w))
                    });
                    let area = estimate(count, n, |u| {
                        let ls = match name {
                            "triangle" => tri.sample_area(&ctx, u, &lambda, None)?,
                            _ => r.sample_area(&ctx, u, &lambda)?,
                        };
                        Some((ls.l[0], ls.wi, ls.pdf_w))
                    });
                    for (label, (mean, se)) in [("solid angle", solid), ("area", area)] {
                        assert!(
                            (mean - exact).abs() < 4.5 * se + 1e-6 * exact,
                            "{name} {label} at {p} n {normal}: {mean} ± {se} vs {exact}"
                        );
                    }
                    if p.y > 1.0 && normal != Vec3::ZERO {
                        assert!(solid.1 < area.1, "{name} at {p}: {solid:?} vs {area:?}");
                    }
                }
            }
        }
    }

    /// Random receivers around slivers, tiny, huge and edge-on triangles and rectangles, on
    /// their planes, behind them, with and without normals: every sample is finite, leaves
    /// towards the light, and its pdf is what `pdf_li` says of the point it found.
    #[test]
    fn samples_are_finite_and_match_pdf_li_everywhere() {
        let lambda = SampledWavelengths::sample_visible(0.3);
        let mut rng = Rng::new(9);
        let base = [
            Vec3::new(-0.5, 0.0, -0.3),
            Vec3::new(0.6, 0.0, -0.4),
            Vec3::new(0.1, 0.0, 0.7),
        ];
        let tris = [
            triangle(base),
            triangle([base[0], base[1], base[0] + 1e-5 * (base[2] - base[0])]),
            triangle([
                base[0],
                base[1],
                base[0] + 1e-3 * (base[1] - base[0]) + Vec3::Z * 1e-7,
            ]),
            triangle(base.map(|p| p * 1e-4)),
            triangle(base.map(|p| p * 1e4)),
            triangle([base[0], base[0], base[1]]),
        ];
        let mut checked = 0;
        for _ in 0..4000 {
            let scale = 10f32.powf(rng.range(-5.0, 2.0));
            let mut p = rng.vec3(-1.0, 1.0) * scale;
            match rng.below(4) {
                0 => p.y = 0.0,
                1 => p.y = p.y.abs() * 1e-6,
                _ => {}
            }
            let n = match rng.below(3) {
                0 => Vec3::ZERO,
                _ => rng.unit_vector(),
            };
            let ctx = LightSampleContext { p, n };
            let u = [rng.f32(), rng.f32()];
            for t in &tris {
                // A caller's radiance (`sample_li_given`) changes nothing but the radiance.
                let plain = format!("{:?}", t.sample_li(&ctx, u, &lambda));
                let le = t.uniform_radiance(&lambda);
                assert_eq!(
                    format!("{:?}", t.sample_li_given(&ctx, u, &lambda, le)),
                    plain
                );
                let marked = crate::spectral::SampledSpectrum::splat(7.0);
                if let Some(m) = t.sample_li_given(&ctx, u, &lambda, Some(marked)) {
                    assert_eq!(m.l, marked);
                    let m = LightLiSample {
                        l: le.unwrap(),
                        ..m
                    };
                    assert_eq!(format!("{:?}", Some(m)), plain);
                }
                if let Some(ls) = t.sample_li(&ctx, u, &lambda) {
                    assert!(ls.pdf_w.is_finite() && ls.pdf_w > 0.0, "{p} {n}: {ls:?}");
                    assert!(ls.wi.is_finite() && ls.p_light.is_finite() && ls.l.is_finite());
                    let pdf = t.pdf_li(&ctx, ls.wi, &hit(ls.p_light, t.n));
                    assert!(pdf.is_finite() && pdf >= 0.0);
                    if t.area > 1e-6 && (ls.p_light - p).length() > 1e-3 * scale {
                        assert!(
                            (pdf / ls.pdf_w - 1.0).abs() < 2e-2,
                            "{p} {n}: {pdf} vs {ls:?}"
                        );
                        checked += 1;
                    }
                }
            }
            let mut r = rect();
            r.corner.y = 0.0;
            if let Some(ls) = r.sample_li(&ctx, u, &lambda) {
                assert!(ls.pdf_w.is_finite() && ls.pdf_w > 0.0, "{p} {n}: {ls:?}");
                assert!(ls.wi.is_finite() && ls.p_light.is_finite() && ls.l.is_finite());
                let pdf = r.pdf_li(&ctx, ls.wi, &hit(ls.p_light, r.n));
                assert!(pdf.is_finite() && pdf >= 0.0);
                if (ls.p_light - p).length() > 1e-3 * scale {
                    assert!(
                        (pdf / ls.pdf_w - 1.0).abs() < 2e-2,
                        "{p} {n}: {pdf} vs {ls:?}"
                    );
                }
            }
        }
        assert!(checked > 1000, "{checked}");
    }

    /// The solid-angle density integrates to 1 over the sphere of directions: 4π p(ω) for
    /// uniform ω (p = 0 where ω misses the light) has mean 1, within 4.5 standard errors.
    #[test]
    fn solid_angle_density_integrates_to_one() {
        let tri = triangle([
            Vec3::new(-0.5, 0.3, -0.3),
            Vec3::new(0.6, 0.3, -0.4),
            Vec3::new(0.1, 0.3, 0.7),
        ]);
        let r = rect();
        let mut rng = Rng::new(13);
        for (ctx, which) in [
            (
                LightSampleContext {
                    p: Vec3::ZERO,
                    n: Vec3::Y,
                },
                0,
            ),
            (
                LightSampleContext {
                    p: Vec3::ZERO,
                    n: Vec3::ZERO,
                },
                0,
            ),
            (
                LightSampleContext {
                    p: Vec3::new(0.2, 1.6, 0.1),
                    n: Vec3::new(0.3, 0.2, 0.9).normalize(),
                },
                1,
            ),
            (
                LightSampleContext {
                    p: Vec3::new(0.2, 1.6, 0.1),
                    n: Vec3::ZERO,
                },
                1,
            ),
        ] {
            let n = 400_000;
            let (mut sum, mut sum2) = (0.0f64, 0.0f64);
            for _ in 0..n {
                let w = crate::sampling::warp::uniform_sphere([rng.f32(), rng.f32()]);
                let h = if which == 0 {
                    // The triangle's plane y = 0.3.
                    let t = 0.3 / w.y;
                    let q = ctx.p + t * w;
                    let b = tri_contains(&tri, q);
                    (t > 0.0 && b).then(|| tri.pdf_li(&ctx, w, &hit(q, tri.n)))
                } else {
                    r.intersect(ctx.p, w, f32::INFINITY)
                        .map(|h| r.pdf_li(&ctx, w, &h))
                };
                let x = f64::from(h.unwrap_or(0.0)) * 4.0 * std::f64::consts::PI;
                sum += x;
                sum2 += x * x;
            }
            let mean = sum / n as f64;
            let se = ((sum2 / n as f64 - mean * mean) / n as f64).sqrt();
            assert!((mean - 1.0).abs() < 4.5 * se, "{ctx:?}: {mean} ± {se}");
        }
    }

    fn tri_contains(t: &TriangleLight, q: Vec3) -> bool {
        let [a, b, c] = t.p.map(|v| v.as_dvec3());
        let q: DVec3 = q.as_dvec3();
        let n = (b - a).cross(c - a);
        [(a, b), (b, c), (c, a)]
            .iter()
            .all(|&(x, y)| (y - x).cross(q - x).dot(n) >= 0.0)
    }
}
