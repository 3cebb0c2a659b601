//! The calibrated EXR image: the renderer's primary output. The only module that names the
//! `exr` crate.
//!
//! File layout (single part, scan lines of 16 rows, ZIP compression, so lossless; rows top to
//! bottom, i.e. increasing y):
//!
//! | channel | content |
//! |---|---|
//! | `R`, `G`, `B` | float32, in the working space (default linear Rec.709 / sRGB primaries with D65 white), absolute: (1, 1, 1) is D65 white of luminance 1 cd/m² (DESIGN §2) |
//! | `XYZ.X`, `XYZ.Y`, `XYZ.Z` | float32, CIE 1931 XYZ on the same absolute scale: `XYZ.Y` is luminance in cd/m² |
//!
//! | header attribute | type | value |
//! |---|---|---|
//! | `chromaticities` | chromaticities | the working space's (`--colorspace`, `ExrMetadata::working_space`): Rec.709 primaries red (0.64, 0.33), green (0.30, 0.60), blue (0.15, 0.06) with the white passed to [`write()`]; ACEScg, P3-D65 or XYZ (`spectral::working_space`) |
//! | `colorspace` | string | the working space's OCIO name, e.g. `ACEScg` or `Linear Rec.709 (sRGB)` |
//! | `whiteLuminance` | float | 2^(−exposure) cd/m²: the luminance of RGB (1, 1, 1), the camera's `exposure` having scaled the image by 2^exposure |
//! | `worldToCamera` | m44f | world (metres, Y up) to OpenEXR's camera space (left-handed, x right, y up, z along the view), when known |
//! | `worldToNDC` | m44f | world to OpenEXR's NDC ((0, 0) top left, (1, 1) bottom right, after the homogeneous divide), when known |
//! | `software` | string | `spectral-render <version>` |
//! | `spectralRender:spp` | int | samples per pixel |
//! | `spectralRender:seed` | int | sampler seed; a seed above 2^31 − 1 is a string of its decimal digits (EXR's int is 32-bit) |
//! | `spectralRender:maxDepth` | int | maximum number of scattering events; −1: unlimited (Russian roulette and the safety cap) |
//! | `spectralRender:rrDepth` | int | the path tracer's first bounce of Russian roulette (`--rr-depth`), when the path tracer made the image |
//! | `spectralRender:split` | int | the continuations the path tracer split each path into at its first vertex (`--split`), when the path tracer made the image |
//! | `spectralRender:exposure` | float | the camera's exposure in stops |
//! | `spectralRender:integrator` | string | integrator name |
//! | `spectralRender:mis` | string | the MIS heuristic (`power`, `balance`), for integrators that combine techniques |
//! | `spectralRender:sampler` | string | the sampler the samples drew from (`zsobol`, `independent`; `--sampler` applies to the path tracer and to the camera subpaths of BDPT and VCM; light tracing draws independent numbers), when known |
//! | `spectralRender:wallTime` | double | render wall-clock time in seconds |
//! | `spectralRender:version` | string | renderer version |
//! | `spectralRender:scene` | string | the scene file, UTF-8 |
//! | `spectralRender:timeCode` | double | the USD time code the stage was read at (`--frame`, each frame of `--frames`, else the stage's `startTimeCode`); absent when the stage was read at each attribute's earliest sample (no time range authored, no `--frame`) |
//! | `spectralRender:usdFramesPerSecond`, `spectralRender:timeCodesPerSecond` | double | the stage's `framesPerSecond` and `timeCodesPerSecond` metadata, when authored |
//! | `framesPerSecond` | rational | OpenEXR's standard attribute: the stage's authored `framesPerSecond` when positive, as n/1 for whole rates, k·1000/1001 for the NTSC rates (23.976, 29.97, …), else n/1000 |
//!
//! The time code is namespaced because OpenEXR's own `timeCode` attribute is a SMPTE time
//! code (hours, minutes, seconds, frames), not a USD time code.
//!
//! Matrices are stored as OpenEXR's `M44f` is (Imath's row-vector convention, p' = p·M, the
//! translation in the last row), which is the column-vector matrix's columns in order.
//! Strings are written as UTF-8 bytes, as OpenEXR's C++ library does. Samples per pixel fit
//! the 32-bit int: a render stops at 2^31 − 1 (`session::image::MAX_SPP`).
//!
//! [`read`] returns every channel as f32 by name and every header attribute as a string:
//! strings verbatim, numbers in Rust's shortest round-trip notation (so `whiteLuminance` reads
//! `"1"`), `chromaticities` as eight space-separated numbers `rx ry gx gy bx by wx wy`,
//! matrices as their sixteen numbers in stored order, other types in their `Debug` form;
//! [`ExrImage::types`] names each attribute's type (`int`, `float`, `double`, `string`, …).

use std::collections::BTreeMap;
use std::fs::File;
use std::io::{self, BufWriter, Cursor, Write};
use std::path::Path;

use exr::image::read::image::ReadLayers;
use exr::image::read::layers::ReadChannels;
use exr::image::read::read as read_exr;
use exr::image::write::WritableImage;
use exr::image::{AnyChannel, AnyChannels, Encoding, FlatSamples, Image, Layer};
use exr::math::Vec2;
use exr::meta::attribute::{AttributeValue, Chromaticities, Text};
use exr::meta::header::LayerAttributes;
use exr::meta::MetaData;

use super::atomic::write_atomically;
use crate::error::{Error, Reason, Result};
use crate::spectral::working_space::WorkingSpace;

/// Rec.709 / sRGB primaries (ITU-R BT.709-6, table 1 item 1.3) as CIE 1931 xy: red, green, blue.
pub const REC709_PRIMARIES_XY: [[f32; 2]; 3] = [[0.64, 0.33], [0.30, 0.60], [0.15, 0.06]];

/// Names of the metadata attributes written from [`ExrMetadata`].
pub const SPP_ATTRIBUTE: &str = "spectralRender:spp";
pub const INTEGRATOR_ATTRIBUTE: &str = "spectralRender:integrator";
pub const SEED_ATTRIBUTE: &str = "spectralRender:seed";
pub const WALL_TIME_ATTRIBUTE: &str = "spectralRender:wallTime";
pub const VERSION_ATTRIBUTE: &str = "spectralRender:version";
pub const SCENE_ATTRIBUTE: &str = "spectralRender:scene";
pub const MAX_DEPTH_ATTRIBUTE: &str = "spectralRender:maxDepth";
pub const RR_DEPTH_ATTRIBUTE: &str = "spectralRender:rrDepth";
pub const SPLIT_ATTRIBUTE: &str = "spectralRender:split";
pub const EXPOSURE_ATTRIBUTE: &str = "spectralRender:exposure";
pub const MIS_ATTRIBUTE: &str = "spectralRender:mis";
pub const TIME_CODE_ATTRIBUTE: &str = "spectralRender:timeCode";
pub const USD_FPS_ATTRIBUTE: &str = "spectralRender:usdFramesPerSecond";
pub const TIME_CODES_PER_SECOND_ATTRIBUTE: &str = "spectralRender:timeCodesPerSecond";
/// OpenEXR's standard frame-rate attribute (rational).
pub const FPS_ATTRIBUTE: &str = "framesPerSecond";
pub const SAMPLER_ATTRIBUTE: &str = "spectralRender:sampler";
/// The OCIO name of the RGB channels' colour space (the attribute OCIO-aware readers use).
pub const COLORSPACE_ATTRIBUTE: &str = "colorspace";

/// The names of the six channels, in the order of `rgb` then `xyz` components.
const CHANNEL_NAMES: [&str; 6] = ["R", "G", "B", "XYZ.X", "XYZ.Y", "XYZ.Z"];

/// How the image was made (see the module docs for the attributes).
#[derive(Clone, Debug, Default)]
pub struct ExrMetadata {
    pub spp: u64,
    pub integrator: String,
    /// The MIS heuristic, for integrators that combine techniques.
    pub mis: Option<String>,
    /// The sampler's name (`SamplerKind::name`), when known.
    pub sampler: Option<String>,
    pub seed: u64,
    /// The depth cap; None: unlimited (written as −1).
    pub max_depth: Option<u32>,
    /// The path tracer's first bounce of Russian roulette, when the path tracer made the image.
    pub rr_depth: Option<u32>,
    /// The path tracer's split at the first vertex, when the path tracer made the image.
    pub split: Option<u32>,
    /// The camera's exposure in stops: the image was scaled by 2^exposure.
    pub exposure: f32,
    pub wall_time_s: f64,
    pub version: String,
    pub scene: String,
    /// World to OpenEXR camera space and to NDC, column-vector matrices as 16 values in
    /// column order.
    pub world_to_camera: Option<[f32; 16]>,
    pub world_to_ndc: Option<[f32; 16]>,
    /// The space of the R, G, B channels (`--colorspace`): the `chromaticities` and
    /// `colorspace` attributes.
    pub working_space: WorkingSpace,
    /// The USD time the stage was read at, when it was one time code.
    pub time: TimeMetadata,
}

/// The USD time code of the image and the stage's rates (see the module docs).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TimeMetadata {
    pub time_code: Option<f64>,
    pub frames_per_second: Option<f64>,
    pub time_codes_per_second: Option<f64>,
}

/// An EXR file as read back: every channel by name (row-major, rows top to bottom) and every
/// header attribute as a string (format in the module docs).
#[derive(Clone, Debug)]
pub struct ExrImage {
    pub width: usize,
    pub height: usize,
    pub channels: BTreeMap<String, Vec<f32>>,
    pub attributes: BTreeMap<String, String>,
    /// The type of each attribute: `int`, `float`, `double`, `string`, `m44f`, or its
    /// `Debug` name for others.
    pub types: BTreeMap<String, String>,
}

/// Writes a float32 EXR with channels R, G, B and XYZ.X, XYZ.Y, XYZ.Z from the row-major
/// (top row first) `rgb` and `xyz` buffers of `width * height` pixels, with the header
/// described in the module docs; `white_xy` is the white point of the `chromaticities`
/// attribute (D65 for our RGB).
///
/// The file is replaced atomically (see `output::atomic`). A NaN or infinite value is refused
/// with an error naming the first such pixel, and nothing is written.
pub fn write(
    path: &Path,
    width: usize,
    height: usize,
    rgb: &[[f32; 3]],
    xyz: &[[f32; 3]],
    white_xy: [f32; 2],
    meta: &ExrMetadata,
) -> Result<()> {
    write_with_channels(path, width, height, rgb, xyz, &[], white_xy, meta)
}

/// [`write()`] with `extra` float32 channels (name, one value per pixel) after the six, e.g.
/// a reference's `variance.R` (`converge`). Extra values must be finite too.
#[allow(clippy::too_many_arguments)]
pub fn write_with_channels(
    path: &Path,
    width: usize,
    height: usize,
    rgb: &[[f32; 3]],
    xyz: &[[f32; 3]],
    extra: &[(&str, Vec<f32>)],
    white_xy: [f32; 2],
    meta: &ExrMetadata,
) -> Result<()> {
    let layers = ExrLayers {
        channels: extra
            .iter()
            .map(|(n, v)| (n.to_string(), v.clone()))
            .collect(),
        strings: Vec::new(),
    };
    write_with_layers(path, width, height, rgb, xyz, &layers, white_xy, meta)
}

/// Extra float32 channels and string attributes written beside R, G, B and XYZ
/// (`output::layers`: spectral radiance, AOVs).
#[derive(Clone, Debug, Default)]
pub struct ExrLayers {
    /// (channel name, one value per pixel, row-major).
    pub channels: Vec<(String, Vec<f32>)>,
    /// (attribute name, string value) in the header.
    pub strings: Vec<(String, String)>,
}

/// [`write()`] with the `layers`' channels and string attributes; every value must be
/// finite, and an attribute may not replace one of the module's.
#[allow(clippy::too_many_arguments)]
pub fn write_with_layers(
    path: &Path,
    width: usize,
    height: usize,
    rgb: &[[f32; 3]],
    xyz: &[[f32; 3]],
    layers: &ExrLayers,
    white_xy: [f32; 2],
    meta: &ExrMetadata,
) -> Result<()> {
    let whole = [0, 0, width, height];
    write_window(
        path,
        (width, height),
        whole,
        rgb,
        xyz,
        layers,
        white_xy,
        meta,
    )
}

/// [`write_with_layers()`] of a window of an image (`--crop`, a stage's `dataWindowNDC`):
/// `rgb`, `xyz` and the layers' channels hold the window's `window.2 × window.3` pixels at
/// (`window.0`, `window.1`) of a `full.0 × full.1` image. The file's data window is the
/// window, its display window the full image.
#[allow(clippy::too_many_arguments)]
pub fn write_window(
    path: &Path,
    full: (usize, usize),
    window: [usize; 4],
    rgb: &[[f32; 3]],
    xyz: &[[f32; 3]],
    layers: &ExrLayers,
    white_xy: [f32; 2],
    meta: &ExrMetadata,
) -> Result<()> {
    let fail = |reason: String| Error::io(path, format!("cannot write EXR: {reason}"));
    let [x, y, width, height] = window;
    let to_i32 = |v: usize| i32::try_from(v).map_err(|_| fail(format!("{v} pixels is too far")));
    let (x, y, fw, fh) = (to_i32(x)?, to_i32(y)?, full.0, full.1);
    let mut image =
        layered_image((width, height), rgb, xyz, layers, white_xy, meta).map_err(fail)?;
    image.layer_data.attributes.layer_position = Vec2(x, y);
    image.attributes.display_window = exr::meta::attribute::IntegerBounds::new((0, 0), (fw, fh));
    write_atomically(path, |file| encode(image, file)).map_err(|e| fail(e.to_string()))
}

/// The image of a `size.0 × size.1` block of pixels with the `layers`' channels and
/// attributes, every value checked finite.
fn layered_image(
    (width, height): (usize, usize),
    rgb: &[[f32; 3]],
    xyz: &[[f32; 3]],
    layers: &ExrLayers,
    white_xy: [f32; 2],
    meta: &ExrMetadata,
) -> std::result::Result<FlatImage, String> {
    check_sizes(width, height, rgb.len(), xyz.len())?;
    check_finite(width, rgb, xyz)?;
    let extra: Vec<(&str, Vec<f32>)> = layers
        .channels
        .iter()
        .map(|(n, v)| (n.as_str(), v.clone()))
        .collect();
    for (name, values) in &extra {
        if values.len() != rgb.len() || !values.iter().all(|v| v.is_finite()) {
            return Err(format!("channel {name} needs one finite value per pixel"));
        }
    }
    if !white_xy.iter().all(|c| c.is_finite()) {
        return Err(format!("white point {white_xy:?} is not finite"));
    }
    let mut image = build_image(width, height, rgb, xyz, &extra, white_xy, meta);
    let other = &mut image.layer_data.attributes.other;
    for (name, value) in &layers.strings {
        if other
            .insert(text(name), AttributeValue::Text(text(value)))
            .is_some()
        {
            return Err(format!("attribute {name} is written twice"));
        }
    }
    Ok(image)
}

/// Reads an EXR file: all channels of its first layer by name, converted to f32, and all
/// header attributes of its first part as strings.
pub fn read(path: &Path) -> Result<ExrImage> {
    let fail = |reason: String| Error::io(path, format!("cannot read EXR: {reason}"));
    let bytes = std::fs::read(path).map_err(|e| fail(e.to_string()))?;
    let (attributes, types) = read_attributes(&bytes).map_err(fail)?;
    let (width, height, channels) = read_channels(&bytes).map_err(fail)?;
    Ok(ExrImage {
        width,
        height,
        channels,
        attributes,
        types,
    })
}

type Channels = BTreeMap<String, Vec<f32>>;

type Attributes = BTreeMap<String, String>;

/// Every attribute of the first header, formatted as the module docs say, and its type.
fn read_attributes(bytes: &[u8]) -> Reason<(Attributes, Attributes)> {
    let meta =
        MetaData::read_from_buffered(Cursor::new(bytes), false).map_err(|e| e.to_string())?;
    let header = meta.headers.first().ok_or("the file has no header")?;
    let (mut values, mut types) = (BTreeMap::new(), BTreeMap::new());
    for (name, value) in header.all_named_attributes() {
        values.insert(utf8(name), attribute_to_string(&value));
        types.insert(utf8(name), type_name(&value));
    }
    Ok((values, types))
}

fn type_name(value: &AttributeValue) -> String {
    match value {
        AttributeValue::I32(_) => "int".into(),
        AttributeValue::F32(_) => "float".into(),
        AttributeValue::F64(_) => "double".into(),
        AttributeValue::Text(_) => "string".into(),
        AttributeValue::Matrix4x4(_) => "m44f".into(),
        AttributeValue::Rational(_) => "rational".into(),
        other => format!("{other:?}")
            .split(['(', ' ', '{'])
            .next()
            .unwrap_or("")
            .to_string(),
    }
}

/// Width, height and the f32 samples of every channel of the first layer.
fn read_channels(bytes: &[u8]) -> Reason<(usize, usize, Channels)> {
    let image = read_exr()
        .no_deep_data()
        .largest_resolution_level()
        .all_channels()
        .first_valid_layer()
        .all_attributes()
        .from_buffered(Cursor::new(bytes))
        .map_err(|e| e.to_string())?;
    let layer = image.layer_data;
    let channel = |c: &AnyChannel<FlatSamples>| {
        (
            utf8(c.name.as_slice()),
            c.sample_data.values_as_f32().collect(),
        )
    };
    let channels = layer.channel_data.list.iter().map(channel).collect();
    Ok((layer.size.width(), layer.size.height(), channels))
}

fn check_sizes(width: usize, height: usize, rgb: usize, xyz: usize) -> Reason<()> {
    if width == 0 || height == 0 {
        return Err(format!("the image is empty ({width}×{height} pixels)"));
    }
    let pixels = width
        .checked_mul(height)
        .ok_or("the image size overflows")?;
    if rgb != pixels || xyz != pixels {
        return Err(format!(
            "{width}×{height} = {pixels} pixels, but {rgb} RGB and {xyz} XYZ values were given"
        ));
    }
    Ok(())
}

/// Finds the first pixel (row-major; R, G, B, X, Y, Z within a pixel) with a NaN or Inf.
fn check_finite(width: usize, rgb: &[[f32; 3]], xyz: &[[f32; 3]]) -> Reason<()> {
    for (index, (rgb, xyz)) in rgb.iter().zip(xyz).enumerate() {
        let values = rgb.iter().chain(xyz);
        if let Some((name, value)) = CHANNEL_NAMES
            .iter()
            .zip(values)
            .find(|(_, v)| !v.is_finite())
        {
            let (x, y) = (index % width, index / width);
            return Err(format!(
                "pixel ({x}, {y}) has the non-finite value {value} in channel {name}; \
                 refusing to write it"
            ));
        }
    }
    Ok(())
}

type FlatImage = Image<Layer<AnyChannels<FlatSamples>>>;

fn build_image(
    width: usize,
    height: usize,
    rgb: &[[f32; 3]],
    xyz: &[[f32; 3]],
    extra: &[(&str, Vec<f32>)],
    white_xy: [f32; 2],
    meta: &ExrMetadata,
) -> FlatImage {
    let channel = |name: &str, pixels: &[[f32; 3]], component: usize| {
        let samples = pixels.iter().map(|p| p[component]).collect();
        // Luminance-like data for every channel (matters only to lossy B44 compression).
        AnyChannel {
            quantize_linearly: false,
            ..AnyChannel::new(name, FlatSamples::F32(samples))
        }
    };
    let list: Vec<_> = (0..3)
        .map(|c| channel(CHANNEL_NAMES[c], rgb, c))
        .chain((0..3).map(|c| channel(CHANNEL_NAMES[3 + c], xyz, c)))
        .chain(extra.iter().map(|(name, values)| AnyChannel {
            quantize_linearly: false,
            ..AnyChannel::new(*name, FlatSamples::F32(values.clone()))
        }))
        .collect();
    let layer = Layer::new(
        (width, height),
        layer_attributes(meta),
        Encoding::SMALL_LOSSLESS,
        AnyChannels::sort(list.into()),
    );
    let mut image = Image::from_layer(layer);
    image.attributes.chromaticities = Some(chromaticities(meta.working_space, white_xy));
    image
}

/// The `chromaticities` of the RGB channels: Rec.709 with the white passed, or the working
/// space's primaries and white.
fn chromaticities(space: WorkingSpace, white_xy: [f32; 2]) -> Chromaticities {
    let (primaries, white) = match space {
        WorkingSpace::LinRec709 => (REC709_PRIMARIES_XY, white_xy),
        _ => {
            let c = space.chromaticities();
            (
                c.primaries.map(|p| p.map(|v| v as f32)),
                c.white.map(|v| v as f32),
            )
        }
    };
    let [red, green, blue] = primaries.map(|[x, y]| Vec2(x, y));
    Chromaticities {
        red,
        green,
        blue,
        white: Vec2(white[0], white[1]),
    }
}

fn layer_attributes(meta: &ExrMetadata) -> LayerAttributes {
    let mut attributes = LayerAttributes {
        white_luminance: Some((-meta.exposure).exp2()),
        software_name: Some(text(format!("spectral-render {}", meta.version).trim_end())),
        world_to_camera: meta.world_to_camera,
        world_to_normalized_device: meta.world_to_ndc,
        ..LayerAttributes::default()
    };
    let int = |v: u64| i32::try_from(v).ok().map(AttributeValue::I32);
    let string = |v: &str| AttributeValue::Text(text(v));
    let mut typed = vec![
        (
            SPP_ATTRIBUTE,
            int(meta.spp).unwrap_or_else(|| string(&meta.spp.to_string())),
        ),
        (
            SEED_ATTRIBUTE,
            int(meta.seed).unwrap_or_else(|| string(&meta.seed.to_string())),
        ),
        (
            MAX_DEPTH_ATTRIBUTE,
            match meta.max_depth {
                Some(d) => int(u64::from(d)).unwrap_or(AttributeValue::I32(i32::MAX)),
                None => AttributeValue::I32(-1),
            },
        ),
        (EXPOSURE_ATTRIBUTE, AttributeValue::F32(meta.exposure)),
        (INTEGRATOR_ATTRIBUTE, string(&meta.integrator)),
        (WALL_TIME_ATTRIBUTE, AttributeValue::F64(meta.wall_time_s)),
        (VERSION_ATTRIBUTE, string(&meta.version)),
        (SCENE_ATTRIBUTE, string(&meta.scene)),
        (COLORSPACE_ATTRIBUTE, string(meta.working_space.ocio_name())),
    ];
    if let Some(mis) = &meta.mis {
        typed.push((MIS_ATTRIBUTE, string(mis)));
    }
    if let Some(d) = meta.rr_depth.and_then(|d| int(u64::from(d))) {
        typed.push((RR_DEPTH_ATTRIBUTE, d));
    }
    if let Some(n) = meta.split.and_then(|n| int(u64::from(n))) {
        typed.push((SPLIT_ATTRIBUTE, n));
    }
    let time = &meta.time;
    for (name, v) in [
        (TIME_CODE_ATTRIBUTE, time.time_code),
        (USD_FPS_ATTRIBUTE, time.frames_per_second),
        (TIME_CODES_PER_SECOND_ATTRIBUTE, time.time_codes_per_second),
    ] {
        if let Some(v) = v.filter(|v| v.is_finite()) {
            typed.push((name, AttributeValue::F64(v)));
        }
    }
    attributes.frames_per_second = time.frames_per_second.and_then(rational);
    if let Some(sampler) = &meta.sampler {
        typed.push((SAMPLER_ATTRIBUTE, string(sampler)));
    }
    for (name, value) in typed {
        attributes.other.insert(text(name), value);
    }
    attributes
}

/// A frame rate as OpenEXR's rational: n/1 for whole rates, k·1000/1001 for the NTSC family
/// (24000/1001 ≈ 23.976, 30000/1001 ≈ 29.97, …), each to 10⁻³, else to the nearest 1/1000;
/// None for a rate that is not positive or does not fit.
fn rational(fps: f64) -> Option<(i32, u32)> {
    if !(fps.is_finite() && fps > 0.0 && fps < 1e6) {
        return None;
    }
    let whole = fps.round();
    if (whole - fps).abs() < 1e-3 {
        return (whole >= 1.0).then_some((whole as i32, 1));
    }
    // The NTSC rates are k·1000/1001 for a whole k (SMPTE ST 12-1).
    let k = (fps * 1.001).round();
    if k >= 1.0 && (k * 1000.0 / 1001.0 - fps).abs() < 1e-3 {
        return Some(((k * 1000.0) as i32, 1001));
    }
    let n = (fps * 1000.0).round();
    (n >= 1.0).then_some((n as i32, 1000))
}

/// Encodes `image` into `file` through a buffer that is flushed explicitly, so that write
/// errors are reported rather than lost when the buffer is dropped.
fn encode(image: FlatImage, file: &mut File) -> io::Result<()> {
    let mut buffered = BufWriter::new(file);
    image
        .write()
        .to_buffered(&mut buffered)
        .map_err(|e| io::Error::other(e.to_string()))?;
    buffered.flush()
}

/// An EXR text holding the UTF-8 bytes of `s` (`Text::from` would panic outside Latin-1).
fn text(s: &str) -> Text {
    Text::from_slice_unchecked(s.as_bytes())
}

fn utf8(bytes: &[u8]) -> String {
    String::from_utf8_lossy(bytes).into_owned()
}

fn attribute_to_string(value: &AttributeValue) -> String {
    match value {
        AttributeValue::Text(text) => utf8(text.as_slice()),
        AttributeValue::F32(v) => v.to_string(),
        AttributeValue::F64(v) => v.to_string(),
        AttributeValue::I32(v) => v.to_string(),
        AttributeValue::Rational((n, d)) => format!("{n}/{d}"),
        AttributeValue::Chromaticities(c) => [c.red, c.green, c.blue, c.white]
            .iter()
            .flat_map(|v| [v.x(), v.y()])
            .map(|v| v.to_string())
            .collect::<Vec<_>>()
            .join(" "),
        AttributeValue::Matrix4x4(m) => m
            .iter()
            .map(|v| v.to_string())
            .collect::<Vec<_>>()
            .join(" "),
        other => format!("{other:?}"),
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use std::fs;
    use std::path::PathBuf;

    const D65_XY: [f32; 2] = [0.3127, 0.3290];

    /// A fresh, empty directory unique to this test and process.
    fn temp_dir(name: &str) -> PathBuf {
        let dir =
            std::env::temp_dir().join(format!("spectral-render-exr-{name}-{}", std::process::id()));
        let _ = fs::remove_dir_all(&dir);
        fs::create_dir_all(&dir).unwrap();
        dir
    }

    fn entries(dir: &Path) -> Vec<String> {
        let mut names: Vec<String> = fs::read_dir(dir)
            .unwrap()
            .map(|entry| entry.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        names
    }

    /// A 3×2 image whose values exercise signs, subnormals, extremes and exact bit patterns.
    fn test_image() -> (Vec<[f32; 3]>, Vec<[f32; 3]>) {
        let rgb = vec![
            [0.0, 1.0, 0.5],
            [-0.0, -2.5, 1e-40],
            [f32::MAX, f32::MIN_POSITIVE, 1.0 / 3.0],
            [0.1, 0.2, 0.3],
            [123456.79, -7e-3, 2.0f32.powi(-20)],
            [1.0, 1.0, 1.0],
        ];
        let xyz = rgb
            .iter()
            .map(|p| [p[2] * 0.9, p[0] + 1.0, -p[1]])
            .collect();
        (rgb, xyz)
    }

    fn test_meta() -> ExrMetadata {
        ExrMetadata {
            spp: 1 << 20,
            integrator: "vcm".into(),
            mis: Some("balance".into()),
            sampler: Some("zsobol".into()),
            seed: u64::MAX,
            max_depth: Some(12),
            rr_depth: Some(5),
            split: Some(4),
            exposure: -8.0,
            wall_time_s: 12.345678901234567,
            version: "0.1.0".into(),
            scene: "scenes/Bühne – 場景.usda".into(),
            world_to_camera: Some(std::array::from_fn(|i| i as f32)),
            world_to_ndc: Some(std::array::from_fn(|i| -(i as f32) / 4.0)),
            working_space: WorkingSpace::LinRec709,
            time: TimeMetadata {
                time_code: Some(12.5),
                frames_per_second: Some(24000.0 / 1001.0),
                time_codes_per_second: Some(48.0),
            },
        }
    }

    #[test]
    fn time_codes_and_rates_are_read_back() {
        let dir = std::env::temp_dir().join(format!("exr-time-{}", std::process::id()));
        fs::create_dir_all(&dir).unwrap();
        let path = dir.join("t.exr");
        let (rgb, xyz) = test_image();
        write(&path, 3, 2, &rgb, &xyz, D65_XY, &test_meta()).unwrap();
        let img = read(&path).unwrap();
        assert_eq!(img.attributes[TIME_CODE_ATTRIBUTE], "12.5");
        assert_eq!(img.types[TIME_CODE_ATTRIBUTE], "double");
        assert_eq!(
            img.attributes[USD_FPS_ATTRIBUTE],
            (24000.0 / 1001.0).to_string()
        );
        assert_eq!(img.attributes[TIME_CODES_PER_SECOND_ATTRIBUTE], "48");
        assert_eq!(img.attributes[FPS_ATTRIBUTE], "24000/1001");
        assert_eq!(img.types[FPS_ATTRIBUTE], "rational");
        // Without a time, none of them.
        let meta = ExrMetadata {
            time: TimeMetadata::default(),
            ..test_meta()
        };
        write(&path, 3, 2, &rgb, &xyz, D65_XY, &meta).unwrap();
        let img = read(&path).unwrap();
        for name in [TIME_CODE_ATTRIBUTE, USD_FPS_ATTRIBUTE, FPS_ATTRIBUTE] {
            assert!(!img.attributes.contains_key(name), "{name}");
        }
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn frame_rates_become_rationals() {
        assert_eq!(rational(24.0), Some((24, 1)));
        assert_eq!(rational(23.976), Some((24000, 1001)));
        assert_eq!(rational(29.97), Some((30000, 1001)));
        assert_eq!(rational(12.5), Some((12500, 1000)));
        assert_eq!(rational(59.94), Some((60000, 1001)));
        assert_eq!(rational(23.5), Some((23500, 1000)));
        for bad in [0.0, -1.0, f64::NAN, f64::INFINITY, 1e9] {
            assert_eq!(rational(bad), None, "{bad}");
        }
    }

    fn component(pixels: &[[f32; 3]], c: usize) -> Vec<u32> {
        pixels.iter().map(|p| p[c].to_bits()).collect()
    }

    fn bits(values: &[f32]) -> Vec<u32> {
        values.iter().map(|v| v.to_bits()).collect()
    }

    #[test]
    fn round_trip_is_bit_exact_in_all_six_channels() {
        let dir = temp_dir("round-trip");
        let path = dir.join("image.exr");
        let (rgb, xyz) = test_image();
        write(&path, 3, 2, &rgb, &xyz, D65_XY, &test_meta()).unwrap();
        let image = read(&path).unwrap();
        assert_eq!((image.width, image.height), (3, 2));
        let names: Vec<&str> = image.channels.keys().map(String::as_str).collect();
        assert_eq!(names, ["B", "G", "R", "XYZ.X", "XYZ.Y", "XYZ.Z"]);
        for c in 0..3 {
            assert_eq!(bits(&image.channels[CHANNEL_NAMES[c]]), component(&rgb, c));
            assert_eq!(
                bits(&image.channels[CHANNEL_NAMES[3 + c]]),
                component(&xyz, c)
            );
        }
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn header_carries_colorimetry_and_metadata() {
        let dir = temp_dir("header");
        let path = dir.join("image.exr");
        let (rgb, xyz) = test_image();
        write(&path, 3, 2, &rgb, &xyz, D65_XY, &test_meta()).unwrap();
        let attributes = read(&path).unwrap().attributes;
        let chromaticities: Vec<f32> = attributes["chromaticities"]
            .split(' ')
            .map(|v| v.parse().unwrap())
            .collect();
        assert_eq!(
            chromaticities,
            [0.64, 0.33, 0.30, 0.60, 0.15, 0.06, 0.3127, 0.3290]
        );
        assert_eq!(attributes["whiteLuminance"], "256");
        assert_eq!(attributes[SPP_ATTRIBUTE], "1048576");
        assert_eq!(attributes[INTEGRATOR_ATTRIBUTE], "vcm");
        assert_eq!(attributes[MIS_ATTRIBUTE], "balance");
        assert_eq!(attributes[SAMPLER_ATTRIBUTE], "zsobol");
        assert_eq!(attributes[SEED_ATTRIBUTE], "18446744073709551615");
        assert_eq!(attributes[MAX_DEPTH_ATTRIBUTE], "12");
        assert_eq!(attributes[RR_DEPTH_ATTRIBUTE], "5");
        assert_eq!(attributes[SPLIT_ATTRIBUTE], "4");
        assert_eq!(attributes[EXPOSURE_ATTRIBUTE], "-8");
        let wall_time: f64 = attributes[WALL_TIME_ATTRIBUTE].parse().unwrap();
        assert_eq!(wall_time, 12.345678901234567);
        let m: Vec<f32> = attributes["worldToCamera"]
            .split(' ')
            .map(|v| v.parse().unwrap())
            .collect();
        assert_eq!(m, (0..16).map(|i| i as f32).collect::<Vec<_>>());
        assert!(attributes.contains_key("worldToNDC"));
        assert_eq!(attributes[VERSION_ATTRIBUTE], "0.1.0");
        assert_eq!(attributes[SCENE_ATTRIBUTE], "scenes/Bühne – 場景.usda");
        assert_eq!(attributes["software"], "spectral-render 0.1.0");
        let types = read(&path).unwrap().types;
        for (name, ty) in [
            (SPP_ATTRIBUTE, "int"),
            (MAX_DEPTH_ATTRIBUTE, "int"),
            (RR_DEPTH_ATTRIBUTE, "int"),
            (SPLIT_ATTRIBUTE, "int"),
            (SEED_ATTRIBUTE, "string"),
            (EXPOSURE_ATTRIBUTE, "float"),
            ("whiteLuminance", "float"),
            (WALL_TIME_ATTRIBUTE, "double"),
            ("worldToCamera", "m44f"),
            ("worldToNDC", "m44f"),
        ] {
            assert_eq!(types[name], ty, "{name}");
        }
        fs::remove_dir_all(&dir).unwrap();
    }

    /// Writes over an existing file with one bad value planted; nothing may change on disk.
    fn assert_refused(name: &str, plant: impl FnOnce(&mut [[f32; 3]], &mut [[f32; 3]])) -> String {
        let dir = temp_dir(name);
        let path = dir.join("image.exr");
        fs::write(&path, b"previous render").unwrap();
        let (mut rgb, mut xyz) = test_image();
        plant(&mut rgb, &mut xyz);
        let error = write(&path, 3, 2, &rgb, &xyz, D65_XY, &test_meta())
            .unwrap_err()
            .to_string();
        assert!(error.contains(&path.display().to_string()), "{error}");
        assert!(!error.contains('\n'), "{error}");
        assert_eq!(fs::read(&path).unwrap(), b"previous render");
        assert_eq!(entries(&dir), ["image.exr"]);
        fs::remove_dir_all(&dir).unwrap();
        error
    }

    #[test]
    fn nan_is_refused_naming_the_first_bad_pixel() {
        let error = assert_refused("nan", |rgb, _| {
            rgb[4][1] = f32::NAN;
            rgb[5][0] = f32::NAN;
        });
        assert!(
            error.contains("pixel (1, 1)") && error.contains("NaN in channel G"),
            "{error}"
        );
    }

    #[test]
    fn infinity_is_refused_naming_the_first_bad_pixel() {
        let error = assert_refused("inf", |rgb, xyz| {
            xyz[2][2] = f32::NEG_INFINITY;
            rgb[3][0] = f32::INFINITY;
        });
        assert!(
            error.contains("pixel (2, 0)") && error.contains("-inf in channel XYZ.Z"),
            "{error}"
        );
    }

    #[test]
    fn writing_over_an_existing_file_replaces_it_without_temp_files() {
        let dir = temp_dir("replace");
        let path = dir.join("image.exr");
        let (rgb, xyz) = test_image();
        write(&path, 3, 2, &rgb, &xyz, D65_XY, &test_meta()).unwrap();
        let doubled: Vec<[f32; 3]> = rgb.iter().map(|p| p.map(|v| v * 0.5)).collect();
        write(&path, 3, 2, &doubled, &xyz, D65_XY, &ExrMetadata::default()).unwrap();
        let image = read(&path).unwrap();
        assert_eq!(bits(&image.channels["R"]), component(&doubled, 0));
        assert_eq!(image.attributes[SPP_ATTRIBUTE], "0");
        assert_eq!(image.attributes["software"], "spectral-render");
        assert_eq!(entries(&dir), ["image.exr"]);
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn missing_directory_is_an_error_naming_the_path() {
        let dir = temp_dir("missing");
        let path = dir.join("no-such-dir").join("image.exr");
        let (rgb, xyz) = test_image();
        let error = write(&path, 3, 2, &rgb, &xyz, D65_XY, &test_meta())
            .unwrap_err()
            .to_string();
        assert!(error.contains(&path.display().to_string()), "{error}");
        assert!(!error.contains('\n'), "{error}");
        assert!(entries(&dir).is_empty());
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn mismatched_buffer_sizes_are_refused() {
        let dir = temp_dir("sizes");
        let path = dir.join("image.exr");
        let (rgb, xyz) = test_image();
        let error = write(&path, 2, 2, &rgb, &xyz, D65_XY, &test_meta())
            .unwrap_err()
            .to_string();
        assert!(error.contains("4 pixels") && error.contains(&path.display().to_string()));
        assert!(write(&path, 0, 6, &[], &[], D65_XY, &test_meta()).is_err());
        assert!(entries(&dir).is_empty());
        fs::remove_dir_all(&dir).unwrap();
    }

    #[test]
    fn reading_a_missing_or_foreign_file_is_an_error_naming_the_path() {
        let dir = temp_dir("read-errors");
        let path = dir.join("not-an.exr");
        assert!(read(&path)
            .unwrap_err()
            .to_string()
            .contains(&path.display().to_string()));
        fs::write(&path, b"not an exr file").unwrap();
        assert!(read(&path)
            .unwrap_err()
            .to_string()
            .contains(&path.display().to_string()));
        fs::remove_dir_all(&dir).unwrap();
    }
}
