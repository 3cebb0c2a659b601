//! The 8-bit sRGB PNG preview: a quick look at a render, not a calibrated record (that is the
//! EXR). PNG encoding itself goes through `crate::imageio`, the one module naming `image`.
//!
//! Each linear Rec.709 component v becomes `round(255 · oetf(clamp(v · 2^exposure, 0, 1)))`
//! with the sRGB OETF of IEC 61966-2-1 (piecewise: linear below 0.0031308, then a 1/2.4
//! power). Clamping is a plain per-channel clip, no tone mapping; NaN is shown black and +Inf
//! white. No colour-space chunk is written: PNG viewers assume sRGB.

use std::path::Path;

use super::atomic::write_atomically;
use crate::error::{Error, Reason, Result};
use crate::imageio::encode_png_rgb8;

/// Writes `rgb` (linear, row-major, top row first, `width * height` pixels) scaled by
/// `2^exposure` as an 8-bit sRGB PNG, replacing `path` atomically (see `output::atomic`).
pub fn write_preview(
    path: &Path,
    width: usize,
    height: usize,
    rgb: &[[f32; 3]],
    exposure: f32,
) -> Result<()> {
    let fail = |reason: String| Error::io(path, format!("cannot write PNG: {reason}"));
    let (w, h) = check_size(width, height, rgb.len()).map_err(fail)?;
    let bytes = encode_srgb8(rgb, exposure);
    write_atomically(path, |file| encode_png_rgb8(file, &bytes, w, h))
        .map_err(|e| fail(e.to_string()))
}

/// Checks that `pixels` matches a non-empty `width × height` that PNG can hold (u32 sides).
fn check_size(width: usize, height: usize, pixels: usize) -> Reason<(u32, u32)> {
    if width == 0 || height == 0 {
        return Err(format!("the image is empty ({width}×{height} pixels)"));
    }
    if width.checked_mul(height) != Some(pixels) {
        return Err(format!(
            "{width}×{height} pixels expected, but {pixels} were given"
        ));
    }
    let too_large = |_| format!("{width}×{height} pixels is too large for PNG");
    Ok((
        u32::try_from(width).map_err(too_large)?,
        u32::try_from(height).map_err(too_large)?,
    ))
}

/// Interleaved 8-bit sRGB bytes of the exposed, clamped image.
fn encode_srgb8(rgb: &[[f32; 3]], exposure: f32) -> Vec<u8> {
    let scale = exposure.exp2();
    rgb.iter()
        .flat_map(|pixel| pixel.map(|v| srgb8(v * scale)))
        .collect()
}

/// One linear value to an 8-bit sRGB code value: clamp to [0, 1] (NaN → 0), OETF, round.
fn srgb8(linear: f32) -> u8 {
    let v = if linear.is_nan() {
        0.0
    } else {
        f64::from(linear.clamp(0.0, 1.0))
    };
    (255.0 * srgb_oetf(v)).round() as u8
}

/// The sRGB opto-electronic transfer function, IEC 61966-2-1:1999 §5.2 (eq. 5.2 inverted).
fn srgb_oetf(v: f64) -> f64 {
    if v <= 0.0031308 {
        12.92 * v
    } else {
        1.055 * v.powf(1.0 / 2.4) - 0.055
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::fs;
    use std::path::PathBuf;

    /// A fresh, empty directory unique to this test and process.
    fn temp_dir(name: &str) -> PathBuf {
        let dir =
            std::env::temp_dir().join(format!("spectral-render-png-{name}-{}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        fs::create_dir_all(&dir).unwrap();
        dir
    }

    /// Writes a preview and reads it back with the `image` crate.
    fn round_trip(name: &str, width: usize, rgb: &[[f32; 3]], exposure: f32) -> image::RgbImage {
        let dir = temp_dir(name);
        let path = dir.join("preview.png");
        write_preview(&path, width, rgb.len() / width, rgb, exposure).unwrap();
        let decoded = image::open(&path).unwrap().into_rgb8();
        assert_eq!(
            fs::read_dir(&dir).unwrap().count(),
            1,
            "temporary file left behind"
        );
        fs::remove_dir_all(&dir).unwrap();
        decoded
    }

    #[test]
    fn black_white_and_mid_grey_follow_the_srgb_oetf() {
        let png = round_trip(
            "values",
            3,
            &[[0.0; 3], [1.0; 3], [0.5, 0.0031308, 0.18]],
            0.0,
        );
        assert_eq!(png.as_raw(), &[0, 0, 0, 255, 255, 255, 188, 10, 118]);
    }

    #[test]
    fn exposure_scales_by_powers_of_two() {
        let png = round_trip("exposure", 2, &[[0.25, 2.0, 0.125], [1.0, 0.5, 4.0]], 1.0);
        assert_eq!(png.as_raw(), &[188, 255, 137, 255, 255, 255]);
        let png = round_trip("exposure-negative", 1, &[[2.0, 1.0, 0.0]], -1.0);
        assert_eq!(png.as_raw(), &[255, 188, 0]);
    }

    #[test]
    fn out_of_range_and_non_finite_values_are_clamped() {
        let rgb = [
            [1.5, -0.5, 1e30],
            [f32::NAN, f32::INFINITY, f32::NEG_INFINITY],
        ];
        let png = round_trip("clamp", 2, &rgb, 0.0);
        assert_eq!(png.as_raw(), &[255, 0, 255, 0, 255, 0]);
    }

    #[test]
    fn dimensions_and_row_order_are_kept() {
        let (width, height) = (5, 3);
        let rgb: Vec<[f32; 3]> = (0..width * height)
            .map(|i| [(i % width) as f32 / 4.0, (i / width) as f32 / 2.0, 0.0])
            .collect();
        let png = round_trip("dimensions", width, &rgb, 0.0);
        assert_eq!(png.dimensions(), (5, 3));
        assert_eq!(png.get_pixel(0, 0).0, [0, 0, 0]);
        assert_eq!(png.get_pixel(4, 0).0, [255, 0, 0]);
        assert_eq!(png.get_pixel(0, 2).0, [0, 255, 0]);
        assert_eq!(png.get_pixel(2, 1).0, [188, 188, 0]);
    }

    #[test]
    fn replaces_an_existing_file_atomically() {
        let dir = temp_dir("replace");
        let path = dir.join("preview.png");
        fs::write(&path, b"old preview").unwrap();
        write_preview(&path, 1, 1, &[[1.0, 0.0, 0.5]], 0.0).unwrap();
        assert_eq!(
            image::open(&path).unwrap().into_rgb8().as_raw(),
            &[255, 0, 188]
        );
        assert_eq!(fs::read_dir(&dir).unwrap().count(), 1);
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn errors_name_the_path_and_leave_nothing_behind() {
        let dir = temp_dir("errors");
        let missing = dir.join("no-such-dir").join("preview.png");
        let error = write_preview(&missing, 1, 1, &[[0.0; 3]], 0.0)
            .unwrap_err()
            .to_string();
        assert!(error.contains(&missing.display().to_string()), "{error}");
        let path = dir.join("preview.png");
        let error = write_preview(&path, 2, 2, &[[0.0; 3]], 0.0)
            .unwrap_err()
            .to_string();
        assert!(
            error.contains(&path.display().to_string()) && !error.contains('\n'),
            "{error}"
        );
        assert_eq!(fs::read_dir(&dir).unwrap().count(), 0);
        fs::remove_dir_all(&dir).unwrap();
    }
}
