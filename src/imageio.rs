//! Reading raster images (lat-long dome textures; later material textures) and encoding
//! PNG. The only module that names the `image` crate (tests aside).

use image::codecs::png::PngEncoder;
use image::{ExtendedColorType, ImageEncoder};
use std::fs::File;
use std::io::{self, BufWriter, Write};
use crate::error::{Error, Result};
use std::path::Path;

/// A decoded image as linear RGB, row-major, top row first.
pub struct RgbImage {
    pub width: usize,
    pub height: usize,
    pub pixels: Vec<[f32; 3]>,
}

/// Reads PNG, JPEG or EXR. 8- and 16-bit images are taken as sRGB-encoded and linearised
/// (IEC 61966-2-1); float images (EXR) are taken as linear.
pub fn read_rgb_linear(path: &Path) -> Result<RgbImage> {
    let img = open(path)?;
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

/// A decoded image as undecoded RGBA (no transfer function applied), row-major, top row
/// first; `is_float` tells whether the file stored floats (EXR) rather than 8/16-bit integers.
pub struct RgbaImage {
    pub width: usize,
    pub height: usize,
    pub pixels: Vec<[f32; 4]>,
    pub is_float: bool,
}

/// Reads PNG, JPEG or EXR as stored: integers mapped to [0, 1], floats as they are, alpha 1
/// when the file has none. The caller decides whether to linearise (material textures).
pub fn read_rgba_raw(path: &Path) -> Result<RgbaImage> {
    let img = open(path)?;
    let is_float = matches!(
        img,
        image::DynamicImage::ImageRgb32F(_) | image::DynamicImage::ImageRgba32F(_)
    );
    let rgba = img.to_rgba32f();
    let (width, height) = (rgba.width() as usize, rgba.height() as usize);
    let pixels = rgba.pixels().map(|p| p.0).collect();
    Ok(RgbaImage {
        width,
        height,
        pixels,
        is_float,
    })
}

/// Decodes the image at `path`: an I/O error when it cannot be read, a scene error when it
/// is not an image the decoder understands.
fn open(path: &Path) -> Result<image::DynamicImage> {
    let reader = image::ImageReader::open(path)
        .map_err(|e| Error::io(path, format!("cannot read image: {e}")))?;
    reader
        .decode()
        .map_err(|e| Error::scene(path, format!("cannot decode image: {e}")))
}

/// PNG-encodes 8-bit RGBA `bytes` into `path` (test images).
#[cfg(any(test, feature = "testing"))]
pub fn write_png_rgba8(path: &Path, bytes: &[u8], width: u32, height: u32) -> io::Result<()> {
    let mut file = File::create(path)?;
    let mut buffered = BufWriter::new(&mut file);
    PngEncoder::new(&mut buffered)
        .write_image(bytes, width, height, ExtendedColorType::Rgba8)
        .map_err(|e| io::Error::other(e.to_string()))?;
    buffered.flush()
}

/// PNG-encodes 8-bit RGB `bytes` into `file`, flushing the buffer explicitly so that write
/// errors are reported.
pub fn encode_png_rgb8(file: &mut File, bytes: &[u8], width: u32, height: u32) -> io::Result<()> {
    let mut buffered = BufWriter::new(file);
    PngEncoder::new(&mut buffered)
        .write_image(bytes, width, height, ExtendedColorType::Rgb8)
        .map_err(|e| io::Error::other(e.to_string()))?;
    buffered.flush()
}

/// The sRGB EOTF (IEC 61966-2-1).
pub fn srgb_to_linear(v: f32) -> f32 {
    if v <= 0.04045 {
        v / 12.92
    } else {
        ((v + 0.055) / 1.055).powf(2.4)
    }
}
