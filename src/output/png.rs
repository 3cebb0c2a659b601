//! The 8-bit PNG preview: a quick look at a render, not a calibrated record (that is the
//! EXR). The pixels arrive as display code values (`output::preview` runs the OCIO display
//! transform); each becomes `round(255 · clamp(v, 0, 1))`, NaN black. PNG encoding itself goes
//! through `crate::imageio`, the one module naming `image`. No colour-space chunk is written.

use std::path::Path;

use super::atomic::write_atomically;
use crate::error::{Error, Reason, Result};
use crate::imageio::encode_png_rgb8;

/// Writes `code` (display code values, row-major, top row first, `width * height` pixels) as
/// an 8-bit PNG, replacing `path` atomically (see `output::atomic`).
pub fn write_code_values(
    path: &Path,
    width: usize,
    height: usize,
    code: &[[f32; 3]],
) -> Result<()> {
    let fail = |reason: String| Error::io(path, format!("cannot write PNG: {reason}"));
    let (w, h) = check_size(width, height, code.len()).map_err(fail)?;
    let bytes: Vec<u8> = code.iter().flat_map(|p| p.map(code8)).collect();
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

/// One code value to 8 bits: clamp to [0, 1] (NaN → 0), round.
fn code8(v: f32) -> u8 {
    let v = if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) };
    (255.0 * v).round() as u8
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
    fn round_trip(name: &str, width: usize, code: &[[f32; 3]]) -> image::RgbImage {
        let dir = temp_dir(name);
        let path = dir.join("preview.png");
        write_code_values(&path, width, code.len() / width, code).unwrap();
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
    fn code_values_are_rounded_to_8_bits() {
        let png = round_trip("values", 3, &[[0.0; 3], [1.0; 3], [0.5, 0.002, 0.998]]);
        assert_eq!(png.as_raw(), &[0, 0, 0, 255, 255, 255, 128, 1, 254]);
    }

    #[test]
    fn out_of_range_and_non_finite_values_are_clamped() {
        let code = [
            [1.5, -0.5, 1e30],
            [f32::NAN, f32::INFINITY, f32::NEG_INFINITY],
        ];
        let png = round_trip("clamp", 2, &code);
        assert_eq!(png.as_raw(), &[255, 0, 255, 0, 255, 0]);
    }

    #[test]
    fn dimensions_and_row_order_are_kept() {
        let (width, height) = (5, 3);
        let code: Vec<[f32; 3]> = (0..width * height)
            .map(|i| [(i % width) as f32 / 4.0, (i / width) as f32 / 2.0, 0.0])
            .collect();
        let png = round_trip("dimensions", width, &code);
        assert_eq!(png.dimensions(), (5, 3));
        assert_eq!(png.get_pixel(0, 0).0, [0, 0, 0]);
        assert_eq!(png.get_pixel(4, 0).0, [255, 0, 0]);
        assert_eq!(png.get_pixel(0, 2).0, [0, 255, 0]);
        assert_eq!(png.get_pixel(2, 1).0, [128, 128, 0]);
    }

    #[test]
    fn replaces_an_existing_file_atomically() {
        let dir = temp_dir("replace");
        let path = dir.join("preview.png");
        fs::write(&path, b"old preview").unwrap();
        write_code_values(&path, 1, 1, &[[1.0, 0.0, 0.5]]).unwrap();
        assert_eq!(
            image::open(&path).unwrap().into_rgb8().as_raw(),
            &[255, 0, 128]
        );
        assert_eq!(fs::read_dir(&dir).unwrap().count(), 1);
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn errors_name_the_path_and_leave_nothing_behind() {
        let dir = temp_dir("errors");
        let missing = dir.join("no-such-dir").join("preview.png");
        let error = write_code_values(&missing, 1, 1, &[[0.0; 3]])
            .unwrap_err()
            .to_string();
        assert!(error.contains(&missing.display().to_string()), "{error}");
        let path = dir.join("preview.png");
        let error = write_code_values(&path, 2, 2, &[[0.0; 3]])
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
