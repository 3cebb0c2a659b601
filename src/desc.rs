//! Plain scene description: what the USD reader produces and the scene builder consumes.
//!
//! Everything here is already resolved to the renderer's conventions (docs/design.md §2):
//! positions in metres, Y up, world space; triangles counter-clockwise when seen from the
//! side their geometric normal points to; every entity carries its USD prim path so that
//! errors and reports can name it.

use glam::{Affine2, DMat4, Mat4, Vec2, Vec3};
use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Arc;

/// The whole stage as plain data.
#[derive(Clone, Debug, Default)]
pub struct SceneDescription {
    /// The file the stage was read from (used in messages and EXR metadata).
    pub source: PathBuf,
    pub meshes: Vec<MeshDesc>,
    pub materials: Vec<MaterialDesc>,
    pub lights: Vec<LightDesc>,
    pub cameras: Vec<CameraDesc>,
    pub render: RenderSettingsDesc,
    /// Unsupported standard prims and attributes that were skipped, one line each.
    pub warnings: Vec<String>,
    /// Stage space (stage units, stage up axis) to world space (metres, Y up), for converting
    /// points and directions given in stage coordinates (light-meter positions and normals).
    pub stage_to_world: DMat4,
    /// The directory holding assets copied out of a `.usdz` package (textures, IES files)
    /// for the builder to open; it is removed when the last description holding it is
    /// dropped.
    pub extracted: Option<Arc<ExtractedAssets>>,
    /// A hash of every layer the stage was composed from, in the order they were read
    /// (identifies the stage in a checkpoint); 0 for a description built in code.
    pub content_hash: u64,
    /// The time the stage was read at.
    pub time: TimeDesc,
}

/// The time a stage was read at.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TimeDesc {
    /// The USD time code; `None`: the earliest time sample of each attribute.
    pub code: Option<f64>,
    /// Where the time came from.
    pub origin: TimeOrigin,
    /// Some attribute that was read has two or more time samples.
    pub animated: bool,
    /// Held interpolation between time samples (linear otherwise).
    pub held: bool,
    /// The stage's `framesPerSecond` and `timeCodesPerSecond` metadata, when authored.
    pub frames_per_second: Option<f64>,
    pub time_codes_per_second: Option<f64>,
}

/// Where the time a stage was read at came from.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub enum TimeOrigin {
    /// Given (`--frame`, `--frames`).
    Given,
    /// The stage's `startTimeCode`.
    StartTimeCode,
    /// No time given and no time range authored: the earliest sample of each attribute.
    #[default]
    Earliest,
}

impl TimeDesc {
    /// A note for the load summary when the stage is animated and no time was given.
    pub fn note(&self) -> Option<String> {
        if !self.animated || self.origin == TimeOrigin::Given {
            return None;
        }
        Some(match self.code {
            Some(t) => format!(
                "the stage is animated; read at its startTimeCode {t} (--frame picks another)"
            ),
            None => "the stage is animated; read at each attribute's earliest time sample \
                     (--frame picks a time code)"
                .to_string(),
        })
    }
}

/// A 64-bit FNV-1a hash of byte strings (Fowler, Noll, Vo; the IETF draft
/// draft-eastlake-fnv, 64-bit offset basis and prime): a fingerprint of content, not a
/// cryptographic digest.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct ContentHash(pub u64);

impl Default for ContentHash {
    fn default() -> Self {
        ContentHash(0xcbf2_9ce4_8422_2325)
    }
}

impl ContentHash {
    /// Folds `bytes` and their length into the hash.
    pub fn add(&mut self, bytes: &[u8]) {
        for &b in bytes.iter().chain(&(bytes.len() as u64).to_le_bytes()) {
            self.0 = (self.0 ^ u64::from(b)).wrapping_mul(0x0000_0100_0000_01b3);
        }
    }
}

/// A temporary directory of assets extracted from a package, removed on drop.
#[derive(Debug)]
pub struct ExtractedAssets {
    pub dir: PathBuf,
}

impl ExtractedAssets {
    /// A fresh directory name under the system's temporary directory, unique to this process
    /// and this call (it is created when the first asset is written).
    pub fn unique() -> ExtractedAssets {
        static COUNT: AtomicUsize = AtomicUsize::new(0);
        let n = COUNT.fetch_add(1, Ordering::Relaxed);
        let name = format!("spectral-render-usdz-{}-{n}", std::process::id());
        ExtractedAssets {
            dir: std::env::temp_dir().join(name),
        }
    }
}

impl Drop for ExtractedAssets {
    fn drop(&mut self) {
        let _ = std::fs::remove_dir_all(&self.dir);
    }
}

/// A triangulated mesh in world space (metres, Y up).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MeshDesc {
    pub prim_path: String,
    pub positions: Vec<Vec3>,
    /// Triangles as indices into `positions`, wound so that the front face (the side
    /// `(p1 - p0) x (p2 - p0)` points to) is the USD front face (`orientation` applied).
    pub indices: Vec<[u32; 3]>,
    /// Optional shading normals, one per triangle corner (vertex and faceVarying
    /// interpolation are both expanded to this), world space, unit length.
    pub normals: Option<Vec<[Vec3; 3]>>,
    /// Optional texture coordinates, one per triangle corner: the primvar named by the
    /// material's `texcoord` (`primvars:st` by default).
    pub uvs: Option<Vec<[Vec2; 3]>>,
    /// Index into `SceneDescription::materials`.
    pub material: Option<usize>,
    pub double_sided: bool,
    /// Set when the prim has `MeshLightAPI` (the mesh itself is a light).
    pub light: Option<EmissionDesc>,
}

/// A spectrum as authored in the stage.
#[derive(Clone, Debug, PartialEq)]
pub enum SpectrumDesc {
    /// Linear Rec.709 RGB, uplifted with Jakob–Hanika 2019.
    Rgb([f32; 3]),
    /// A file in `spectra/`, e.g. `"colorchecker/dark_skin"`.
    Named(String),
    /// (nm, value) pairs, linearly interpolated.
    Samples(Vec<(f32, f32)>),
}

/// What a material prim resolved to.
#[derive(Clone, Debug, PartialEq)]
pub struct MaterialDesc {
    pub prim_path: String,
    pub kind: MaterialKind,
    /// `emissiveColor` of a UsdPreviewSurface: an emitter of that RGB radiance in nits.
    pub emission: Option<[f32; 3]>,
    /// The inputs of a `spectral:*` shader connected to a `UsdUVTexture`, by input name
    /// (`"reflectance"`, `"roughness"`); a UsdPreviewSurface keeps its own in
    /// [`PreviewSurfaceDesc::textures`].
    pub textures: Vec<(String, TextureDesc)>,
    /// The float2 primvar every texture of the material reads through its
    /// `UsdPrimvarReader_float2` (`"st"` when it has no textures): a material reads one
    /// texture-coordinate set, which the meshes it is bound to keep.
    pub texcoord: String,
}

impl MaterialDesc {
    /// The texture on input `name` of a `spectral:*` shader, if any.
    pub fn texture(&self, name: &str) -> Option<&TextureDesc> {
        self.textures
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, t)| t)
    }

    /// Every texture the material reads (of either kind of shader).
    pub fn all_textures(&self) -> impl Iterator<Item = &TextureDesc> {
        let preview = match &self.kind {
            MaterialKind::PreviewSurface(ps) => ps.textures.as_slice(),
            _ => &[],
        };
        self.textures.iter().chain(preview).map(|(_, t)| t)
    }
}

#[derive(Clone, Debug, PartialEq)]
pub enum MaterialKind {
    /// `spectral:diffuse`: Lambertian (roughness 0) or Oren–Nayar (σ in radians).
    Diffuse {
        reflectance: SpectrumDesc,
        roughness: f32,
    },
    /// `spectral:conductor`.
    Conductor {
        eta: SpectrumDesc,
        k: SpectrumDesc,
        roughness: f32,
    },
    /// `spectral:dielectric`.
    Dielectric {
        ior: IorDesc,
        roughness: f32,
        thin: bool,
    },
    /// `spectral:plastic`.
    Plastic {
        reflectance: SpectrumDesc,
        ior: f32,
        roughness: f32,
    },
    /// `UsdPreviewSurface`.
    PreviewSurface(PreviewSurfaceDesc),
}

/// Index of refraction of a dielectric.
#[derive(Clone, Debug, PartialEq)]
pub enum IorDesc {
    Constant(f32),
    /// A named glass in `spectra/glass/`, e.g. `"BK7"`.
    Glass(String),
    /// Sellmeier B and C coefficients (C in µm²).
    Sellmeier {
        b: [f32; 3],
        c: [f32; 3],
    },
}

/// The inputs of a UsdPreviewSurface shader, with the spec's defaults.
#[derive(Clone, Debug, PartialEq)]
pub struct PreviewSurfaceDesc {
    pub diffuse_color: [f32; 3],
    pub emissive_color: [f32; 3],
    pub use_specular_workflow: bool,
    pub specular_color: [f32; 3],
    pub metallic: f32,
    pub roughness: f32,
    pub clearcoat: f32,
    pub clearcoat_roughness: f32,
    pub opacity: f32,
    pub opacity_threshold: f32,
    pub ior: f32,
    /// Tangent-space normal, components in [−1, 1].
    pub normal: [f32; 3],
    /// Inputs connected to a `UsdUVTexture`, by input name (`"diffuseColor"`, ...); the
    /// value fields above then hold the spec default and are unused.
    pub textures: Vec<(String, TextureDesc)>,
}

impl PreviewSurfaceDesc {
    /// The texture connected to input `name`, if any.
    pub fn texture(&self, name: &str) -> Option<&TextureDesc> {
        self.textures
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, t)| t)
    }
}

/// A `UsdUVTexture` node feeding a material input.
#[derive(Clone, Debug, PartialEq)]
pub struct TextureDesc {
    /// The texture shader's prim path (for messages).
    pub shader_path: String,
    /// `inputs:file`, resolved to an absolute path; empty when the node has none (the texture
    /// is then its `fallback` everywhere).
    pub file: PathBuf,
    /// The `UsdPrimvarReader_float2` varname feeding `inputs:st` ("st" by default).
    pub st_primvar: String,
    /// The `UsdTransform2d` nodes between the primvar reader and the texture, composed
    /// (st ↦ texture coordinates); `None` without any.
    pub st_transform: Option<Affine2>,
    pub wrap_s: Wrap,
    pub wrap_t: Wrap,
    pub color_space: ColorSpace,
    pub scale: [f32; 4],
    pub bias: [f32; 4],
    pub fallback: [f32; 4],
    /// The output the material input is connected to.
    pub channel: TextureChannel,
}

/// UsdUVTexture `wrapS` / `wrapT` (`useMetadata` is read as repeat).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Wrap {
    Repeat,
    Clamp,
    Mirror,
    Black,
}

/// UsdUVTexture `sourceColorSpace`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ColorSpace {
    /// sRGB for 8/16-bit files, raw for float files.
    Auto,
    Srgb,
    Raw,
}

/// The UsdUVTexture output a material input reads.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TextureChannel {
    Rgb,
    R,
    G,
    B,
    A,
}

impl TextureChannel {
    /// The channel index of a single-channel output; `None` for `rgb`.
    pub fn index(self) -> Option<usize> {
        match self {
            TextureChannel::Rgb => None,
            TextureChannel::R => Some(0),
            TextureChannel::G => Some(1),
            TextureChannel::B => Some(2),
            TextureChannel::A => Some(3),
        }
    }
}

impl Default for PreviewSurfaceDesc {
    fn default() -> Self {
        // Defaults from the UsdPreviewSurface specification.
        PreviewSurfaceDesc {
            diffuse_color: [0.18; 3],
            emissive_color: [0.0; 3],
            use_specular_workflow: false,
            specular_color: [0.0; 3],
            metallic: 0.0,
            roughness: 0.5,
            clearcoat: 0.0,
            clearcoat_roughness: 0.01,
            opacity: 1.0,
            opacity_threshold: 0.0,
            ior: 1.5,
            normal: [0.0, 0.0, 1.0],
            textures: Vec::new(),
        }
    }
}

/// The spectral shape of an emitter when `spectral:emission*` is authored.
#[derive(Clone, Debug, PartialEq)]
pub enum SpdDesc {
    /// A named SPD: `"CIE-A"`, `"CIE-D65"`, `"CIE-F11"`, `"LED-B3"`, ...
    Named(String),
    /// `"blackbody"` with `spectral:temperature` in kelvin.
    Blackbody(f32),
    /// `spectral:emission:samples`, (nm, value) pairs.
    Samples(Vec<(f32, f32)>),
}

/// The UsdLux `LightAPI` inputs shared by every light, plus our `spectral:` ones.
#[derive(Clone, Debug, PartialEq)]
pub struct EmissionDesc {
    pub color: [f32; 3],
    /// Luminance in nits (docs/design.md §2).
    pub intensity: f32,
    pub exposure: f32,
    pub normalize: bool,
    /// `inputs:enableColorTemperature` ? `inputs:colorTemperature` : None.
    pub color_temperature: Option<f32>,
    pub spd: Option<SpdDesc>,
    /// `spectral:luminousFlux` in lm (replaces intensity).
    pub luminous_flux: Option<f32>,
    /// `spectral:luminousIntensity` in cd (replaces intensity).
    pub luminous_intensity: Option<f32>,
    /// `spectral:lightGroup`: the light group (`--light-groups`) the light belongs to.
    pub light_group: Option<String>,
}

impl Default for EmissionDesc {
    fn default() -> Self {
        EmissionDesc {
            color: [1.0; 3],
            intensity: 1.0,
            exposure: 0.0,
            normalize: false,
            color_temperature: None,
            spd: None,
            luminous_flux: None,
            luminous_intensity: None,
            light_group: None,
        }
    }
}

/// A UsdLux light (other than a mesh light, which lives on its `MeshDesc`).
#[derive(Clone, Debug, PartialEq)]
pub struct LightDesc {
    pub prim_path: String,
    pub kind: LightKind,
    /// Light-to-world transform in metres, Y up. UsdLux lights emit along their local -Z.
    pub to_world: Mat4,
    pub emission: EmissionDesc,
    /// UsdLux ShapingAPI inputs, when the light has any (rect, disk, sphere, cylinder).
    pub shaping: Option<ShapingDesc>,
    /// `inputs:shadow:enable` (fallback true). False: next-event shadow rays towards this
    /// light pass through occluders (not physical; the path integrator and meters only).
    pub shadows: bool,
}

/// The UsdLux ShapingAPI inputs of a light (`inputs:shaping:*`), with the schema's meaning:
/// all angles are measured from the light's emission axis, local −Z.
#[derive(Clone, Debug, PartialEq)]
pub struct ShapingDesc {
    /// `shaping:cone:angle` in degrees; 180 or more means no cone.
    pub cone_angle_deg: f32,
    /// `shaping:cone:softness`, clamped to [0, 1].
    pub cone_softness: f32,
    /// `shaping:focus`; 0 (or negative, which the schema ignores) means no focus.
    pub focus: f32,
    /// `shaping:focusTint`, linear Rec.709.
    pub focus_tint: [f32; 3],
    pub ies: Option<IesDesc>,
}

impl Default for ShapingDesc {
    /// Shaping that changes nothing.
    fn default() -> Self {
        ShapingDesc {
            cone_angle_deg: 180.0,
            cone_softness: 0.0,
            focus: 0.0,
            focus_tint: [0.0; 3],
            ies: None,
        }
    }
}

/// `shaping:ies:*`: an LM-63 profile that scales the emitted luminance per direction.
#[derive(Clone, Debug, PartialEq)]
pub struct IesDesc {
    /// Absolute path of the `.ies` file.
    pub file: PathBuf,
    /// `shaping:ies:angleScale`.
    pub angle_scale: f32,
    /// `shaping:ies:normalize`.
    pub normalize: bool,
}

#[derive(Clone, Debug, PartialEq)]
pub enum LightKind {
    /// Centred on the origin in the local XY plane, emitting towards -Z.
    Rect {
        width: f32,
        height: f32,
        /// `inputs:texture:file` (st along local +X and +Y), multiplying the emission.
        texture: Option<Box<TextureDesc>>,
    },
    /// Centred on the origin in the local XY plane, emitting towards -Z.
    Disk { radius: f32 },
    /// `point`: `treatAsPoint`, a point light with the sphere's far field.
    Sphere { radius: f32, point: bool },
    /// Along the local X axis; `line`: `treatAsLine`, a line light with the cylinder's far field.
    Cylinder {
        radius: f32,
        length: f32,
        line: bool,
    },
    /// Shining along the local -Z axis; `angle` is the angular diameter in degrees.
    Distant { angle_deg: f32 },
    /// An environment; `texture` is a lat-long image (absolute path) or None for constant.
    Dome { texture: Option<PathBuf> },
    /// A UsdLux PortalLight: a `width` × `height` rectangle in the local XY plane guiding the
    /// sampling of the dome lights (their light passes along local −Z); emits nothing.
    Portal { width: f32, height: f32 },
}

/// A UsdGeomCamera.
#[derive(Clone, Debug, PartialEq)]
pub struct CameraDesc {
    pub prim_path: String,
    /// Camera-to-world in metres, Y up; the camera looks along its local -Z with +Y up.
    pub to_world: Mat4,
    /// Focal length and apertures in the same unit (tenths of a stage unit in USD).
    pub focal_length: f32,
    pub horizontal_aperture: f32,
    pub vertical_aperture: f32,
    /// Clipping range in metres.
    pub clip_near: f32,
    pub clip_far: f32,
    /// 0 means a pinhole.
    pub f_stop: f32,
    /// Focus distance in metres.
    pub focus_distance: f32,
    /// Lens radius in metres for the thin-lens model (0 for a pinhole), already derived
    /// from focal length, fStop and the stage's units.
    pub lens_radius: f32,
    pub exposure: f32,
}

/// The RenderSettings prim, if any.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct RenderSettingsDesc {
    pub resolution: Option<(u32, u32)>,
    /// Prim path of the camera the settings name.
    pub camera: Option<String>,
    /// `dataWindowNDC`, when it is not the whole image.
    pub data_window: Option<DataWindowDesc>,
}

/// A RenderSettings or RenderProduct `dataWindowNDC`: the part of the image to render,
/// (xmin, ymin, xmax, ymax) in NDC with y up from the bottom (UsdRenderSettingsBase),
/// within [0, 1] and not empty (the reader refuses others).
#[derive(Clone, Debug, PartialEq)]
pub struct DataWindowDesc {
    pub ndc: [f64; 4],
    /// The prim that authored it (for messages).
    pub prim_path: String,
}
