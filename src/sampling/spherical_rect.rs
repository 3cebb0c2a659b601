//! Uniform sampling of the directions from a point towards a rectangle: the spherical
//! rectangle it subtends, by the area-preserving parametrisation of Ureña, Fajardo and King
//! 2013, "An Area-Preserving Parametrization for Spherical Rectangles", EGSR (§3, Algorithm 1:
//! the local frame, the four great-circle normals, the interior angles γᵢ and the solid angle
//! S = Σγᵢ − 2π; §4 the sampling of x then of y). [`SphericalRect::invert`] maps a point back
//! to its primary sample, which a warp of the primary sample (`sampling::bilinear`) needs for
//! its density: u₀ is the solid angle of the sub-rectangle [x₀, x] × [y₀, y₁] over S (the
//! paper's §4 construction read backwards), u₁ from the paper's h = y/√(d² + y²).
//!
//! Computed in f64: S is a difference of angles near π/2 for small rectangles.

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
    /// k = 2π − γ₂ − γ₃.
    k: f64,
    /// Solid angle S (sr).
    pub area: f64,
}

/// The angle between the great circles of unit normals n and m: acos(−n·m).
#[inline]
fn angle(n: DVec3, m: DVec3) -> f64 {
    (-n.dot(m)).clamp(-1.0, 1.0).acos()
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
        // Normals of the planes through o and each edge: v00×v10, v10×v11, v11×v01, v01×v00.
        let n0 = DVec3::new(0.0, z0, -y0).normalize();
        let n1 = DVec3::new(-z0, 0.0, x1).normalize();
        let n2 = DVec3::new(0.0, -z0, y1).normalize();
        let n3 = DVec3::new(z0, 0.0, -x0).normalize();
        let (g0, g1, g2, g3) = (angle(n0, n1), angle(n1, n2), angle(n2, n3), angle(n3, n0));
        let k = TAU - g2 - g3;
        let area = g0 + g1 - k;
        if !(area > 0.0 && area.is_finite()) {
            return None;
        }
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
            b0: n0.z,
            b1: n2.z,
            k,
            area,
        })
    }

    /// The point of the rectangle for primary sample `u` (Algorithm 1's sample): the
    /// sub-rectangle of solid angle u₀ S fixes x, then y is uniform in h = y/√(d² + y²).
    /// Corners: u = (0, 0) → the corner, (1, 0) → corner + e_x, (0, 1) → corner + e_y.
    pub fn sample(&self, u: [f32; 2]) -> DVec3 {
        let au = f64::from(u[0]) * self.area + self.k;
        let (sin_au, cos_au) = au.sin_cos();
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
        // The sub-rectangle [x0, xu]: its γ₀ and γ₁ with x₁ := xu (γ₂, γ₃ and k unchanged).
        let n0 = DVec3::new(0.0, self.z0, -self.y0).normalize();
        let n1 = DVec3::new(-self.z0, 0.0, xu).normalize();
        let n2 = DVec3::new(0.0, -self.z0, self.y1).normalize();
        let sub = angle(n0, n1) + angle(n1, n2) - self.k;
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
