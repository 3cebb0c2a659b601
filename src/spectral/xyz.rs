//! From spectra to CIE 1931 XYZ in photometric units (Y in cd/m² for a radiance).

use super::data;
use super::dense::{DenseSpectrum, LaneLookup, DENSE_LEN};
use super::{SampledSpectrum, SampledWavelengths, K_M, N_LAMBDA};
use glam::Vec4;
use std::sync::OnceLock;

/// Monte Carlo estimate of K_m ∫ L(λ) {x̄,ȳ,z̄}(λ) dλ from one set of hero wavelengths:
/// the mean over lanes of L(λᵢ) x̄(λᵢ) / p(λᵢ) (lanes with pdf 0 contribute nothing).
/// A black `l` (every lane weighted 0 below) is zero without the rows' lookup: about one
/// image sample in six on the peers' box (design.md §8, "The per-sample cost, seventh pass").
#[inline]
pub fn sampled_to_xyz(l: SampledSpectrum, w: &SampledWavelengths) -> [f32; 3] {
    if l.is_black() {
        return [0.0; 3];
    }
    let cmf = cmf_rows().at(w.lambda);
    let (l, pdf) = (Vec4::from_array(l.0), Vec4::from_array(w.pdf));
    // A lane with pdf 0 or L 0 is weighted 0, where it used to be skipped: the rows are
    // finite (the tables' loader rejects non-finite values, and lanes outside the range are
    // zero), so it adds ±0, and the sums start at +0 and so are never −0, which adding ±0
    // leaves unchanged. The same sums, in the same order, as skipping it (tested).
    let carried = pdf.cmpne(Vec4::ZERO) & l.cmpne(Vec4::ZERO);
    let v = Vec4::select(carried, l / pdf, Vec4::ZERO);
    let mut xyz = Vec4::ZERO;
    for (i, row) in cmf.iter().enumerate() {
        xyz += v[i] * *row;
    }
    [xyz.x, xyz.y, xyz.z].map(|c| c * K_M / N_LAMBDA as f32)
}

/// The CIE 1931 observer as one table of rows (x̄, ȳ, z̄, 0) at every integer nm: a
/// wavelength's three values are one interpolation of two rows, where the three tables of
/// [`data::cie_xyz`] took three lookups of two reads each (once per image sample in the film,
/// design.md §8, session 41). The values are those tables' `eval` bit for bit (tested).
struct CmfRows {
    rows: Box<[Vec4; DENSE_LEN]>,
}

impl CmfRows {
    /// (x̄, ȳ, z̄, 0)(λ) of each lane, zero outside the range: per component the arithmetic of
    /// [`DenseSpectrum::eval_lanes`].
    #[inline]
    fn at(&self, lambda: [f32; N_LAMBDA]) -> [Vec4; N_LAMBDA] {
        let at = LaneLookup::new(lambda);
        let inside = at.inside.bitmask();
        std::array::from_fn(|i| {
            let (k, t) = (at.index[i], at.t[i]);
            let v = self.rows[k] * (1.0 - t) + self.rows[k + 1] * t;
            if inside & (1 << i) != 0 {
                v
            } else {
                Vec4::ZERO
            }
        })
    }
}

fn cmf_rows() -> &'static CmfRows {
    static ROWS: OnceLock<CmfRows> = OnceLock::new();
    ROWS.get_or_init(|| {
        let [x, y, z] = data::cie_xyz();
        let mut rows = Box::new([Vec4::ZERO; DENSE_LEN]);
        for (k, r) in rows.iter_mut().enumerate() {
            *r = Vec4::new(x.values[k], y.values[k], z.values[k], 0.0);
        }
        CmfRows { rows }
    })
}

/// XYZ of a reflectance `r` lit by D65 scaled to luminance 1, from one set of hero
/// wavelengths ([`sampled_to_xyz`]): a white reflectance gives the white point at Y = 1, so
/// in an RGB space with a D65 white it is (1, 1, 1). This is pbrt-v4's conversion of an
/// albedo (`GBufferFilm::AddSample`: albedo × the colour space's illuminant, normalised to
/// Y = 1, to RGB with the sample's wavelengths).
#[inline]
pub fn reflectance_to_xyz(r: SampledSpectrum, w: &SampledWavelengths) -> [f32; 3] {
    static D65: OnceLock<DenseSpectrum> = OnceLock::new();
    let d65 = D65.get_or_init(|| {
        let d = data::illuminant("CIE-D65").expect("CIE-D65 is embedded");
        d.scaled((1.0 / luminance(d)) as f32)
    });
    sampled_to_xyz(
        SampledSpectrum::from_fn(|i| r[i] * d65.eval(w.lambda[i])),
        w,
    )
}

/// K_m ∫ s(λ) {x̄,ȳ,z̄}(λ) dλ on the 1 nm grid.
pub fn dense_to_xyz(s: &DenseSpectrum) -> [f64; 3] {
    let [xb, yb, zb] = data::cie_xyz();
    [xb, yb, zb].map(|cmf| K_M as f64 * s.inner_product(cmf))
}

/// Luminance (cd/m²) of a radiance spectrum, or luminous quantity of any spectral one:
/// K_m ∫ s(λ) ȳ(λ) dλ.
pub fn luminance(s: &DenseSpectrum) -> f64 {
    K_M as f64 * s.inner_product(&data::cie_xyz()[1])
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `sampled_to_xyz` as it was written before the rows (three tables, a lane skipped when
    /// its pdf or L is 0): the reference of the bit-for-bit test below.
    fn sampled_to_xyz_by_tables(l: SampledSpectrum, w: &SampledWavelengths) -> [f32; 3] {
        if l.is_black() {
            return [0.0; 3];
        }
        let [xb, yb, zb] = data::cie_xyz().each_ref().map(|c| c.eval_lanes(w.lambda));
        let mut xyz = [0.0f32; 3];
        for i in 0..N_LAMBDA {
            if w.pdf[i] == 0.0 || l[i] == 0.0 {
                continue;
            }
            let v = l[i] / w.pdf[i];
            xyz[0] += v * xb[i];
            xyz[1] += v * yb[i];
            xyz[2] += v * zb[i];
        }
        xyz.map(|c| c * K_M / N_LAMBDA as f32)
    }

    /// The rows and the weighted lanes give the three tables' skipped-lane sums bit for bit:
    /// for sampled wavelengths with all four pdfs and with the secondaries terminated, and
    /// for L with zeros of either sign, negative, huge, infinite and NaN lanes (NaN for NaN).
    #[test]
    fn sampled_to_xyz_is_the_three_tables_sum_bit_for_bit() {
        let mut rng = crate::testing::rng::Rng::new(17);
        let specials = [0.0, -0.0, -1.5, 3e38, f32::INFINITY, f32::NAN, 1e-30];
        for k in 0..20_000 {
            let mut w = SampledWavelengths::sample_visible(rng.f32());
            if k % 3 == 0 {
                w.terminate_secondary();
            }
            if k % 7 == 0 {
                // A wavelength outside the range (0 rows) with a nonzero pdf.
                w.lambda[1] = 900.0;
            }
            let mut l = SampledSpectrum::ZERO;
            for v in l.0.iter_mut() {
                *v = if rng.below(4) == 0 {
                    specials[rng.below(specials.len())]
                } else {
                    rng.range(0.0, 10.0)
                };
            }
            let (got, want) = (sampled_to_xyz(l, &w), sampled_to_xyz_by_tables(l, &w));
            for (g, x) in got.iter().zip(want) {
                // A NaN is a NaN (its sign bit is the operations' choice; the film drops it).
                let same = g.to_bits() == x.to_bits() || (g.is_nan() && x.is_nan());
                assert!(same, "{l:?} {w:?}: {got:?} vs {want:?}");
            }
        }
    }

    /// The rows' values are the three tables' `eval` bit for bit, at nodes, between them, at
    /// the ends, outside the range and at NaN.
    #[test]
    fn the_observer_rows_are_the_three_tables_bit_for_bit() {
        let tables = data::cie_xyz();
        let mut rng = crate::testing::rng::Rng::new(3);
        let mut lambdas: Vec<f32> = vec![360.0, 830.0, 829.999, 359.999, 830.001, 555.0, f32::NAN];
        lambdas.extend((0..4000).map(|_| rng.range(340.0, 850.0)));
        for quad in lambdas.chunks(N_LAMBDA) {
            let mut lambda = [555.5; N_LAMBDA];
            lambda[..quad.len()].copy_from_slice(quad);
            let rows = cmf_rows().at(lambda);
            for (i, l) in lambda.iter().enumerate() {
                for (c, table) in tables.iter().enumerate() {
                    let want = table.eval(*l).to_bits();
                    assert_eq!(rows[i][c].to_bits(), want, "λ = {l}, component {c}");
                }
                assert_eq!(rows[i].w, 0.0);
            }
        }
    }

    #[test]
    fn y_bar_integral_matches_cie() {
        // ∫ȳ dλ over 360–830 nm at 1 nm is 106.856895 (CIE 015:2018 tables; colour-science).
        let one = DenseSpectrum::constant(1.0);
        let y = one.inner_product(&data::cie_xyz()[1]);
        assert!((y - 106.856_895).abs() < 1e-3, "{y}");
    }

    #[test]
    fn monte_carlo_estimate_is_unbiased_for_a_constant() {
        let n = 20_000;
        let mut y = 0.0f64;
        for i in 0..n {
            let w = SampledWavelengths::sample_visible((i as f32 + 0.5) / n as f32);
            y += sampled_to_xyz(SampledSpectrum::ONE, &w)[1] as f64;
        }
        let expected = K_M as f64 * 106.856_895;
        assert!((y / n as f64 / expected - 1.0).abs() < 1e-3);
    }

    #[test]
    fn a_white_reflectance_is_the_d65_white_at_luminance_one() {
        // Stratified wavelengths: the mean converges to K_m ∫ D65 {x̄,ȳ,z̄} / L(D65), whose
        // Rec.709 RGB is (1, 1, 1) (our XYZ is referred to this D65, `color.rs`).
        let n = 20_000;
        let mut xyz = [0.0f64; 3];
        for i in 0..n {
            let w = SampledWavelengths::sample_visible((i as f32 + 0.5) / n as f32);
            let v = reflectance_to_xyz(SampledSpectrum::ONE, &w);
            (0..3).for_each(|c| xyz[c] += f64::from(v[c]) / f64::from(n));
        }
        let rgb = super::super::color::xyz_to_rgb(xyz);
        for c in rgb {
            assert!((c - 1.0).abs() < 2e-3, "{rgb:?}");
        }
    }
}
