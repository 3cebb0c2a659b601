//! The ellipsoid a SphereLight becomes under a non-uniform scale or a shear: the image
//! x = c + M u of the unit sphere |u| = 1 by a linear map M (the light's transform times its
//! radius). Two samplers, both exact for any invertible M:
//!
//! - **From outside: the cone through the map.** In the sphere's own space (x' = M⁻¹(x − c))
//!   the receiver sees the unit sphere in a cone, sampled uniformly as [`super::SphereLight`]
//!   does (PBR 4ed §6.2.4); a direction ω' maps to ω = Mω'/|Mω'|. A linear map carries rays
//!   through the receiver to rays through its image, so every sample lands on the visible
//!   part of the ellipsoid, and the density follows from the Jacobian of the direction map,
//!   dω'/dω = |det M⁻¹| / |M⁻¹ω|³ (Heitz, Dupuy, Hill & Neubelt 2016, "Real-time polygonal-light
//!   shading with linearly transformed cosines", §3.1 eq. 3). For M a multiple of a rotation
//!   it reduces to the sphere's cone pdf.
//! - **By area (from inside, and for emission).** u uniform on the unit sphere (density
//!   1/(4π)) mapped by M. A surface element dA' with unit normal u maps to
//!   dA = |det M| |M⁻ᵀu| dA' with normal M⁻ᵀu/|M⁻ᵀu| (Nanson's formula, n da = J F⁻ᵀ N dA;
//!   Holzapfel, "Nonlinear Solid Mechanics", 2000, eq. 2.54), so the density per unit area at
//!   x = c + Mu is p_A(x) = 1 / (4π |det M| |M⁻ᵀu|). Not uniform, but exact: no surface area
//!   enters the pdf.
//!
//! The surface area (no closed form: elliptic integrals) is needed only for `normalize` and
//! the photometric totals; it is the integral of the same factor over the unit sphere,
//! computed once by quadrature ([`Ellipsoid::surface_area`]).

use super::{area_to_solid_angle, LightHit};
use crate::math::{Frame, INV_2PI, INV_4PI};
use crate::sampling::warp::{uniform_cone_gap, uniform_sphere};
use glam::{Mat3, Vec3};
use std::f32::consts::PI;

#[derive(Clone, Debug, PartialEq)]
pub struct Ellipsoid {
    /// The linear part: world offset from the centre = `m · u`, |u| = 1.
    pub m: Mat3,
    pub m_inv: Mat3,
    /// |det m|.
    pub det: f32,
    /// Surface area, m² (quadrature).
    pub area: f32,
}

/// A sampled direction from a receiver outside the ellipsoid.
#[derive(Clone, Copy, Debug)]
pub struct ConeSample {
    pub wi: Vec3,
    pub pdf_w: f32,
}

impl Ellipsoid {
    /// None when `m` is singular.
    pub fn new(m: Mat3) -> Option<Ellipsoid> {
        let det = m.determinant().abs();
        if !det.is_normal() {
            return None;
        }
        let m_inv = m.inverse();
        let area = Self::surface_area(&m_inv, det);
        Some(Ellipsoid {
            m,
            m_inv,
            det,
            area,
        })
    }

    /// ∫ |det M| |M⁻ᵀu| dω(u) over the unit sphere, by the midpoint rule in θ and φ in f64
    /// (the integrand is smooth and periodic in φ; the rule's error in θ is O(h²); the tests
    /// check it against the closed form of spheroids).
    fn surface_area(m_inv: &Mat3, det: f32) -> f32 {
        let (rows, cols) = (768usize, 384usize);
        let a = m_inv.as_dmat3();
        let mut sum = 0.0f64;
        for i in 0..rows {
            let theta = (i as f64 + 0.5) * std::f64::consts::PI / rows as f64;
            let (s, z) = theta.sin_cos();
            let mut ring = 0.0f64;
            for j in 0..cols {
                let phi = (j as f64 + 0.5) * std::f64::consts::TAU / cols as f64;
                let u = glam::DVec3::new(s * phi.cos(), s * phi.sin(), z);
                ring += a.transpose().mul_vec3(u).length();
            }
            sum += ring * s;
        }
        let cell = (std::f64::consts::PI / rows as f64) * (std::f64::consts::TAU / cols as f64);
        (sum * cell * f64::from(det)) as f32
    }

    /// The largest distance of a surface point from the centre (the largest singular value
    /// of M), bounded above by the Frobenius norm.
    pub fn bounding_radius(&self) -> f32 {
        (self.m.x_axis.length_squared()
            + self.m.y_axis.length_squared()
            + self.m.z_axis.length_squared())
        .sqrt()
    }

    /// Area projected along unit `w`: π |det M| |M⁻¹w| (the shadow of {|M⁻¹x| ≤ 1} on the plane
    /// ⊥ w; for M = diag(a, b, c) and w = ẑ it is πab).
    pub fn projected_area(&self, w: Vec3) -> f32 {
        PI * self.det * (self.m_inv * w).length()
    }

    /// The largest projected area, π |det M| max |M⁻¹w|: the largest eigenvalue of M⁻ᵀM⁻¹
    /// by power iteration (its Rayleigh quotient converges to the maximum even when the
    /// top eigenvalues coincide).
    pub fn peak_projected_area(&self) -> f32 {
        let b = (self.m_inv.transpose() * self.m_inv).as_dmat3();
        let mut v = glam::DVec3::new(0.577, 0.5775, 0.5771);
        for _ in 0..200 {
            v = (b * v).normalize();
        }
        (f64::from(PI * self.det) * v.dot(b * v).sqrt()) as f32
    }

    /// The outward unit normal at the image of unit `u`, and the area factor |det M| |M⁻ᵀu|.
    fn normal_and_jacobian(&self, u: Vec3) -> (Vec3, f32) {
        let g = self.m_inv.transpose() * u;
        let len = g.length();
        (g / len, self.det * len)
    }

    /// A point by area: (offset from the centre, outward normal, density per unit area).
    pub fn sample_area(&self, u: [f32; 2]) -> (Vec3, Vec3, f32) {
        let s = uniform_sphere(u);
        let (n, jac) = self.normal_and_jacobian(s);
        (self.m * s, n, INV_4PI / jac)
    }

    /// Density per unit area of [`Ellipsoid::sample_area`] at the surface point `offset`
    /// from the centre.
    pub fn pdf_area(&self, offset: Vec3) -> f32 {
        let u = (self.m_inv * offset).normalize_or_zero();
        if u == Vec3::ZERO {
            return 0.0;
        }
        INV_4PI / self.normal_and_jacobian(u).1
    }

    /// The receiver `o` (offset from the centre) in the sphere's space, and the gap 1 − cos θmax
    /// of the cone it sees the unit sphere in there; None from inside.
    fn cone(&self, o: Vec3) -> Option<(Vec3, f32)> {
        let o_unit = self.m_inv * o;
        let dist2 = o_unit.length_squared();
        if dist2 <= 1.0001 {
            return None;
        }
        let sin2_max = 1.0 / dist2;
        Some((o_unit, sin2_max / (1.0 + (1.0 - sin2_max).max(0.0).sqrt())))
    }

    /// Solid-angle density of the cone sampler from outside, given the cone's gap.
    fn cone_pdf(&self, gap: f32, wi: Vec3) -> f32 {
        let q = (self.m_inv * wi).length();
        INV_2PI / gap / (self.det * q * q * q)
    }

    /// Samples a direction from the receiver at offset `o` from the centre; None from inside.
    pub fn sample_cone(&self, o: Vec3, u: [f32; 2]) -> Option<ConeSample> {
        let (o_unit, gap) = self.cone(o)?;
        let w_unit = Frame::from_normal(-o_unit.normalize()).to_world(uniform_cone_gap(u, gap));
        let wi = (self.m * w_unit).normalize();
        let pdf_w = self.cone_pdf(gap, wi);
        pdf_w.is_finite().then_some(ConeSample { wi, pdf_w })
    }

    /// The solid-angle density with which a receiver at offset `o` (absolute position
    /// `receiver`) finds direction `wi` meeting the surface at `hit`: the cone's from
    /// outside, the area sampler's converted by eq. 4.9 from inside.
    pub fn pdf_li(&self, o: Vec3, receiver: Vec3, wi: Vec3, hit: &LightHit, center: Vec3) -> f32 {
        match self.cone(o) {
            Some((_, gap)) => self.cone_pdf(gap, wi),
            None => area_to_solid_angle(self.pdf_area(hit.p - center), receiver, hit.p, hit.n),
        }
    }

    /// True when the receiver at offset `o` is inside (the area sampler applies).
    pub fn contains(&self, o: Vec3) -> bool {
        self.cone(o).is_none()
    }

    /// Nearest hit with t in (0, t_max) of the ray o + t d (o relative to the centre): the
    /// unit-sphere test on (M⁻¹o, M⁻¹d), whose t is the world ray's (the map is linear).
    /// Returns (t, offset of the hit from the centre, outward normal).
    pub fn intersect(&self, o: Vec3, d: Vec3, t_max: f32) -> Option<(f32, Vec3, Vec3)> {
        let (f, dd) = (self.m_inv * o, self.m_inv * d);
        let a = dd.length_squared();
        let b_half = f.dot(dd);
        // Discriminant as 1 − |f − (f·d̂)d̂|² (Haines et al., Ray Tracing Gems ch. 7, eq. 10).
        let perp = f - (b_half / a) * dd;
        let disc = a * (1.0 - perp.length_squared());
        if disc < 0.0 {
            return None;
        }
        let q = -(b_half + b_half.signum() * disc.sqrt());
        let c = f.length_squared() - 1.0;
        let (mut t0, mut t1) = (c / q, q / a);
        if t0 > t1 {
            std::mem::swap(&mut t0, &mut t1);
        }
        let t = if t0 > 0.0 { t0 } else { t1 };
        if !(t > 0.0 && t < t_max) {
            return None;
        }
        let u = (f + t * dd).normalize();
        let (n, _) = self.normal_and_jacobian(u);
        Some((t, self.m * u, n))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Quat;

    fn stretched() -> Ellipsoid {
        let rot = Mat3::from_quat(Quat::from_euler(glam::EulerRot::XYZ, 0.4, -0.7, 1.1));
        Ellipsoid::new(rot * Mat3::from_diagonal(Vec3::new(0.3, 0.9, 0.15))).unwrap()
    }

    /// The quadrature area against the closed form of a spheroid (a = b = 1, c): for a prolate
    /// one 2π(1 + c·asin(e)/e), e² = 1 − 1/c² (Beyer, CRC Standard Math Tables, ellipsoid of
    /// revolution).
    #[test]
    fn surface_area_matches_the_spheroid_closed_form() {
        let c = 3.0f64;
        let e = (1.0 - 1.0 / (c * c)).sqrt();
        let exact = 2.0 * std::f64::consts::PI * (1.0 + c * e.asin() / e);
        let s = Ellipsoid::new(Mat3::from_diagonal(Vec3::new(1.0, 1.0, c as f32))).unwrap();
        assert!((f64::from(s.area) / exact - 1.0).abs() < 1e-5, "{}", s.area);
        let round = Ellipsoid::new(Mat3::from_diagonal(Vec3::splat(0.5))).unwrap();
        assert!((round.area / PI - 1.0).abs() < 1e-5);
    }

    /// Cone samples land on the surface, face the receiver, and `pdf_li` at the hit returns
    /// the sample's own density; the intersection's normal is the gradient's direction.
    #[test]
    fn cone_samples_hit_the_visible_side_with_their_own_pdf() {
        let e = stretched();
        let center = Vec3::new(0.2, 1.0, -0.3);
        let receiver = Vec3::new(1.5, -0.4, 0.6);
        let o = receiver - center;
        for i in 0..400 {
            let u = [
                ((i * 37) % 400) as f32 / 400.0 + 1e-3,
                (i as f32 + 0.5) / 400.0,
            ];
            let s = e.sample_cone(o, u).unwrap();
            let (t, off, n) = e
                .intersect(o, s.wi, f32::INFINITY)
                .expect("a cone sample misses");
            assert!(n.dot(-s.wi) > -1e-3, "back side");
            assert!(((e.m_inv * off).length() - 1.0).abs() < 1e-4);
            let hit = LightHit {
                p: center + off,
                n,
                t,
            };
            let pdf = e.pdf_li(o, receiver, s.wi, &hit, center);
            assert!((pdf / s.pdf_w - 1.0).abs() < 1e-4);
        }
    }
}
