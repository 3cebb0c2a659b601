//! Fresnel equations and Snell's law (PBR 4ed §9.3).
//!
//! - [`fr_dielectric`]: unpolarised reflectance of a dielectric interface, PBR 4ed eq. 9.4–9.6,
//!   with the relative IOR inverted when light arrives from inside (cos θi < 0).
//! - [`fr_complex`]: the same equations with a complex index η + ik for conductors
//!   (PBR 4ed §9.3.6, `FrComplex`); at normal incidence it reduces to
//!   ((n−1)² + k²) / ((n+1)² + k²).
//! - [`schlick`]: Schlick's approximation F0 + (1 − F0)(1 − cos θ)⁵ (Schlick 1994), used only
//!   by the UsdPreviewSurface mapping, whose specification is written in terms of F0.
//! - [`refract`]: Snell's law in vector form, PBR 4ed eq. 9.19, returning the relative IOR
//!   η' = ηt/ηi of the crossing actually made.
//! - [`diffuse_fresnel`]: the hemispherical average F_dr(η) = ∫ F(μ) 2μ dμ (the diffuse
//!   Fresnel reflectance of d'Eon & Irving 2011 §5.2, here by quadrature rather than a fit).

use crate::math::safe_sqrt;
use crate::spectral::SampledSpectrum;
use glam::Vec3;

/// Unpolarised Fresnel reflectance at a dielectric interface. `cos_theta_i` is measured
/// against the normal on the side of the incident medium; a negative value means the light
/// arrives from inside and η is inverted. `eta` = η_inside / η_outside. Returns 1 under
/// total internal reflection.
#[inline]
pub fn fr_dielectric(cos_theta_i: f32, eta: f32) -> f32 {
    let mut cos_i = cos_theta_i.clamp(-1.0, 1.0);
    let mut eta = eta;
    if cos_i < 0.0 {
        eta = 1.0 / eta;
        cos_i = -cos_i;
    }
    let sin2_i = 1.0 - cos_i * cos_i;
    let sin2_t = sin2_i / (eta * eta);
    if sin2_t >= 1.0 {
        return 1.0;
    }
    let cos_t = safe_sqrt(1.0 - sin2_t);
    let r_parl = (eta * cos_i - cos_t) / (eta * cos_i + cos_t);
    let r_perp = (cos_i - eta * cos_t) / (cos_i + eta * cos_t);
    0.5 * (r_parl * r_parl + r_perp * r_perp)
}

/// A complex number, just enough for the conductor Fresnel equations.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Complex {
    re: f32,
    im: f32,
}

impl Complex {
    fn new(re: f32, im: f32) -> Complex {
        Complex { re, im }
    }

    fn add(self, o: Complex) -> Complex {
        Complex::new(self.re + o.re, self.im + o.im)
    }

    fn sub(self, o: Complex) -> Complex {
        Complex::new(self.re - o.re, self.im - o.im)
    }

    fn mul(self, o: Complex) -> Complex {
        Complex::new(
            self.re * o.re - self.im * o.im,
            self.re * o.im + self.im * o.re,
        )
    }

    fn scale(self, s: f32) -> Complex {
        Complex::new(self.re * s, self.im * s)
    }

    fn norm(self) -> f32 {
        self.re * self.re + self.im * self.im
    }

    fn div(self, o: Complex) -> Complex {
        let d = o.norm();
        Complex::new(
            (self.re * o.re + self.im * o.im) / d,
            (self.im * o.re - self.re * o.im) / d,
        )
    }

    /// Principal square root (PBR 4ed §B.2.8 `pstd::sqrt` for complex numbers).
    fn sqrt(self) -> Complex {
        let n = self.re.hypot(self.im);
        if n == 0.0 {
            return Complex::new(0.0, 0.0);
        }
        let t1 = (0.5 * (n + self.re.abs())).sqrt();
        let t2 = 0.5 * self.im / t1;
        if self.re >= 0.0 {
            Complex::new(t1, t2)
        } else {
            Complex::new(t2.abs(), t1.copysign(self.im))
        }
    }
}

/// Fresnel reflectance of a conductor with complex index `eta + i k` relative to the outside
/// medium, for light at `cos_theta_i` ∈ [0, 1] (PBR 4ed §9.3.6).
#[inline]
pub fn fr_complex(cos_theta_i: f32, eta: f32, k: f32) -> f32 {
    let cos_i = cos_theta_i.clamp(0.0, 1.0);
    let eta = Complex::new(eta, k);
    let sin2_i = 1.0 - cos_i * cos_i;
    let sin2_t = Complex::new(sin2_i, 0.0).div(eta.mul(eta));
    let cos_t = Complex::new(1.0, 0.0).sub(sin2_t).sqrt();
    let ci = Complex::new(cos_i, 0.0);
    let r_parl = eta.scale(cos_i).sub(cos_t).div(eta.scale(cos_i).add(cos_t));
    let r_perp = ci.sub(eta.mul(cos_t)).div(ci.add(eta.mul(cos_t)));
    0.5 * (r_parl.norm() + r_perp.norm())
}

/// [`fr_complex`] per wavelength.
#[inline]
pub fn fr_complex_spectrum(
    cos_theta_i: f32,
    eta: SampledSpectrum,
    k: SampledSpectrum,
) -> SampledSpectrum {
    SampledSpectrum::from_fn(|i| fr_complex(cos_theta_i, eta[i], k[i]))
}

/// Schlick's approximation with F90 = 1, per wavelength.
#[inline]
pub fn schlick(cos_theta: f32, f0: SampledSpectrum) -> SampledSpectrum {
    let m = (1.0 - cos_theta.abs().min(1.0)).max(0.0);
    let m5 = (m * m) * (m * m) * m;
    f0 + (SampledSpectrum::ONE - f0) * m5
}

/// [`schlick`] for one wavelength.
#[inline]
pub fn schlick1(cos_theta: f32, f0: f32) -> f32 {
    schlick(cos_theta, SampledSpectrum::splat(f0))[0]
}

/// Refracts `wi` (pointing away from the surface) through the interface with normal `n`
/// and relative IOR `eta` = η_inside/η_outside, `n` pointing outside. Returns the transmitted
/// direction (pointing away on the other side) and the relative IOR η' = ηt/ηi of this
/// crossing, or `None` under total internal reflection (PBR 4ed eq. 9.19, `Refract`).
#[inline]
pub fn refract(wi: Vec3, n: Vec3, eta: f32) -> Option<(Vec3, f32)> {
    let mut cos_i = n.dot(wi);
    let (mut eta, mut n) = (eta, n);
    if cos_i < 0.0 {
        eta = 1.0 / eta;
        cos_i = -cos_i;
        n = -n;
    }
    let sin2_i = (1.0 - cos_i * cos_i).max(0.0);
    let sin2_t = sin2_i / (eta * eta);
    if sin2_t >= 1.0 {
        return None;
    }
    let cos_t = safe_sqrt(1.0 - sin2_t);
    let wt = -wi / eta + (cos_i / eta - cos_t) * n;
    Some((wt, eta))
}

/// F_dr(η) = ∫₀¹ F(μ, η) 2μ dμ, the reflectance of the interface under uniform diffuse
/// illumination from the side where the relative IOR is `eta` (composite Simpson rule in
/// f64, split at the critical angle when η < 1; accurate to ~1e-6).
pub fn diffuse_fresnel(eta: f32) -> f32 {
    let f = |mu: f64| fr_dielectric(mu as f32, eta) as f64 * 2.0 * mu;
    let critical = if eta < 1.0 {
        (1.0 - (eta as f64).powi(2)).max(0.0).sqrt()
    } else {
        0.0
    };
    // Below the critical cosine F = 1 exactly: that part integrates to μc².
    (critical * critical + simpson(f, critical, 1.0, 4096)) as f32
}

/// Composite Simpson rule with `n` (even) intervals.
pub(crate) fn simpson(f: impl Fn(f64) -> f64, a: f64, b: f64, n: usize) -> f64 {
    let h = (b - a) / n as f64;
    let mut sum = f(a) + f(b);
    for i in 1..n {
        let w = if i % 2 == 1 { 4.0 } else { 2.0 };
        sum += w * f(a + i as f64 * h);
    }
    sum * h / 3.0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn dielectric_normal_incidence_and_tir() {
        let r0 = ((1.5f32 - 1.0) / 2.5).powi(2);
        assert!((fr_dielectric(1.0, 1.5) - r0).abs() < 1e-6);
        assert!((fr_dielectric(-1.0, 1.5) - r0).abs() < 1e-6);
        // From inside glass beyond the critical angle asin(1/1.5) = 41.8°.
        assert_eq!(fr_dielectric(-50f32.to_radians().cos(), 1.5), 1.0);
        assert!(fr_dielectric(-40f32.to_radians().cos(), 1.5) < 1.0);
        assert!(fr_dielectric(0.3, 1.0) < 1e-10);
        assert!((fr_dielectric(0.0, 1.5) - 1.0).abs() < 1e-6);
    }

    #[test]
    fn complex_fresnel_reduces_to_the_dielectric_one_and_the_normal_formula() {
        for cos in [0.05f32, 0.3, 0.7, 1.0] {
            assert!((fr_complex(cos, 1.5, 0.0) - fr_dielectric(cos, 1.5)).abs() < 1e-5);
        }
        let (n, k) = (0.2f32, 3.5f32);
        let expected = ((n - 1.0).powi(2) + k * k) / ((n + 1.0).powi(2) + k * k);
        assert!((fr_complex(1.0, n, k) - expected).abs() < 1e-6);
        assert!((fr_complex(0.0, n, k) - 1.0).abs() < 1e-5);
    }

    #[test]
    fn refraction_obeys_snell_and_reverses() {
        let n = Vec3::Z;
        let wi = Vec3::new(0.6, 0.0, 0.8);
        let (wt, etap) = refract(wi, n, 1.5).unwrap();
        assert_eq!(etap, 1.5);
        assert!((wt.length() - 1.0).abs() < 1e-6 && wt.z < 0.0);
        assert!((0.6 - 1.5 * wt.x.abs()).abs() < 1e-6);
        let (back, etap2) = refract(wt, n, 1.5).unwrap();
        assert!((back - wi).length() < 1e-5 && (etap2 - 1.0 / 1.5).abs() < 1e-7);
        assert!(refract(Vec3::new(0.8, 0.0, -0.6), n, 1.5).is_none());
    }

    #[test]
    fn diffuse_fresnel_obeys_the_transmittance_relation() {
        // η² (1 − F_dr(1/η)) = 1 − F_dr(η) (energy through an interface under diffuse light).
        for eta in [1.1f32, 1.33, 1.5, 2.4] {
            let ext = diffuse_fresnel(eta);
            let int = diffuse_fresnel(1.0 / eta);
            assert!(
                (eta * eta * (1.0 - int) - (1.0 - ext)).abs() < 2e-5,
                "{eta}"
            );
        }
        // d'Eon & Irving's fit gives F_dr(1.5) ≈ 0.0918 (external).
        assert!((diffuse_fresnel(1.5) - 0.0918).abs() < 5e-4);
    }
}
