//! Reading raster images (lat-long dome textures; later material textures) and encoding
//! PNG. The only module that names the `image` crate (tests aside).

use crate::error::{Error, Result};
use image::codecs::png::PngEncoder;
use image::{ExtendedColorType, ImageDecoder, ImageEncoder};
use std::fs::File;
use std::io::{self, BufWriter, Write};
use std::path::Path;

/// The most pixels an image may have: 2^25 (8192 × 4096, an 8K lat-long dome), about 720 MB
/// once held as linear RGBA `f32` texels with their MIP pyramid.
pub const MAX_PIXELS: u64 = 1 << 25;

/// The most decoded sample bytes (at the file's own bit depth) one byte of file may declare:
/// deflate (PNG, zip-compressed EXR) packs at most 1032 bytes into one, and half-float EXR
/// channels are decoded to 32 bits; a file declaring more is truncated or corrupt.
const MAX_EXPANSION: u64 = 2100;

/// A decoded image as linear RGB, row-major, top row first.
pub struct RgbImage {
    pub width: usize,
    pub height: usize,
    pub pixels: Vec<[f32; 3]>,
}

/// Reads PNG, JPEG or EXR. 8- and 16-bit images are taken as sRGB-encoded and linearised
/// (IEC 61966-2-1); float images (EXR) are taken as linear.
pub fn read_rgb_linear(path: &Path) -> Result<RgbImage> {
    let raw = read_rgba_raw(path)?;
    let decode = |v: f32| if raw.is_float { v } else { srgb_to_linear(v) };
    let pixels = raw
        .pixels
        .iter()
        .map(|p| [decode(p[0]), decode(p[1]), decode(p[2])])
        .collect();
    Ok(RgbImage {
        width: raw.width,
        height: raw.height,
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
    let (width, height) = (img.width() as usize, img.height() as usize);
    Ok(RgbaImage {
        width,
        height,
        pixels: rgba_f32(img),
        is_float,
    })
}

/// The pixels as RGBA `f32`, converting 8-bit images directly (one copy of the image in
/// memory besides the result, not two).
fn rgba_f32(img: image::DynamicImage) -> Vec<[f32; 4]> {
    let unit = |v: u8| f32::from(v) / 255.0;
    match img {
        image::DynamicImage::ImageRgba8(b) => b.pixels().map(|p| p.0.map(unit)).collect(),
        image::DynamicImage::ImageRgb8(b) => b
            .pixels()
            .map(|p| [unit(p[0]), unit(p[1]), unit(p[2]), 1.0])
            .collect(),
        other => other.into_rgba32f().pixels().map(|p| p.0).collect(),
    }
}

/// Decodes the image at `path`: an I/O error when it cannot be read (or is not a regular
/// file), a scene error when it is not an image the decoder understands or its header
/// declares more pixels than [`MAX_PIXELS`] or than its size can hold.
fn open(path: &Path) -> Result<image::DynamicImage> {
    let cannot_read =
        |e: &dyn std::fmt::Display| Error::io(path, format!("cannot read image: {e}"));
    let file_bytes = match std::fs::metadata(path) {
        Ok(m) if m.is_file() => m.len(),
        Ok(_) => return Err(cannot_read(&"not a regular file")),
        Err(e) => return Err(cannot_read(&e)),
    };
    let cannot_decode =
        |e: image::ImageError| Error::scene(path, format!("cannot decode image: {e}"));
    let mut reader = image::ImageReader::open(path).map_err(|e| cannot_read(&e))?;
    let mut limits = image::Limits::default();
    limits.max_alloc = Some(MAX_PIXELS * 16 + (64 << 20));
    reader.limits(limits);
    let decoder = reader.into_decoder().map_err(cannot_decode)?;
    check_declared_size(&decoder, file_bytes).map_err(|r| Error::scene(path, r))?;
    image::DynamicImage::from_decoder(decoder).map_err(cannot_decode)
}

/// The header's size against [`MAX_PIXELS`] and the file's length, before decoding.
fn check_declared_size(
    decoder: &impl ImageDecoder,
    file_bytes: u64,
) -> std::result::Result<(), String> {
    let (w, h) = decoder.dimensions();
    let pixels = u64::from(w) * u64::from(h);
    if pixels > MAX_PIXELS {
        return Err(format!(
            "the image is {w}×{h} pixels; at most {MAX_PIXELS} (2^25, e.g. 8192×4096) are read"
        ));
    }
    let bits = u64::from(decoder.original_color_type().bits_per_pixel());
    let declared = pixels * bits / 8;
    if declared > MAX_EXPANSION * file_bytes + 4096 {
        return Err(format!(
            "the header declares {w}×{h} pixels ({declared} bytes) but the file has only \
             {file_bytes} bytes: it is truncated or corrupt"
        ));
    }
    Ok(())
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
