//! The closed set of spectrum representations the scene stores. Evaluated per sample into
//! a [`SampledSpectrum`]; never copied on the hot path (materials and lights hold them).

use super::blackbody::planck;
use super::dense::DenseSpectrum;
use super::uplift::{RgbIlluminantSpectrum, Sigmoid};
use super::{SampledSpectrum, SampledWavelengths};
use std::sync::Arc;

#[derive(Clone, Debug, PartialEq)]
pub enum Spectrum {
    Constant(f32),
    /// A bounded reflectance from RGB (Jakob–Hanika sigmoid polynomial).
    Sigmoid(Sigmoid),
    /// An illuminant from RGB: scale · sigmoid(λ) · D65(λ) (pbrt-v4 RGBIlluminantSpectrum).
    RgbIlluminant(RgbIlluminantSpectrum),
    /// Tabulated data times a scale.
    Dense {
        data: Arc<DenseSpectrum>,
        scale: f32,
    },
    /// Planck's law at `kelvin` times a scale (W·m⁻²·sr⁻¹·nm⁻¹ before scaling).
    Blackbody {
        kelvin: f32,
        scale: f32,
    },
}

impl Spectrum {
    /// True when both are the same representation with bit-identical parameters (so +0 and
    /// −0 differ): then they evaluate to the same bits at every λ. Conservative: false for
    /// RGB illuminants, and for any two representations of one function.
    pub fn same_bits(&self, other: &Spectrum) -> bool {
        let bits = |v: &[f32; 3]| v.map(f32::to_bits);
        match (self, other) {
            (Spectrum::Constant(a), Spectrum::Constant(b)) => a.to_bits() == b.to_bits(),
            (Spectrum::Sigmoid(a), Spectrum::Sigmoid(b)) => bits(&a.c) == bits(&b.c),
            (Spectrum::Dense { data: a, scale: x }, Spectrum::Dense { data: b, scale: y }) => {
                x.to_bits() == y.to_bits()
                    && (Arc::ptr_eq(a, b)
                        || a.values
                            .iter()
                            .zip(b.values.iter())
                            .all(|(u, v)| u.to_bits() == v.to_bits()))
            }
            (
                Spectrum::Blackbody {
                    kelvin: a,
                    scale: x,
                },
                Spectrum::Blackbody {
                    kelvin: b,
                    scale: y,
                },
            ) => a.to_bits() == b.to_bits() && x.to_bits() == y.to_bits(),
            _ => false,
        }
    }

    #[inline]
    pub fn eval(&self, lambda: f32) -> f32 {
        match self {
            Spectrum::Constant(c) => *c,
            Spectrum::Sigmoid(s) => s.eval(lambda),
            Spectrum::RgbIlluminant(s) => s.eval(lambda),
            Spectrum::Dense { data, scale } => data.eval(lambda) * scale,
            Spectrum::Blackbody { kelvin, scale } => planck(lambda, *kelvin) * scale,
        }
    }

    /// The spectrum at the path's wavelengths: the representation is matched once for the
    /// four lanes, not per lane (the same values as [`Spectrum::eval`] per lane).
    #[inline]
    pub fn sample(&self, w: &SampledWavelengths) -> SampledSpectrum {
        match self {
            Spectrum::Constant(c) => SampledSpectrum::splat(*c),
            Spectrum::Dense { data, scale } => {
                SampledSpectrum(data.eval_lanes(w.lambda).map(|v| v * scale))
            }
            _ => SampledSpectrum::from_fn(|i| self.eval(w.lambda[i])),
        }
    }

    /// The spectrum on the 1 nm grid (for integrals such as luminance and power).
    pub fn to_dense(&self) -> DenseSpectrum {
        DenseSpectrum::from_fn(|l| self.eval(l))
    }

    /// The spectrum as the scene stores it for rendering: the closed forms that cost more per
    /// evaluation than a table lookup — the sigmoid polynomial (two fused multiply-adds, in
    /// software without the `fma` target feature, a square root and a division) and the RGB
    /// illuminant (the same and a D65 lookup) — tabulated on the 1 nm grid and linearly
    /// interpolated ([`DenseSpectrum`], docs/design.md §8 "Hot path"); the others unchanged.
    /// Equal at every integer nm, so integrals on that grid (luminance, power) do not change;
    /// in between the table differs by the interpolation error, at most h²/8 · max |s''| with
    /// h = 1 nm (below 10⁻³ of the peak for the uplift's most saturated colours, tested; 7·10⁻⁵ for the
    /// Cornell box's red wall). A sigmoid whose polynomial is constant (c₀ = c₁ = 0: the
    /// uplift's greys, black and white) is the constant it evaluates to, exactly, and
    /// costs a splat per hit rather than four table lookups.
    pub fn tabulated(self) -> Spectrum {
        match self {
            Spectrum::Sigmoid(s) if s.c[0] == 0.0 && s.c[1] == 0.0 => {
                Spectrum::Constant(s.eval(super::LAMBDA_MIN))
            }
            Spectrum::Sigmoid(_) | Spectrum::RgbIlluminant(_) => Spectrum::Dense {
                data: Arc::new(self.to_dense()),
                scale: 1.0,
            },
            other => other,
        }
    }

    /// This spectrum times a constant.
    pub fn scaled(&self, s: f32) -> Spectrum {
        match self {
            Spectrum::Constant(c) => Spectrum::Constant(c * s),
            Spectrum::Dense { data, scale } => Spectrum::Dense {
                data: data.clone(),
                scale: scale * s,
            },
            Spectrum::Blackbody { kelvin, scale } => Spectrum::Blackbody {
                kelvin: *kelvin,
                scale: scale * s,
            },
            Spectrum::RgbIlluminant(r) => Spectrum::RgbIlluminant(r.scaled(s)),
            Spectrum::Sigmoid(_) => Spectrum::Dense {
                data: Arc::new(self.to_dense()),
                scale: s,
            },
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spectral::uplift::{reflectance, RgbIlluminantSpectrum};
    use crate::spectral::{LAMBDA_MAX, LAMBDA_MIN};

    /// The largest |table − closed form| over a 0.01 nm grid, relative to the peak.
    fn max_relative_error(s: &Spectrum) -> f32 {
        let t = s.clone().tabulated();
        let n = ((LAMBDA_MAX - LAMBDA_MIN) * 100.0) as usize;
        let (mut err, mut peak) = (0.0f32, 0.0f32);
        for k in 0..=n {
            let l = LAMBDA_MIN + k as f32 * 0.01;
            err = err.max((t.eval(l) - s.eval(l)).abs());
            peak = peak.max(s.eval(l).abs());
        }
        if peak > 0.0 {
            err / peak
        } else {
            err
        }
    }

    /// Every reflectance and illuminant the uplift makes of a grid of colours (primaries,
    /// saturated mixes and greys included) is tabulated within its interpolation bound, and
    /// exactly at integer nm.
    #[test]
    fn tables_match_the_closed_forms() {
        let levels = [0.0, 0.02, 0.1, 0.3, 0.5, 0.7, 0.9, 0.98, 1.0];
        let mut worst = 0.0f32;
        for r in levels {
            for g in levels {
                for b in levels {
                    let sig = Spectrum::Sigmoid(reflectance([r, g, b]));
                    let ill = Spectrum::RgbIlluminant(RgbIlluminantSpectrum::new([r, g, b]));
                    for s in [sig, ill] {
                        worst = worst.max(max_relative_error(&s));
                        let t = s.clone().tabulated();
                        for l in [LAMBDA_MIN, 517.0, LAMBDA_MAX] {
                            assert_eq!(t.eval(l), s.eval(l), "{r} {g} {b} at {l} nm");
                        }
                    }
                }
            }
        }
        assert!(worst < 1e-3, "{worst}");
    }

    #[test]
    fn grey_sigmoids_become_their_constant() {
        for v in [0.0, 0.18, 0.5, 1.0] {
            let s = Spectrum::Sigmoid(reflectance([v, v, v]));
            let t = s.clone().tabulated();
            assert!(matches!(t, Spectrum::Constant(_)), "{v}: {t:?}");
            for l in [LAMBDA_MIN, 517.3, LAMBDA_MAX] {
                assert_eq!(t.eval(l), s.eval(l), "{v} at {l} nm");
            }
        }
        let coloured = Spectrum::Sigmoid(reflectance([0.2, 0.5, 0.1])).tabulated();
        assert!(matches!(coloured, Spectrum::Dense { .. }));
    }

    #[test]
    fn other_representations_are_kept() {
        let c = Spectrum::Constant(0.5);
        assert_eq!(c.clone().tabulated(), c);
        let d = Spectrum::Dense {
            data: Arc::new(DenseSpectrum::constant(0.25)),
            scale: 2.0,
        };
        assert_eq!(d.clone().tabulated(), d);
    }
}
