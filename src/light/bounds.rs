//! Conservative bounds of a light's emission in space and direction, and the importance of a
//! light at a receiver that the spatial light sampler (`spatial.rs`) chooses by.
//!
//! The bounds are those of Conty Estevez and Kulla 2018, "Importance Sampling of Many Lights
//! with Adaptive Tree Splitting" (HPG; the "orientation bounds" of their §4.1), as PBR 4ed
//! §12.6.1 ("Light Bounds") writes them: an axis-aligned box holding the emitter, its power φ,
//! a cone of surface normals (axis w, half-angle θo) and the spread θe of emission beyond a
//! normal (π/2 for a surface that emits over its hemisphere). The importance at a point p
//! with normal n is their eq. (3) with the book's conservative angles:
//!
//! I(p, n) = φ · cos θ′ / d² · cos θ′ᵢ,
//!
//! with d the distance from p to the box's centre (at least the box's half diagonal, so a
//! receiver inside the box's bounding sphere does not make it infinite), θ′ = max(0, θw − θo
//! − θb) where θw is the angle between w and the direction from the centre to p and θb the
//! half-angle of the cone that bounds the box as seen from p; I = 0 where θ′ ≥ θe (p is
//! outside every direction the light emits into). θ′ᵢ = max(0, θᵢ − θb) with θᵢ the angle
//! between n and the direction to the centre (|cos|: a BSDF may transmit); the factor is 1
//! for a receiver without a normal (a point in space). Every angle is taken in cosines and
//! sines (cos(a − b) = cos a cos b + sin a sin b), without inverse trigonometric functions.
//!
//! Bounds are conservative: I > 0 wherever the light can send light to p, so a sampler that
//! never picks a light of importance 0 stays unbiased.

use super::Light;
use glam::Vec3;

/// A light's bounds (see the module's documentation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightBounds {
    pub lo: Vec3,
    pub hi: Vec3,
    /// Luminous power, lm (the power sampler's weight, `Light::luminous_power`).
    pub phi: f32,
    /// The normal cone's axis (any unit vector when θo = π).
    pub w: Vec3,
    pub cos_theta_o: f32,
    pub cos_theta_e: f32,
    /// Emits on both sides of its surface: θw is measured from ±w, whichever is nearer.
    pub two_sided: bool,
}

/// sin θ from cos θ, for θ in [0, π].
#[inline]
fn sin_of(cos: f32) -> f32 {
    (1.0 - cos * cos).max(0.0).sqrt()
}

impl LightBounds {
    /// A surface that emits over the hemisphere of normal `n` (one-sided or not), inside the
    /// box of `points`.
    fn surface(points: &[Vec3], n: Vec3, phi: f32, two_sided: bool) -> LightBounds {
        let (lo, hi) = points
            .iter()
            .fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), &p| {
                (lo.min(p), hi.max(p))
            });
        LightBounds {
            lo,
            hi,
            phi,
            w: n,
            cos_theta_o: 1.0,
            cos_theta_e: 0.0,
            two_sided,
        }
    }

    /// An emitter that may send light in every direction, inside the ball (`centre`, `r`).
    fn omni(centre: Vec3, r: f32, phi: f32) -> LightBounds {
        LightBounds {
            lo: centre - Vec3::splat(r),
            hi: centre + Vec3::splat(r),
            phi,
            w: Vec3::Z,
            cos_theta_o: -1.0,
            cos_theta_e: 0.0,
            two_sided: false,
        }
    }

    /// Bounds that hold both: the boxes' union, the powers' sum, and the normal cone about
    /// this one's axis that holds both cones (half-angle max(θo, θ(w, w′) + θo′), every
    /// direction past π); both sides if either emits on both.
    pub fn union(&self, other: &LightBounds) -> LightBounds {
        let cos_ww = self.w.dot(other.w).clamp(-1.0, 1.0);
        let sin_ww = sin_of(cos_ww);
        let (cos_o2, sin_o2) = (other.cos_theta_o, sin_of(other.cos_theta_o));
        // cos(θ(w, w′) + θo′), or −1 where the sum passes π.
        let sum_cos = cos_ww * cos_o2 - sin_ww * sin_o2;
        let sum_sin = sin_ww * cos_o2 + cos_ww * sin_o2;
        let reach = if self.cos_theta_o <= -1.0 || other.cos_theta_o <= -1.0 || sum_sin < 0.0 {
            -1.0
        } else {
            sum_cos
        };
        LightBounds {
            lo: self.lo.min(other.lo),
            hi: self.hi.max(other.hi),
            phi: self.phi + other.phi,
            w: self.w,
            cos_theta_o: self.cos_theta_o.min(reach),
            cos_theta_e: self.cos_theta_e.min(other.cos_theta_e),
            two_sided: self.two_sided || other.two_sided,
        }
    }

    /// The importance I(p, n) of the module's documentation (n = 0: no normal factor):
    /// [`Bounds4::importance`]'s, one lane.
    pub fn importance(&self, p: Vec3, n: Vec3) -> f32 {
        Bounds4::new(&[*self]).importance(p, n)[0]
    }
}

/// Four lights' bounds as lanes (structure of arrays), for the importance of four at once
/// (plain loops over the lanes, which the compiler turns into SIMD). Unused lanes have φ = 0
/// and so importance 0.
#[derive(Clone, Copy, Debug, Default)]
pub struct Bounds4 {
    centre: [[f32; 4]; 3],
    half_diagonal2: [f32; 4],
    w: [[f32; 4]; 3],
    cos_o: [f32; 4],
    sin_o: [f32; 4],
    cos_e: [f32; 4],
    phi: [f32; 4],
    two_sided: [bool; 4],
}

impl Bounds4 {
    /// Up to four bounds as lanes.
    pub fn new(bounds: &[LightBounds]) -> Bounds4 {
        let mut b = Bounds4 {
            cos_o: [1.0; 4],
            ..Bounds4::default()
        };
        for (k, lb) in bounds.iter().take(4).enumerate() {
            let c = 0.5 * (lb.lo + lb.hi);
            for a in 0..3 {
                b.centre[a][k] = c[a];
                b.w[a][k] = lb.w[a];
            }
            b.half_diagonal2[k] = 0.25 * (lb.hi - lb.lo).length_squared();
            b.cos_o[k] = lb.cos_theta_o;
            b.sin_o[k] = sin_of(lb.cos_theta_o);
            b.cos_e[k] = lb.cos_theta_e;
            b.phi[k] = lb.phi;
            b.two_sided[k] = lb.two_sided;
        }
        b
    }

    /// The four importances at `p` with normal `n` (0: none). Each lane: the cone that bounds
    /// the box from p is its bounding sphere's (every direction from inside the sphere);
    /// θ′ = max(0, θw − θo − θb) and θ′ᵢ = max(0, θᵢ − θb) in cosines and sines; importance 0
    /// where cos θ′ ≤ cos θe (or a NaN says nothing); finite, so that the sum over a scene's
    /// groups is (`spatial::MAX_GROUPS` of them).
    #[inline]
    pub fn importance(&self, p: Vec3, n: Vec3) -> [f32; 4] {
        // Lane-wise steps without branches (selects), so that each becomes one SIMD operation.
        let d = [0, 1, 2].map(|a| lanes(|k| p[a] - self.centre[a][k]));
        let l2 = lanes(|k| d[0][k] * d[0][k] + d[1][k] * d[1][k] + d[2][k] * d[2][k]);
        let hd2 = self.half_diagonal2;
        let d2 = lanes(|k| l2[k].max(hd2[k]).max(f32::MIN_POSITIVE));
        let inv_l = lanes(|k| if l2[k] > 0.0 { 1.0 / l2[k].sqrt() } else { 0.0 });
        let wi = [0, 1, 2].map(|a| lanes(|k| d[a][k] * inv_l[k]));
        let inside = lanes(|k| if l2[k] <= hd2[k] { 1.0 } else { 0.0 });
        let sin2_b = lanes(|k| if inside[k] > 0.0 { 0.0 } else { hd2[k] / l2[k] });
        let cos_b = lanes(|k| {
            if inside[k] > 0.0 {
                -1.0
            } else {
                (1.0 - sin2_b[k]).max(0.0).sqrt()
            }
        });
        let sin_b = lanes(|k| sin2_b[k].sqrt());
        let cos_w = lanes(|k| {
            let c = self.w[0][k] * wi[0][k] + self.w[1][k] * wi[1][k] + self.w[2][k] * wi[2][k];
            if self.two_sided[k] {
                c.abs()
            } else {
                c
            }
        });
        let sin_w = lanes(|k| sin_of(cos_w[k]));
        let (cos_wo, sin_wo) = minus_clamped4(cos_w, sin_w, self.cos_o, self.sin_o);
        let (cos_x, _) = minus_clamped4(cos_wo, sin_wo, cos_b, sin_b);
        let mut imp = lanes(|k| {
            if cos_x[k] > self.cos_e[k] {
                self.phi[k] * cos_x[k] / d2[k]
            } else {
                0.0
            }
        });
        if n != Vec3::ZERO {
            let cos_i = lanes(|k| (n.x * wi[0][k] + n.y * wi[1][k] + n.z * wi[2][k]).abs());
            let sin_i = lanes(|k| sin_of(cos_i[k]));
            let (cos_ii, _) = minus_clamped4(cos_i, sin_i, cos_b, sin_b);
            imp = lanes(|k| imp[k] * cos_ii[k]);
        }
        lanes(|k| {
            if imp[k] > 0.0 {
                imp[k].min(f32::MAX / 256.0)
            } else {
                0.0
            }
        })
    }
}

/// Four lanes from `f` of the lane's index.
#[inline(always)]
fn lanes(f: impl Fn(usize) -> f32) -> [f32; 4] {
    [f(0), f(1), f(2), f(3)]
}

/// (cos, sin) of max(0, a − b) from those of a and b, angles in [0, π], lane by lane.
#[inline(always)]
fn minus_clamped4(
    cos_a: [f32; 4],
    sin_a: [f32; 4],
    cos_b: [f32; 4],
    sin_b: [f32; 4],
) -> ([f32; 4], [f32; 4]) {
    let c = lanes(|k| {
        if cos_a[k] >= cos_b[k] {
            1.0
        } else {
            cos_a[k] * cos_b[k] + sin_a[k] * sin_b[k]
        }
    });
    let s = lanes(|k| {
        if cos_a[k] >= cos_b[k] {
            0.0
        } else {
            sin_a[k] * cos_b[k] - cos_a[k] * sin_b[k]
        }
    });
    (c, s)
}

impl Light {
    /// The light's bounds, or None for an infinite light (it has no place in space).
    pub fn bounds(&self) -> Option<LightBounds> {
        let phi = self.luminous_power(0.0);
        Some(match self {
            Light::Triangle(l) => LightBounds::surface(&l.p, l.n, phi, l.two_sided),
            Light::Rect(l) => {
                let c = l.corner;
                let corners = [c, c + l.edge_u, c + l.edge_v, c + l.edge_u + l.edge_v];
                LightBounds::surface(&corners, l.n, phi, false)
            }
            Light::Disk(l) => {
                let [a, b] = l.axes;
                let e = a * a + b * b;
                let extent = Vec3::new(e.x.sqrt(), e.y.sqrt(), e.z.sqrt());
                LightBounds::surface(
                    &[l.center - extent, l.center + extent],
                    l.frame.n,
                    phi,
                    false,
                )
            }
            Light::Sphere(l) => LightBounds::omni(l.center, sphere_radius(l), phi),
            Light::Point(l) => LightBounds::omni(l.sphere.center, sphere_radius(&l.sphere), phi),
            Light::Cylinder(l) => LightBounds::omni(l.center, cylinder_radius(l), phi),
            Light::Line(l) => {
                LightBounds::omni(l.cylinder.center, cylinder_radius(&l.cylinder), phi)
            }
            Light::Distant(_) | Light::Dome(_) => return None,
        })
    }
}

/// The radius of a ball that holds the sphere (or its ellipsoid: the Frobenius norm of the
/// linear map bounds its largest semi-axis).
fn sphere_radius(l: &super::SphereLight) -> f32 {
    match &l.ellipsoid {
        Some(e) => {
            let m = e.m;
            (m.x_axis.length_squared() + m.y_axis.length_squared() + m.z_axis.length_squared())
                .sqrt()
        }
        None => l.radius,
    }
}

/// The radius of a ball that holds the cylinder, caps included.
fn cylinder_radius(l: &super::CylinderLight) -> f32 {
    (0.25 * l.length * l.length + l.radius * l.radius).sqrt()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::light::{RectLight, SphereLight, TriangleLight};
    use crate::spectral::Spectrum;
    use crate::testing::rng::Rng;

    /// A random one- or two-sided triangle, rectangle or sphere light of scale `s`.
    fn light(rng: &mut Rng, kind: u32, s: f32) -> Light {
        let c = rng.vec3(-2.0 * s, 2.0 * s);
        match kind {
            0 | 1 => Light::Triangle(TriangleLight::new(
                "/T".into(),
                [
                    c + rng.vec3(-0.5 * s, 0.5 * s),
                    c + rng.vec3(-0.5 * s, 0.5 * s),
                    c + rng.vec3(-0.5 * s, 0.5 * s),
                ],
                Spectrum::Constant(1.0),
                kind == 1,
            )),
            2 => {
                let (eu, ev0) = (rng.vec3(-0.5 * s, 0.5 * s), rng.vec3(-0.5 * s, 0.5 * s));
                let ev = ev0 - eu * (ev0.dot(eu) / eu.length_squared());
                Light::Rect(RectLight::new(
                    "/R".into(),
                    c,
                    eu,
                    ev,
                    eu.cross(ev),
                    Spectrum::Constant(1.0),
                ))
            }
            _ => Light::Sphere(SphereLight {
                prim_path: "/S".into(),
                center: c,
                radius: 0.3 * s * rng.f32(),
                radiance: Spectrum::Constant(1.0),
                shaping: None,
                ellipsoid: None,
            }),
        }
    }

    /// Points of the light's surface and the normal each emits about (None: every way).
    fn surface_points(light: &Light, rng: &mut Rng) -> Vec<(Vec3, Option<(Vec3, bool)>)> {
        (0..64)
            .map(|_| {
                let (a, b) = (rng.f32(), rng.f32());
                match light {
                    Light::Triangle(t) => {
                        let (a, b) = if a + b > 1.0 {
                            (1.0 - a, 1.0 - b)
                        } else {
                            (a, b)
                        };
                        let p = t.p[0] + a * (t.p[1] - t.p[0]) + b * (t.p[2] - t.p[0]);
                        (p, Some((t.n, t.two_sided)))
                    }
                    Light::Rect(r) => (r.corner + a * r.edge_u + b * r.edge_v, Some((r.n, false))),
                    Light::Sphere(s) => (s.center + s.radius * rng.unit_vector(), None),
                    _ => unreachable!(),
                }
            })
            .collect()
    }

    /// Wherever a point of the light emits towards the receiver (and the receiver's normal is
    /// not exactly edge-on), the importance is positive: the bounds never rule out light
    /// that can arrive. Receivers near, far, on the light's plane, behind it, inside the box.
    #[test]
    fn importance_is_positive_wherever_light_can_arrive() {
        let mut rng = Rng::new(0x9e37_79b9_7f4a_7c15);
        let mut checked = 0;
        for case in 0..4000 {
            let s = [1e-3f32, 1.0, 1e3][case % 3];
            let l = light(&mut rng, (case / 3 % 4) as u32, s);
            let b = l.bounds().unwrap();
            let points = surface_points(&l, &mut rng);
            for k in 0..8 {
                let p = match k {
                    0 => points[0].0 + 1e-3 * s * rng.unit_vector(),
                    1 => b.lo + (b.hi - b.lo) * Vec3::new(rng.f32(), rng.f32(), rng.f32()),
                    _ => rng.vec3(-10.0 * s, 10.0 * s),
                };
                let n = if k % 2 == 0 {
                    Vec3::ZERO
                } else {
                    rng.unit_vector()
                };
                let imp = b.importance(p, n);
                assert!(imp.is_finite() && imp >= 0.0, "case {case}: {imp}");
                let reaches = points.iter().any(|&(y, e)| {
                    let w = p - y;
                    let emits = match e {
                        None => true,
                        Some((ln, two)) => ln.dot(w) > 0.0 || (two && ln.dot(w) < 0.0),
                    };
                    emits && (n == Vec3::ZERO || n.dot(w) != 0.0)
                });
                if reaches {
                    checked += 1;
                    assert!(
                        imp > 0.0,
                        "case {case} point {k}: light arrives, importance 0"
                    );
                }
            }
        }
        assert!(checked > 10_000, "{checked}");
    }

    #[test]
    fn importance_is_finite_and_not_negative_on_degenerate_input() {
        let b = LightBounds::omni(Vec3::ONE, 0.0, 1e30);
        for p in [
            Vec3::ONE,
            Vec3::ZERO,
            Vec3::splat(f32::NAN),
            Vec3::splat(f32::INFINITY),
        ] {
            for n in [Vec3::ZERO, Vec3::Y, Vec3::splat(f32::NAN)] {
                let imp = b.importance(p, n);
                assert!(imp.is_finite() && imp >= 0.0, "{p} {n}: {imp}");
            }
        }
    }

    /// The union's cone holds every direction of both cones.
    #[test]
    fn union_holds_both_cones() {
        let mut rng = Rng::new(7);
        for case in 0..2000 {
            let cone = |rng: &mut Rng| {
                let cos_o = if case % 5 == 0 {
                    1.0
                } else {
                    2.0 * rng.f32() - 1.0
                };
                LightBounds {
                    lo: Vec3::ZERO,
                    hi: Vec3::ONE,
                    phi: 1.0,
                    w: rng.unit_vector(),
                    cos_theta_o: cos_o,
                    cos_theta_e: 0.0,
                    two_sided: false,
                }
            };
            let (a, b) = (cone(&mut rng), cone(&mut rng));
            let u = a.union(&b);
            for c in [a, b] {
                for _ in 0..50 {
                    let d = rng.unit_vector();
                    if c.w.dot(d) >= c.cos_theta_o {
                        assert!(
                            u.w.dot(d) >= u.cos_theta_o - 1e-5,
                            "case {case}: {} < {}",
                            u.w.dot(d),
                            u.cos_theta_o
                        );
                    }
                }
            }
            assert_eq!(u.phi, 2.0);
        }
    }
}
