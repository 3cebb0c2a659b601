//! Photometry of spectra: luminous flux / luminance, radiant flux, luminous efficacy,
//! chromaticity and correlated colour temperature (CCT) — the spectral half of the
//! `spectral-render lights` report (the geometric half is `light::report`).
//!
//! Conventions (docs/design.md §2): spectra on the 1 nm grid over 360–830 nm, integrals by the
//! trapezoidal rule on that grid (what `numpy.trapezoid` does in colour-science), K_m = 683 lm/W.
//!
//! | quantity | formula | colour-science 0.4.7 equivalent |
//! |---|---|---|
//! | luminous (flux, luminance, intensity …) | K_m ∫ S(λ) V(λ) dλ | `colour.luminous_flux(sd)` |
//! | radiant | ∫ S(λ) dλ over 360–830 nm | `np.trapezoid(sd.values, sd.wavelengths)` |
//! | luminous efficacy (lm/W) | K_m ∫ S V dλ / ∫ S dλ | `colour.luminous_efficacy(sd)` |
//! | chromaticity x, y | X/(X+Y+Z), Y/(X+Y+Z) with CIE 1931 2° | `XYZ_to_xy(sd_to_XYZ(sd, method="Integration"))` |
//! | CCT, Duv | Ohno 2014 (the "Ohno 2013" method) in CIE 1960 uv | `colour.uv_to_CCT(uv)` (its default) |
//!
//! V(λ) is the CIE 1924 photopic function (`spectra/cie/cie1924_photopic.csv`); it equals the
//! CIE 1931 ȳ used for the image's luminance to 5e-13, so luminance in the EXR and here agree.
//!
//! CCT follows colour-science's `uv_to_CCT_Ohno2013` step for step: a Planckian table from
//! 1000 K to 100 000 K with the same geometric spacing (1.001, widening towards 1.0001 at high
//! CCT), the nearest entry, then the triangular solution (|Duv| < 0.002) or the parabolic one
//! (Ohno 2014, LEUKOS 10(1), eqs. 5–12). Two deliberate differences remain, both documented
//! and measured by `tests/photometry.rs`: our locus uses the CODATA 2018 radiation constant
//! c₂ = hc/k = 0.014387769 m·K (colour-science: 0.014388, which shifts every CCT by 1.6e-5
//! relative, −0.1 K at 6500 K) and our 360–830 nm observer (colour-science's default shape is
//! 360–780 nm).

use super::blackbody::planck_f64;
use super::dense::{DenseSpectrum, DENSE_LEN};
use super::{data, xyz, K_M, LAMBDA_MIN};
use std::sync::OnceLock;

/// K_m ∫ S(λ) V(λ) dλ: lumens for a spectral power, cd/m² for a spectral radiance, cd for a
/// spectral intensity (colour-science's `luminous_flux`).
pub fn luminous(s: &DenseSpectrum) -> f64 {
    K_M as f64 * s.inner_product(data::cie_v())
}

/// ∫ S(λ) dλ over 360–830 nm (W for a spectral power in W/nm).
pub fn radiant(s: &DenseSpectrum) -> f64 {
    s.inner_product(&DenseSpectrum::constant(1.0))
}

/// Luminous efficacy of radiation in lm/W, K_m ∫ S V / ∫ S with the radiometric integral over
/// 360–830 nm; None for a spectrum without power.
pub fn luminous_efficacy(s: &DenseSpectrum) -> Option<f64> {
    let e = radiant(s);
    (e > 0.0).then(|| luminous(s) / e)
}

/// CIE 1931 xy chromaticity; None for a black spectrum.
pub fn chromaticity(s: &DenseSpectrum) -> Option<[f64; 2]> {
    xyz_to_xy(xyz::dense_to_xyz(s))
}

/// XYZ → xy; None when X + Y + Z is not positive.
pub fn xyz_to_xy(xyz: [f64; 3]) -> Option<[f64; 2]> {
    let sum = xyz[0] + xyz[1] + xyz[2];
    (sum > 0.0 && sum.is_finite()).then(|| [xyz[0] / sum, xyz[1] / sum])
}

/// CIE 1931 xy → CIE 1960 UCS uv: u = 4x / (−2x + 12y + 3), v = 6y / (−2x + 12y + 3).
pub fn xy_to_uv(xy: [f64; 2]) -> [f64; 2] {
    let d = -2.0 * xy[0] + 12.0 * xy[1] + 3.0;
    [4.0 * xy[0] / d, 6.0 * xy[1] / d]
}

/// Correlated colour temperature and the signed distance Duv from the Planckian locus in
/// CIE 1960 uv (positive above the locus).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cct {
    pub kelvin: f64,
    pub duv: f64,
}

/// CIE 015:2018 §9.5: a CCT is only meaningful within this distance of the locus.
pub const MAX_DUV: f64 = 0.05;

/// Ohno's CCT of a CIE 1960 uv chromaticity. None outside the table's 1000–100 000 K range
/// (the nearest entry is an end of the table) or for non-finite input.
pub fn cct_ohno2014(uv: [f64; 2]) -> Option<Cct> {
    if !(uv[0].is_finite() && uv[1].is_finite()) {
        return None;
    }
    let table = planckian_table();
    let dist = |e: &LocusEntry| (e.u - uv[0]).hypot(e.v - uv[1]);
    let (i, _) = table
        .iter()
        .map(dist)
        .enumerate()
        .min_by(|a, b| a.1.total_cmp(&b.1))?;
    if i == 0 || i == table.len() - 1 {
        return None;
    }
    let (p, c, n) = (&table[i - 1], &table[i], &table[i + 1]);
    let (dp, dc, dn) = (dist(p), dist(c), dist(n));
    // Triangular solution (Ohno 2014 eqs. 5–8).
    let l = (n.u - p.u).hypot(n.v - p.v);
    let x = (dp * dp - dn * dn + l * l) / (2.0 * l);
    let t_tri = p.t + (n.t - p.t) * (x / l);
    let v_tx = p.v + (n.v - p.v) * (x / l);
    let sign = (uv[1] - v_tx).signum();
    let duv_tri = (dp * dp - x * x).max(0.0).sqrt() * sign;
    if duv_tri.abs() < 0.002 {
        return Some(Cct {
            kelvin: t_tri,
            duv: duv_tri,
        });
    }
    // Parabolic solution (Ohno 2014 eqs. 9–12).
    let xx = (n.t - c.t) * (p.t - n.t) * (c.t - p.t);
    let a = (p.t * (dn - dc) + c.t * (dp - dn) + n.t * (dc - dp)) / xx;
    let b = -(p.t * p.t * (dn - dc) + c.t * c.t * (dp - dn) + n.t * n.t * (dc - dp)) / xx;
    let cc = -(dp * (n.t - c.t) * c.t * n.t
        + dc * (p.t - n.t) * p.t * n.t
        + dn * (c.t - p.t) * p.t * c.t)
        / xx;
    let t = -b / (2.0 * a);
    Some(Cct {
        kelvin: t,
        duv: (a * t * t + b * t + cc) * sign,
    })
}

/// CCT of a spectrum (via its CIE 1931 chromaticity).
pub fn cct(s: &DenseSpectrum) -> Option<Cct> {
    chromaticity(s).and_then(|xy| cct_ohno2014(xy_to_uv(xy)))
}

/// The photometric summary of one spectrum.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpectrumPhotometry {
    /// K_m ∫ S V dλ (cd/m² for a radiance).
    pub luminous: f64,
    /// ∫ S dλ over 360–830 nm.
    pub radiant: f64,
    pub efficacy: Option<f64>,
    pub xy: Option<[f64; 2]>,
    /// None when the chromaticity is farther than [`MAX_DUV`] from the locus or outside
    /// 1000–100 000 K.
    pub cct: Option<Cct>,
}

pub fn summarize(s: &DenseSpectrum) -> SpectrumPhotometry {
    let xy = chromaticity(s);
    let cct = xy
        .and_then(|xy| cct_ohno2014(xy_to_uv(xy)))
        .filter(|c| c.duv.abs() <= MAX_DUV);
    SpectrumPhotometry {
        luminous: luminous(s),
        radiant: radiant(s),
        efficacy: luminous_efficacy(s),
        xy,
        cct,
    }
}

struct LocusEntry {
    t: f64,
    u: f64,
    v: f64,
}

/// colour-science's `planckian_table(cmfs, 1000, 100000, 1.001)`: T = 1000, 1001, then ×1.001
/// with the step shrinking linearly towards ×1.0001 at 100 000 K, then 99 999 and 100 000.
fn planckian_table() -> &'static [LocusEntry] {
    static TABLE: OnceLock<Vec<LocusEntry>> = OnceLock::new();
    TABLE.get_or_init(|| {
        const START: f64 = 1000.0;
        const END: f64 = 100_000.0;
        const SPACING: f64 = 1.001;
        let mut temps = vec![START, START + 1.0];
        let (mut t, mut step) = (START + 1.0, SPACING);
        loop {
            t *= step;
            if t >= END {
                break;
            }
            temps.push(t);
            let d = ((t - START) / (END - START)).clamp(0.0, 1.0);
            step = SPACING * (1.0 - d) + (1.0 + (SPACING - 1.0) / 10.0) * d;
        }
        temps.extend([END - 1.0, END]);
        temps.into_iter().map(locus_entry).collect()
    })
}

/// uv of a blackbody at `t` kelvin, integrated in f64 against the 1 nm observer.
fn locus_entry(t: f64) -> LocusEntry {
    let [xb, yb, zb] = data::cie_xyz();
    let mut xyz = [0.0f64; 3];
    for i in 0..DENSE_LEN {
        let w = if i == 0 || i == DENSE_LEN - 1 {
            0.5
        } else {
            1.0
        };
        let p = w * planck_f64(LAMBDA_MIN as f64 + i as f64, t);
        xyz[0] += p * xb.values[i] as f64;
        xyz[1] += p * yb.values[i] as f64;
        xyz[2] += p * zb.values[i] as f64;
    }
    let xy = xyz_to_xy(xyz).expect("a blackbody has colour");
    let [u, v] = xy_to_uv(xy);
    LocusEntry { t, u, v }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn blackbody(t: f64) -> DenseSpectrum {
        DenseSpectrum::from_fn(|l| planck_f64(l as f64, t) as f32)
    }

    #[test]
    fn cct_of_blackbodies_is_their_temperature() {
        for t in [1500.0, 2856.0, 4000.0, 6500.0, 12000.0, 40000.0] {
            let c = cct(&blackbody(t)).unwrap();
            assert!((c.kelvin / t - 1.0).abs() < 2e-5, "{t}: {c:?}");
            assert!(c.duv.abs() < 1e-5, "{t}: {c:?}");
        }
    }

    #[test]
    fn cct_off_the_locus_uses_the_parabola_and_signs_duv() {
        // Ohno 2014's example (and colour-science's docstring): uv (0.1978, 0.3122) gives
        // about 6507 K, Duv +0.00322.
        let c = cct_ohno2014([0.1978, 0.3122]).unwrap();
        assert!((c.kelvin - 6507.5).abs() < 2.0, "{c:?}");
        assert!((c.duv - 0.003_223).abs() < 2e-5, "{c:?}");
        let below = cct_ohno2014([0.1978, 0.3022]).unwrap();
        assert!(below.duv < -0.002, "{below:?}");
    }

    #[test]
    fn efficacy_of_monochromatic_555_nm_is_k_m() {
        let s = DenseSpectrum::from_fn(|l| if l == 555.0 { 1.0 } else { 0.0 });
        let eta = luminous_efficacy(&s).unwrap();
        assert!((eta / K_M as f64 - 1.0).abs() < 1e-6, "{eta}");
        assert_eq!(luminous_efficacy(&DenseSpectrum::constant(0.0)), None);
    }

    #[test]
    fn equal_energy_white_is_at_one_third() {
        let xy = chromaticity(&DenseSpectrum::constant(1.0)).unwrap();
        assert!((xy[0] - 1.0 / 3.0).abs() < 2e-4 && (xy[1] - 1.0 / 3.0).abs() < 2e-4);
        assert_eq!(chromaticity(&DenseSpectrum::constant(0.0)), None);
    }
}
