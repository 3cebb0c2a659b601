//! The Trowbridge–Reitz (GGX) microfacet distribution (PBR 4ed §9.6) with Smith's
//! height-correlated masking–shadowing (G below; PBR 4ed §9.6.3) and visible-normal sampling
//! (Heitz 2018, "Sampling the GGX Distribution of Visible Normals", JCGT 7(4)).
//!
//! All directions are in the local shading frame (normal +Z). Formulas:
//! - D(ωm) = 1 / (π αx αy cos⁴θm (1 + tan²θm (cos²φm/αx² + sin²φm/αy²))²)  (PBR 4ed eq. 9.16)
//! - Λ(ω) = (√(1 + α² tan²θ) − 1) / 2 with α² = (αx cosφ)² + (αy sinφ)²  (eq. 9.20)
//! - G1 = 1/(1 + Λ(ω)), G(ωo, ωi) = 1/(1 + Λ(ωo) + Λ(ωi))  (eq. 9.18, 9.26)
//! - visible normals D_ω(ωm) = G1(ω)/|cos θ| · D(ωm) · max(0, ω·ωm)  (eq. 9.23)
//!
//! For an isotropic distribution (αx = αy = α) φ drops out (cos²φ + sin²φ = 1), and the
//! reflection pair has closed forms without the half vector's normalisation or any tangent
//! (the same functions, rearranged; they differ from the general forms by float round-off):
//! - D(ωm) = α² / (π (α² cos²θm + sin²θm)²), and with h = ωo + ωi unnormalised,
//!   cos²θm = h_z²/|h|², so D = α²/π · (|h|² / (h_x² + h_y² + α² h_z²))²  (eq. 9.16);
//! - 1 + 2Λ(ω) = √(1 + α² tan²θ) = s(ω)/|cos θ| with s(ω) = √(cos²θ + α² sin²θ) (eq. 9.20), so
//!   G/(4 |cos θo| |cos θi|) = 1 / (2 (|cos θi| s(ωo) + |cos θo| s(ωi)))  (eq. 9.26, 9.33;
//!   the "visibility" form of the Smith term used by real-time renderers),
//!   and the reflection pdf G1(ωo) D / (4 |cos θo|) = D / (2 (|cos θo| + s(ωo)))  (eq. 9.28:
//!   ωo·ωm cancels).

use crate::math::safe_sqrt;
use glam::{Vec2, Vec3};
use std::f32::consts::PI;

/// Below this α the distribution is treated as a perfect mirror (pbrt's `EffectivelySmooth`):
/// D then spans more than the f32 range and the delta lobe is both exact and NaN-free.
pub const SMOOTH_ALPHA: f32 = 1e-3;

#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TrowbridgeReitz {
    pub alpha_x: f32,
    pub alpha_y: f32,
}

#[inline]
fn cos2_theta(w: Vec3) -> f32 {
    w.z * w.z
}

#[inline]
fn sin2_theta(w: Vec3) -> f32 {
    (1.0 - cos2_theta(w)).max(0.0)
}

/// (cos φ, sin φ) of a direction; (1, 0) at the pole.
#[inline]
fn cos_sin_phi(w: Vec3) -> (f32, f32) {
    let s = sin2_theta(w).sqrt();
    if s == 0.0 {
        (1.0, 0.0)
    } else {
        ((w.x / s).clamp(-1.0, 1.0), (w.y / s).clamp(-1.0, 1.0))
    }
}

impl TrowbridgeReitz {
    pub fn new(alpha_x: f32, alpha_y: f32) -> TrowbridgeReitz {
        TrowbridgeReitz { alpha_x, alpha_y }
    }

    pub fn isotropic(alpha: f32) -> TrowbridgeReitz {
        TrowbridgeReitz::new(alpha, alpha)
    }

    /// αx = αy: D and Λ do not depend on φ.
    #[inline]
    pub fn is_isotropic(&self) -> bool {
        self.alpha_x == self.alpha_y
    }

    #[inline]
    pub fn effectively_smooth(&self) -> bool {
        self.alpha_x.max(self.alpha_y) < SMOOTH_ALPHA
    }

    /// The distribution of microfacet normals (per unit solid angle of ωm, projected: ∫ D cos = 1).
    #[inline]
    pub fn d(&self, wm: Vec3) -> f32 {
        let cos2 = cos2_theta(wm);
        let cos4 = cos2 * cos2;
        if cos4 < 1e-16 {
            return 0.0;
        }
        let tan2 = sin2_theta(wm) / cos2;
        let e = if self.is_isotropic() {
            tan2 / (self.alpha_x * self.alpha_x)
        } else {
            let (c, s) = cos_sin_phi(wm);
            tan2 * ((c / self.alpha_x).powi(2) + (s / self.alpha_y).powi(2))
        };
        1.0 / (PI * self.alpha_x * self.alpha_y * cos4 * (1.0 + e) * (1.0 + e))
    }

    /// Smith's auxiliary function Λ(ω).
    #[inline]
    pub fn lambda(&self, w: Vec3) -> f32 {
        let cos2 = cos2_theta(w);
        if cos2 == 0.0 {
            return f32::INFINITY;
        }
        let tan2 = sin2_theta(w) / cos2;
        let alpha2 = if self.is_isotropic() {
            self.alpha_x * self.alpha_x
        } else {
            let (c, s) = cos_sin_phi(w);
            (c * self.alpha_x).powi(2) + (s * self.alpha_y).powi(2)
        };
        0.5 * ((1.0 + alpha2 * tan2).sqrt() - 1.0)
    }

    #[inline]
    pub fn g1(&self, w: Vec3) -> f32 {
        1.0 / (1.0 + self.lambda(w))
    }

    #[inline]
    pub fn g(&self, wo: Vec3, wi: Vec3) -> f32 {
        1.0 / (1.0 + self.lambda(wo) + self.lambda(wi))
    }

    /// The distribution of normals visible from `w`.
    #[inline]
    pub fn d_visible(&self, w: Vec3, wm: Vec3) -> f32 {
        let cos = w.z.abs();
        if cos == 0.0 {
            return 0.0;
        }
        self.g1(w) / cos * self.d(wm) * w.dot(wm).abs()
    }

    /// pdf of [`Self::sample_wm`] per unit solid angle of ωm.
    #[inline]
    pub fn pdf(&self, w: Vec3, wm: Vec3) -> f32 {
        self.d_visible(w, wm)
    }

    /// Samples a visible normal from `w` (Heitz 2018, listing 1, with pbrt's polar disk
    /// warp): stretch to the hemisphere configuration, sample the projected area of the
    /// hemisphere, unstretch. For `w` below the surface the normal is visible from −`w`.
    #[inline]
    pub fn sample_wm(&self, w: Vec3, u: [f32; 2]) -> Vec3 {
        let mut wh = Vec3::new(self.alpha_x * w.x, self.alpha_y * w.y, w.z).normalize();
        if wh.z < 0.0 {
            wh = -wh;
        }
        let t1 = if wh.z < 0.99999 {
            Vec3::Z.cross(wh).normalize()
        } else {
            Vec3::X
        };
        let t2 = wh.cross(t1);
        let mut p = uniform_disk_polar(u);
        let h = safe_sqrt(1.0 - p.x * p.x);
        let s = 0.5 * (1.0 + wh.z);
        p.y = (1.0 - s) * h + s * p.y;
        let pz = safe_sqrt(1.0 - p.length_squared());
        let nh = p.x * t1 + p.y * t2 + pz * wh;
        Vec3::new(self.alpha_x * nh.x, self.alpha_y * nh.y, nh.z.max(1e-6)).normalize()
    }
}

/// A reflection pair (ωo, ωi) evaluated at once: [`TrowbridgeReitz::reflection_eval_pair`].
#[derive(Clone, Copy, Debug)]
pub struct ReflectionPair {
    /// The half vector (ωo + ωi) / |ωo + ωi| and D G / (4 |cos θo| |cos θi|).
    pub wm: Vec3,
    pub dg: f32,
    /// The reflection pdfs of ωi from ωo and of ωo from ωi.
    pub pdf_fwd: f32,
    pub pdf_rev: f32,
}

/// Microfacet reflection shared by the conductor and the coats (PBR 4ed §9.6.5): the half
/// vector ωm = (ωo + ωi)/|ωo + ωi| (eq. 9.32), f = D(ωm) G(ωo, ωi) F / (4 |cos θo| |cos θi|)
/// (eq. 9.33), and the pdf of ωi = reflect(ωo, ωm) with ωm from the visible normals,
/// D_ωo(ωm) / (4 |ωo·ωm|) (eq. 9.28). Every function accepts ωo on either side.
impl TrowbridgeReitz {
    /// (ωm, D G / (4 |cos θo| |cos θi|)), or `None` when ωi is not a reflection of ωo.
    /// The pair's terms ([`Self::reflection_eval_pair`]; once inlined, the pdfs are dropped).
    #[inline]
    pub fn reflection_eval(&self, wo: Vec3, wi: Vec3) -> Option<(Vec3, f32)> {
        let r = self.reflection_eval_pair(wo, wi)?;
        Some((r.wm, r.dg))
    }

    /// [`Self::reflection_eval`] of (ωo, ωi) with [`Self::reflection_pdf`] of (ωo, ωi) and of
    /// (ωi, ωo), bit for bit, sharing D(ωm) and Λ(ωo), Λ(ωi) (what a vertex merge needs,
    /// `BsdfEval`); `None` where `reflection_eval` has none (both pdfs are then 0).
    #[inline(always)]
    pub fn reflection_eval_pair(&self, wo: Vec3, wi: Vec3) -> Option<ReflectionPair> {
        if wo.z * wi.z <= 0.0 {
            return None;
        }
        self.reflection_eval_pair_at(wo, self.wo_term(wo), wi)
    }

    /// What [`Self::reflection_eval_pair_at`] takes of ωo alone: s(ωo) of an isotropic
    /// distribution (the module header), unused (0) for an anisotropic one. A vertex that
    /// evaluates several pairs from one ωo (next event estimation, then BSDF sampling)
    /// computes it once.
    #[inline]
    pub fn wo_term(&self, wo: Vec3) -> f32 {
        if self.is_isotropic() {
            self.smith_root(wo)
        } else {
            0.0
        }
    }

    /// [`Self::reflection_eval_pair`] given `s_o` = [`Self::wo_term`] of `wo`: the same
    /// operations, so the same bits.
    #[inline(always)]
    pub fn reflection_eval_pair_at(&self, wo: Vec3, s_o: f32, wi: Vec3) -> Option<ReflectionPair> {
        if wo.z * wi.z <= 0.0 {
            return None;
        }
        if self.is_isotropic() {
            self.isotropic_pair(wo, wi, s_o)
        } else {
            self.anisotropic_pair(wo, wi)
        }
    }

    /// [`Self::reflection_eval_pair`] by the general formulas (out of line: the isotropic
    /// closed forms, inlined, are what the callers run nearly always).
    #[inline(never)]
    fn anisotropic_pair(&self, wo: Vec3, wi: Vec3) -> Option<ReflectionPair> {
        let wm = (wo + wi).try_normalize()?;
        let (cos_o, cos_i) = (wo.z.abs(), wi.z.abs());
        let d = self.d(wm);
        let (lambda_o, lambda_i) = (self.lambda(wo), self.lambda(wi));
        let dg = d * (1.0 / (1.0 + lambda_o + lambda_i)) / (4.0 * cos_o * cos_i);
        // The pdfs take the normal on ωo's side, as `reflection_pdf` does.
        let (wm_p, d_p) = if wm.z < 0.0 {
            (-wm, self.d(-wm))
        } else {
            (wm, d)
        };
        let pdf = |w: Vec3, lambda: f32| {
            let dot = w.dot(wm_p).abs();
            (1.0 / (1.0 + lambda)) / w.z.abs() * d_p * dot / (4.0 * dot)
        };
        Some(ReflectionPair {
            wm,
            dg,
            pdf_fwd: pdf(wo, lambda_o),
            pdf_rev: pdf(wi, lambda_i),
        })
    }

    /// The isotropic [`Self::reflection_eval_pair`] by the closed forms of the module's
    /// header, given s(ωo) = `s_o`: a square root for s(ωi), one for the Fresnel's ωo·ωm, no
    /// tangent.
    #[inline(always)]
    fn isotropic_pair(&self, wo: Vec3, wi: Vec3, s_o: f32) -> Option<ReflectionPair> {
        let h = wo + wi;
        let (rho2, hz2) = (h.x * h.x + h.y * h.y, h.z * h.z);
        let len2 = rho2 + hz2;
        if !(len2 > 0.0 && len2.is_finite()) {
            return None;
        }
        let wm = h * (1.0 / len2.sqrt());
        let a2 = self.alpha_x * self.alpha_x;
        // cos⁴θm < 10⁻¹⁶: D = 0, as `d` has it.
        let d = if hz2 < 1e-8 * len2 {
            0.0
        } else {
            let r = len2 / (rho2 + a2 * hz2);
            a2 * (1.0 / PI) * (r * r)
        };
        let (cos_o, cos_i) = (wo.z.abs(), wi.z.abs());
        let s_i = self.smith_root(wi);
        Some(ReflectionPair {
            wm,
            dg: d / (2.0 * (cos_i * s_o + cos_o * s_i)),
            pdf_fwd: d / (2.0 * (cos_o + s_o)),
            pdf_rev: d / (2.0 * (cos_i + s_i)),
        })
    }

    /// s(ω) = √(cos²θ + α² sin²θ) = |cos θ| (1 + 2Λ(ω)) of an isotropic distribution.
    #[inline]
    fn smith_root(&self, w: Vec3) -> f32 {
        let a2 = self.alpha_x * self.alpha_x;
        (cos2_theta(w) + a2 * sin2_theta(w)).sqrt()
    }

    /// pdf per unit solid angle of ωi for [`Self::sample_reflection`]: the pair's forward pdf.
    #[inline]
    pub fn reflection_pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        self.reflection_eval_pair(wo, wi).map_or(0.0, |r| r.pdf_fwd)
    }

    /// The pdf of ωi = reflect(ωo, ωm) for a sampled visible normal ωm.
    #[inline]
    fn reflection_pdf_at(&self, wo: Vec3, wm: Vec3) -> f32 {
        if self.is_isotropic() {
            return self.d(wm) / (2.0 * (wo.z.abs() + self.smith_root(wo)));
        }
        self.pdf(wo, wm) / (4.0 * wo.dot(wm).abs())
    }

    /// ωi = reflect(ωo, ωm) with ωm a visible normal, its pdf, and ωm (oriented like ωo).
    #[inline]
    pub fn sample_reflection(&self, wo: Vec3, u: [f32; 2]) -> Option<(Vec3, f32, Vec3)> {
        let wm = self.sample_wm(wo, u);
        let wi = crate::math::reflect(wo, wm);
        if wo.z * wi.z <= 0.0 {
            return None;
        }
        let pdf = self.reflection_pdf_at(wo, wm);
        let wm = if wm.dot(wo) < 0.0 { -wm } else { wm };
        Some((wi, pdf, wm))
    }
}

/// Polar map of the unit square to the unit disk (PBR 4ed §A.5.1).
#[inline]
fn uniform_disk_polar(u: [f32; 2]) -> Vec2 {
    let r = u[0].sqrt();
    let theta = 2.0 * PI * u[1];
    Vec2::new(r * theta.cos(), r * theta.sin())
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sampling::warp::uniform_sphere;
    use crate::sampling::Sampler;

    #[test]
    fn projected_area_of_the_normals_is_one() {
        // ∫ D(ωm) cos θm dωm = 1 (PBR 4ed eq. 9.13), by uniform sphere sampling.
        for d in [
            TrowbridgeReitz::isotropic(0.5),
            TrowbridgeReitz::new(0.3, 0.8),
        ] {
            let mut s = Sampler::new(3, 0, 0);
            let n = 400_000;
            let sum: f64 = (0..n)
                .map(|_| {
                    let w = uniform_sphere(s.get_2d());
                    (d.d(w) * w.z.max(0.0) * 4.0 * PI) as f64
                })
                .sum();
            assert!((sum / n as f64 - 1.0).abs() < 0.01, "{}", sum / n as f64);
        }
    }

    /// (D G / (4 cos θo cos θi), pdf(ωi | ωo), pdf(ωo | ωi)) of an isotropic GGX as PBR 4ed
    /// eq. 9.16, 9.18, 9.20, 9.28 write them, in f64 (the reference for the closed forms).
    fn reference_pair(alpha: f64, wo: Vec3, wi: Vec3) -> (f64, f64, f64) {
        let (wo, wi) = (wo.as_dvec3(), wi.as_dvec3());
        let wm = (wo + wi).normalize();
        let wm = if wm.z < 0.0 { -wm } else { wm };
        let tan2 = |w: glam::DVec3| (1.0 - w.z * w.z) / (w.z * w.z);
        let e = tan2(wm) / (alpha * alpha);
        let d = 1.0 / (std::f64::consts::PI * alpha * alpha * wm.z.powi(4) * (1.0 + e).powi(2));
        let lambda = |w: glam::DVec3| 0.5 * ((1.0 + alpha * alpha * tan2(w)).sqrt() - 1.0);
        let (lo, li) = (lambda(wo), lambda(wi));
        let (co, ci) = (wo.z.abs(), wi.z.abs());
        let dg = d / (1.0 + lo + li) / (4.0 * co * ci);
        let pdf = |w: glam::DVec3, l: f64| {
            d / (1.0 + l) / w.z.abs() * w.dot(wm).abs() / (4.0 * w.dot(wm).abs())
        };
        (dg, pdf(wo, lo), pdf(wi, li))
    }

    #[test]
    fn isotropic_closed_forms_are_the_general_formulas() {
        // The isotropic pair (module header) against the textbook formulas in f64, on pairs
        // on either side of the surface, from a near-mirror to α > 1.
        let mut s = Sampler::new(6, 0, 0);
        for alpha in [0.002f32, 0.05, 0.3, 1.0, 1.7] {
            let d = TrowbridgeReitz::isotropic(alpha);
            let mut checked = 0;
            for _ in 0..20_000 {
                let (wo, wi) = (uniform_sphere(s.get_2d()), uniform_sphere(s.get_2d()));
                let Some(r) = d.reflection_eval_pair(wo, wi) else {
                    assert!(wo.z * wi.z <= 0.0, "{wo} {wi}");
                    continue;
                };
                let (dg, fwd, rev) = reference_pair(alpha as f64, wo, wi);
                let close = |a: f32, b: f64| (a as f64 - b).abs() <= 2e-6 * b.abs() + 1e-30;
                assert!((r.wm - (wo + wi).normalize()).length() < 1e-6, "{alpha}");
                assert!(close(r.dg, dg), "{alpha} {wo} {wi}: {} {dg}", r.dg);
                assert!(close(r.pdf_fwd, fwd), "{alpha}: {} {fwd}", r.pdf_fwd);
                assert!(close(r.pdf_rev, rev), "{alpha}: {} {rev}", r.pdf_rev);
                checked += 1;
            }
            assert!(checked > 9_000, "{checked}");
        }
    }

    #[test]
    fn visible_normals_integrate_to_one_and_match_their_sampler() {
        let d = TrowbridgeReitz::new(0.2, 0.6);
        let w = Vec3::new(0.5, -0.3, 0.2).normalize();
        let mut s = Sampler::new(4, 0, 0);
        for _ in 0..1000 {
            let wm = d.sample_wm(w, s.get_2d());
            assert!(wm.z > 0.0 && (wm.length() - 1.0).abs() < 1e-4);
            assert!(w.dot(wm) >= -1e-4);
        }
        let n = 400_000;
        let sum: f64 = (0..n)
            .map(|_| {
                let wm = uniform_sphere(s.get_2d());
                let visible = w.dot(wm) > 0.0 && wm.z > 0.0;
                (d.pdf(w, wm) * 4.0 * PI * if visible { 1.0 } else { 0.0 }) as f64
            })
            .sum();
        assert!((sum / n as f64 - 1.0).abs() < 0.01, "{}", sum / n as f64);
    }
}
