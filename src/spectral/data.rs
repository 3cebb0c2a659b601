//! The reference spectral data of `spectra/`, embedded in the binary (so it runs from any
//! directory) and parsed lazily, once, on first use.
//!
//! | token (`<dir>/<stem>`)         | content                                        | accessor            |
//! |--------------------------------|------------------------------------------------|---------------------|
//! | `cie/cie1931_2deg`             | x̄, ȳ, z̄ of the CIE 1931 2° observer           | [`cie_xyz`]         |
//! | `cie/cie1924_photopic`         | V(λ), CIE 1924                                 | [`cie_v`], [`named`]|
//! | `illuminants/CIE-D65`, …       | relative SPDs: A, D50, D65, F1–F12, LED-B1–B5  | [`illuminant`], [`named`] |
//! | `colorchecker/dark_skin`, …    | the 24 BabelColor average reflectances         | [`named`]           |
//! | `metal/Au`, `Ag`, `Cu`, `Al`   | complex index n, k                             | [`metal`]           |
//! | `glass/BK7`, `fused_silica`    | Sellmeier coefficients                         | [`glass`]           |
//! | `rgb2spec/srgb_64.bin`         | Jakob–Hanika 2019 coefficient table            | [`rgb2spec_table`]  |
//!
//! Every CSV starts with `#` lines naming its source, licence and units, then a header line,
//! then rows; `spectra/README.md` is the inventory and `tools/gen_spectra.py` regenerates it.
//! The embedded files are ours, so a malformed one is a bug (caught by the tests below), and
//! parsing panics with the file's name rather than returning an error.

use super::dense::DenseSpectrum;
use super::sellmeier::Sellmeier;
use std::sync::OnceLock;

/// (`<dir>/<stem>`, file text) for `spectra/<dir>/<stem>.csv`.
macro_rules! csv {
    ($($token:literal),* $(,)?) => {
        &[$(($token, include_str!(concat!("../../spectra/", $token, ".csv")))),*]
    };
}

const CMF_FILE: (&str, &str) = csv!["cie/cie1931_2deg"][0];

/// Files holding one spectrum each (second column), reachable through [`named`].
const SINGLE: &[(&str, &str)] = csv![
    "cie/cie1924_photopic",
    "illuminants/CIE-A",
    "illuminants/CIE-D50",
    "illuminants/CIE-D65",
    "illuminants/CIE-F1",
    "illuminants/CIE-F2",
    "illuminants/CIE-F3",
    "illuminants/CIE-F4",
    "illuminants/CIE-F5",
    "illuminants/CIE-F6",
    "illuminants/CIE-F7",
    "illuminants/CIE-F8",
    "illuminants/CIE-F9",
    "illuminants/CIE-F10",
    "illuminants/CIE-F11",
    "illuminants/CIE-F12",
    "illuminants/LED-B1",
    "illuminants/LED-B2",
    "illuminants/LED-B3",
    "illuminants/LED-B4",
    "illuminants/LED-B5",
    "colorchecker/dark_skin",
    "colorchecker/light_skin",
    "colorchecker/blue_sky",
    "colorchecker/foliage",
    "colorchecker/blue_flower",
    "colorchecker/bluish_green",
    "colorchecker/orange",
    "colorchecker/purplish_blue",
    "colorchecker/moderate_red",
    "colorchecker/purple",
    "colorchecker/yellow_green",
    "colorchecker/orange_yellow",
    "colorchecker/blue",
    "colorchecker/green",
    "colorchecker/red",
    "colorchecker/yellow",
    "colorchecker/magenta",
    "colorchecker/cyan",
    "colorchecker/white_9_5",
    "colorchecker/neutral_8",
    "colorchecker/neutral_6_5",
    "colorchecker/neutral_5",
    "colorchecker/neutral_3_5",
    "colorchecker/black_2",
];

/// Complex index of refraction tables (columns wavelength_nm, n, k).
const METALS: &[(&str, &str)] = csv!["metal/Au", "metal/Ag", "metal/Cu", "metal/Al"];

/// Sellmeier coefficient tables (columns i, B, C_um2).
const GLASSES: &[(&str, &str)] = csv!["glass/BK7", "glass/fused_silica"];

const ILLUMINANT_NAMES: &[&str] = &[
    "CIE-A", "CIE-D50", "CIE-D65", "CIE-F1", "CIE-F2", "CIE-F3", "CIE-F4", "CIE-F5", "CIE-F6",
    "CIE-F7", "CIE-F8", "CIE-F9", "CIE-F10", "CIE-F11", "CIE-F12", "LED-B1", "LED-B2", "LED-B3",
    "LED-B4", "LED-B5",
];

static RGB2SPEC_SRGB_64: &[u8] = include_bytes!("../../spectra/rgb2spec/srgb_64.bin");

/// A parsed CSV: its `#` comment lines (without the `#`), column names and numeric rows.
struct Table<'a> {
    #[cfg_attr(not(test), allow(dead_code))] // checked by the tests
    comments: Vec<&'a str>,
    columns: Vec<&'a str>,
    rows: Vec<Vec<f64>>,
}

fn parse(token: &str, text: &'static str) -> Table<'static> {
    let fail = |what: String| -> ! { panic!("embedded spectra/{token}.csv: {what}") };
    let mut lines = text.lines().map(str::trim).filter(|l| !l.is_empty());
    let mut comments = Vec::new();
    let header = loop {
        match lines.next() {
            Some(l) if l.starts_with('#') => comments.push(l[1..].trim()),
            Some(l) => break l,
            None => fail("no header line".into()),
        }
    };
    let columns: Vec<&str> = header.split(',').map(str::trim).collect();
    let rows = lines
        .map(|l| {
            let row: Vec<f64> = l
                .split(',')
                .map(|v| {
                    v.trim()
                        .parse()
                        .unwrap_or_else(|_| fail(format!("bad number in {l:?}")))
                })
                .collect();
            if row.len() != columns.len() {
                fail(format!("row {l:?} does not match header {header:?}"));
            }
            row
        })
        .collect();
    Table {
        comments,
        columns,
        rows,
    }
}

/// Column `col` of a table against its first column, resampled to the 1 nm grid.
fn column(token: &str, table: &Table, col: usize) -> DenseSpectrum {
    let samples: Vec<(f32, f32)> = table
        .rows
        .iter()
        .map(|r| (r[0] as f32, r[col] as f32))
        .collect();
    DenseSpectrum::from_samples(&samples)
        .unwrap_or_else(|| panic!("embedded spectra/{token}.csv: empty or unsorted wavelengths"))
}

/// x̄, ȳ, z̄ of the CIE 1931 2° standard observer (CIE 015:2018), 1 nm, 360–830 nm.
pub fn cie_xyz() -> &'static [DenseSpectrum; 3] {
    static CMF: OnceLock<[DenseSpectrum; 3]> = OnceLock::new();
    CMF.get_or_init(|| {
        let (token, text) = CMF_FILE;
        let t = parse(token, text);
        [1, 2, 3].map(|c| column(token, &t, c))
    })
}

/// The CIE 1924 photopic luminous efficiency function V(λ).
pub fn cie_v() -> &'static DenseSpectrum {
    named("cie/cie1924_photopic").expect("V(λ) is embedded")
}

fn singles() -> &'static [(&'static str, DenseSpectrum)] {
    static S: OnceLock<Vec<(&'static str, DenseSpectrum)>> = OnceLock::new();
    S.get_or_init(|| {
        SINGLE
            .iter()
            .map(|&(token, text)| (token, column(token, &parse(token, text), 1)))
            .collect()
    })
}

/// A standard illuminant's relative SPD by name: "CIE-A", "CIE-D50", "CIE-D65",
/// "CIE-F1".."CIE-F12", "LED-B1".."LED-B5" (see [`illuminant_names`]).
pub fn illuminant(name: &str) -> Option<&'static DenseSpectrum> {
    singles()
        .iter()
        .find(|(t, _)| t.strip_prefix("illuminants/") == Some(name))
        .map(|(_, s)| s)
}

/// The names [`illuminant`] accepts.
pub fn illuminant_names() -> &'static [&'static str] {
    ILLUMINANT_NAMES
}

/// Any single-valued spectrum file by `<dir>/<stem>`, e.g. `"colorchecker/dark_skin"`,
/// `"illuminants/CIE-D65"`, `"cie/cie1924_photopic"`.
pub fn named(token: &str) -> Option<&'static DenseSpectrum> {
    singles().iter().find(|(t, _)| *t == token).map(|(_, s)| s)
}

/// Every token [`named`] accepts, in a stable order (for error messages and docs).
pub fn named_tokens() -> Vec<&'static str> {
    SINGLE.iter().map(|(t, _)| *t).collect()
}

type Nk = (&'static str, DenseSpectrum, DenseSpectrum);

fn metals() -> &'static [Nk] {
    static M: OnceLock<Vec<Nk>> = OnceLock::new();
    M.get_or_init(|| {
        METALS
            .iter()
            .map(|&(token, text)| {
                let t = parse(token, text);
                assert_eq!(
                    t.columns,
                    ["wavelength_nm", "n", "k"],
                    "embedded spectra/{token}.csv header"
                );
                (token, column(token, &t, 1), column(token, &t, 2))
            })
            .collect()
    })
}

/// A metal's complex index (n, k) by `"Au"` or `"metal/Au"` (Au, Ag, Cu, Al).
pub fn metal(token: &str) -> Option<(&'static DenseSpectrum, &'static DenseSpectrum)> {
    let name = token.strip_prefix("metal/").unwrap_or(token);
    metals()
        .iter()
        .find(|(t, _, _)| t.strip_prefix("metal/") == Some(name))
        .map(|(_, n, k)| (n, k))
}

fn glasses() -> &'static [(&'static str, Sellmeier)] {
    static G: OnceLock<Vec<(&'static str, Sellmeier)>> = OnceLock::new();
    G.get_or_init(|| {
        GLASSES
            .iter()
            .map(|&(token, text)| {
                let t = parse(token, text);
                assert_eq!(
                    t.columns,
                    ["i", "B", "C_um2"],
                    "embedded spectra/{token}.csv header"
                );
                assert_eq!(
                    t.rows.len(),
                    3,
                    "embedded spectra/{token}.csv: three Sellmeier terms"
                );
                let s = Sellmeier {
                    b: [0, 1, 2].map(|i| t.rows[i][1] as f32),
                    c: [0, 1, 2].map(|i| t.rows[i][2] as f32),
                };
                (token, s)
            })
            .collect()
    })
}

/// A glass's Sellmeier coefficients by `"BK7"`, `"fused_silica"` (or `"glass/BK7"`, ...).
pub fn glass(token: &str) -> Option<Sellmeier> {
    let name = token.strip_prefix("glass/").unwrap_or(token);
    glasses()
        .iter()
        .find(|(t, _)| t.strip_prefix("glass/") == Some(name))
        .map(|(_, s)| *s)
}

/// The names [`metal`] and [`glass`] accept without their directory.
pub fn metal_names() -> Vec<&'static str> {
    METALS.iter().map(|(t, _)| &t["metal/".len()..]).collect()
}

/// See [`metal_names`].
pub fn glass_names() -> Vec<&'static str> {
    GLASSES.iter().map(|(t, _)| &t["glass/".len()..]).collect()
}

/// The raw bytes of `spectra/rgb2spec/srgb_64.bin` (format in `spectra/rgb2spec/srgb_64.md`),
/// decoded by [`super::uplift`].
pub fn rgb2spec_table() -> &'static [u8] {
    RGB2SPEC_SRGB_64
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::spectral::{xyz, LAMBDA_MIN};

    fn all_files() -> Vec<(&'static str, &'static str)> {
        let mut v = vec![CMF_FILE];
        v.extend_from_slice(SINGLE);
        v.extend_from_slice(METALS);
        v.extend_from_slice(GLASSES);
        v
    }

    #[test]
    fn every_file_states_source_licence_units() {
        for (token, text) in all_files() {
            let t = parse(token, text);
            for key in ["source:", "licence:", "units:"] {
                assert!(
                    t.comments.iter().any(|c| c.starts_with(key)),
                    "{token}: no '{key}' line"
                );
            }
            assert!(t.columns.len() >= 2 && !t.rows.is_empty(), "{token}");
        }
    }

    #[test]
    fn colour_science_curves_are_on_the_1nm_grid() {
        for (token, text) in std::iter::once(CMF_FILE).chain(SINGLE.iter().copied()) {
            let t = parse(token, text);
            assert_eq!(t.rows.len(), 471, "{token}");
            for (i, r) in t.rows.iter().enumerate() {
                assert_eq!(r[0], (LAMBDA_MIN as usize + i) as f64, "{token}");
            }
        }
    }

    #[test]
    fn cie_observer_and_v() {
        let one = DenseSpectrum::constant(1.0);
        let y = one.inner_product(&cie_xyz()[1]);
        assert!((y - 106.856_895).abs() < 1e-3, "∫ȳ = {y}");
        assert_eq!(cie_v().eval(555.0), 1.0);
        assert_eq!(cie_xyz()[1].eval(555.0), 1.0);
        // V(λ) and ȳ(λ) are the same function (CIE 015:2018).
        for l in (360..=830).step_by(5) {
            assert!(
                (cie_v().eval(l as f32) - cie_xyz()[1].eval(l as f32)).abs() < 1e-6,
                "{l}"
            );
        }
    }

    #[test]
    fn illuminants() {
        assert_eq!(illuminant_names().len(), 20);
        for name in illuminant_names() {
            let s = illuminant(name).unwrap_or_else(|| panic!("{name}"));
            assert!(
                s.values.iter().all(|v| *v >= 0.0) && s.max_value() > 0.0,
                "{name}"
            );
            assert!(std::ptr::eq(
                s,
                named(&format!("illuminants/{name}")).unwrap()
            ));
        }
        for name in ["CIE-A", "CIE-D50", "CIE-D65"] {
            assert_eq!(illuminant(name).unwrap().eval(560.0), 100.0, "{name}");
        }
        assert!(illuminant("D65").is_none() && illuminant("CIE-F13").is_none());
        // D65 white point (CIE 015:2018 Table T.3, 2°): x = 0.31272, y = 0.32903.
        let w = xyz::dense_to_xyz(illuminant("CIE-D65").unwrap());
        let s = w[0] + w[1] + w[2];
        assert!(
            (w[0] / s - 0.31272).abs() < 5e-5 && (w[1] / s - 0.32903).abs() < 5e-5,
            "{w:?}"
        );
    }

    #[test]
    fn colorchecker() {
        let patches: Vec<_> = named_tokens()
            .into_iter()
            .filter(|t| t.starts_with("colorchecker/"))
            .collect();
        assert_eq!(patches.len(), 24);
        for t in patches {
            let s = named(t).unwrap();
            assert!(s.values.iter().all(|v| (0.0..=1.0).contains(v)), "{t}");
        }
        // Neutral patches: roughly flat, white ≈ 0.9, black ≈ 0.03.
        assert!((named("colorchecker/white_9_5").unwrap().eval(550.0) - 0.9).abs() < 0.05);
        assert!((named("colorchecker/black_2").unwrap().eval(550.0) - 0.031).abs() < 0.01);
        assert!(named("colorchecker/nope").is_none() && named("dark_skin").is_none());
    }

    #[test]
    fn colorchecker_xyz_matches_colour_science() {
        // colour.sd_to_XYZ(patch × D65 scaled to 100 cd/m², k=683, method="Integration") with
        // colour-science 0.4.7 (tools/check_colorchecker.py --print-reference 100).
        let d65 = illuminant("CIE-D65").unwrap();
        let d65 = d65.scaled((100.0 / xyz::luminance(d65)) as f32);
        let expected = [
            ("dark_skin", [11.147603, 10.072722, 6.803994]),
            ("red", [19.572507, 11.700475, 5.028450]),
            ("cyan", [14.635437, 19.961662, 39.311902]),
            ("white_9_5", [86.236755, 91.236811, 95.415540]),
            ("black_2", [3.052601, 3.200794, 3.540096]),
        ];
        for (name, want) in expected {
            let r = named(&format!("colorchecker/{name}")).unwrap();
            let lit = DenseSpectrum::from_fn(|l| r.eval(l) * d65.eval(l));
            let got = xyz::dense_to_xyz(&lit);
            for c in 0..3 {
                assert!(
                    (got[c] / want[c] - 1.0).abs() < 2e-5,
                    "{name}: {got:?} vs {want:?}"
                );
            }
        }
    }

    #[test]
    fn metals() {
        assert_eq!(metal_names(), ["Au", "Ag", "Cu", "Al"]);
        let (n, k) = metal("Au").unwrap();
        assert!((n.eval(550.0) - 0.4).abs() < 0.1 && (k.eval(550.0) - 2.3).abs() < 0.2);
        assert_eq!(metal("metal/Au").unwrap().0, n);
        let (n, k) = metal("Ag").unwrap();
        assert!(n.eval(550.0) < 0.1 && (k.eval(550.0) - 3.5).abs() < 0.3);
        let (n, k) = metal("Cu").unwrap();
        assert!((n.eval(650.0) - 0.2).abs() < 0.1 && (k.eval(650.0) - 3.6).abs() < 0.3);
        let (n, k) = metal("Al").unwrap();
        assert!((n.eval(550.0) - 0.96).abs() < 0.1 && (k.eval(550.0) - 6.7).abs() < 0.3);
        for name in metal_names() {
            let (n, k) = metal(name).unwrap();
            assert!(
                n.values.iter().chain(k.values.iter()).all(|v| *v > 0.0),
                "{name}"
            );
        }
        assert!(metal("Pt").is_none());
    }

    #[test]
    fn glasses() {
        let bk7 = glass("BK7").unwrap();
        assert!((bk7.ior(587.6) - 1.5168).abs() < 1e-4, "{}", bk7.ior(587.6));
        assert_eq!(glass("glass/BK7"), Some(bk7));
        let silica = glass("fused_silica").unwrap();
        assert!(
            (silica.ior(587.6) - 1.4585).abs() < 1e-4,
            "{}",
            silica.ior(587.6)
        );
        assert!(bk7.is_dispersive() && silica.is_dispersive());
        assert_eq!(glass_names(), ["BK7", "fused_silica"]);
        assert!(glass("SF11").is_none());
    }

    #[test]
    fn rgb2spec_table_has_its_magic() {
        assert_eq!(&rgb2spec_table()[..4], b"SPEC");
    }
}
