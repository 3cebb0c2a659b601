//! Image textures for material inputs (`UsdUVTexture` read through
//! `UsdPrimvarReader_float2`, optionally through `UsdTransform2d` nodes), on UsdPreviewSurface
//! and on the colour and roughness inputs of the `spectral:*` shaders.
//!
//! - **Storage.** An [`ImageTexture`] holds RGBA `f32` texels, row-major, top row first, already
//!   decoded to linear values for `sourceColorSpace = sRGB` (alpha is never decoded). It is
//!   loaded once per (file, colour space) by [`TextureCache`] and shared through `Arc`; the
//!   material keeps a [`TextureInput`] (the image plus the node's wrap modes, scale, bias and
//!   output channel), so a lookup returns plain values and allocates nothing.
//! - **st convention.** USD's (0, 0) is the *bottom-left* of the image, so v is flipped:
//!   texel row 0 (the top of the file) covers v ∈ [1 − 1/h, 1]. st comes from the float2
//!   primvar the reader names (one per material, `MaterialDesc::texcoord`), through the
//!   composed `UsdTransform2d` nodes (`TextureInput::transform`: in · scale, rotated
//!   counter-clockwise by `rotation` degrees, plus `translation`, as the UsdPreviewSurface
//!   specification defines it).
//! - **MIP pyramid** (`mip.rs`, PBR 4ed §10.4.3): built once at load, every level the exact
//!   box average of the one above at ⌊size / 2⌋ per axis, down to 1 × 1.
//! - **Filtering.** A lookup takes a [`TexCoord`]: st and its derivatives per pixel
//!   (`coord.rs`; from the camera's footprint at the hit, `Scene::tex_coord`). Within a
//!   level, bilinear between the four texel centres around (u·w − ½, (1 − v)·h − ½); across
//!   levels trilinear, as pbrt-v4's `MIPMap::Filter` with `FilterFunction::Trilinear`: the
//!   level log2(width · max(w, h)) for width = 2 · max |∂st/∂x|, |∂st/∂y|, interpolated
//!   between the two levels around it. A zero footprint ([`TexCoord::point`]) is bilinear at
//!   level 0, exactly the lookup without MIP-mapping; normal maps, opacity and emission use
//!   it (as pbrt-v4), and so does every lookup when filtering is off
//!   ([`TextureFilter::Finest`]). A UsdTransform2d maps the derivatives by its linear part.
//! - **Wrap modes** (UsdUVTexture `wrapS`/`wrapT`): repeat, clamp (to the edge texel), mirror
//!   (period 2n), black (texels outside the image are (0, 0, 0, 0)); `useMetadata` is read as
//!   repeat. The output is `texel · scale + bias`, per channel, as the spec says.
//! - **Spectra.** Colour outputs are uplifted per lookup: the bilinear *RGB* goes through
//!   [`crate::spectral::uplift::reflectance_lookup`] (the table lookup of Jakob–Hanika 2019,
//!   ~0.1 µs), which reproduces the RGB under D65 to ~5e-3 (`spectra/rgb2spec/srgb_64.md`).
//!   Interpolating RGB (not sigmoid coefficients) keeps the filtered colour exact.
//!
//! ```usda
//! def Shader "Checker" {
//!     uniform token info:id = "UsdUVTexture"
//!     asset inputs:file = @checker.png@
//!     float2 inputs:st.connect = </Mat/St.outputs:result>
//!     token inputs:wrapS = "repeat"
//!     token inputs:sourceColorSpace = "sRGB"
//!     float3 outputs:rgb
//! }
//! ```

mod coord;
mod mip;

pub use coord::{TexCoord, TextureFilter};

use crate::desc::{ColorSpace, TextureChannel, TextureDesc, Wrap};
use crate::error::Reason;
use crate::imageio;
use glam::{Affine2, Vec2};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

/// A decoded image with its MIP pyramid: linear RGBA texels, row-major, top row first.
#[derive(Debug)]
pub struct ImageTexture {
    /// Level 0 is the image; level k + 1 is level k box-filtered to ⌊size / 2⌋ per axis (at
    /// least 1), down to 1 × 1 (`mip.rs`).
    levels: Vec<Level>,
}

/// One level of the pyramid.
#[derive(Debug)]
struct Level {
    width: usize,
    height: usize,
    texels: Vec<[f32; 4]>,
}

impl ImageTexture {
    /// An image from texels (row-major, top row first) and its pyramid; `None` when the sizes
    /// disagree or a texel is not finite.
    pub fn from_texels(width: usize, height: usize, texels: Vec<[f32; 4]>) -> Option<Self> {
        let finite = texels.iter().flatten().all(|x| x.is_finite());
        let ok = width > 0 && height > 0 && texels.len() == width * height && finite;
        ok.then(|| Self {
            levels: mip::pyramid(Level {
                width,
                height,
                texels,
            }),
        })
    }

    /// Reads `path` and decodes it per `color_space` (auto: sRGB for 8/16-bit, raw for float).
    pub fn load(path: &Path, color_space: ColorSpace) -> Reason<Self> {
        let img = imageio::read_rgba_raw(path).map_err(|e| e.to_string())?;
        let srgb = match color_space {
            ColorSpace::Srgb => true,
            ColorSpace::Raw => false,
            ColorSpace::Auto => !img.is_float,
        };
        let decode = |p: [f32; 4]| {
            if srgb {
                let d = imageio::srgb_to_linear;
                [d(p[0]), d(p[1]), d(p[2]), p[3]]
            } else {
                p
            }
        };
        let texels = img.pixels.into_iter().map(decode).collect();
        Self::from_texels(img.width, img.height, texels)
            .ok_or_else(|| format!("image {} has non-finite texels", path.display()))
    }

    /// The number of pyramid levels (1 + ⌊log2 max(w, h)⌋).
    pub fn levels(&self) -> usize {
        self.levels.len()
    }

    /// (width, height) of pyramid level `k`.
    pub fn level_size(&self, k: usize) -> (usize, usize) {
        let l = &self.levels[k];
        (l.width, l.height)
    }

    /// Texel (x, y) of level `k` (x right, y down from the top row), without wrapping.
    pub fn level_texel(&self, k: usize, x: usize, y: usize) -> [f32; 4] {
        let l = &self.levels[k];
        l.texels[y * l.width + x]
    }

    /// Bilinear lookup of level 0 at USD st = `uv` ((0, 0) is the bottom-left of the image).
    #[inline]
    pub fn bilinear(&self, uv: Vec2, wrap: [Wrap; 2]) -> [f32; 4] {
        self.levels[0].bilinear(uv, wrap)
    }

    /// Trilinear lookup for a filter `width` in st units (pbrt-v4 `MIPMap::Filter` with
    /// `FilterFunction::Trilinear`, PBR 4ed §10.4.3): the level whose texels are `width`
    /// wide, level = log2(width · max(w, h)) clamped to the pyramid, interpolated linearly
    /// between the bilinear lookups of the two levels around it. A width of 0 (or NaN) is
    /// exactly [`ImageTexture::bilinear`].
    #[inline]
    pub fn trilinear(&self, uv: Vec2, width: f32, wrap: [Wrap; 2]) -> [f32; 4] {
        let base = &self.levels[0];
        let level = (width * base.width.max(base.height) as f32).log2();
        let last = self.levels.len() - 1;
        if level.is_nan() || level <= 0.0 {
            return base.bilinear(uv, wrap);
        }
        if level >= last as f32 {
            return self.levels[last].bilinear(uv, wrap);
        }
        let k = level as usize;
        let t = level - k as f32;
        let (a, b) = (
            self.levels[k].bilinear(uv, wrap),
            self.levels[k + 1].bilinear(uv, wrap),
        );
        std::array::from_fn(|c| a[c] + t * (b[c] - a[c]))
    }
}

impl Level {
    /// The texel at integer coordinates (x right, y down from the top row), after wrapping.
    #[inline]
    fn texel(&self, x: i64, y: i64, wrap: [Wrap; 2]) -> [f32; 4] {
        match (
            wrap_index(x, self.width, wrap[0]),
            wrap_index(y, self.height, wrap[1]),
        ) {
            (Some(i), Some(j)) => self.texels[j * self.width + i],
            _ => [0.0; 4],
        }
    }

    /// Bilinear between the four texel centres around (u·w − ½, (1 − v)·h − ½).
    #[inline]
    fn bilinear(&self, uv: Vec2, wrap: [Wrap; 2]) -> [f32; 4] {
        let x = uv.x as f64 * self.width as f64 - 0.5;
        let y = (1.0 - uv.y as f64) * self.height as f64 - 0.5;
        let (x0, y0) = (x.floor(), y.floor());
        let (fx, fy) = ((x - x0) as f32, (y - y0) as f32);
        let (x0, y0) = (x0 as i64, y0 as i64);
        let t00 = self.texel(x0, y0, wrap);
        let t10 = self.texel(x0 + 1, y0, wrap);
        let t01 = self.texel(x0, y0 + 1, wrap);
        let t11 = self.texel(x0 + 1, y0 + 1, wrap);
        std::array::from_fn(|c| {
            let top = t00[c] + fx * (t10[c] - t00[c]);
            let bottom = t01[c] + fx * (t11[c] - t01[c]);
            top + fy * (bottom - top)
        })
    }
}

/// The texel index along one axis of size `n`; `None` outside the image in black mode.
#[inline]
fn wrap_index(i: i64, n: usize, wrap: Wrap) -> Option<usize> {
    let n = n as i64;
    let k = match wrap {
        Wrap::Repeat => i.rem_euclid(n),
        Wrap::Clamp => i.clamp(0, n - 1),
        Wrap::Mirror => {
            let m = i.rem_euclid(2 * n);
            if m >= n {
                2 * n - 1 - m
            } else {
                m
            }
        }
        Wrap::Black => {
            if !(0..n).contains(&i) {
                return None;
            }
            i
        }
    };
    Some(k as usize)
}

/// A texture bound to a material input: the shared image plus the UsdUVTexture node's
/// parameters. Cheap to clone (an `Arc` and a few floats).
#[derive(Clone, Debug)]
pub struct TextureInput {
    pub image: Arc<ImageTexture>,
    pub wrap: [Wrap; 2],
    pub scale: [f32; 4],
    pub bias: [f32; 4],
    /// Returned when st is not finite.
    pub fallback: [f32; 4],
    pub channel: TextureChannel,
    /// UsdTransform2d applied to st before the lookup (`None`: identity).
    pub transform: Option<Affine2>,
}

impl TextureInput {
    /// `texel · scale + bias` at `tc` (through the UsdTransform2d), all four channels,
    /// filtered over `tc`'s footprint (bilinear at level 0 for a point).
    #[inline]
    pub fn rgba(&self, tc: TexCoord) -> [f32; 4] {
        let tc = match &self.transform {
            Some(t) => tc.transformed(t),
            None => tc,
        };
        if !tc.uv.is_finite() {
            return self.fallback;
        }
        let t = self.image.trilinear(tc.uv, tc.filter_width(), self.wrap);
        std::array::from_fn(|c| t[c] * self.scale[c] + self.bias[c])
    }

    /// The colour output: `outputs:rgb`, or a single channel replicated.
    #[inline]
    pub fn rgb(&self, tc: TexCoord) -> [f32; 3] {
        let t = self.rgba(tc);
        match self.channel.index() {
            Some(c) => [t[c]; 3],
            None => [t[0], t[1], t[2]],
        }
    }

    /// The float output: `outputs:r/g/b/a`, or the red channel of `outputs:rgb`.
    #[inline]
    pub fn float(&self, tc: TexCoord) -> f32 {
        self.rgba(tc)[self.channel.index().unwrap_or(0)]
    }
}

/// Images loaded while building a scene, one per (file, colour space).
#[derive(Default)]
pub struct TextureCache {
    images: HashMap<(PathBuf, ColorSpace), Arc<ImageTexture>>,
}

impl TextureCache {
    /// The [`TextureInput`] of `desc`, loading its image on first use.
    pub fn input(&mut self, desc: &TextureDesc) -> Reason<TextureInput> {
        if desc.file.as_os_str().is_empty() {
            return Ok(Self::constant(desc));
        }
        let key = (desc.file.clone(), desc.color_space);
        let image = match self.images.get(&key) {
            Some(image) => image.clone(),
            None => {
                let image = Arc::new(ImageTexture::load(&desc.file, desc.color_space)?);
                self.images.insert(key, image.clone());
                image
            }
        };
        Ok(TextureInput {
            image,
            wrap: [desc.wrap_s, desc.wrap_t],
            scale: desc.scale,
            bias: desc.bias,
            fallback: desc.fallback,
            channel: desc.channel,
            transform: desc.st_transform,
        })
    }

    /// A texture node without a file: its fallback everywhere (one texel, scale 1, bias 0).
    fn constant(desc: &TextureDesc) -> TextureInput {
        let texel = desc.fallback.map(|v| if v.is_finite() { v } else { 0.0 });
        let image = ImageTexture::from_texels(1, 1, vec![texel]).expect("one finite texel");
        TextureInput {
            image: Arc::new(image),
            wrap: [desc.wrap_s, desc.wrap_t],
            scale: [1.0; 4],
            bias: [0.0; 4],
            fallback: texel,
            channel: desc.channel,
            transform: None,
        }
    }

    /// How many distinct images are loaded.
    #[cfg(any(test, feature = "testing"))]
    pub fn len(&self) -> usize {
        self.images.len()
    }

    #[cfg(any(test, feature = "testing"))]
    pub fn is_empty(&self) -> bool {
        self.images.is_empty()
    }
}

#[cfg(test)]
mod tests;
