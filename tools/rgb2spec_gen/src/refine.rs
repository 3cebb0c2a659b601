//! Polishes the table against the renderer's own colorimetry.
//!
//! `rgb2spec::optimize` fits each node in CIELAB against its built-in 5 nm CIE 1931 and D65
//! tables (linearly interpolated, Simpson 3/8 quadrature) and a rounded sRGB matrix
//! (3.240479, ...). The renderer instead integrates the 1 nm tables of `spectra/` with the
//! trapezoid rule and derives its Rec.709 matrix from the primaries and *its* D65 white
//! (`src/spectral/color.rs`). The two differ by up to ~1e-3 in linear RGB, which is the size of
//! the round-trip tolerance of docs/design.md §2. So every node is refined here by Newton's method
//! on the exact quantity the renderer computes:
//!
//! ```text
//! rgb(c) = M⁻¹ · K_m Σ_λ w_λ S(c₀λ² + c₁λ + c₂) D65n(λ) {x̄,ȳ,z̄}(λ)     (1 nm, trapezoid w_λ)
//! ```
//!
//! starting from the crate's solution, in the normalised variable t = (λ − 360)/470 (the
//! crate's parameterisation, well conditioned), and converted back to λ in nm on output.

use std::fs;
use std::path::Path;

const LAMBDA_MIN: f64 = 360.0;
const LAMBDA_RANGE: f64 = 470.0;
const N: usize = 471;

/// Rec.709 primaries' xy chromaticities (ITU-R BT.709-6), as in `src/spectral/color.rs`.
const PRIMARIES: [[f64; 2]; 3] = [[0.64, 0.33], [0.30, 0.60], [0.15, 0.06]];

type M3 = [[f64; 3]; 3];

/// The crate's bound on the largest normalised coefficient (`gauss_newton` rescales past it):
/// refined solutions above it for colours near white (all components > 0.5) are not used,
/// because coefficients that grow without bound towards the white corner cannot be
/// interpolated (towards saturated corners such as (1, 1, 0) they stay usable).
pub const MAX_COEFF: f64 = 200.0;

/// Per-wavelength weights: rgb_ch = Σ_λ weights[λ][ch] · s(λ).
pub struct Colorimetry {
    weights: Vec<[f64; 3]>,
    t: Vec<f64>,
}

/// Reads the numeric columns of a `spectra/` CSV (comment lines and the header skipped),
/// rounded to f32 as the renderer stores them.
fn read_csv(path: &Path) -> Result<Vec<Vec<f64>>, String> {
    let text = fs::read_to_string(path).map_err(|e| format!("{}: {e}", path.display()))?;
    let rows: Vec<Vec<f64>> = text
        .lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
        .skip(1)
        .map(|l| {
            l.split(',')
                .map(|v| v.trim().parse::<f32>().map(f64::from))
                .collect::<Result<_, _>>()
        })
        .collect::<Result<_, _>>()
        .map_err(|e| format!("{}: {e}", path.display()))?;
    if rows.len() != N
        || rows
            .iter()
            .enumerate()
            .any(|(i, r)| r[0] != LAMBDA_MIN + i as f64)
    {
        return Err(format!("{}: expected 360..=830 nm at 1 nm", path.display()));
    }
    Ok(rows)
}

fn mul(a: &M3, b: &M3) -> M3 {
    let mut m = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            m[i][j] = (0..3).map(|k| a[i][k] * b[k][j]).sum();
        }
    }
    m
}

fn mul_v(a: &M3, v: [f64; 3]) -> [f64; 3] {
    [0, 1, 2].map(|i| a[i][0] * v[0] + a[i][1] * v[1] + a[i][2] * v[2])
}

fn inverse(m: &M3) -> M3 {
    let c = |i: usize, j: usize| {
        let (i1, i2, j1, j2) = ((i + 1) % 3, (i + 2) % 3, (j + 1) % 3, (j + 2) % 3);
        m[i1][j1] * m[i2][j2] - m[i1][j2] * m[i2][j1]
    };
    let det: f64 = (0..3).map(|j| m[0][j] * c(0, j)).sum();
    // The inverse is the transposed cofactor matrix over the determinant.
    [0, 1, 2].map(|r| [0, 1, 2].map(|col| c(col, r) / det))
}

impl Colorimetry {
    /// Loads `spectra/cie/cie1931_2deg.csv` and `spectra/illuminants/CIE-D65.csv`.
    pub fn load(spectra: &Path) -> Result<Colorimetry, String> {
        let cmf = read_csv(&spectra.join("cie/cie1931_2deg.csv"))?;
        let d65 = read_csv(&spectra.join("illuminants/CIE-D65.csv"))?;
        let trap = |i: usize| if i == 0 || i == N - 1 { 0.5 } else { 1.0 };
        // White XYZ of D65 (any scale), then the matrix of color.rs (SMPTE RP 177).
        let mut w = [0.0; 3];
        for i in 0..N {
            for (c, wc) in w.iter_mut().enumerate() {
                *wc += trap(i) * d65[i][1] * cmf[i][c + 1];
            }
        }
        let white = [w[0] / w[1], 1.0, w[2] / w[1]];
        let col = |p: [f64; 2]| [p[0] / p[1], 1.0, (1.0 - p[0] - p[1]) / p[1]];
        let cols = PRIMARIES.map(col);
        let p: M3 = [0, 1, 2].map(|r| [cols[0][r], cols[1][r], cols[2][r]]);
        let s = mul_v(&inverse(&p), white);
        let rgb_to_xyz = mul(&p, &[[s[0], 0.0, 0.0], [0.0, s[1], 0.0], [0.0, 0.0, s[2]]]);
        let xyz_to_rgb = inverse(&rgb_to_xyz);
        // D65 normalised to Y = 1: the K_m of the renderer cancels.
        let weights = (0..N)
            .map(|i| {
                let d = (d65[i][1] / w[1]) as f32 as f64;
                let xyz = [1, 2, 3].map(|c| trap(i) * d * cmf[i][c]);
                mul_v(&xyz_to_rgb, xyz)
            })
            .collect();
        let t = (0..N).map(|i| i as f64 / LAMBDA_RANGE).collect();
        Ok(Colorimetry { weights, t })
    }

    /// rgb of the normalised-λ coefficients `a` and, if asked, its Jacobian d rgb / d a.
    fn rgb(&self, a: [f64; 3], jac: Option<&mut M3>) -> [f64; 3] {
        let mut out = [0.0; 3];
        let mut j = [[0.0; 3]; 3];
        for (w, &t) in self.weights.iter().zip(&self.t) {
            let x = (a[0] * t + a[1]) * t + a[2];
            let r = 1.0 / (1.0 + x * x).sqrt();
            let s = 0.5 + 0.5 * x * r;
            let ds = 0.5 * r * r * r;
            for c in 0..3 {
                out[c] += w[c] * s;
                let g = w[c] * ds;
                j[c][0] += g * t * t;
                j[c][1] += g * t;
                j[c][2] += g;
            }
        }
        if let Some(jac) = jac {
            *jac = j;
        }
        out
    }

    /// rgb of normalised-λ coefficients.
    pub fn rgb_of(&self, a: [f64; 3]) -> [f64; 3] {
        self.rgb(a, None)
    }

    /// Relative RGB residual (per component, scaled by the largest target component).
    pub fn error(&self, a: [f64; 3], target: [f64; 3]) -> f64 {
        let rgb = self.rgb(a, None);
        let z = target.iter().copied().fold(0.0, f64::max).max(1e-12);
        (0..3)
            .map(|c| ((rgb[c] - target[c]) / z).abs())
            .fold(0.0, f64::max)
    }

    /// Newton's method with step halving on the max-norm residual; returns the best
    /// coefficients found and their residual.
    pub fn solve(&self, target: [f64; 3], start: [f64; 3]) -> ([f64; 3], f64) {
        let mut a = start;
        let mut err = self.error(a, target);
        for _ in 0..30 {
            if err < 1e-9 {
                break;
            }
            let mut jac = [[0.0; 3]; 3];
            let rgb = self.rgb(a, Some(&mut jac));
            let det = jac[0][0] * (jac[1][1] * jac[2][2] - jac[1][2] * jac[2][1])
                - jac[0][1] * (jac[1][0] * jac[2][2] - jac[1][2] * jac[2][0])
                + jac[0][2] * (jac[1][0] * jac[2][1] - jac[1][1] * jac[2][0]);
            if !det.is_finite() || det.abs() < 1e-300 {
                break;
            }
            let step = mul_v(&inverse(&jac), [0, 1, 2].map(|c| rgb[c] - target[c]));
            let mut h = 1.0;
            let mut improved = false;
            while h > 1e-4 {
                let cand = [0, 1, 2].map(|k| a[k] - h * step[k]);
                let e = self.error(cand, target);
                if e.is_finite() && e < err {
                    a = cand;
                    err = e;
                    improved = true;
                    break;
                }
                h *= 0.5;
            }
            if !improved {
                break;
            }
        }
        (a, err)
    }
}

/// nm-convention coefficients (c₀λ² + c₁λ + c₂) → normalised t = (λ − 360)/470.
pub fn to_normalised(c: [f64; 3]) -> [f64; 3] {
    let (l0, r) = (LAMBDA_MIN, LAMBDA_RANGE);
    [
        c[0] * r * r,
        (2.0 * c[0] * l0 + c[1]) * r,
        (c[0] * l0 + c[1]) * l0 + c[2],
    ]
}

/// Inverse of [`to_normalised`] (the crate's conversion in `optimize`).
pub fn to_nm(a: [f64; 3]) -> [f64; 3] {
    let (c0, c1) = (LAMBDA_MIN, 1.0 / LAMBDA_RANGE);
    [
        a[0] * c1 * c1,
        a[1] * c1 - 2.0 * a[0] * c0 * c1 * c1,
        a[2] - a[1] * c0 * c1 + a[0] * (c0 * c1) * (c0 * c1),
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn conversions_are_inverse() {
        let a = [3.0, -7.0, 1.5];
        let b = to_normalised(to_nm(a));
        for k in 0..3 {
            assert!((a[k] - b[k]).abs() < 1e-9, "{b:?}");
        }
    }
}
