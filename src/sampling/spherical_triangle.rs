//! Uniform sampling of the directions from a point towards a triangle: the spherical triangle
//! the triangle subtends (Arvo 1995, "Stratified Sampling of Spherical Triangles", SIGGRAPH,
//! §2 and Figure 2's algorithm; PBR 4ed §6.5.4). The density is 1/Ω per solid angle, Ω the
//! triangle's solid angle (Van Oosterom and Strackee 1983, "The Solid Angle of a Plane
//! Triangle", IEEE Trans. Biomed. Eng. 30(2), eq. 8: tan(Ω/2) = |a·(b × c)| /
//! (1 + a·b + b·c + c·a)). [`SphericalTriangle::invert`] maps a direction back to the primary
//! sample, which a warp of the primary sample (`sampling::bilinear`) needs for its density.
//!
//! Computed in f64: the sub-triangle construction subtracts nearly equal quantities for
//! small and sliver triangles; its one atan2 (Ω) and one sincos (the rotation by u₀Ω) are f32
//! evaluations of f64 arguments (`math::angle32`: the angle within 2⁻²¹ of its magnitude),
//! which the density (f32) allows.

use crate::math::angle32;
use glam::{DVec3, Vec3};

/// The spherical triangle (a, b, c) of unit directions and what Arvo's sampling needs of it.
#[derive(Clone, Copy, Debug)]
pub struct SphericalTriangle {
    a: DVec3,
    b: DVec3,
    c: DVec3,
    /// Solid angle Ω (sr).
    pub area: f64,
    /// The interior angle α at a, as cos and sin.
    cos_alpha: f64,
    sin_alpha: f64,
    /// Unit tangent at a of the arc towards c (the arc Ĉ moves along).
    tangent_ac: DVec3,
}

/// The solid angle of the spherical triangle of unit vectors a, b, c (Van Oosterom and
/// Strackee's eq. 8).
#[inline]
pub fn solid_angle(a: DVec3, b: DVec3, c: DVec3) -> f64 {
    let num = a.dot(b.cross(c)).abs();
    let den = 1.0 + a.dot(b) + b.dot(c) + c.dot(a);
    2.0 * angle32::atan2(num, den)
}

/// The unit component of `v` orthogonal to the unit vector `a` (zero if `v` is along `a`).
#[inline]
fn tangent(a: DVec3, v: DVec3) -> DVec3 {
    (v - v.dot(a) * a).normalize_or_zero()
}

impl SphericalTriangle {
    /// The triangle `v` seen from `p`; None when a vertex coincides with `p` or the solid angle
    /// is zero or not finite.
    pub fn new(p: Vec3, v: [Vec3; 3]) -> Option<SphericalTriangle> {
        let o = p.as_dvec3();
        let [a, b, c] = v.map(|x| (x.as_dvec3() - o).normalize_or_zero());
        if a == DVec3::ZERO || b == DVec3::ZERO || c == DVec3::ZERO {
            return None;
        }
        let area = solid_angle(a, b, c);
        let (tb, tc) = (tangent(a, b), tangent(a, c));
        if !(area > 0.0 && area.is_finite()) || tb == DVec3::ZERO || tc == DVec3::ZERO {
            return None;
        }
        Some(SphericalTriangle {
            a,
            b,
            c,
            area,
            cos_alpha: tb.dot(tc).clamp(-1.0, 1.0),
            sin_alpha: tb.cross(tc).length().min(1.0),
            tangent_ac: tc,
        })
    }

    /// The vertices as unit directions (a, b, c).
    pub fn vertices(&self) -> [Vec3; 3] {
        [self.a, self.b, self.c].map(|v| v.as_vec3())
    }

    /// The direction of primary sample `u`: u₀ picks the sub-triangle (a, b, ĉ) of area u₀ Ω,
    /// ĉ on the arc from a to c; u₁ the point on the arc from b to ĉ at cos θ = 1 − u₁(1 − ĉ·b)
    /// (Arvo's eqs. for q = cos of arc aĉ and for z). Corners: u = (·, 0) → b, (0, 1) → a,
    /// (1, 1) → c.
    pub fn sample(&self, u: [f32; 2]) -> DVec3 {
        let (a, b) = (self.a, self.b);
        let area_hat = f64::from(u[0]) * self.area;
        // sin and cos of (Â − α) by the difference identities.
        let (sin_ah, cos_ah) = angle32::sin_cos(area_hat);
        let s = sin_ah * self.cos_alpha - cos_ah * self.sin_alpha;
        let t = cos_ah * self.cos_alpha + sin_ah * self.sin_alpha;
        let uu = t - self.cos_alpha;
        let vv = s + self.sin_alpha * a.dot(b);
        let den = (vv * s + uu * t) * self.sin_alpha;
        let q = if den == 0.0 {
            1.0
        } else {
            (((vv * t - uu * s) * self.cos_alpha - vv) / den).clamp(-1.0, 1.0)
        };
        let c_hat = q * a + (1.0 - q * q).max(0.0).sqrt() * self.tangent_ac;
        let z = 1.0 - f64::from(u[1]) * (1.0 - c_hat.dot(b));
        let z = z.clamp(-1.0, 1.0);
        let w = tangent(b, c_hat);
        (z * b + (1.0 - z * z).max(0.0).sqrt() * w).normalize_or_zero()
    }

    /// The primary sample that [`Self::sample`] maps to direction `w` (unit, inside the
    /// triangle): ĉ where the great circle through b and w meets the arc ac, u₀ = area(a, b, ĉ)/Ω,
    /// u₁ = (1 − w·b)/(1 − ĉ·b); clamped to [0, 1]².
    pub fn invert(&self, w: Vec3) -> [f32; 2] {
        let (a, b, c) = (self.a, self.b, self.c);
        let w = w.as_dvec3();
        let mut c_hat = b.cross(w).cross(a.cross(c)).normalize_or_zero();
        if c_hat.dot(a + c) < 0.0 {
            c_hat = -c_hat;
        }
        if c_hat == DVec3::ZERO {
            // w is b (up to rounding): u₁ = 0, where the density does not depend on u₀.
            return [0.5, 0.0];
        }
        let u0 = solid_angle(a, b, c_hat) / self.area;
        let den = 1.0 - c_hat.dot(b);
        let u1 = if den > 0.0 {
            (1.0 - w.dot(b)) / den
        } else {
            0.0
        };
        [u0.clamp(0.0, 1.0) as f32, u1.clamp(0.0, 1.0) as f32]
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::rng::Rng;

    fn random_triangle(rng: &mut Rng) -> (Vec3, [Vec3; 3]) {
        let p = rng.vec3(-1.0, 1.0);
        (
            p,
            [
                rng.vec3(-2.0, 2.0),
                rng.vec3(-2.0, 2.0),
                rng.vec3(-2.0, 2.0),
            ],
        )
    }

    /// Every sample is a unit direction that hits the triangle.
    #[test]
    fn samples_hit_the_triangle() {
        let mut rng = Rng::new(11);
        for _ in 0..200 {
            let (p, v) = random_triangle(&mut rng);
            let Some(t) = SphericalTriangle::new(p, v) else {
                continue;
            };
            let n = (v[1] - v[0]).cross(v[2] - v[0]).as_dvec3();
            for _ in 0..50 {
                let w = t.sample([rng.f32(), rng.f32()]);
                assert!((w.length() - 1.0).abs() < 1e-9);
                // Barycentrics of the ray's plane hit.
                let o = p.as_dvec3();
                let s = n.dot(v[0].as_dvec3() - o) / n.dot(w);
                assert!(s > 0.0, "behind the receiver");
                let x = o + s * w;
                let area2 = n.length();
                let (p0, p1, p2) = (v[0].as_dvec3(), v[1].as_dvec3(), v[2].as_dvec3());
                let b1 = (x - p0).cross(p2 - p0).dot(n) / (area2 * area2);
                let b2 = (p1 - p0).cross(x - p0).dot(n) / (area2 * area2);
                let tol = 1e-6;
                assert!(
                    b1 >= -tol && b2 >= -tol && b1 + b2 <= 1.0 + tol,
                    "{b1} {b2}"
                );
            }
        }
    }

    /// `invert` undoes `sample` (away from the corner b, where u₀ is not determined).
    #[test]
    fn invert_undoes_sample() {
        let mut rng = Rng::new(12);
        for _ in 0..200 {
            let (p, v) = random_triangle(&mut rng);
            let Some(t) = SphericalTriangle::new(p, v) else {
                continue;
            };
            if t.area < 1e-3 {
                continue;
            }
            for _ in 0..20 {
                let u = [rng.range(0.01, 0.99), rng.range(0.05, 0.99)];
                let back = t.invert(t.sample(u).as_vec3());
                assert!(
                    (back[0] - u[0]).abs() < 2e-3 && (back[1] - u[1]).abs() < 2e-3,
                    "{u:?} -> {back:?} (area {})",
                    t.area
                );
            }
        }
    }

    /// The solid angle of an octant's triangle (the three axes) is 4π/8, within the f32 atan2's
    /// bound (`math::angle32`, 2⁻²¹ relative).
    #[test]
    fn octant_solid_angle() {
        let t = SphericalTriangle::new(Vec3::ZERO, [Vec3::X, Vec3::Y, Vec3::Z]).unwrap();
        let exact = std::f64::consts::FRAC_PI_2;
        assert!((t.area - exact).abs() < 2f64.powi(-21) * exact);
    }
}
