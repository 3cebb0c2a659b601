//! `spectral-render lights STAGE [--json]`: the photometric report of every light (docs/design.md
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

use super::common::{clap_message, print_summary};
use super::frames::FrameArgs;
use crate::error::{Error, Result};
use crate::light::report::{self, LightReport};
use crate::output::json;
use crate::scene;
use clap::Parser;
use serde::Serialize;
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
    #[command(flatten)]
    when: FrameArgs,
}

/// Entry point: `argv[0]` is "lights".
pub fn main(argv: Vec<OsString>) -> Result<()> {
    let args = match LightsArgs::try_parse_from(argv) {
        Ok(args) => args,
        Err(e) if !e.use_stderr() => e.exit(),
        Err(e) => return Err(Error::option(clap_message(&e))),
    };
    let time = args.when.read_time();
    let scene = scene::load_at(&args.scene, None, scene::Machinery::default(), time)?;
    print_summary(&scene);
    let reports = report::report(&scene.lights);
    let out = if args.json {
        document(&args.scene.display().to_string(), &reports)?
    } else {
        table(&reports)
    };
    print!("{out}");
    Ok(())
}

/// The JSON document (format in the module docs).
#[derive(Serialize)]
struct Document<'a> {
    stage: &'a str,
    lights: Vec<LightJson<'a>>,
}

#[derive(Serialize)]
struct LightJson<'a> {
    prim: &'a str,
    #[serde(rename = "type")]
    kind: &'a str,
    luminous_flux_lm: Option<f64>,
    peak_intensity_cd: Option<f64>,
    luminance_cd_m2: Option<f64>,
    illuminance_lx: Option<f64>,
    area_m2: Option<f64>,
    radiant_flux_w: Option<f64>,
    chromaticity: Option<Xy>,
    cct_k: Option<f64>,
    duv: Option<f64>,
    luminous_efficacy_lm_w: Option<f64>,
    shaped: bool,
    note: Option<&'a str>,
}

#[derive(Serialize)]
struct Xy {
    x: f64,
    y: f64,
}

fn document(stage: &str, reports: &[LightReport]) -> Result<String> {
    let lights = reports
        .iter()
        .map(|r| LightJson {
            prim: &r.prim_path,
            kind: r.kind,
            luminous_flux_lm: r.luminous_flux,
            peak_intensity_cd: r.peak_intensity,
            luminance_cd_m2: r.luminance,
            illuminance_lx: r.illuminance,
            area_m2: r.area,
            radiant_flux_w: r.radiant_flux,
            chromaticity: r.spectrum.xy.map(|[x, y]| Xy { x, y }),
            cct_k: r.spectrum.cct.map(|c| c.kelvin),
            duv: r.spectrum.cct.map(|c| c.duv),
            luminous_efficacy_lm_w: r.spectrum.efficacy,
            shaped: r.shaped,
            note: r.note,
        })
        .collect();
    json::pretty(&Document { stage, lights })
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

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn json_escapes_the_stage_path() {
        assert_eq!(
            document("s\"", &[]).unwrap(),
            "{\n  \"stage\": \"s\\\"\",\n  \"lights\": []\n}\n"
        );
    }
}
