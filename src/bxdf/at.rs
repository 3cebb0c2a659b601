//! A BSDF at one outgoing direction ωo: what a path vertex evaluates from a single ωo —
//! next event estimation's f and pdf of the light's direction, then the BSDF sample — with
//! the terms of ωo alone computed once (issue 18, "hot-path hygiene"; docs/design.md §8
//! "The per-hit shading cost").
//!
//! The shading frame's ωo and, for the plastic (the Cornell box's UsdPreviewSurface), its
//! [`PlasticAt`]: the coat's albedo lookup at μo, the coat's sampling probability and the
//! microfacet term s(ωo). [`Bsdf::f_pdf`] and [`Bsdf::sample_f`] are this type's methods
//! on a fresh `at`, so sharing changes no bit: the same operations on the same values.

use super::plastic::PlasticAt;
use super::{Bsdf, BsdfSample, Bxdf, TransportMode};
use crate::spectral::SampledSpectrum;
use glam::Vec3;

/// [`Bsdf`] at a fixed ωo ([`Bsdf::at`]).
#[derive(Clone, Copy, Debug)]
pub struct BsdfAt<'a> {
    pub bsdf: &'a Bsdf,
    /// ωo in the shading frame.
    wo: Vec3,
    /// The plastic's terms of ωo (None for every other model).
    plastic: Option<PlasticAt>,
}

impl Bsdf {
    /// This BSDF at `wo` (world space), for several evaluations and a sample from it.
    #[inline]
    pub fn at(&self, wo: Vec3) -> BsdfAt<'_> {
        let wo = self.frame.to_local(wo);
        let plastic = match &self.bxdf {
            Bxdf::Plastic(b) => Some(b.at(wo)),
            _ => None,
        };
        BsdfAt {
            bsdf: self,
            wo,
            plastic,
        }
    }
}

impl BsdfAt<'_> {
    /// (f(ωo, `wi`), pdf of `wi` from ωo): [`Bsdf::f_pdf`].
    #[inline]
    pub fn f_pdf(&self, wi: Vec3, mode: TransportMode) -> (SampledSpectrum, f32) {
        let wi = self.bsdf.frame.to_local(wi);
        if self.wo.z == 0.0 {
            return (SampledSpectrum::ZERO, 0.0);
        }
        match (&self.bsdf.bxdf, &self.plastic) {
            (Bxdf::Plastic(b), Some(at)) => b.f_pdf_at(at, wi),
            (bxdf, _) => bxdf.f_pdf(self.wo, wi, mode),
        }
    }

    /// A sampled direction from ωo ([`Bsdf::sample_f`]).
    #[inline(always)]
    pub fn sample_f(&self, uc: f32, u: [f32; 2], mode: TransportMode) -> Option<BsdfSample> {
        if self.wo.z == 0.0 {
            return None;
        }
        let s = match (&self.bsdf.bxdf, &self.plastic) {
            (Bxdf::Plastic(b), Some(at)) => b.sample_f_at(at, uc, u)?,
            (bxdf, _) => bxdf.sample_f(self.wo, uc, u, mode)?,
        };
        if s.pdf_w == 0.0 || s.f.is_black() || s.wi.z == 0.0 || !s.pdf_w.is_finite() {
            return None;
        }
        Some(BsdfSample {
            wi: self.bsdf.frame.to_world(s.wi),
            ..s
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::testing::bxdf_examples::examples;
    use crate::testing::rng::Rng;

    fn bits(s: SampledSpectrum) -> [u32; 4] {
        s.0.map(f32::to_bits)
    }

    /// One `at` per ωo serves any number of pairs and samples, in any order: its pairs have
    /// the bits of the BSDF's own `f` and `pdf` (computed without shared terms), its samples
    /// those of a fresh `at` (the plastic's samples carry their direction's `f` and `pdf`:
    /// `bxdf::tests`). ωo and ωi on either side, and at the horizon.
    #[test]
    fn shared_terms_of_wo_change_no_bit() {
        let mut rng = Rng::new(33);
        let mut samples = 0;
        for ex in examples() {
            let bsdf = Bsdf::new(ex.bxdf, rng.unit_vector());
            for k in 0..200 {
                let wo = if k % 40 == 0 {
                    bsdf.frame.to_world(Vec3::X)
                } else {
                    rng.unit_vector()
                };
                let at = bsdf.at(wo);
                for j in 0..8 {
                    let mode = [TransportMode::Radiance, TransportMode::Importance][j % 2];
                    let wi = rng.unit_vector();
                    let (f, pdf) = at.f_pdf(wi, mode);
                    assert_eq!(bits(f), bits(bsdf.f(wo, wi, mode)), "{} f", ex.name);
                    assert_eq!(
                        pdf.to_bits(),
                        bsdf.pdf(wo, wi, mode).to_bits(),
                        "{}",
                        ex.name
                    );
                    let (uc, u) = (rng.f32(), [rng.f32(), rng.f32()]);
                    let s = at.sample_f(uc, u, mode);
                    let fresh = bsdf.sample_f(wo, uc, u, mode);
                    assert_eq!(s.is_some(), fresh.is_some(), "{}", ex.name);
                    let (Some(s), Some(t)) = (s, fresh) else {
                        continue;
                    };
                    assert_eq!(
                        s.wi.to_array().map(f32::to_bits),
                        t.wi.to_array().map(f32::to_bits)
                    );
                    assert_eq!(bits(s.f), bits(t.f), "{}", ex.name);
                    assert_eq!(s.pdf_w.to_bits(), t.pdf_w.to_bits(), "{}", ex.name);
                    samples += 1;
                }
            }
        }
        assert!(samples > 1000, "{samples}");
    }
}
