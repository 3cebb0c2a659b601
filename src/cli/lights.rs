//! `spectral-render lights STAGE [--json]`: the photometric report of every light (DESIGN.md
//! §1): luminous flux (lm), peak luminous intensity (cd), luminance (cd/m²), illuminance (lx,
//! distant and dome lights), chromaticity x, y, CCT (K) and Duv, and the luminous efficacy of
//! the spectrum (lm/W), computed from each light's spectral radiance and geometry
//! (`light::report`, `spectral::photometry`).
//!
//! JSON (`--json`), one object per light in scene order; quantities that are not defined for
//! a light (flux of a dome, CCT farther than Duv 0.05 from the Planckian locus, …) are `null`:
//!
//! ```json
//! {
//!   "stage": "scenes/room.usda",
//!   "lights": [
//!     {
//!       "prim": "/Room/Lights/Panel_0",
//!       "type": "RectLight",
//!       "luminous_flux_lm": 3000.0,
//!       "peak_intensity_cd": 954.93,
//!       "luminance_cd_m2": 2652.58,
//!       "illuminance_lx": null,
//!       "area_m2": 0.36,
//!       "radiant_flux_w": 9.52,
//!       "chromaticity": { "x": 0.3776, "y": 0.3813 },
//!       "cct_k": 4102.6,
//!       "duv": 0.0012,
//!       "luminous_efficacy_lm_w": 315.1,
//!       "shaped": false,
//!       "note": null
//!     }
//!   ]
//! }
//! ```

use super::render::print_summary;
use crate::light::report::{self, LightReport};
use crate::scene;
use clap::Parser;
use std::ffi::OsString;
use std::fmt::Write;
use std::path::PathBuf;

/// Report each light's photometry: flux, peak intensity, luminance, chromaticity, CCT and
/// luminous efficacy.
#[derive(Parser, Debug)]
#[command(name = "spectral-render lights", version, about)]
struct LightsArgs {
    /// The stage to read (.usda, .usdc or .usdz).
    scene: PathBuf,
    /// Print JSON instead of a table.
    #[arg(long)]
    json: bool,
}

/// Entry point: `argv[0]` is "lights".
pub fn main(argv: Vec<OsString>) -> Result<(), String> {
    let args = LightsArgs::parse_from(argv);
    let scene = scene::load(&args.scene, None).map_err(|e| e.to_string())?;
    print_summary(&scene);
    let reports = report::report(&scene.lights);
    let out = if args.json {
        json(&args.scene.display().to_string(), &reports)
    } else {
        table(&reports)
    };
    print!("{out}");
    Ok(())
}

/// The report as JSON (format in the module docs).
pub fn json(stage: &str, reports: &[LightReport]) -> String {
    let mut s = format!("{{\n  \"stage\": {},\n  \"lights\": [", quote(stage));
    for (i, r) in reports.iter().enumerate() {
        let sp = &r.spectrum;
        let fields = [
            ("prim", quote(&r.prim_path)),
            ("type", quote(r.kind)),
            ("luminous_flux_lm", number(r.luminous_flux)),
            ("peak_intensity_cd", number(r.peak_intensity)),
            ("luminance_cd_m2", number(r.luminance)),
            ("illuminance_lx", number(r.illuminance)),
            ("area_m2", number(r.area)),
            ("radiant_flux_w", number(r.radiant_flux)),
            (
                "chromaticity",
                match sp.xy {
                    Some([x, y]) => format!("{{ \"x\": {}, \"y\": {} }}", num(x), num(y)),
                    None => "null".into(),
                },
            ),
            ("cct_k", number(sp.cct.map(|c| c.kelvin))),
            ("duv", number(sp.cct.map(|c| c.duv))),
            ("luminous_efficacy_lm_w", number(sp.efficacy)),
            ("shaped", r.shaped.to_string()),
            ("note", r.note.map_or("null".into(), quote)),
        ];
        s += if i == 0 { "\n    {" } else { ",\n    {" };
        for (k, (name, value)) in fields.iter().enumerate() {
            let sep = if k + 1 < fields.len() { "," } else { "" };
            let _ = write!(s, "\n      \"{name}\": {value}{sep}");
        }
        s += "\n    }";
    }
    s += if reports.is_empty() {
        "]\n}\n"
    } else {
        "\n  ]\n}\n"
    };
    s
}

/// A human-readable table, one light per line.
fn table(reports: &[LightReport]) -> String {
    let opt =
        |v: Option<f64>, digits: usize| v.map_or("-".to_string(), |v| format!("{v:.digits$}"));
    let mut s = format!(
        "{:<32} {:<13} {:>12} {:>12} {:>14} {:>10} {:>7} {:>7} {:>8} {:>8} {:>8}\n",
        "prim", "type", "flux lm", "peak cd", "L cd/m²", "E lx", "x", "y", "CCT K", "Duv", "lm/W"
    );
    for r in reports {
        let sp = &r.spectrum;
        let _ = writeln!(
            s,
            "{:<32} {:<13} {:>12} {:>12} {:>14} {:>10} {:>7} {:>7} {:>8} {:>8} {:>8}{}",
            r.prim_path,
            r.kind,
            opt(r.luminous_flux, 1),
            opt(r.peak_intensity, 1),
            opt(r.luminance, 1),
            opt(r.illuminance, 1),
            opt(sp.xy.map(|c| c[0]), 4),
            opt(sp.xy.map(|c| c[1]), 4),
            opt(sp.cct.map(|c| c.kelvin), 0),
            opt(sp.cct.map(|c| c.duv), 4),
            opt(sp.efficacy, 1),
            if r.shaped { "  (shaped)" } else { "" },
        );
    }
    s
}

/// A JSON number, or null for None and non-finite values.
fn number(v: Option<f64>) -> String {
    v.map_or("null".into(), num)
}

fn num(v: f64) -> String {
    if v.is_finite() {
        format!("{v}")
    } else {
        "null".into()
    }
}

/// A JSON string literal.
fn quote(s: &str) -> String {
    let mut q = String::with_capacity(s.len() + 2);
    q.push('"');
    for c in s.chars() {
        match c {
            '"' => q.push_str("\\\""),
            '\\' => q.push_str("\\\\"),
            c if (c as u32) < 0x20 => {
                let _ = write!(q, "\\u{:04x}", c as u32);
            }
            c => q.push(c),
        }
    }
    q.push('"');
    q
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn json_escapes_and_nulls() {
        assert_eq!(quote("a\"b\\c\n"), "\"a\\\"b\\\\c\\u000a\"");
        assert_eq!(number(None), "null");
        assert_eq!(number(Some(f64::NAN)), "null");
        assert_eq!(number(Some(1.5)), "1.5");
        assert_eq!(
            json("s", &[]),
            "{\n  \"stage\": \"s\",\n  \"lights\": []\n}\n"
        );
    }
}
