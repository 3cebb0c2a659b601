//! RGB → spectrum uplift with the sigmoid-polynomial function space of
//! W. Jakob and J. Hanika, "A Low-Dimensional Function Space for Efficient Spectral
//! Upsampling", Computer Graphics Forum 38(2), 2019 (Eurographics), as pbrt-v4 uses it
//! (PBR 4ed §4.6.6, `RGBSigmoidPolynomial`, `RGBToSpectrumTable`, `RGBIlluminantSpectrum`).
//!
//! A reflectance is s(λ) = S(c₀λ² + c₁λ + c₂), a quadratic polynomial mapped through the
//! algebraic sigmoid S(x) = ½ + x / (2√(1 + x²)) (the paper's function space), bounded in
//! [0, 1] by construction. The coefficients for an RGB come from the paper's precomputed table,
//! embedded from `spectra/rgb2spec/srgb_64.bin` (sRGB/Rec.709 primaries, D65; see its `.md`
//! sidecar): the largest component selects one of three 64³ blocks, its value is looked up on a
//! smoothstep² grid (`scale`) and the other two, divided by it, on a uniform grid, and the
//! coefficients are interpolated trilinearly, as in the paper's runtime code and pbrt-v4.
//!
//! That lookup alone reproduces the RGB under D65 only to ~5e-3 (interpolation between nodes);
//! docs/design.md §2 asks for 1e-3. So [`reflectance`] finishes it with a few Newton steps on the
//! renderer's own colorimetry (the same 1 nm CIE tables, D65 and Rec.709 matrix that
//! `xyz::dense_to_xyz` and `color::xyz_to_rgb` use), which leaves ~1e-5, the precision of f32
//! coefficients. Greys are exact.
//!
//! Illuminants follow pbrt-v4's `RGBIlluminantSpectrum`: scale · s(λ) · D65(λ) with
//! scale = 2·max(rgb) and s the reflectance of rgb / scale, so the sigmoid never saturates;
//! here D65 is normalised to 1 cd/m² ([`d65_normalized`]) so that the colour (1, 1, 1) is D65
//! white of luminance 1 cd/m² (docs/design.md §2).

use super::dense::DenseSpectrum;
use super::{color, data, xyz, K_M};
use std::sync::OnceLock;

/// A bounded reflectance s(λ) = S(c₀λ² + c₁λ + c₂), λ in nm (Jakob–Hanika 2019).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Sigmoid {
    pub c: [f32; 3],
}

/// The algebraic sigmoid S(x) = ½ + x / (2√(1 + x²)) of Jakob–Hanika 2019, with its
/// limits 0 and 1 at x = ∓∞.
#[inline]
fn sigmoid(x: f32) -> f32 {
    if x.is_infinite() {
        return if x > 0.0 { 1.0 } else { 0.0 };
    }
    0.5 + x / (2.0 * (1.0 + x * x).sqrt())
}

impl Sigmoid {
    /// The constant reflectance `v` ∈ [0, 1]: c = (0, 0, S⁻¹(v)), S⁻¹(v) = (v − ½)/√(v(1 − v))
    /// (±∞ at the ends, which [`Sigmoid::eval`] maps to 0 and 1), as pbrt-v4 does for greys.
    pub fn constant(v: f32) -> Sigmoid {
        let v = v.clamp(0.0, 1.0);
        let x = match v {
            0.0 => f32::NEG_INFINITY,
            1.0 => f32::INFINITY,
            _ => ((v as f64 - 0.5) / (v as f64 * (1.0 - v as f64)).sqrt()) as f32,
        };
        Sigmoid { c: [0.0, 0.0, x] }
    }

    /// s(λ), λ in nm.
    #[inline]
    pub fn eval(&self, lambda: f32) -> f32 {
        let [c0, c1, c2] = self.c;
        sigmoid(c0.mul_add(lambda, c1).mul_add(lambda, c2))
    }

    /// max over [`super::LAMBDA_MIN`, `super::LAMBDA_MAX`] of s(λ): at an end or at the
    /// parabola's vertex λ = −c₁/(2c₀) (S is monotonic).
    pub fn max_value(&self) -> f32 {
        let ends = self
            .eval(super::LAMBDA_MIN)
            .max(self.eval(super::LAMBDA_MAX));
        let vertex = -self.c[1] / (2.0 * self.c[0]);
        if (super::LAMBDA_MIN..=super::LAMBDA_MAX).contains(&vertex) {
            ends.max(self.eval(vertex))
        } else {
            ends
        }
    }
}

/// The decoded coefficient table (format in `spectra/rgb2spec/srgb_64.md`).
struct Table {
    res: usize,
    /// Grid of the largest component's value, increasing from 0 to 1.
    scale: Vec<f32>,
    /// `[l][z][y][x][3]` coefficients, l = index of the largest component.
    data: Vec<f32>,
}

fn table() -> &'static Table {
    static T: OnceLock<Table> = OnceLock::new();
    T.get_or_init(|| decode(data::rgb2spec_table()))
}

fn decode(bytes: &[u8]) -> Table {
    let word = |i: usize| -> [u8; 4] { bytes[4 * i..4 * i + 4].try_into().expect("4 bytes") };
    assert_eq!(&bytes[..4], b"SPEC", "rgb2spec table: bad magic");
    let res = u32::from_le_bytes(word(1)) as usize;
    let n_data = 3 * res * res * res * 3;
    assert!(
        res >= 2 && bytes.len() == 4 * (2 + res + n_data),
        "rgb2spec table: bad size"
    );
    let floats = |start: usize, n: usize| -> Vec<f32> {
        (start..start + n)
            .map(|i| f32::from_le_bytes(word(i)))
            .collect()
    };
    Table {
        res,
        scale: floats(2, res),
        data: floats(2 + res, n_data),
    }
}

/// The sigmoid-polynomial reflectance of a linear Rec.709 RGB, components clamped to [0, 1]
/// (NaN → 0), bounded in [0, 1] at every λ.
///
/// Greys are exact ([`Sigmoid::constant`]). Otherwise the trilinear lookup of the embedded
/// table (which alone round-trips only to ~5e-3: see `spectra/rgb2spec/srgb_64.md`) is polished
/// by Newton's method on the renderer's own colorimetry (`xyz::dense_to_xyz`,
/// `color::xyz_to_rgb`), so that the reflectance seen under D65 reproduces `rgb` to ~1e-5
/// (the f32 coefficients' precision) — docs/design.md §2 asks for 1e-3. Costs ~10 µs (up to ~0.1 ms
/// within a few percent of white): call it when building a scene, not per sample.
pub fn reflectance(rgb: [f32; 3]) -> Sigmoid {
    let rgb = clamp_rgb(rgb);
    if rgb[0] == rgb[1] && rgb[1] == rgb[2] {
        return Sigmoid::constant(rgb[0]);
    }
    polish(rgb, lookup(rgb))
}

/// The table lookup alone, without the Newton polish of [`reflectance`]: about 100× faster,
/// with a round-trip error up to ~5e-3 (see `spectra/rgb2spec/srgb_64.md`). For per-texel
/// uplift of images (dome and material textures), where that is far below the image's own
/// quantisation; greys stay exact.
pub fn reflectance_lookup(rgb: [f32; 3]) -> Sigmoid {
    let rgb = clamp_rgb(rgb);
    if rgb[0] == rgb[1] && rgb[1] == rgb[2] {
        return Sigmoid::constant(rgb[0]);
    }
    lookup(rgb)
}

fn clamp_rgb(rgb: [f32; 3]) -> [f32; 3] {
    rgb.map(|v| if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) })
}

/// Cell index i with scale[i] ≤ z < scale[i+1], clamped to [0, res − 2].
fn find_interval(scale: &[f32], z: f32) -> usize {
    scale
        .partition_point(|&s| s <= z)
        .saturating_sub(1)
        .min(scale.len() - 2)
}

/// Trilinear interpolation of the table's coefficients (Jakob–Hanika 2019, as in their
/// reference code and pbrt-v4's `RGBToSpectrumTable`): the largest component l selects the
/// block and, through the `scale` grid, the z coordinate; the other two divided by it are the
/// uniform x, y coordinates.
fn lookup(rgb: [f32; 3]) -> Sigmoid {
    let t = table();
    let res = t.res;
    // Largest component (ties go to the later one, as the table was built).
    let l = (1..3).fold(0, |m, j| if rgb[j] >= rgb[m] { j } else { m });
    let z = rgb[l];
    let k = (res - 1) as f32 / z;
    let (x, y) = (rgb[(l + 1) % 3] * k, rgb[(l + 2) % 3] * k);
    let xi = (x as usize).min(res - 2);
    let yi = (y as usize).min(res - 2);
    let zi = find_interval(&t.scale, z);
    let (dx, dy) = (x - xi as f32, y - yi as f32);
    let dz = (z - t.scale[zi]) / (t.scale[zi + 1] - t.scale[zi]);
    let at = |xo: usize, yo: usize, zo: usize, c: usize| {
        t.data[((((l * res + zi + zo) * res + yi + yo) * res + xi + xo) * 3) + c]
    };
    let lerp = |a: f32, b: f32, w: f32| a + w * (b - a);
    let c = [0, 1, 2].map(|c| {
        let plane = |zo| {
            let y0 = lerp(at(0, 0, zo, c), at(1, 0, zo, c), dx);
            let y1 = lerp(at(0, 1, zo, c), at(1, 1, zo, c), dx);
            lerp(y0, y1, dy)
        };
        lerp(plane(0), plane(1), dz)
    });
    Sigmoid { c }
}

/// Wavelength normalisation of the Newton iteration (the optimiser's t = (λ − 360)/470).
const T_RANGE: f64 = 470.0;

/// rgb = Σ_λ w_λ s(λ): the renderer's `color::xyz_to_rgb(xyz::dense_to_xyz(s · D65n))` as
/// per-nm weights (trapezoid rule on the 1 nm grid).
struct Colorimetry {
    w: Vec<[f64; 3]>,
}

fn colorimetry() -> &'static Colorimetry {
    static C: OnceLock<Colorimetry> = OnceLock::new();
    C.get_or_init(|| {
        let [xb, yb, zb] = data::cie_xyz();
        let d65 = d65_normalized();
        let m = [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]].map(color::xyz_to_rgb);
        let n = xb.values.len();
        let w = (0..n)
            .map(|i| {
                let trap = if i == 0 || i == n - 1 { 0.5 } else { 1.0 };
                let k = K_M as f64 * trap * d65.values[i] as f64;
                let xyz = [xb, yb, zb].map(|c| k * c.values[i] as f64);
                [0, 1, 2].map(|ch| (0..3).map(|j| m[j][ch] * xyz[j]).sum())
            })
            .collect();
        Colorimetry { w }
    })
}

impl Colorimetry {
    /// rgb of the t-coefficients `a` and its Jacobian d rgb / d a.
    fn rgb(&self, a: [f64; 3]) -> ([f64; 3], [[f64; 3]; 3]) {
        let (mut rgb, mut jac) = ([0.0; 3], [[0.0; 3]; 3]);
        for (i, w) in self.w.iter().enumerate() {
            let t = i as f64 / T_RANGE;
            let x = (a[0] * t + a[1]) * t + a[2];
            let r = 1.0 / (1.0 + x * x).sqrt();
            let (s, ds) = (0.5 + 0.5 * x * r, 0.5 * r * r * r);
            for ch in 0..3 {
                rgb[ch] += w[ch] * s;
                let g = w[ch] * ds;
                jac[ch][0] += g * t * t;
                jac[ch][1] += g * t;
                jac[ch][2] += g;
            }
        }
        (rgb, jac)
    }
}

/// λ-in-nm coefficients → t-coefficients, t = (λ − 360)/470, and back.
fn to_t(c: [f32; 3]) -> [f64; 3] {
    let [c0, c1, c2] = c.map(f64::from);
    let l0 = super::LAMBDA_MIN as f64;
    [
        c0 * T_RANGE * T_RANGE,
        (2.0 * c0 * l0 + c1) * T_RANGE,
        (c0 * l0 + c1) * l0 + c2,
    ]
}

fn to_nm(a: [f64; 3]) -> [f32; 3] {
    let (l0, k) = (super::LAMBDA_MIN as f64, 1.0 / T_RANGE);
    let c0 = a[0] * k * k;
    let c1 = a[1] * k - 2.0 * c0 * l0;
    [
        c0 as f32,
        c1 as f32,
        (a[2] - a[1] * k * l0 + c0 * l0 * l0) as f32,
    ]
}

fn solve3(m: [[f64; 3]; 3], b: [f64; 3]) -> Option<[f64; 3]> {
    let det3 = |m: [[f64; 3]; 3]| {
        m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1])
            - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0])
            + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
    };
    let det = det3(m);
    if !det.is_normal() {
        return None;
    }
    // Cramer's rule.
    let x = [0, 1, 2].map(|k| {
        let mut mk = m;
        for r in 0..3 {
            mk[r][k] = b[r];
        }
        det3(mk) / det
    });
    x.iter().all(|v| v.is_finite()).then_some(x)
}

/// Newton's method on rgb(a) = target in the t-coefficients, with step shortening; returns the
/// best iterate and its error (max over channels of |rgb − target| / max(target)).
fn newton(cm: &Colorimetry, target: [f64; 3], mut a: [f64; 3], tol: f64) -> ([f64; 3], f64) {
    let scale = target.iter().copied().fold(0.0, f64::max);
    let error = |rgb: [f64; 3]| {
        (0..3)
            .map(|i| (rgb[i] - target[i]).abs())
            .fold(0.0, f64::max)
            / scale
    };
    let (mut rgb, mut jac) = cm.rgb(a);
    let mut err = error(rgb);
    for _ in 0..12 {
        if err <= tol || err.is_nan() {
            break;
        }
        let Some(step) = solve3(jac, [0, 1, 2].map(|i| rgb[i] - target[i])) else {
            break;
        };
        let mut h = 1.0;
        loop {
            let cand = [0, 1, 2].map(|k| a[k] - h * step[k]);
            let (r, j) = cm.rgb(cand);
            let e = error(r);
            if e < err {
                (a, rgb, jac, err) = (cand, r, j, e);
                break;
            }
            h *= 0.25;
            if h < 1e-3 {
                return (a, err);
            }
        }
    }
    (a, err)
}

/// Refines the table's estimate by Newton's method on the renderer's colorimetry. Where that
/// stalls (close to white, the solution's coefficients grow without bound and the table's
/// estimate is poor) it falls back to continuation from the grey of the same mean, whose
/// solution is exact, towards `target` in 16 steps. Returns the best result found.
fn polish(target: [f32; 3], start: Sigmoid) -> Sigmoid {
    const TOL: f64 = 1e-7;
    let cm = colorimetry();
    let target = target.map(f64::from);
    let (mut best, mut err) = newton(cm, target, to_t(start.c), TOL);
    if err > 1e-5 {
        let grey = (target[0] + target[1] + target[2]) / 3.0;
        let mut a = to_t(Sigmoid::constant(grey as f32).c);
        let steps = 16;
        for k in 1..=steps {
            let f = k as f64 / steps as f64;
            let t = target.map(|v| grey + f * (v - grey));
            a = newton(cm, t, a, if k == steps { TOL } else { 1e-5 }).0;
        }
        let (a, e) = newton(cm, target, a, TOL);
        if e < err {
            (best, err) = (a, e);
        }
    }
    let _ = err;
    let c = to_nm(best);
    if c.iter().all(|v| v.is_finite()) {
        Sigmoid { c }
    } else {
        start
    }
}

/// D65 normalised to luminance 1 cd/m²: D65(λ) / (K_m ∫ D65 ȳ dλ).
pub fn d65_normalized() -> &'static DenseSpectrum {
    static D: OnceLock<DenseSpectrum> = OnceLock::new();
    D.get_or_init(|| {
        let d65 = data::illuminant("CIE-D65").expect("D65 is embedded");
        d65.scaled((1.0 / xyz::luminance(d65)) as f32)
    })
}

/// An emission spectrum from a linear Rec.709 RGB (pbrt-v4 `RGBIlluminantSpectrum`):
/// scale · s(λ) · D65n(λ), so that (1, 1, 1) is D65 of luminance 1 cd/m².
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RgbIlluminantSpectrum {
    pub scale: f32,
    pub sigmoid: Sigmoid,
}

impl RgbIlluminantSpectrum {
    /// scale = 2·max(rgb), sigmoid = [`reflectance`]`(rgb / scale)`; black for rgb ≤ 0.
    pub fn new(rgb: [f32; 3]) -> Self {
        Self::with(rgb, reflectance)
    }

    /// As [`Self::new`] with [`reflectance_lookup`]: for per-texel use.
    pub fn new_lookup(rgb: [f32; 3]) -> Self {
        Self::with(rgb, reflectance_lookup)
    }

    fn with(rgb: [f32; 3], uplift: fn([f32; 3]) -> Sigmoid) -> Self {
        let m = rgb[0].max(rgb[1]).max(rgb[2]);
        if m.is_nan() || m <= 0.0 {
            return RgbIlluminantSpectrum {
                scale: 0.0,
                sigmoid: Sigmoid::constant(0.0),
            };
        }
        let scale = 2.0 * m;
        RgbIlluminantSpectrum {
            scale,
            sigmoid: uplift(rgb.map(|v| v / scale)),
        }
    }

    /// Spectral radiance (per unit of the RGB) at `lambda` nm.
    #[inline]
    pub fn eval(&self, lambda: f32) -> f32 {
        self.scale * self.sigmoid.eval(lambda) * d65_normalized().eval(lambda)
    }

    /// This spectrum times `s`.
    pub fn scaled(&self, s: f32) -> Self {
        RgbIlluminantSpectrum {
            scale: self.scale * s,
            ..*self
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spectral::color;

    /// Linear Rec.709 RGB of a reflectance seen under D65 (white = (1, 1, 1)).
    fn round_trip(s: &Sigmoid) -> [f64; 3] {
        let d65 = d65_normalized();
        let lit = DenseSpectrum::from_fn(|l| s.eval(l) * d65.eval(l));
        color::xyz_to_rgb(xyz::dense_to_xyz(&lit))
    }

    /// Deterministic test colours: corners, greys, primaries, the 24 ColorChecker patches
    /// and pseudo-random points of [0, 1]³.
    fn test_colours() -> Vec<[f32; 3]> {
        let mut v = vec![
            [0.0, 0.0, 0.0],
            [1.0, 1.0, 1.0],
            [1.0, 0.0, 0.0],
            [0.0, 1.0, 0.0],
            [0.0, 0.0, 1.0],
            [1.0, 1.0, 0.0],
            [0.0, 1.0, 1.0],
            [1.0, 0.0, 1.0],
            [0.5, 0.0, 0.0],
            [0.0, 0.1, 0.0],
            [0.0, 0.0, 0.02],
        ];
        v.extend([0.001, 0.01, 0.18, 0.5, 0.9, 0.999].map(|g| [g; 3]));
        // Near white and near black, where the coefficients grow without bound.
        v.extend([
            [0.98, 1.0, 1.0],
            [1.0, 1.0, 0.99],
            [0.95, 0.97, 1.0],
            [1e-5, 0.0, 0.0],
            [2e-6, 1e-6, 0.0],
        ]);
        v.extend(colorchecker_rgb());
        let mut state = 0x2545_f491_4f6c_dd1d_u64;
        let mut next = || {
            state ^= state << 13;
            state ^= state >> 7;
            state ^= state << 17;
            (state >> 40) as f32 / (1u64 << 24) as f32
        };
        while v.len() < 200 {
            v.push([next(), next(), next()]);
        }
        v
    }

    fn colorchecker_rgb() -> Vec<[f32; 3]> {
        let d65 = d65_normalized();
        data::named_tokens()
            .into_iter()
            .filter(|t| t.starts_with("colorchecker/"))
            .map(|t| {
                let r = data::named(t).unwrap();
                let lit = DenseSpectrum::from_fn(|l| r.eval(l) * d65.eval(l));
                color::xyz_to_rgb(xyz::dense_to_xyz(&lit)).map(|c| c.clamp(0.0, 1.0) as f32)
            })
            .collect()
    }

    /// (max relative error over components > 0.1, max absolute error, worst input, number
    /// outside 1e-3 relative / 1e-4 absolute).
    fn errors(
        colours: &[[f32; 3]],
        uplift: fn([f32; 3]) -> Sigmoid,
    ) -> (f64, f64, [f32; 3], usize) {
        let (mut rel, mut abs, mut worst, mut fails) = (0.0f64, 0.0f64, [0.0; 3], 0);
        for &rgb in colours {
            let out = round_trip(&uplift(rgb));
            let mut ok = true;
            for i in 0..3 {
                let e = (out[i] - rgb[i] as f64).abs();
                ok &= e <= (1e-3 * rgb[i] as f64).max(1e-4);
                let r = if rgb[i] > 0.1 { e / rgb[i] as f64 } else { 0.0 };
                if r > rel || e > abs {
                    worst = rgb;
                }
                rel = rel.max(r);
                abs = abs.max(e);
            }
            fails += usize::from(!ok);
        }
        (rel, abs, worst, fails)
    }

    #[test]
    fn reflectance_round_trips_under_d65() {
        let colours = test_colours();
        assert_eq!(colours.len(), 200);
        let (rel, abs, worst, fails) = errors(&colours, reflectance);
        eprintln!(
            "uplift round trip: max rel error {rel:.2e}, max abs error {abs:.2e} (worst {worst:?})"
        );
        assert_eq!(
            fails, 0,
            "{fails} of 200 outside 1e-3 relative / 1e-4 absolute"
        );
        assert!(rel < 1e-4 && abs < 1e-4, "{rel} {abs}");
    }

    #[test]
    fn the_table_alone_is_a_starting_point() {
        // The trilinear lookup without polishing, as pbrt-v4 uses such a table, for the record
        // (greys excluded: `reflectance` solves them exactly without the table).
        let colours: Vec<_> = test_colours()
            .into_iter()
            .filter(|c| c[0] != c[1] || c[1] != c[2])
            .collect();
        let (rel, abs, worst, _) = errors(&colours, |rgb| lookup(clamp_rgb(rgb)));
        eprintln!("table lookup alone: max rel {rel:.2e}, max abs {abs:.2e} (worst {worst:?})");
        assert!(abs < 0.1, "{abs}");
    }

    #[test]
    fn greys_are_exact_and_flat() {
        for g in [0.0, 1e-4, 0.18, 0.5, 0.75, 1.0] {
            let s = reflectance([g; 3]);
            for l in [360.0, 555.0, 830.0] {
                assert!((s.eval(l) - g).abs() < 1e-6, "{g} at {l}: {}", s.eval(l));
            }
        }
    }

    #[test]
    fn reflectances_are_bounded() {
        for rgb in test_colours() {
            let s = reflectance(rgb);
            let m = s.max_value();
            assert!((0.0..=1.0).contains(&m), "{rgb:?}");
            for l in 360..=830 {
                let v = s.eval(l as f32);
                assert!(
                    (0.0..=1.0).contains(&v) && v <= m + 1e-6,
                    "{rgb:?} at {l}: {v}"
                );
            }
        }
        // Out-of-range input is clamped.
        assert_eq!(reflectance([2.0, -1.0, 0.5]), reflectance([1.0, 0.0, 0.5]));
        assert_eq!(reflectance([f32::NAN, 0.0, 0.0]), reflectance([0.0; 3]));
    }

    #[test]
    fn illuminant_white_is_d65_of_unit_luminance() {
        let s = RgbIlluminantSpectrum::new([1.0, 1.0, 1.0]);
        assert_eq!(s.scale, 2.0);
        let dense = DenseSpectrum::from_fn(|l| s.eval(l));
        assert!((xyz::luminance(&dense) - 1.0).abs() < 1e-4);
        let w = xyz::dense_to_xyz(&dense);
        let xy = [w[0] / (w[0] + w[1] + w[2]), w[1] / (w[0] + w[1] + w[2])];
        let d65 = color::white_xy();
        assert!(
            (xy[0] - d65[0]).abs() < 1e-6 && (xy[1] - d65[1]).abs() < 1e-6,
            "{xy:?}"
        );
        assert!((luminance_of(&s.scaled(100.0)) - 100.0).abs() < 1e-2);
    }

    fn luminance_of(s: &RgbIlluminantSpectrum) -> f64 {
        xyz::luminance(&DenseSpectrum::from_fn(|l| s.eval(l)))
    }

    #[test]
    fn illuminant_colours_round_trip() {
        for rgb in [
            [1.0, 0.0, 0.0],
            [0.2, 3.0, 0.5],
            [10.0, 10.0, 10.0],
            [0.0, 0.0, 0.4],
        ] {
            let s = RgbIlluminantSpectrum::new(rgb);
            let out = color::xyz_to_rgb(xyz::dense_to_xyz(&DenseSpectrum::from_fn(|l| s.eval(l))));
            for i in 0..3 {
                assert!(
                    (out[i] - rgb[i] as f64).abs() <= (1e-3 * rgb[i] as f64).max(1e-4),
                    "{rgb:?} -> {out:?}"
                );
            }
        }
        let black = RgbIlluminantSpectrum::new([0.0; 3]);
        assert_eq!(black.scale, 0.0);
        assert_eq!(black.eval(550.0), 0.0);
    }

    #[test]
    fn d65_normalized_has_unit_luminance() {
        assert!((xyz::luminance(d65_normalized()) - 1.0).abs() < 1e-6);
    }
}
