//! Emission sampling for light subpaths: [`Light::sample_le`] draws a point on a light and a
//! direction leaving it, [`Light::pdf_le`] gives the densities of any such pair (PBR 4ed
//! §12.1, `Light::SampleLe` / `PDF_Le`; Veach 1997 §8.3.1 for light-path starts).
//!
//! Conventions: `pdf_pos_a` is per unit area of the light (for infinite lights: of the disk
//! through which their rays enter the scene), `pdf_dir_w` per unit solid angle (1 for a delta
//! direction). Finite lights emit cosine-weighted about their normal (two-sided mesh lights
//! pick a side with probability ½); the radiance comes from [`Light::l`], so a directional
//! profile added to a light later is honoured without touching this file. Distant and dome
//! lights sample a direction as their `sample_li` does and a point on the disk of the
//! scene's bounding sphere perpendicular to it, pdf 1/(πR²) (PBR 4ed §12.4.1, §12.5.1).

use super::{Light, LightHit, LightSampleContext, LineLight, PointLight};
use crate::geometry::offset::gamma;
use crate::math::Frame;
use crate::math::INV_4PI;
use crate::sampling::warp::{
    concentric_disk, cosine_hemisphere, cosine_hemisphere_pdf, uniform_sphere, uniform_triangle,
};
use crate::spectral::{SampledSpectrum, SampledWavelengths};
use glam::Vec3;
use std::f32::consts::PI;

/// A sphere bounding everything light paths can reach (triangles and light shapes).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SceneSphere {
    pub center: Vec3,
    pub radius: f32,
}

impl SceneSphere {
    /// The sphere (`center`, `radius`) bounding the scene's triangles grown to contain the
    /// analytic light shapes among `lights` too (1 % to spare).
    pub fn enclosing<'a>(
        center: Vec3,
        radius: f32,
        lights: impl IntoIterator<Item = &'a Light>,
    ) -> SceneSphere {
        let mut r = radius;
        for light in lights {
            let (c, e) = match light {
                Light::Rect(l) => (l.corner, l.edge_u.length() + l.edge_v.length()),
                Light::Disk(l) => (l.center, l.radius),
                Light::Sphere(l) => (l.center, l.radius),
                Light::Cylinder(l) => (l.center, l.radius + 0.5 * l.length),
                Light::Point(l) => (l.p(), 0.0),
                Light::Line(l) => (l.cylinder.center, 0.5 * l.length()),
                _ => continue,
            };
            r = r.max((c - center).length() + e);
        }
        SceneSphere {
            center,
            radius: r * 1.01,
        }
    }

    /// Area of the disk through which infinite lights enter the scene.
    pub fn disk_area(&self) -> f32 {
        PI * self.radius * self.radius
    }
}

/// A ray leaving a light, with the radiance it carries and its sampling densities.
#[derive(Clone, Copy, Debug)]
pub struct LightLeSample {
    /// Origin on the light (for infinite lights: on the disk outside the scene).
    pub p: Vec3,
    /// Absolute error bound of `p`, for spawning the ray.
    pub p_error: Vec3,
    /// Geometric normal at `p` on the emitting side (the direction itself for infinite lights).
    pub n: Vec3,
    /// Unit direction of travel.
    pub w: Vec3,
    /// Radiance carried along the ray (a delta distant light: its irradiance).
    pub l: SampledSpectrum,
    pub pdf_pos_a: f32,
    pub pdf_dir_w: f32,
    /// The direction distribution is a Dirac delta (distant light of zero angle).
    pub delta_dir: bool,
    /// The position is a delta (point light) or a delta across a line (line light).
    pub delta_pos: bool,
    pub infinite: bool,
}

impl LightLeSample {
    /// |cos θ| at the light between its normal and the ray; 1 for infinite lights, whose
    /// positional density is already per area perpendicular to the ray.
    #[inline]
    pub fn cos_light(&self) -> f32 {
        if self.infinite {
            1.0
        } else {
            self.n.dot(self.w).abs()
        }
    }
}

/// Densities returned by [`Light::pdf_le`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LePdf {
    pub pos_a: f32,
    pub dir_w: f32,
}

impl Light {
    /// True for lights whose emission is a Dirac delta (a distant light of zero angle, a point
    /// or a line light): no ray can hit them, and their densities are relative to the delta.
    pub fn is_delta(&self) -> bool {
        matches!(self, Light::Point(_) | Light::Line(_))
            || matches!(self, Light::Distant(d) if d.is_delta())
    }

    /// True for lights whose position is a delta (point, line): no ray can hit them, and
    /// their rays leave from a point with no surface.
    pub fn is_delta_position(&self) -> bool {
        matches!(self, Light::Point(_) | Light::Line(_))
    }

    /// A delta light's next-event density relative to its delta: 1, or 1/ℓ per unit length
    /// for a line light (its `sample_li` picks the point along the segment).
    pub fn delta_pdf(&self) -> f32 {
        match self {
            Light::Line(l) => 1.0 / l.length(),
            _ => 1.0,
        }
    }

    /// Samples an emitted ray: `u_pos` picks the point, `u_dir` the direction.
    pub fn sample_le(
        &self,
        u_pos: [f32; 2],
        u_dir: [f32; 2],
        sphere: &SceneSphere,
        lambda: &SampledWavelengths,
    ) -> Option<LightLeSample> {
        match self {
            Light::Triangle(t) => {
                let b = uniform_triangle(u_pos);
                let p = b[0] * t.p[0] + b[1] * t.p[1] + b[2] * t.p[2];
                let err =
                    gamma(6) * (b[0] * t.p[0].abs() + b[1] * t.p[1].abs() + b[2] * t.p[2].abs());
                self.emit_cosine(p, err, t.n, t.area, t.two_sided, u_dir, lambda)
            }
            Light::Rect(r) => {
                let p = r.corner + u_pos[0] * r.edge_u + u_pos[1] * r.edge_v;
                self.emit_cosine(p, gamma(6) * p.abs(), r.n, r.area, false, u_dir, lambda)
            }
            Light::Disk(d) => {
                let p = d.point(concentric_disk(u_pos));
                self.emit_cosine(
                    p,
                    gamma(6) * p.abs(),
                    d.frame.n,
                    d.area(),
                    false,
                    u_dir,
                    lambda,
                )
            }
            Light::Sphere(s) => {
                let (p, n, pdf_a) = s.sample_area(u_pos);
                let err = gamma(5) * (s.center.abs() + (p - s.center).abs());
                self.emit_cosine(p, err, n, 1.0 / pdf_a, false, u_dir, lambda)
            }
            Light::Cylinder(c) => {
                let (p, n) = c.point_on_side(u_pos);
                let err = gamma(5)
                    * (c.center.abs() + (c.radius * n).abs() + (0.5 * c.length * c.frame.n).abs());
                self.emit_cosine(p, err, n, c.area(), false, u_dir, lambda)
            }
            Light::Distant(_) | Light::Dome(_) => self.emit_infinite(u_pos, u_dir, sphere, lambda),
            Light::Point(l) => self.emit_uniform(l.p(), 1.0, u_dir, lambda),
            Light::Line(l) => {
                let p = l.point(u_pos[0]);
                self.emit_uniform(p, 1.0 / l.length(), u_dir, lambda)
            }
        }
    }

    /// Densities with which [`Light::sample_le`] produces the point `p` (geometric normal `n`)
    /// and the direction `w` leaving it; for infinite lights `p` and `n` are ignored and `w`
    /// is the direction of travel. Every light's points are uniform over its area (a
    /// textured emitter's too: only its radiance varies) except an ellipsoidal sphere light's,
    /// whose density depends on `p`. A delta direction has density 1 relative to its delta,
    /// as in `sample_li`.
    pub fn pdf_le(&self, p: Vec3, n: Vec3, w: Vec3, sphere: &SceneSphere) -> LePdf {
        let cosine = |area: f32, two_sided: bool| {
            let c = n.dot(w);
            let dir_w = if two_sided {
                0.5 * cosine_hemisphere_pdf(c.abs())
            } else {
                cosine_hemisphere_pdf(c)
            };
            LePdf {
                pos_a: if area > 0.0 { 1.0 / area } else { 0.0 },
                dir_w,
            }
        };
        match self {
            Light::Triangle(t) => cosine(t.area, t.two_sided),
            Light::Rect(r) => cosine(r.area, false),
            Light::Disk(d) => cosine(d.area(), false),
            Light::Sphere(s) => cosine(1.0 / s.pdf_area(p), false),
            Light::Cylinder(c) => cosine(c.area(), false),
            Light::Distant(d) => LePdf {
                pos_a: 1.0 / sphere.disk_area(),
                dir_w: if d.is_delta() { 1.0 } else { d.pdf_li(-w) },
            },
            Light::Dome(d) => LePdf {
                pos_a: 1.0 / sphere.disk_area(),
                // Emission samples the dome as `sample_li` does from the sphere's centre.
                dir_w: d.pdf_li(sphere.center, -w),
            },
            Light::Point(_) => LePdf {
                pos_a: 1.0,
                dir_w: PointLight::DIR_PDF,
            },
            Light::Line(l) => LePdf {
                pos_a: 1.0 / l.length(),
                dir_w: LineLight::DIR_PDF,
            },
        }
    }

    /// A point already chosen on a flat or spherical emitter with normal `n`, and a
    /// cosine-weighted direction about it (PBR 4ed §12.5.1, DiffuseAreaLight::SampleLe).
    /// `area` is the reciprocal of the point's density per unit area (the emitter's area
    /// when points are uniform).
    #[allow(clippy::too_many_arguments)]
    fn emit_cosine(
        &self,
        p: Vec3,
        p_error: Vec3,
        n: Vec3,
        area: f32,
        two_sided: bool,
        u_dir: [f32; 2],
        lambda: &SampledWavelengths,
    ) -> Option<LightLeSample> {
        if area <= 0.0 || n == Vec3::ZERO {
            return None;
        }
        let (n, u, side_pdf) = if two_sided {
            if u_dir[0] < 0.5 {
                (n, [u_dir[0] * 2.0, u_dir[1]], 0.5)
            } else {
                (-n, [(u_dir[0] - 0.5) * 2.0, u_dir[1]], 0.5)
            }
        } else {
            (n, u_dir, 1.0)
        };
        let w_local = cosine_hemisphere(u);
        let w = Frame::from_normal(n).to_world(w_local);
        let pdf_dir_w = side_pdf * cosine_hemisphere_pdf(w_local.z);
        if pdf_dir_w <= 0.0 {
            return None;
        }
        let hit = LightHit { p, n, t: 0.0 };
        Some(LightLeSample {
            p,
            p_error,
            n,
            w,
            l: self.l(&hit, w, lambda),
            pdf_pos_a: 1.0 / area,
            pdf_dir_w,
            delta_dir: false,
            delta_pos: false,
            infinite: false,
        })
    }

    /// Point and line lights: the point already chosen (density `pdf_pos`: 1 relative to a
    /// point's delta, 1/ℓ along a line) and a uniform direction (PBR 4ed §12.1,
    /// PointLight::SampleLe). The normal is set to the direction, so `cos_light` is 1: the
    /// carried quantity is an intensity, with no projected-area cosine.
    fn emit_uniform(
        &self,
        p: Vec3,
        pdf_pos: f32,
        u_dir: [f32; 2],
        lambda: &SampledWavelengths,
    ) -> Option<LightLeSample> {
        if !(pdf_pos > 0.0 && pdf_pos.is_finite()) {
            return None;
        }
        let w = uniform_sphere(u_dir);
        let hit = LightHit { p, n: w, t: 0.0 };
        Some(LightLeSample {
            p,
            p_error: gamma(5) * p.abs(),
            n: w,
            w,
            l: self.l(&hit, w, lambda),
            pdf_pos_a: pdf_pos,
            pdf_dir_w: INV_4PI,
            delta_dir: false,
            delta_pos: true,
            infinite: false,
        })
    }

    /// Distant and dome lights: a direction as `sample_li` draws it (reversed), then a point on
    /// the scene disk perpendicular to it (PBR 4ed §12.4.1, DistantLight::SampleLe).
    fn emit_infinite(
        &self,
        u_pos: [f32; 2],
        u_dir: [f32; 2],
        sphere: &SceneSphere,
        lambda: &SampledWavelengths,
    ) -> Option<LightLeSample> {
        let ctx = LightSampleContext {
            p: sphere.center,
            n: Vec3::ZERO,
        };
        let li = self.sample_li(&ctx, u_dir, lambda)?;
        if li.pdf_w <= 0.0 || li.l.is_black() {
            return None;
        }
        let w = -li.wi;
        let frame = Frame::from_normal(w);
        let q = concentric_disk(u_pos) * sphere.radius;
        let p = sphere.center + sphere.radius * li.wi + q.x * frame.s + q.y * frame.t;
        Some(LightLeSample {
            p,
            p_error: Vec3::ZERO,
            n: w,
            w,
            l: li.l,
            pdf_pos_a: 1.0 / sphere.disk_area(),
            pdf_dir_w: li.pdf_w,
            delta_dir: li.delta,
            delta_pos: false,
            infinite: true,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::light::ellipsoid::Ellipsoid;
    use crate::light::{DiskLight, RectLight, SphereLight, TriangleLight};
    use crate::sampling::Sampler;
    use crate::spectral::Spectrum;

    fn lights() -> Vec<Light> {
        let white = Spectrum::Constant(1.0);
        vec![
            Light::Triangle(TriangleLight::new(
                "/t".into(),
                [Vec3::ZERO, Vec3::X, Vec3::Y],
                white.clone(),
                true,
            )),
            Light::Rect(RectLight::new(
                "/r".into(),
                Vec3::ONE,
                Vec3::X,
                Vec3::Z * 2.0,
                -Vec3::Y,
                white.clone(),
            )),
            Light::Disk(DiskLight::round(
                "/d".into(),
                Vec3::ZERO,
                Frame::from_normal(Vec3::new(0.0, 0.6, 0.8)),
                0.3,
                white.clone(),
            )),
            Light::Disk(DiskLight {
                axes: [Vec3::new(0.5, 0.1, 0.0), Vec3::new(0.2, 0.0, 0.1)],
                ..DiskLight::round(
                    "/ellipse".into(),
                    Vec3::ONE,
                    // ∝ a × b, the ellipse's plane normal.
                    Frame::from_normal(Vec3::new(0.01, -0.05, -0.02).normalize()),
                    0.3,
                    white.clone(),
                )
            }),
            Light::Sphere(SphereLight {
                prim_path: "/s".into(),
                center: Vec3::splat(0.5),
                radius: 0.2,
                radiance: white.clone(),
                shaping: None,
                ellipsoid: None,
            }),
            Light::Sphere(SphereLight {
                prim_path: "/e".into(),
                center: Vec3::splat(-0.5),
                radius: 0.6,
                radiance: white,
                shaping: None,
                ellipsoid: Ellipsoid::new(glam::Mat3::from_cols(
                    Vec3::new(0.3, 0.1, 0.0),
                    Vec3::new(0.0, 0.5, 0.2),
                    Vec3::new(0.1, 0.0, 0.15),
                ))
                .map(Box::new),
            }),
        ]
    }

    #[test]
    fn pdf_le_matches_sample_le() {
        let sphere = SceneSphere {
            center: Vec3::ZERO,
            radius: 3.0,
        };
        let lambda = SampledWavelengths::sample_visible(0.3);
        let mut s = Sampler::new(1, 2, 3);
        for light in lights() {
            for _ in 0..200 {
                let Some(le) = light.sample_le(s.get_2d(), s.get_2d(), &sphere, &lambda) else {
                    continue;
                };
                let pdf = light.pdf_le(le.p, le.n, le.w, &sphere);
                assert!((pdf.pos_a / le.pdf_pos_a - 1.0).abs() < 1e-4);
                assert!((pdf.dir_w / le.pdf_dir_w - 1.0).abs() < 1e-3, "{light:?}");
                assert!(le.n.dot(le.w) > 0.0 && !le.l.is_black());
            }
        }
    }

    #[test]
    fn emitted_power_is_pi_area_radiance() {
        // E[L cos / (pdf_pos pdf_dir)] = π A L per emitting side (PBR 4ed §4.1.2).
        let sphere = SceneSphere {
            center: Vec3::ZERO,
            radius: 3.0,
        };
        let lambda = SampledWavelengths::sample_visible(0.3);
        let mut s = Sampler::new(4, 5, 6);
        for light in lights() {
            let n = 4000;
            let (mut sum, mut sum2) = (0.0f64, 0.0f64);
            for _ in 0..n {
                if let Some(le) = light.sample_le(s.get_2d(), s.get_2d(), &sphere, &lambda) {
                    let v = (le.l[0] * le.cos_light() / (le.pdf_pos_a * le.pdf_dir_w)) as f64;
                    sum += v;
                    sum2 += v * v;
                }
            }
            let (area, sides) = match &light {
                Light::Triangle(t) => (t.area, 2.0),
                Light::Rect(r) => (r.area, 1.0),
                Light::Disk(d) => (d.area(), 1.0),
                Light::Sphere(s) => (s.area(), 1.0),
                _ => unreachable!(),
            };
            let expected = (PI * area * sides) as f64;
            // Uniform points make every term equal (rounding only); an ellipsoid's points are
            // not uniform, so its mean gets 5 standard errors of the terms' spread on top.
            let mean = sum / n as f64;
            let sem = ((sum2 / n as f64 - mean * mean).max(0.0) / n as f64).sqrt();
            assert!(
                (mean - expected).abs() < 1e-4 * expected + 5.0 * sem,
                "{light:?}: {mean} vs {expected}"
            );
        }
    }
}
