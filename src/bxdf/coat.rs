//! A specular coat: the reflection lobe of a smooth or rough (GGX) dielectric interface, with
//! the directional albedo E(μ) = ∫ f cos θi dωi that layered models need to pass the rest of
//! the energy to what lies beneath (the "albedo scaling" of Kulla & Conty 2017, "Revisiting
//! Physically Based Shading at Imageworks", §layering; Kelemen & Szirmay-Kalos 2001).
//!
//! The plastic and the UsdPreviewSurface base and clearcoat are built from it. Directions are
//! local and on the same side (the callers mirror ωo into the upper hemisphere first).
//!
//! E(μ) is exact for a smooth coat (E = F(μ)); for a rough coat it is tabulated when the
//! material is built, at [`TABLE_SIZE`] nodes uniform in √μ, by a 64×64 stratified quadrature
//! of the visible-normal estimator F(ωo·ωm) G(ωo, ωi)/G1(ωo) (Heitz 2018 §4), and linearly
//! interpolated. The Fresnel used for E is a scalar bound of the per-wavelength one (the
//! largest F0), so that 1 − E never exceeds the true transmittance at any wavelength.

use super::fresnel::{diffuse_fresnel, fr_dielectric, schlick, schlick1, simpson};
use super::microfacet::TrowbridgeReitz;
use crate::spectral::SampledSpectrum;
use glam::Vec3;
use std::collections::HashMap;
use std::sync::{Mutex, MutexGuard, OnceLock, PoisonError};

/// Nodes of a rough coat's albedo table.
pub const TABLE_SIZE: usize = 16;
/// Strata per axis of the quadrature that fills the table.
const QUADRATURE: usize = 64;

/// How the coat reflects: a dielectric interface (η = η_coat / η_outside) or Schlick's
/// approximation with a spectral F0 (UsdPreviewSurface's specular workflow).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum CoatFresnel {
    Dielectric { eta: f32 },
    Schlick { f0: SampledSpectrum },
}

impl CoatFresnel {
    /// F at the cosine between ωo and the (micro)normal, per wavelength.
    #[inline]
    pub fn eval(&self, cos: f32) -> SampledSpectrum {
        match *self {
            CoatFresnel::Dielectric { eta } => SampledSpectrum::splat(fr_dielectric(cos, eta)),
            CoatFresnel::Schlick { f0 } => schlick(cos, f0),
        }
    }
}

/// A scalar Fresnel that bounds [`CoatFresnel`] from above at every wavelength.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ScalarFresnel {
    Dielectric { eta: f32 },
    Schlick { f0: f32 },
}

impl ScalarFresnel {
    #[inline]
    fn eval(&self, cos: f32) -> f32 {
        match *self {
            ScalarFresnel::Dielectric { eta } => fr_dielectric(cos, eta),
            ScalarFresnel::Schlick { f0 } => schlick1(cos, f0),
        }
    }
}

/// The coat's directional albedo E(μ).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum CoatAlbedo {
    /// Smooth coat: E(μ) = F(μ) exactly.
    Smooth(ScalarFresnel),
    /// Rough coat: E at μ = (j / (N − 1))², j = 0 … N − 1.
    Table([f32; TABLE_SIZE]),
}

impl CoatAlbedo {
    /// The albedo of the coat `distrib` with Fresnel `fresnel` (computed once per material;
    /// a rough coat's table is kept for the process, so that materials alike share one
    /// computation).
    pub fn new(distrib: TrowbridgeReitz, fresnel: ScalarFresnel) -> CoatAlbedo {
        if distrib.effectively_smooth() {
            return CoatAlbedo::Smooth(fresnel);
        }
        let key = memo_key(distrib, fresnel);
        let known = tables().get(&key).copied();
        CoatAlbedo::Table(known.unwrap_or_else(|| {
            let table = rough_table(distrib, fresnel);
            let mut kept = tables();
            if kept.len() < MEMO_TABLES {
                kept.insert(key, table);
            }
            table
        }))
    }

    /// (1 − t)·a + t·b, for two albedos of the same distribution (both smooth Schlick, or
    /// both tables); `a` otherwise. Exact for Schlick coats interpolated in F0, since E is
    /// linear in F0.
    #[inline]
    pub fn lerp(a: &CoatAlbedo, b: &CoatAlbedo, t: f32) -> CoatAlbedo {
        use ScalarFresnel::Schlick;
        match (a, b) {
            (CoatAlbedo::Table(x), CoatAlbedo::Table(y)) => {
                CoatAlbedo::Table(std::array::from_fn(|j| x[j] + t * (y[j] - x[j])))
            }
            (CoatAlbedo::Smooth(Schlick { f0: x }), CoatAlbedo::Smooth(Schlick { f0: y })) => {
                CoatAlbedo::Smooth(Schlick {
                    f0: x + t * (y - x),
                })
            }
            _ => *a,
        }
    }

    /// E(μ) for μ = |cos θ|.
    #[inline]
    pub fn eval(&self, mu: f32) -> f32 {
        match self {
            CoatAlbedo::Smooth(f) => f.eval(mu),
            CoatAlbedo::Table(t) => {
                let x = mu.abs().min(1.0).sqrt() * (TABLE_SIZE - 1) as f32;
                // x ∈ [0, N − 1] (NaN.min(1) is 1): through i32 the conversion is one
                // instruction, where `as usize` saturates in several; the same index.
                let i = (x as i32).min(TABLE_SIZE as i32 - 2) as usize;
                let a = x - i as f32;
                (1.0 - a) * t[i] + a * t[i + 1]
            }
        }
    }

    /// 1 − E(μ): what the coat lets through to the layer below.
    #[inline]
    pub fn transmittance(&self, mu: f32) -> f32 {
        self.eval_and_transmittance(mu).1
    }

    /// (E(μ), 1 − E(μ)) from one lookup, for callers that need both.
    #[inline]
    pub fn eval_and_transmittance(&self, mu: f32) -> (f32, f32) {
        let e = self.eval(mu);
        (e, (1.0 - e).max(0.0))
    }

    /// The hemispherical average of the transmittance, T̄ = ∫₀¹ (1 − E(μ)) 2μ dμ.
    pub fn average_transmittance(&self) -> f32 {
        match self {
            CoatAlbedo::Smooth(ScalarFresnel::Dielectric { eta }) => 1.0 - diffuse_fresnel(*eta),
            // ∫ (1 − μ)⁵ 2μ dμ = 2 B(2, 6) = 1/21.
            CoatAlbedo::Smooth(ScalarFresnel::Schlick { f0 }) => 1.0 - (f0 + (1.0 - f0) / 21.0),
            CoatAlbedo::Table(_) => {
                // In x = √μ the integrand (1 − E) 4x³ is smooth between the nodes.
                let f = |x: f64| (1.0 - self.eval((x * x) as f32) as f64) * 4.0 * x.powi(3);
                let n = 64;
                (0..TABLE_SIZE - 1)
                    .map(|j| {
                        let h = 1.0 / (TABLE_SIZE - 1) as f64;
                        simpson(f, j as f64 * h, (j + 1) as f64 * h, n)
                    })
                    .sum::<f64>() as f32
            }
        }
    }
}

/// Rough coats' tables computed so far in this process, by [`memo_key`]: a table takes about
/// 16 M instructions (16 nodes × 64² quadrature points), and a stage's materials often repeat
/// their roughness and Fresnel (the peers' Cornell box: six of them alike). The same inputs
/// give the same bits whether computed or recalled.
static TABLES: OnceLock<Mutex<HashMap<MemoKey, [f32; TABLE_SIZE]>>> = OnceLock::new();
/// The tables kept at most (16 floats and a 16-byte key each: under 0.5 MB); past that a
/// table is computed and not kept.
const MEMO_TABLES: usize = 4096;

/// The kept tables, locked (a panic elsewhere while it was held leaves whole entries only).
fn tables() -> MutexGuard<'static, HashMap<MemoKey, [f32; TABLE_SIZE]>> {
    TABLES
        .get_or_init(Default::default)
        .lock()
        .unwrap_or_else(PoisonError::into_inner)
}

/// (α_x, α_y, Fresnel kind, its parameter), as bits.
type MemoKey = (u32, u32, u8, u32);

fn memo_key(distrib: TrowbridgeReitz, fresnel: ScalarFresnel) -> MemoKey {
    let (kind, value) = match fresnel {
        ScalarFresnel::Dielectric { eta } => (0, eta),
        ScalarFresnel::Schlick { f0 } => (1, f0),
    };
    (
        distrib.alpha_x.to_bits(),
        distrib.alpha_y.to_bits(),
        kind,
        value.to_bits(),
    )
}

/// E at the table's nodes μ = (j / (N − 1))², j = 0 … N − 1.
fn rough_table(distrib: TrowbridgeReitz, fresnel: ScalarFresnel) -> [f32; TABLE_SIZE] {
    std::array::from_fn(|j| {
        let x = j as f32 / (TABLE_SIZE - 1) as f32;
        rough_albedo(distrib, fresnel, (x * x).max(1e-4))
    })
}

/// E(μ) of a rough coat by stratified quadrature over the visible normals.
fn rough_albedo(distrib: TrowbridgeReitz, fresnel: ScalarFresnel, mu: f32) -> f32 {
    let wo = Vec3::new((1.0 - mu * mu).max(0.0).sqrt(), 0.0, mu);
    let mut sum = 0.0f64;
    for a in 0..QUADRATURE {
        for b in 0..QUADRATURE {
            let u = [
                (a as f32 + 0.5) / QUADRATURE as f32,
                (b as f32 + 0.5) / QUADRATURE as f32,
            ];
            let Some((wi, _, wm)) = distrib.sample_reflection(wo, u) else {
                continue;
            };
            let w = fresnel.eval(wo.dot(wm)) * distrib.g(wo, wi) / distrib.g1(wo);
            sum += w as f64;
        }
    }
    (sum / (QUADRATURE * QUADRATURE) as f64) as f32
}

/// The coat lobe: GGX (or mirror) reflection with a Fresnel model. Plain data, built per hit.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpecularCoat {
    pub distrib: TrowbridgeReitz,
    pub fresnel: CoatFresnel,
}

impl SpecularCoat {
    pub fn new(distrib: TrowbridgeReitz, fresnel: CoatFresnel) -> SpecularCoat {
        SpecularCoat { distrib, fresnel }
    }

    /// The albedo of this coat, bounded over the wavelengths (cold: once per material).
    pub fn albedo(&self) -> CoatAlbedo {
        let bound = match self.fresnel {
            CoatFresnel::Dielectric { eta } => ScalarFresnel::Dielectric { eta },
            CoatFresnel::Schlick { f0 } => ScalarFresnel::Schlick {
                f0: f0.max_value().clamp(0.0, 1.0),
            },
        };
        CoatAlbedo::new(self.distrib, bound)
    }

    #[inline]
    pub fn is_delta(&self) -> bool {
        self.distrib.effectively_smooth()
    }

    /// The glossy part of f (zero for a mirror coat).
    #[inline]
    pub fn f(&self, wo: Vec3, wi: Vec3) -> SampledSpectrum {
        if self.is_delta() {
            return SampledSpectrum::ZERO;
        }
        match self.distrib.reflection_eval(wo, wi) {
            Some((wm, dg)) => self.fresnel.eval(wo.dot(wm)) * dg,
            None => SampledSpectrum::ZERO,
        }
    }

    #[inline]
    pub fn pdf(&self, wo: Vec3, wi: Vec3) -> f32 {
        if self.is_delta() {
            return 0.0;
        }
        self.distrib.reflection_pdf(wo, wi)
    }

    /// (f, pdf of ωi from ωo): bit for bit `f(wo, wi)` and `pdf(wo, wi)`, sharing the
    /// microfacet terms, given `s_o` = `self.distrib.wo_term(wo)`, the term of ωo alone that a
    /// vertex shares between its pairs (`PlasticAt`).
    #[inline]
    pub fn f_pdf_at(&self, wo: Vec3, s_o: f32, wi: Vec3) -> (SampledSpectrum, f32) {
        if self.is_delta() {
            return (SampledSpectrum::ZERO, 0.0);
        }
        match self.distrib.reflection_eval_pair_at(wo, s_o, wi) {
            Some(r) => (self.fresnel.eval(wo.dot(r.wm)) * r.dg, r.pdf_fwd),
            None => (SampledSpectrum::ZERO, 0.0),
        }
    }

    /// (f, pdf of ωi from ωo, pdf of ωo from ωi): bit for bit `f(wo, wi)`, `pdf(wo, wi)` and
    /// `pdf(wi, wo)`, sharing the microfacet terms.
    #[inline]
    pub fn eval_pair(&self, wo: Vec3, wi: Vec3) -> (SampledSpectrum, f32, f32) {
        if self.is_delta() {
            return (SampledSpectrum::ZERO, 0.0, 0.0);
        }
        match self.distrib.reflection_eval_pair(wo, wi) {
            Some(r) => (self.fresnel.eval(wo.dot(r.wm)) * r.dg, r.pdf_fwd, r.pdf_rev),
            None => (SampledSpectrum::ZERO, 0.0, 0.0),
        }
    }

    /// A glossy direction ωi; `None` for a sample below the horizon.
    #[inline]
    pub fn sample(&self, wo: Vec3, u: [f32; 2]) -> Option<Vec3> {
        Some(self.distrib.sample_reflection(wo, u)?.0)
    }

    /// The mirror reflectance F(μo) of a smooth coat.
    #[inline]
    pub fn mirror_reflectance(&self, wo: Vec3) -> SampledSpectrum {
        self.fresnel.eval(wo.z.abs())
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A recalled table is the computed one bit for bit, for either Fresnel, and inputs that
    /// differ in any part of the key get their own.
    #[test]
    fn recalled_tables_are_the_computed_ones() {
        let d = TrowbridgeReitz::new(0.3, 0.45);
        for f in [
            ScalarFresnel::Dielectric { eta: 1.37 },
            ScalarFresnel::Schlick { f0: 0.07 },
        ] {
            let fresh = CoatAlbedo::Table(rough_table(d, f));
            assert_eq!(CoatAlbedo::new(d, f), fresh);
            assert_eq!(CoatAlbedo::new(d, f), fresh, "recalled");
        }
        let a = CoatAlbedo::new(d, ScalarFresnel::Schlick { f0: 0.07 });
        let others = [
            CoatAlbedo::new(d, ScalarFresnel::Dielectric { eta: 0.07 }),
            CoatAlbedo::new(
                TrowbridgeReitz::new(0.45, 0.3),
                ScalarFresnel::Schlick { f0: 0.07 },
            ),
            CoatAlbedo::new(d, ScalarFresnel::Schlick { f0: 0.08 }),
        ];
        assert!(others.iter().all(|o| *o != a));
    }

    #[test]
    fn smooth_average_transmittance_is_one_minus_diffuse_fresnel() {
        let a = CoatAlbedo::new(
            TrowbridgeReitz::isotropic(0.0),
            ScalarFresnel::Dielectric { eta: 1.5 },
        );
        assert!((a.average_transmittance() - (1.0 - 0.0918)).abs() < 5e-4);
        let s = CoatAlbedo::Smooth(ScalarFresnel::Schlick { f0: 0.04 });
        let numeric = 1.0
            - simpson(
                |mu| schlick1(mu as f32, 0.04) as f64 * 2.0 * mu,
                0.0,
                1.0,
                1000,
            );
        assert!((s.average_transmittance() as f64 - numeric).abs() < 1e-5);
    }

    #[test]
    fn rough_table_tends_to_fresnel_as_alpha_shrinks() {
        let f = ScalarFresnel::Dielectric { eta: 1.5 };
        let a = CoatAlbedo::new(TrowbridgeReitz::isotropic(0.002), f);
        for mu in [0.1f32, 0.3, 0.5, 0.8, 1.0] {
            let e = a.eval(mu);
            assert!((e - fr_dielectric(mu, 1.5)).abs() < 0.01, "{mu}: {e}");
        }
    }

    #[test]
    fn rough_table_interpolates_its_own_quadrature() {
        // Between the nodes the linear interpolant stays within 2e-3 of the quadrature.
        let d = TrowbridgeReitz::isotropic(0.5);
        let f = ScalarFresnel::Dielectric { eta: 1.5 };
        let a = CoatAlbedo::new(d, f);
        for k in 0..40 {
            let mu = 0.01 + 0.99 * k as f32 / 39.0;
            let exact = rough_albedo(d, f, mu);
            assert!((a.eval(mu) - exact).abs() < 2e-3, "{mu}");
        }
    }
}
