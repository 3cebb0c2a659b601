//! Reference images of `converge` as EXR files: read from any absolute EXR — ours (R, G, B
//! and XYZ.*) or another renderer's (R, G, B only, as Mitsuba 3 writes) — and written with
//! their measured noise.
//!
//! Channels read: `R`, `G`, `B` (required unless all of `XYZ.X`, `XYZ.Y`, `XYZ.Z` are there,
//! from which RGB is then computed); Y is `XYZ.Y`, else computed from RGB (Rec.709, D65);
//! `variance.R`, `variance.G`, `variance.B` and `variance.Y` (the per-pixel variance of the
//! reference's mean), when all four are present, make the noise known.

use super::exr;
use crate::converge::metrics::{Reference, ReferenceVariance};
use crate::error::{Error, Result};
use crate::spectral::color;
use std::collections::BTreeMap;
use std::path::Path;

/// The variance channels `converge` writes and reads.
pub const VARIANCE_CHANNELS: [&str; 4] = ["variance.R", "variance.G", "variance.B", "variance.Y"];

/// Reads a reference image (see the module docs); non-finite values are an error.
pub fn read(path: &Path) -> Result<Reference> {
    let image = exr::read(path)?;
    let fail = |reason: String| Error::io(path, format!("cannot use as a reference: {reason}"));
    let ch = &image.channels;
    let rgb = match (
        triple(ch, ["R", "G", "B"]),
        triple(ch, ["XYZ.X", "XYZ.Y", "XYZ.Z"]),
    ) {
        (Some(rgb), _) => rgb,
        (None, Some(xyz)) => xyz
            .iter()
            .map(|p| to_f32(color::xyz_to_rgb(p.map(f64::from))))
            .collect(),
        (None, None) => {
            let names: Vec<&str> = ch.keys().map(String::as_str).collect();
            return Err(fail(format!(
                "it has neither R, G, B nor XYZ.X, XYZ.Y, XYZ.Z channels (it has: {})",
                names.join(", ")
            )));
        }
    };
    let y = match ch.get("XYZ.Y") {
        Some(y) => y.clone(),
        None => rgb
            .iter()
            .map(|p| color::rgb_to_xyz(p.map(f64::from))[1] as f32)
            .collect(),
    };
    let variance = match (
        triple(ch, ["variance.R", "variance.G", "variance.B"]),
        ch.get("variance.Y"),
    ) {
        (Some(rgb), Some(y)) => Some(ReferenceVariance { rgb, y: y.clone() }),
        _ => None,
    };
    let finite = rgb.iter().flatten().chain(&y).all(|v| v.is_finite());
    if !finite {
        return Err(fail("it has NaN or infinite pixels".into()));
    }
    Ok(Reference {
        width: image.width,
        height: image.height,
        rgb,
        y,
        variance,
    })
}

/// Writes `reference` (RGB, XYZ from RGB, and its variance channels when known).
pub fn write(path: &Path, reference: &Reference, meta: &exr::ExrMetadata) -> Result<()> {
    let xyz: Vec<[f32; 3]> = reference
        .rgb
        .iter()
        .map(|p| to_f32(color::rgb_to_xyz(p.map(f64::from))))
        .collect();
    let mut extra = Vec::new();
    if let Some(v) = &reference.variance {
        for c in 0..3 {
            extra.push((VARIANCE_CHANNELS[c], v.rgb.iter().map(|p| p[c]).collect()));
        }
        extra.push((VARIANCE_CHANNELS[3], v.y.clone()));
    }
    let white = color::white_xy().map(|c| c as f32);
    exr::write_with_channels(
        path,
        reference.width,
        reference.height,
        &reference.rgb,
        &xyz,
        &extra,
        white,
        meta,
    )
}

/// Three channels as pixels, when all three are present.
fn triple(ch: &BTreeMap<String, Vec<f32>>, names: [&str; 3]) -> Option<Vec<[f32; 3]>> {
    let [a, b, c] = names.map(|n| ch.get(n));
    let (a, b, c) = (a?, b?, c?);
    Some((0..a.len()).map(|i| [a[i], b[i], c[i]]).collect())
}

fn to_f32(p: [f64; 3]) -> [f32; 3] {
    p.map(|c| c as f32)
}
