//! Reading raster images (lat-long dome textures; later material textures). The only
//! module that names the `image` crate.

use std::path::Path;

/// A decoded image as linear RGB, row-major, top row first.
pub struct RgbImage {
    pub width: usize,
    pub height: usize,
    pub pixels: Vec<[f32; 3]>,
}

/// Reads PNG, JPEG or EXR. 8- and 16-bit images are taken as sRGB-encoded and linearised
/// (IEC 61966-2-1); float images (EXR) are taken as linear.
pub fn read_rgb_linear(path: &Path) -> Result<RgbImage, String> {
    let img =
        image::open(path).map_err(|e| format!("cannot read image {}: {e}", path.display()))?;
    let is_float = matches!(
        img,
        image::DynamicImage::ImageRgb32F(_) | image::DynamicImage::ImageRgba32F(_)
    );
    let rgb = img.to_rgb32f();
    let (width, height) = (rgb.width() as usize, rgb.height() as usize);
    let decode = |v: f32| if is_float { v } else { srgb_to_linear(v) };
    let pixels = rgb
        .pixels()
        .map(|p| [decode(p.0[0]), decode(p.0[1]), decode(p.0[2])])
        .collect();
    Ok(RgbImage {
        width,
        height,
        pixels,
    })
}

/// Writes 8-bit RGB as PNG to `path` (the caller handles atomicity).
pub fn write_png_rgb8(path: &Path, width: usize, height: usize, data: &[u8]) -> Result<(), String> {
    image::save_buffer_with_format(
        path,
        data,
        width as u32,
        height as u32,
        image::ColorType::Rgb8,
        image::ImageFormat::Png,
    )
    .map_err(|e| format!("cannot write {}: {e}", path.display()))
}

/// The sRGB EOTF (IEC 61966-2-1).
pub fn srgb_to_linear(v: f32) -> f32 {
    if v <= 0.04045 {
        v / 12.92
    } else {
        ((v + 0.055) / 1.055).powf(2.4)
    }
}
