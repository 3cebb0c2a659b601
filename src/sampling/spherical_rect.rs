//! Uniform sampling of the directions from a point towards a rectangle: the spherical
//! rectangle it subtends, by the area-preserving parametrisation of Ureña, Fajardo and King
//! 2013, "An Area-Preserving Parametrization for Spherical Rectangles", EGSR (§3, Algorithm 1:
//! the local frame, the four great-circle normals, the interior angles γᵢ and the solid angle
//! S = Σγᵢ − 2π; §4 the sampling of x then of y). [`SphericalRect::invert`] maps a point back
//! to its primary sample, which a warp of the primary sample (`sampling::bilinear`) needs for
//! its density: u₀ is the solid angle of the sub-rectangle [x₀, x] × [y₀, y₁] over S (the
//! paper's §4 construction read backwards), u₁ from the paper's h = y/√(d² + y²).
//!
//! The paper's interior angles γᵢ (four acos of the dot products of adjacent great-circle
//! normals) are not taken. S is the argument of a product of four complex numbers, one atan2
//! ([`rect_solid_angle`]). Sampling needs e^{i(u₀S + k)}, k = 2π − γ₂ − γ₃: e^{iγ₂} and e^{iγ₃}
//! are in closed form from the local coordinates (the normals' dot and cross products written
//! out: cos γ₂ = x₀y₁/(r₃r₂), sin γ₂ = |z₀| |v₀₁|/(r₃r₂) with r₃ = √(x₀² + z₀²), r₂ = √(y₁² +
//! z₀²); cos γ₃ = −x₀y₀/(r₃r₀), sin γ₃ = |z₀| |v₀₀|/(r₃r₀), r₀ = √(y₀² + z₀²)), so e^{ik} is their
//! product conjugated, and only the rotation by u₀S takes a sincos. The coordinates and their
//! products are in f64 (the paper's x from the angle subtracts nearly equal quantities for
//! small rectangles); the one atan2 and the one sincos are f32 evaluations of f64 arguments
//! (`math::angle32`: the angle within 2⁻²¹ of its magnitude).

use crate::math::angle32;
use glam::{DVec3, Vec3};
use std::f64::consts::TAU;

/// A rectangle seen from a point, in the paper's local frame (x, y along the edges, z away
/// from the rectangle, which lies at z = z₀ < 0).
#[derive(Clone, Copy, Debug)]
pub struct SphericalRect {
    o: DVec3,
    x: DVec3,
    y: DVec3,
    z: DVec3,
    x0: f64,
    x1: f64,
    y0: f64,
    y1: f64,
    z0: f64,
    /// n₀.z and n₂.z of the normals of the great circles through the edges y = y₀ and y = y₁.
    b0: f64,
    b1: f64,
    /// (cos k, sin k), k = 2π − γ₂ − γ₃.
    cos_k: f64,
    sin_k: f64,
    /// Distances to the corners v₀₀, v₁₀, v₀₁, v₁₁.
    len: [f64; 4],
    /// Solid angle S (sr).
    pub area: f64,
}

/// The solid angle of the rectangle [x₀, x₁] × [y₀, y₁] in the plane z = z₀ seen from the
/// origin, given the corners' distances `l` = [l₀₀, l₁₀, l₀₁, l₁₁]: the rectangle as four signed
/// quadrants at the foot of the perpendicular, S = F(x₁, y₁) − F(x₀, y₁) − F(x₁, y₀) + F(x₀,
/// y₀), each quadrant's solid angle F(x, y) = atan(xy/(h l)) = arg(h l + i xy), h = |z₀|
/// (Ureña et al.'s S = Σγᵢ − 2π for the quadrant [0, x] × [0, y]: three of its γᵢ are π/2, the
/// fourth π/2 + atan(xy/(h l)) by the closed forms in the module's notes), summed as the
/// argument of the product of the four complex numbers (two conjugated). S ∈ (0, 2π): the
/// argument is S − 2π when negative, which only a foot inside the rectangle allows (a
/// rectangle beside the foot lies in a half-plane, S ≤ π; there all four terms are positive,
/// so the sign is exact); beside it a negative argument is rounding of S ≈ 0.
#[inline]
fn rect_solid_angle(x: [f64; 2], y: [f64; 2], z0: f64, l: [f64; 4]) -> f64 {
    let ([x0, x1], [y0, y1], h) = (x, y, z0.abs());
    let [l00, l10, l01, l11] = l;
    let mul = |(a, b): (f64, f64), (c, d): (f64, f64)| (a * c - b * d, a * d + b * c);
    let f = |x: f64, y: f64, l: f64| (h * l, x * y);
    let conj = |(a, b): (f64, f64)| (a, -b);
    let p = mul(
        mul(f(x1, y1, l11), conj(f(x0, y1, l01))),
        mul(f(x0, y0, l00), conj(f(x1, y0, l10))),
    );
    let s = angle32::atan2(p.1, p.0);
    if s >= 0.0 || s.is_nan() {
        s
    } else if x0 < 0.0 && x1 > 0.0 && y0 < 0.0 && y1 > 0.0 {
        s + TAU
    } else {
        0.0
    }
}

impl SphericalRect {
    /// The rectangle corner + [0, 1]·e_x + [0, 1]·e_y (e_x ⊥ e_y) seen from `o`; None when `o`
    /// lies in its plane or an edge is zero.
    pub fn new(o: Vec3, corner: Vec3, ex: Vec3, ey: Vec3) -> Option<SphericalRect> {
        let (ex, ey) = (ex.as_dvec3(), ey.as_dvec3());
        let (lx, ly) = (ex.length(), ey.length());
        if !(lx > 0.0 && ly > 0.0) {
            return None;
        }
        let (x, y) = (ex / lx, ey / ly);
        let mut z = x.cross(y);
        let o = o.as_dvec3();
        let d = corner.as_dvec3() - o;
        let mut z0 = d.dot(z);
        if z0 > 0.0 {
            z = -z;
            z0 = -z0;
        }
        if z0.is_nan() || z0 >= 0.0 {
            return None;
        }
        let (x0, y0) = (d.dot(x), d.dot(y));
        let (x1, y1) = (x0 + lx, y0 + ly);
        let zz = z0 * z0;
        let (xx0, xx1, yy0, yy1) = (x0 * x0, x1 * x1, y0 * y0, y1 * y1);
        let len = [xx0 + yy0, xx1 + yy0, xx0 + yy1, xx1 + yy1].map(|s| (s + zz).sqrt());
        let [l00, _, l01, _] = len;
        let area = rect_solid_angle([x0, x1], [y0, y1], z0, len);
        if !(area > 0.0 && area.is_finite()) {
            return None;
        }
        let (r0, r2, r3) = ((yy0 + zz).sqrt(), (yy1 + zz).sqrt(), (xx0 + zz).sqrt());
        // e^{iγ₂} r₃r₂ and e^{iγ₃} r₃r₀, multiplied; e^{ik} is the product's conjugate over its
        // length r₃² r₀ r₂.
        let (c2, s2) = (x0 * y1, z0.abs() * l01);
        let (c3, s3) = (-x0 * y0, z0.abs() * l00);
        let inv = 1.0 / (r3 * r3 * r0 * r2);
        Some(SphericalRect {
            o,
            x,
            y,
            z,
            x0,
            x1,
            y0,
            y1,
            z0,
            b0: -y0 / r0,
            b1: y1 / r2,
            cos_k: (c2 * c3 - s2 * s3) * inv,
            sin_k: -(c2 * s3 + s2 * c3) * inv,
            len,
            area,
        })
    }

    /// n·ω for the unit directions ω towards the corners v₀₀, v₁₀, v₀₁, v₁₁ (primary samples
    /// (0, 0), (1, 0), (0, 1), (1, 1)), from the local coordinates.
    #[inline]
    pub fn corner_cosines(&self, n: Vec3) -> [f32; 4] {
        let n = n.as_dvec3();
        let (nx, ny, nz) = (n.dot(self.x), n.dot(self.y), n.dot(self.z) * self.z0);
        let (a0, a1, b0, b1) = (nx * self.x0, nx * self.x1, ny * self.y0, ny * self.y1);
        let [l00, l10, l01, l11] = self.len;
        [
            (a0 + b0 + nz) / l00,
            (a1 + b0 + nz) / l10,
            (a0 + b1 + nz) / l01,
            (a1 + b1 + nz) / l11,
        ]
        .map(|c| c as f32)
    }

    /// The point of the rectangle for primary sample `u` (Algorithm 1's sample): the
    /// sub-rectangle of solid angle u₀ S fixes x, then y is uniform in h = y/√(d² + y²).
    /// Corners: u = (0, 0) → the corner, (1, 0) → corner + e_x, (0, 1) → corner + e_y.
    pub fn sample(&self, u: [f32; 2]) -> DVec3 {
        // e^{i au}, au = u₀S + k, as the rotation of e^{ik} by u₀S.
        let (s, c) = angle32::sin_cos(f64::from(u[0]) * self.area);
        let cos_au = c * self.cos_k - s * self.sin_k;
        let sin_au = s * self.cos_k + c * self.sin_k;
        let fu = (cos_au * self.b0 - self.b1) / sin_au;
        let cu = (fu.signum() / (fu * fu + self.b0 * self.b0).sqrt()).clamp(-1.0, 1.0);
        let xu = -(cu * self.z0) / (1.0 - cu * cu).max(0.0).sqrt();
        let xu = if xu.is_nan() {
            self.x0
        } else {
            xu.clamp(self.x0, self.x1)
        };
        let d2 = xu * xu + self.z0 * self.z0;
        let h0 = self.y0 / (d2 + self.y0 * self.y0).sqrt();
        let h1 = self.y1 / (d2 + self.y1 * self.y1).sqrt();
        let hv = h0 + f64::from(u[1]) * (h1 - h0);
        let hv2 = hv * hv;
        // Algorithm 1's guard hv² < 1 − ε against the pole of y = h d/√(1 − h²), in f64.
        let yv = if hv2 < 1.0 - 1e-12 {
            (hv * d2.sqrt() / (1.0 - hv2).sqrt()).clamp(self.y0, self.y1)
        } else {
            self.y1
        };
        self.o + xu * self.x + yv * self.y + self.z0 * self.z
    }

    /// The primary sample [`Self::sample`] maps to the point `p` of the rectangle, clamped to
    /// [0, 1]².
    pub fn invert(&self, p: Vec3) -> [f32; 2] {
        let d = p.as_dvec3() - self.o;
        let (xu, yv) = (
            d.dot(self.x).clamp(self.x0, self.x1),
            d.dot(self.y).clamp(self.y0, self.y1),
        );
        // The sub-rectangle [x0, xu]'s solid angle.
        let zz = self.z0 * self.z0;
        let (xx0, xxu, yy0, yy1) = (
            self.x0 * self.x0,
            xu * xu,
            self.y0 * self.y0,
            self.y1 * self.y1,
        );
        let l = [xx0 + yy0, xxu + yy0, xx0 + yy1, xxu + yy1].map(|s| (s + zz).sqrt());
        let sub = rect_solid_angle([self.x0, xu], [self.y0, self.y1], self.z0, l);
        let d2 = xu * xu + self.z0 * self.z0;
        let h = |y: f64| y / (d2 + y * y).sqrt();
        let (h0, h1) = (h(self.y0), h(self.y1));
        let u1 = if h1 > h0 {
            (h(yv) - h0) / (h1 - h0)
        } else {
            0.5
        };
        [
            (sub / self.area).clamp(0.0, 1.0) as f32,
            u1.clamp(0.0, 1.0) as f32,
        ]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::spherical_triangle::solid_angle;
    use crate::testing::rng::Rng;

    fn random_rect(rng: &mut Rng) -> (Vec3, Vec3, Vec3, Vec3) {
        let x = rng.unit_vector();
        let (ex, ey) = (
            x * rng.range(0.05, 2.0),
            x.any_orthonormal_vector() * rng.range(0.05, 2.0),
        );
        (rng.vec3(-1.0, 1.0), rng.vec3(-1.0, 1.0), ex, ey)
    }

    /// The solid angle is the sum of the two spherical triangles' (Van Oosterom–Strackee).
    #[test]
    fn solid_angle_is_two_triangles() {
        let mut rng = Rng::new(21);
        for _ in 0..500 {
            let (o, c, ex, ey) = random_rect(&mut rng);
            let Some(r) = SphericalRect::new(o, c, ex, ey) else {
                continue;
            };
            let v = [c, c + ex, c + ex + ey, c + ey].map(|p| (p - o).as_dvec3().normalize());
            let s = solid_angle(v[0], v[1], v[2]) + solid_angle(v[0], v[2], v[3]);
            assert!((r.area - s).abs() < 1e-6 * (1.0 + s), "{} vs {s}", r.area);
        }
    }

    /// The solid angle of a rectangle in the plane z = −h from its corners' signed terms,
    /// S = Σ ±atan(x y/(h √(x² + y² + h²))), as four f64 atan.
    fn quadrant_sum(r: &SphericalRect) -> f64 {
        let h = -r.z0;
        let f = |x: f64, y: f64| (x * y / (h * (x * x + y * y + h * h).sqrt())).atan();
        f(r.x1, r.y1) - f(r.x0, r.y1) - f(r.x1, r.y0) + f(r.x0, r.y0)
    }

    /// The closed form of S (one f32 atan2 of the complex product) against the four f64 atan on
    /// slivers (10⁻⁵:1), tiny (10⁻⁴ m edges) and huge (10⁴ m) rectangles, and receivers from
    /// 10⁻⁶ of the size above the plane to 10³ sizes away: relative error below 10⁻⁶ (the angle
    /// error bound of `math::angle32`, 2⁻²¹, and the reference's own rounding).
    #[test]
    fn closed_form_solid_angle_matches_the_quadrant_sum() {
        let mut rng = Rng::new(23);
        let mut checked = 0;
        for k in 0..20_000 {
            let size = [1.0, 1e-4, 1e4][k % 3];
            let x = rng.unit_vector();
            let (mut a, mut b) = (rng.range(0.05, 2.0), rng.range(0.05, 2.0));
            if k % 5 == 0 {
                a *= 1e-5;
            }
            let (ex, ey) = (x * a * size, x.any_orthonormal_vector() * b * size);
            b = 10f32.powf(rng.range(-6.0, 3.0));
            let c = rng.vec3(-1.0, 1.0) * size;
            let o = c + ex.cross(ey).normalize() * b * size + rng.range(-2.0, 2.0) * (ex + ey);
            let Some(r) = SphericalRect::new(o, c, ex, ey) else {
                continue;
            };
            let exact = quadrant_sum(&r);
            if exact < 1e-9 {
                continue;
            }
            assert!(
                (r.area - exact).abs() < 1e-6 * exact,
                "{k}: {} vs {exact} (z0 {}, x {} {}, y {} {})",
                r.area,
                r.z0,
                r.x0,
                r.x1,
                r.y0,
                r.y1
            );
            checked += 1;
        }
        assert!(checked > 15_000, "{checked}");
    }

    /// Samples lie on the rectangle and `invert` undoes `sample`.
    #[test]
    fn samples_lie_on_the_rectangle_and_invert() {
        let mut rng = Rng::new(22);
        for _ in 0..300 {
            let (o, c, ex, ey) = random_rect(&mut rng);
            let Some(r) = SphericalRect::new(o, c, ex, ey) else {
                continue;
            };
            for _ in 0..20 {
                let u = [rng.range(0.01, 0.99), rng.range(0.01, 0.99)];
                let p = r.sample(u);
                let q = p - c.as_dvec3();
                let a = q.dot(ex.as_dvec3()) / ex.as_dvec3().length_squared();
                let b = q.dot(ey.as_dvec3()) / ey.as_dvec3().length_squared();
                let plane = q.dot(ex.cross(ey).as_dvec3().normalize());
                assert!(a > -1e-6 && a < 1.0 + 1e-6 && b > -1e-6 && b < 1.0 + 1e-6);
                assert!(plane.abs() < 1e-6);
                let back = r.invert(p.as_vec3());
                assert!(
                    (back[0] - u[0]).abs() < 1e-3 && (back[1] - u[1]).abs() < 1e-3,
                    "{u:?} -> {back:?}"
                );
            }
        }
    }
}
