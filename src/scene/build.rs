//! From the plain [`SceneDescription`] to the render [`Scene`]: spectra resolved and
//! validated, lights built in absolute units, triangles put behind the BVH, a camera chosen.

use super::analysis::{self, SceneFeatures};
use super::limits;
use super::machinery::Machinery;
use super::prim::{self, Prim};
use super::render_scene::{Mesh, Scene, Summary};
use crate::accel::bvh::Bvh;
use crate::bxdf::TrowbridgeReitz;
use crate::desc::*;
use crate::error::Reason;
use crate::error::{Error, Result};
use crate::imageio;
use crate::light::dome::LatLong;
use crate::light::ellipsoid::Ellipsoid;
use crate::light::emission::{self, Photometric};
use crate::light::ies::IesProfile;
use crate::light::portal::Portal;
use crate::light::rect::RectTexture;
use crate::light::report;
use crate::light::shaping::Shaping;
use crate::light::EmissiveTexture;
use crate::light::*;
use crate::material::normal_map::Tangents;
use crate::material::preview::{PreviewLobes, PreviewTextures};
use crate::material::{
    AlphaTexture, ColorInput, FloatInput, Material, PlasticMaterial, PreviewMaterial,
};
use crate::math::Frame;
use crate::sampling::distribution::Distribution2D;
use crate::sensor::Camera;
use crate::spectral::sellmeier::Sellmeier;
use crate::spectral::uplift::{self, RgbIlluminantSpectrum};
use crate::spectral::{data, DenseSpectrum, Spectrum};
use crate::texture::{TextureCache, TextureInput};
use glam::{Mat3, Mat4, Vec2, Vec3};
use std::f32::consts::PI;
use std::sync::Arc;

/// Image width when neither RenderSettings nor the command line gives a resolution.
const DEFAULT_WIDTH: u32 = 640;

/// The render scene of `desc`; `resolution` overrides RenderSettings.
pub fn build(desc: &SceneDescription, resolution: Option<(u32, u32)>) -> Result<Scene> {
    build_with(desc, resolution, Machinery::default())
}

/// [`build`] with the pieces of `machinery` kept where the scene does not need them.
pub fn build_with(
    desc: &SceneDescription,
    resolution: Option<(u32, u32)>,
    machinery: Machinery,
) -> Result<Scene> {
    let geometry = geometry(desc, machinery)?;
    let lights = desc
        .lights
        .iter()
        .filter(|l| !is_portal(l))
        .map(|l| light(l).map_err(|r| Error::prim(&desc.source, &l.prim_path, r)))
        .collect::<Result<Vec<_>>>()?;
    assemble(desc, geometry, lights, None, resolution, machinery)
}

/// The parts of a scene made from its meshes and materials: what `scene::rebuild` keeps
/// across frames whose meshes and materials did not change.
pub(super) struct Geometry {
    pub materials: Vec<Material>,
    pub meshes: Vec<Mesh>,
    pub prims: Vec<Prim>,
    pub bvh: Bvh,
    pub center: Vec3,
    pub radius: f32,
    /// The triangle lights of emissive meshes (the scene's first lights).
    pub mesh_lights: Vec<Light>,
    /// What building the materials had to say.
    pub warnings: Vec<String>,
}

/// Materials (with their textures), meshes, their triangle lights and the BVH of `desc`.
pub(super) fn geometry(desc: &SceneDescription, machinery: Machinery) -> Result<Geometry> {
    let file = &desc.source;
    let mut warnings = Vec::new();
    let mut textures = TextureCache::default();
    let mut materials = desc
        .materials
        .iter()
        .map(|m| {
            material(m, &mut textures, &mut warnings)
                .map_err(|r| Error::prim(file, &m.prim_path, r))
        })
        .collect::<Result<Vec<_>>>()?;
    if machinery.all_lobes {
        for m in &mut materials {
            if let Material::Preview(p) = m {
                p.lobes = PreviewLobes::Full;
            }
        }
    }
    let emissive = emissive_textures(desc, &mut textures)?;
    let default_material = materials.len() as u32;
    materials.push(Material::Diffuse {
        reflectance: ColorInput::Constant(Spectrum::Constant(0.18)),
    });

    let mut mesh_lights = Vec::new();
    let mut meshes = Vec::new();
    for m in &desc.meshes {
        meshes.push(
            mesh(
                desc,
                m,
                &materials,
                &emissive,
                default_material,
                &mut mesh_lights,
            )
            .map_err(|r| Error::prim(file, &m.prim_path, r))?,
        );
    }
    let (prims, triangles) = prim::flatten(&meshes);
    let bvh = Bvh::build(&triangles);
    let (center, radius) = bounding_sphere(&bvh);
    Ok(Geometry {
        materials,
        meshes,
        prims,
        bvh,
        center,
        radius,
        mesh_lights,
        warnings,
    })
}

/// The scene of `desc` from its geometry, its UsdLux lights (built, in `desc.lights`'
/// order) and, when given, a light sampler already made for exactly these lights.
pub(super) fn assemble(
    desc: &SceneDescription,
    geometry: Geometry,
    usd_lights: Vec<Light>,
    light_sampler: Option<LightSampler>,
    resolution: Option<(u32, u32)>,
    machinery: Machinery,
) -> Result<Scene> {
    let file = &desc.source;
    let mut warnings = desc.warnings.clone();
    warn_clamped_temperatures(desc, &mut warnings);
    warnings.extend(geometry.warnings.iter().cloned());
    let Geometry {
        materials,
        meshes,
        prims,
        bvh,
        center,
        radius,
        mesh_lights: mut lights,
        ..
    } = geometry;
    let triangles = prims.len();
    lights.extend(usd_lights);
    attach_portals(desc, &mut lights, &mut warnings)?;
    if lights.is_empty() {
        warnings.push(
            "the stage has no lights (UsdLux lights, MeshLightAPI prims or emissive \
             materials), so it renders black"
                .into(),
        );
    }
    let camera = camera(desc, resolution, center, radius)?;
    let light_sampler = light_sampler.unwrap_or_else(|| {
        if machinery.light_table {
            LightSampler::table(&lights, radius)
        } else {
            LightSampler::new(&lights, radius)
        }
    });
    let infinite_lights = indices_where(&lights, Light::is_infinite);
    let shape_lights = indices_where(&lights, Light::is_analytic_shape);
    let shadowless = indices_where(&lights, |l| {
        desc.lights
            .iter()
            .any(|d| !d.shadows && d.prim_path == l.prim_path())
    });
    let summary = Summary {
        meshes: meshes.len(),
        triangles,
        materials: desc.materials.len(),
        lights: desc.lights.len() + desc.meshes.iter().filter(|m| m.light.is_some()).count(),
        camera: camera.prim_path.clone(),
        warnings,
        time: desc.time,
    };
    let all_opaque = materials.iter().all(Material::is_opaque);
    let any_textured = materials.iter().any(Material::is_textured);
    let radiance_class = crate::light::radiance_class::radiance_classes(&lights);
    let dispersive = machinery.dispersion_checks || materials.iter().any(Material::is_dispersive);
    let specular_like = materials
        .iter()
        .map(|m| analysis::lobes::lobes(m).specular_like())
        .collect();
    let mut scene = Scene {
        source: file.clone(),
        meshes,
        prims,
        bvh,
        all_opaque,
        any_textured,
        dispersive,
        specular_like,
        materials,
        lights,
        light_sampler,
        radiance_class,
        infinite_lights,
        shape_lights,
        shadowless,
        camera,
        center,
        radius,
        summary,
        stage_to_world: desc.stage_to_world,
        content_hash: desc.content_hash,
        features: SceneFeatures::default(),
        data_window: desc.render.data_window.clone(),
        light_groups: Vec::new(),
        emission_layers: Default::default(),
    };
    scene.light_groups = super::emission_layers::group_names(desc, &scene.lights);
    let material_paths: Vec<String> = desc.materials.iter().map(|m| m.prim_path.clone()).collect();
    scene.features = analysis::analyze(&scene, &material_paths);
    Ok(scene)
}

/// A colour temperature outside the range its tint is defined for is clamped to it
/// (`emission::color_temperature_rgb`): said in the load summary rather than silently.
fn warn_clamped_temperatures(desc: &SceneDescription, warnings: &mut Vec<String>) {
    let lights = desc.lights.iter().map(|l| (&l.prim_path, &l.emission));
    let meshes = desc
        .meshes
        .iter()
        .filter_map(|m| m.light.as_ref().map(|e| (&m.prim_path, e)));
    for (path, e) in lights.chain(meshes) {
        let Some(k) = e.color_temperature else {
            continue;
        };
        let (lo, hi) = emission::COLOR_TEMPERATURE_RANGE;
        if !(lo..=hi).contains(&k) {
            warnings.push(format!(
                "{path}: inputs:colorTemperature {k} K is outside {lo}–{hi} K; the tint of \
                 {} K is used",
                k.clamp(lo, hi)
            ));
        }
    }
}

fn indices_where(lights: &[Light], f: impl Fn(&Light) -> bool) -> Vec<u32> {
    lights
        .iter()
        .enumerate()
        .filter(|(_, l)| f(l))
        .map(|(i, _)| i as u32)
        .collect()
}

/// A reflectance spectrum from its description, validated to lie in [0, 1]; an RGB one uplifted
/// and tabulated at 1 nm for rendering (`Spectrum::tabulated`).
pub fn reflectance(s: &SpectrumDesc) -> Reason<Spectrum> {
    let dense = match s {
        SpectrumDesc::Rgb(rgb) => {
            if rgb.iter().any(|c| !c.is_finite()) {
                return Err(format!("reflectance {rgb:?} is not finite"));
            }
            return Ok(Spectrum::Sigmoid(uplift::reflectance(*rgb)).tabulated());
        }
        SpectrumDesc::Named(token) => data::named(token)
            .cloned()
            .ok_or_else(|| format!("unknown spectrum '{token}' (not a file in spectra/)"))?,
        SpectrumDesc::Samples(samples) => DenseSpectrum::from_samples(samples)
            .ok_or("reflectance samples must be finite (nm, value) pairs sorted by wavelength")?,
    };
    if dense.values.iter().any(|&v| !(0.0..=1.0).contains(&v)) {
        return Err("a reflectance must lie in [0, 1] at every wavelength".into());
    }
    Ok(Spectrum::Dense {
        data: Arc::new(dense),
        scale: 1.0,
    })
}

/// The render material of a material prim (the models of `material/` and `bxdf/`).
fn material(
    m: &MaterialDesc,
    textures: &mut TextureCache,
    warnings: &mut Vec<String>,
) -> Reason<Material> {
    let path = &m.prim_path;
    let texture = |name: &str, cache: &mut TextureCache| {
        m.texture(name).map(|t| texture_input(cache, t)).transpose()
    };
    match &m.kind {
        MaterialKind::Diffuse {
            reflectance: r,
            roughness,
        } => {
            let reflectance = color_input(r, texture("reflectance", textures)?)?;
            let sigma = non_negative("roughness", *roughness)?;
            Ok(match texture("roughness", textures)? {
                Some(t) => Material::OrenNayar {
                    reflectance,
                    sigma: FloatInput::Texture(t),
                },
                None if sigma == 0.0 => Material::Diffuse { reflectance },
                None => Material::OrenNayar {
                    reflectance,
                    sigma: FloatInput::Constant(sigma),
                },
            })
        }
        MaterialKind::Conductor { eta, k, roughness } => Ok(Material::Conductor {
            eta: conductor_spectrum(eta, "eta", false)?,
            k: conductor_spectrum(k, "k", true)?,
            distrib: TrowbridgeReitz::isotropic(non_negative("roughness", *roughness)?),
            roughness: alpha_texture(texture("roughness", textures)?),
        }),
        MaterialKind::Dielectric {
            ior,
            roughness,
            thin,
        } => {
            let alpha = texture("roughness", textures)?;
            dielectric(path, ior, (*roughness, alpha), *thin, warnings)
        }
        MaterialKind::Plastic {
            reflectance: r,
            ior,
            roughness,
        } => {
            let mut p = PlasticMaterial::new(
                reflectance(r)?,
                *ior,
                non_negative("roughness", *roughness)?,
            );
            p.reflectance = color_input(r, texture("reflectance", textures)?)?;
            Ok(Material::Plastic(match texture("roughness", textures)? {
                Some(t) => p.with_roughness_texture(t),
                None => p,
            }))
        }
        MaterialKind::PreviewSurface(ps) => preview_surface(path, ps, textures, warnings),
    }
}

/// A reflectance input: the texture when there is one, else the spectrum `r`.
fn color_input(r: &SpectrumDesc, texture: Option<TextureInput>) -> Reason<ColorInput> {
    Ok(match texture {
        Some(t) => ColorInput::Texture(t),
        None => ColorInput::Constant(reflectance(r)?),
    })
}

/// A textured GGX α (no coat levels).
fn alpha_texture(texture: Option<TextureInput>) -> Option<AlphaTexture> {
    texture.map(|texture| AlphaTexture {
        texture,
        coats: None,
    })
}

/// `spectral:dielectric`: an interface, or a thin slab with `inputs:thin`; `roughness` is
/// the constant α and the texture replacing it.
fn dielectric(
    path: &str,
    i: &IorDesc,
    roughness: (f32, Option<TextureInput>),
    thin: bool,
    warnings: &mut Vec<String>,
) -> Reason<Material> {
    let ior = ior(i)?;
    let alpha = non_negative("roughness", roughness.0)?;
    if !thin {
        let distrib = TrowbridgeReitz::isotropic(alpha);
        let roughness = alpha_texture(roughness.1);
        return Ok(Material::Dielectric {
            ior,
            distrib,
            roughness,
        });
    }
    if alpha > 0.0 || roughness.1.is_some() {
        warnings.push(format!(
            "{path}: a thin dielectric is always smooth; inputs:roughness ignored"
        ));
    }
    Ok(Material::ThinDielectric { ior })
}

/// The slot of a textured UsdPreviewSurface input; `None` for inputs the BSDF does not read
/// from textures (`emissiveColor` is read by [`emissive_textures`]).
fn preview_slot<'a>(
    t: &'a mut PreviewTextures,
    input: &str,
) -> Option<&'a mut Option<TextureInput>> {
    Some(match input {
        "diffuseColor" => &mut t.diffuse,
        "specularColor" => &mut t.specular,
        "metallic" => &mut t.metallic,
        "roughness" => &mut t.roughness,
        "clearcoat" => &mut t.clearcoat,
        "clearcoatRoughness" => &mut t.clearcoat_roughness,
        "opacity" => &mut t.opacity,
        "normal" => &mut t.normal,
        _ => return None,
    })
}

/// UsdPreviewSurface (mapping in `material/preview.rs`).
fn preview_surface(
    path: &str,
    ps: &PreviewSurfaceDesc,
    textures: &mut TextureCache,
    warnings: &mut Vec<String>,
) -> Reason<Material> {
    let n = Vec3::from_array(ps.normal);
    if n.try_normalize().is_none_or(|n| n.z <= 0.0) {
        warnings.push(format!(
            "{path}: UsdPreviewSurface normal {:?} does not point out of the surface; using (0, 0, 1)",
            ps.normal
        ));
    }
    let diffuse = reflectance(&SpectrumDesc::Rgb(ps.diffuse_color))?;
    let specular = reflectance(&SpectrumDesc::Rgb(ps.specular_color))?;
    let mut m = PreviewMaterial::new(ps, diffuse, specular);
    for (input, tex) in &ps.textures {
        if input == "normal" && decoded_as_srgb(tex) {
            warnings.push(format!(
                "{}: a normal map decoded as sRGB (sourceColorSpace '{:?}'); normal maps are \
                 usually raw",
                tex.shader_path, tex.color_space
            ));
        }
        let Some(slot) = preview_slot(&mut m.textures, input) else {
            continue;
        };
        *slot = Some(texture_input(textures, tex)?);
    }
    m.prepare_textures();
    Ok(Material::Preview(Box::new(m)))
}

/// True when the texture's colour is sRGB-decoded: `sRGB`, or `auto` on a non-float file.
fn decoded_as_srgb(tex: &TextureDesc) -> bool {
    let float_file = tex
        .file
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("exr") || e.eq_ignore_ascii_case("hdr"));
    match tex.color_space {
        ColorSpace::Srgb => true,
        ColorSpace::Auto => !float_file,
        ColorSpace::Raw => false,
    }
}

/// The image and node parameters of a texture, loaded through the cache.
fn texture_input(cache: &mut TextureCache, tex: &TextureDesc) -> Reason<TextureInput> {
    cache
        .input(tex)
        .map_err(|e| format!("texture <{}>: {e}", tex.shader_path))
}

/// The texture on each material's UsdPreviewSurface `emissiveColor`, if any.
fn emissive_textures(
    desc: &SceneDescription,
    cache: &mut TextureCache,
) -> Result<Vec<Option<Arc<TextureInput>>>> {
    fn emissive(m: &MaterialDesc) -> Option<&TextureDesc> {
        match &m.kind {
            MaterialKind::PreviewSurface(ps) => ps.texture("emissiveColor"),
            _ => None,
        }
    }
    desc.materials
        .iter()
        .map(|m| match emissive(m) {
            Some(tex) => texture_input(cache, tex)
                .map(|t| Some(Arc::new(t)))
                .map_err(|r| Error::prim(&desc.source, &m.prim_path, r)),
            None => Ok(None),
        })
        .collect()
}

/// A roughness (α or σ) that must be ≥ 0.
fn non_negative(name: &str, v: f32) -> Reason<f32> {
    if v.is_finite() && v >= 0.0 {
        Ok(v)
    } else {
        Err(format!(
            "inputs:{name} must be a finite number ≥ 0, got {v}"
        ))
    }
}

/// η (`k_part` false) or k (true) of a conductor: a metal in `spectra/metal/`, any tabulated
/// spectrum, or samples. η must be positive and k non-negative at every wavelength.
fn conductor_spectrum(s: &SpectrumDesc, what: &str, k_part: bool) -> Reason<Spectrum> {
    let dense = match s {
        SpectrumDesc::Named(token) => match (data::metal(token), data::named(token)) {
            (Some((n, k)), _) => if k_part { k } else { n }.clone(),
            (None, Some(d)) => d.clone(),
            (None, None) => {
                return Err(format!(
                    "unknown {what} spectrum '{token}' (metals: {}; or a file in spectra/)",
                    data::metal_names().join(", ")
                ))
            }
        },
        SpectrumDesc::Samples(samples) => DenseSpectrum::from_samples(samples).ok_or(format!(
            "{what} samples must be finite (nm, value) pairs sorted by wavelength"
        ))?,
        SpectrumDesc::Rgb(_) => {
            return Err(format!(
                "a conductor's {what} must be a spectrum, not a colour"
            ))
        }
    };
    let valid = |v: f32| v.is_finite() && if k_part { v >= 0.0 } else { v > 0.0 };
    if !dense.values.iter().all(|&v| valid(v)) {
        let bound = if k_part { "≥ 0" } else { "> 0" };
        return Err(format!(
            "a conductor's {what} must be {bound} at every wavelength"
        ));
    }
    Ok(Spectrum::Dense {
        data: Arc::new(dense),
        scale: 1.0,
    })
}

/// A dielectric's IOR as Sellmeier coefficients (a constant is the one-term form B₁ = n² − 1).
fn ior(i: &IorDesc) -> Reason<Sellmeier> {
    let s = match i {
        IorDesc::Constant(n) if n.is_finite() && *n > 0.0 => Sellmeier::constant(*n),
        IorDesc::Constant(n) => return Err(format!("inputs:ior must be positive, got {n}")),
        IorDesc::Glass(name) => data::glass(name).ok_or_else(|| {
            format!(
                "unknown glass '{name}' (known: {})",
                data::glass_names().join(", ")
            )
        })?,
        IorDesc::Sellmeier { b, c } => Sellmeier { b: *b, c: *c },
    };
    let mut lambda = crate::spectral::LAMBDA_MIN;
    while lambda <= crate::spectral::LAMBDA_MAX {
        let l2 = (lambda * 1e-3).powi(2);
        let n2: f32 = 1.0
            + (0..3)
                .filter(|&j| s.b[j] != 0.0)
                .map(|j| s.b[j] * l2 / (l2 - s.c[j]))
                .sum::<f32>();
        if !(n2.is_finite() && n2 > 0.0) {
            return Err(format!(
                "the Sellmeier coefficients give no real index of refraction at {lambda} nm"
            ));
        }
        lambda += 1.0;
    }
    Ok(s)
}

/// Validates a mesh, assigns its material and turns emissive meshes into triangle lights.
fn mesh(
    desc: &SceneDescription,
    m: &MeshDesc,
    materials: &[Material],
    emissive: &[Option<Arc<TextureInput>>],
    default_material: u32,
    lights: &mut Vec<Light>,
) -> Reason<Mesh> {
    let n = m.positions.len();
    if let Some(bad) = m.indices.iter().flatten().find(|&&i| i as usize >= n) {
        return Err(format!(
            "face vertex index {bad} is out of range (the mesh has {n} points)"
        ));
    }
    limits::check_points(&m.positions)?;
    let material = m.material.map_or(default_material, |i| i as u32);
    let tangents = if materials[material as usize].perturbs_normal() {
        Tangents::of(&m.positions, &m.indices, m.uvs.as_deref())
    } else {
        Tangents::Unused
    };
    let emission = match m.material.and_then(|i| emissive[i].as_ref()) {
        Some(t) if m.light.is_none() => {
            limits::check_luminance(texture_peak(t))?;
            Some((Emitter::Textured(t.clone()), m.double_sided))
        }
        _ => match mesh_emission(desc, m)? {
            Some((r, two)) => {
                limits::check_luminance(limits::luminance(&r))?;
                Some((Emitter::Constant(r), two))
            }
            None => None,
        },
    };
    let light_offset = emission.map(|(emitter, two_sided)| {
        let offset = lights.len() as u32;
        for (k, t) in m.indices.iter().enumerate() {
            let p = t.map(|i| m.positions[i as usize]);
            let light = match &emitter {
                Emitter::Constant(r) => {
                    TriangleLight::new(m.prim_path.clone(), p, r.clone(), two_sided)
                }
                Emitter::Textured(texture) => {
                    TriangleLight::new(m.prim_path.clone(), p, Spectrum::Constant(0.0), two_sided)
                        .with_texture(EmissiveTexture {
                            texture: texture.clone(),
                            uv: corner_uvs(m, k),
                        })
                }
            };
            lights.push(Light::Triangle(light));
        }
        offset
    });
    Ok(Mesh {
        prim_path: m.prim_path.clone(),
        positions: m.positions.clone(),
        indices: m.indices.clone(),
        normals: m.normals.clone(),
        uvs: m.uvs.clone(),
        tangents,
        material,
        light_offset,
    })
}

/// What an emissive mesh emits.
enum Emitter {
    Constant(Spectrum),
    /// A textured UsdPreviewSurface `emissiveColor` (RGB radiance in nits per unit).
    Textured(Arc<TextureInput>),
}

/// The st of triangle `k`'s corners: the mesh's, or (0, 0), (1, 0), (0, 1) without st (the
/// barycentric fallback of `SurfaceHit::uv`).
fn corner_uvs(m: &MeshDesc, k: usize) -> [Vec2; 3] {
    m.uvs
        .as_ref()
        .map_or([Vec2::ZERO, Vec2::X, Vec2::Y], |uvs| uvs[k])
}

/// The radiance of an emissive mesh (MeshLightAPI first, then the material's emissiveColor).
fn mesh_emission(desc: &SceneDescription, m: &MeshDesc) -> Reason<Option<(Spectrum, bool)>> {
    let area: f32 = m
        .indices
        .iter()
        .map(|t| {
            let p = t.map(|i| m.positions[i as usize]);
            0.5 * (p[1] - p[0]).cross(p[2] - p[0]).length()
        })
        .sum();
    let sides = if m.double_sided { 2.0 } else { 1.0 };
    if let Some(e) = &m.light {
        let geometry = Photometric {
            area: Some(area),
            flux_per_nit: Some(sides * PI * area),
            intensity_per_nit: e.luminous_intensity.map(|_| mesh_peak_projected_area(m)),
        };
        return Ok(Some((emission::radiance(e, geometry)?, m.double_sided)));
    }
    let emissive = m
        .material
        .and_then(|i| desc.materials.get(i))
        .and_then(|mat| mat.emission);
    match emissive {
        Some(rgb) if rgb.iter().any(|&c| c > 0.0) => {
            let e = EmissionDesc {
                color: rgb,
                ..Default::default()
            };
            let geometry = Photometric {
                area: Some(area),
                flux_per_nit: None,
                intensity_per_nit: None,
            };
            Ok(Some((emission::radiance(&e, geometry)?, m.double_sided)))
        }
        _ => Ok(None),
    }
}

/// The largest projected area of a mesh light (for `spectral:luminousIntensity`).
fn mesh_peak_projected_area(m: &MeshDesc) -> f32 {
    let patches: Vec<(Vec3, f32)> = m
        .indices
        .iter()
        .map(|t| {
            let p = t.map(|i| m.positions[i as usize]);
            let c = (p[1] - p[0]).cross(p[2] - p[0]);
            (c.normalize_or_zero(), 0.5 * c.length())
        })
        .collect();
    report::peak_projected_area(&patches, m.double_sided)
}

fn bounding_sphere(bvh: &Bvh) -> (Vec3, f32) {
    if bvh.triangle_count() == 0 {
        return (Vec3::ZERO, 1.0);
    }
    let (lo, hi) = bvh.bounds();
    let center = 0.5 * (lo + hi);
    (center, (0.5f32 * (hi - lo).length()).max(1e-3))
}

/// The scale a transform applies to the plane or space of `axes` (local axes, 0 = X), which
/// must be uniform there: equal lengths, at right angles. A non-uniform scale or a shear
/// turns a sphere into an ellipsoid and a circle into an ellipse, shapes these lights do not
/// sample, so it is refused rather than rounded (`what` names the light type).
fn round_scale(m: &Mat4, axes: &[usize], what: &str) -> Reason<f32> {
    const TOLERANCE: f32 = 1e-4;
    let columns = [m.x_axis, m.y_axis, m.z_axis].map(|c| c.truncate());
    let lengths: Vec<f32> = axes.iter().map(|&a| columns[a].length()).collect();
    let (lo, hi) = lengths
        .iter()
        .fold((f32::MAX, 0.0f32), |(lo, hi), &l| (lo.min(l), hi.max(l)));
    let skew = axes.iter().enumerate().any(|(i, &a)| {
        axes[i + 1..].iter().any(|&b| {
            let cos = columns[a].dot(columns[b]) / (lengths[i] * columns[b].length());
            cos.abs() > TOLERANCE
        })
    });
    if hi - lo > TOLERANCE * hi || skew {
        let names = ["x", "y", "z"];
        let scales: Vec<String> = axes
            .iter()
            .zip(&lengths)
            .map(|(&a, l)| format!("{} {l}", names[a]))
            .collect();
        return Err(format!(
            "the transform scales this {what} non-uniformly ({}{}), which would make it {}; \
             such lights are not supported (scale its radius instead)",
            scales.join(", "),
            if skew { ", with shear" } else { "" },
            if axes.len() == 3 {
                "an ellipsoid"
            } else {
                "an ellipse"
            }
        ));
    }
    Ok(lengths
        .iter()
        .product::<f32>()
        .powf(1.0 / axes.len() as f32))
}

/// The stage's PortalLights given to every DomeLight (built anew each time: a kept dome of an
/// earlier frame gets this frame's portals); a warning when no dome takes them.
fn attach_portals(
    desc: &SceneDescription,
    lights: &mut [Light],
    warnings: &mut Vec<String>,
) -> Result<()> {
    let mut portals = Vec::new();
    for l in &desc.lights {
        if let LightKind::Portal { width, height } = l.kind {
            let p =
                portal(l, width, height).map_err(|r| Error::prim(&desc.source, &l.prim_path, r))?;
            portals.push(p);
        }
    }
    for l in lights.iter_mut() {
        if let Light::Dome(d) = l {
            d.portals.clone_from(&portals);
        }
    }
    if !portals.is_empty() && !lights.iter().any(|l| matches!(l, Light::Dome(_))) {
        warnings.push("the stage's PortalLights guide no DomeLight: they change nothing".into());
    }
    Ok(())
}

/// Whether `l` is a PortalLight (not a light: `attach_portals` gives it to the domes).
pub(super) fn is_portal(l: &LightDesc) -> bool {
    matches!(l.kind, LightKind::Portal { .. })
}

/// A UsdLux light in absolute units, with its shaping, within the bounds of `limits.rs`.
pub(super) fn light(l: &LightDesc) -> Reason<Light> {
    let size = match &l.kind {
        LightKind::Rect { width, height, .. } => width.max(*height),
        LightKind::Disk { radius } | LightKind::Sphere { radius, .. } => *radius,
        LightKind::Cylinder { radius, length, .. } => radius.max(*length),
        LightKind::Distant { .. } | LightKind::Dome { .. } | LightKind::Portal { .. } => 1.0,
    };
    limits::check_transform(&l.to_world, size)?;
    let light = build_light(l)?;
    limits::check_luminance(peak_luminance(&light))?;
    Ok(light)
}

/// The largest luminance (cd/m²) `light` emits in any direction (an upper bound for domes).
fn peak_luminance(light: &Light) -> f64 {
    let shaped = |r: &Spectrum, s: &Option<Shaping>| {
        limits::luminance(r)
            * s.as_ref()
                .map_or(1.0, |s| f64::from(s.photometry.max_factor))
    };
    match light {
        Light::Rect(l) => {
            shaped(&l.radiance, &l.shaping) * l.texture.as_ref().map_or(1.0, |t| f64::from(t.peak))
        }
        Light::Disk(l) => shaped(&l.radiance, &l.shaping),
        Light::Sphere(l) => shaped(&l.radiance, &l.shaping),
        Light::Cylinder(l) => shaped(&l.radiance, &l.shaping),
        Light::Point(l) => shaped(&l.sphere.radiance, &l.sphere.shaping),
        Light::Line(l) => shaped(&l.cylinder.radiance, &l.cylinder.shaping),
        Light::Triangle(l) => limits::luminance(&l.radiance),
        Light::Distant(l) => limits::luminance(&l.radiance),
        // A textured dome's texels are checked as it is built (`dome`).
        Light::Dome(l) => match &l.map {
            None => limits::luminance(&l.radiance),
            Some(_) => 0.0,
        },
    }
}

/// The largest channel of an emissive texture's output (`texel · scale + bias`), which
/// bounds the luminance it emits.
fn texture_peak(t: &TextureInput) -> f64 {
    let (w, h) = t.image.level_size(0);
    let mut peak = 0.0f64;
    for y in 0..h {
        for x in 0..w {
            let texel = t.image.level_texel(0, x, y);
            for ((v, s), b) in texel.iter().zip(t.scale).zip(t.bias).take(3) {
                let out = f64::from(*v) * f64::from(s) + f64::from(b);
                peak = peak.max(out.abs());
            }
        }
    }
    peak
}

/// [`light`] without the bounds.
fn build_light(l: &LightDesc) -> Reason<Light> {
    Ok(match &l.kind {
        LightKind::Rect {
            width,
            height,
            texture,
        } => rect(l, *width, *height, texture.as_deref())?,
        LightKind::Disk { radius } => disk(l, *radius)?,
        LightKind::Sphere { radius, point } => as_point(sphere(l, *radius)?, *point),
        LightKind::Cylinder {
            radius,
            length,
            line,
        } => as_line(cylinder(l, *radius, *length)?, *line),
        LightKind::Distant { angle_deg } => distant(l, *angle_deg)?,
        LightKind::Dome { texture } => dome(l, texture.as_deref())?,
        LightKind::Portal { .. } => return Err("a PortalLight is not a light".into()),
    })
}

/// PortalLight: the rectangle in world space, its dome side along the light's local +Z.
fn portal(l: &LightDesc, width: f32, height: f32) -> Reason<Portal> {
    let m = &l.to_world;
    limits::check_transform(m, width.max(height))?;
    let corner = m.transform_point3(Vec3::new(-0.5 * width, -0.5 * height, 0.0));
    let eu = m.transform_vector3(Vec3::new(width, 0.0, 0.0));
    let ev = m.transform_vector3(Vec3::new(0.0, height, 0.0));
    Portal::new(corner, eu, ev, m.transform_vector3(Vec3::Z))
        .ok_or_else(|| "the PortalLight has no area".to_string())
}

/// RectLight: the rectangle's corner and edges in world space, emitting along world −Z of
/// the light (−(edge_u × edge_v)).
fn rect(l: &LightDesc, width: f32, height: f32, texture: Option<&TextureDesc>) -> Reason<Light> {
    let m = &l.to_world;
    let corner = m.transform_point3(Vec3::new(-0.5 * width, -0.5 * height, 0.0));
    let eu = m.transform_vector3(Vec3::new(width, 0.0, 0.0));
    let ev = m.transform_vector3(Vec3::new(0.0, height, 0.0));
    let area = eu.cross(ev).length();
    let n = (-eu.cross(ev)).normalize_or_zero();
    let flat = Photometric {
        area: Some(area),
        flux_per_nit: Some(PI * area),
        intensity_per_nit: Some(area),
    };
    let (shaping, g) = shaped(l, flat, |w| area * n.dot(w).max(0.0))?;
    let radiance = emission::radiance(&l.emission, g)?;
    let texture = match texture {
        Some(t) => {
            let input = TextureCache::default().input(t)?;
            Some(RectTexture::new(Arc::new(input)))
        }
        None => None,
    };
    Ok(Light::Rect(
        RectLight::new(l.prim_path.clone(), corner, eu, ev, n, radiance)
            .with_shaping(shaping)
            .with_texture(texture),
    ))
}

/// DiskLight, emitting along local −Z: a round disk under a uniform in-plane scale, else the
/// ellipse the transform makes of it (semi-axes the images of the local X and Y radii).
fn disk(l: &LightDesc, radius: f32) -> Reason<Light> {
    let m = &l.to_world;
    let center = m.transform_point3(Vec3::ZERO);
    let axes = [Vec3::X, Vec3::Y].map(|a| m.transform_vector3(a * radius));
    let back = m.transform_vector3(Vec3::Z);
    let round = round_scale(m, &[0, 1], "DiskLight").map(|scale| {
        let frame = Frame::from_normal(-back.normalize());
        DiskLight::round(
            String::new(),
            center,
            frame,
            radius * scale,
            Spectrum::Constant(0.0),
        )
    });
    let disk = match round {
        Ok(d) => d,
        Err(_) => {
            let n = axes[0].cross(axes[1]).normalize_or_zero();
            if n == Vec3::ZERO {
                return Err("the transform makes this DiskLight degenerate".into());
            }
            let n = if n.dot(back) > 0.0 { -n } else { n };
            DiskLight {
                axes,
                ..DiskLight::round(
                    String::new(),
                    center,
                    Frame::from_normal(n),
                    axes[0].length().max(axes[1].length()),
                    Spectrum::Constant(0.0),
                )
            }
        }
    };
    let frame = disk.frame;
    let (area, n) = (disk.area(), frame.n);
    let flat = Photometric {
        area: Some(area),
        flux_per_nit: Some(PI * area),
        intensity_per_nit: Some(area),
    };
    let (shaping, g) = shaped(l, flat, |w| area * n.dot(w).max(0.0))?;
    Ok(Light::Disk(DiskLight {
        prim_path: l.prim_path.clone(),
        radiance: emission::radiance(&l.emission, g)?,
        shaping,
        ..disk
    }))
}

/// SphereLight: Φ = π A L. Under a uniform scale a sphere of radius r (A = 4πr², projected
/// area πr² in every direction); otherwise the ellipsoid the transform makes of it, sampled
/// as such (`light/ellipsoid.rs`), never rounded to a sphere.
fn sphere(l: &LightDesc, radius: f32) -> Reason<Light> {
    let m = &l.to_world;
    let center = m.transform_point3(Vec3::ZERO);
    let Ok(scale) = round_scale(m, &[0, 1, 2], "SphereLight") else {
        return ellipsoid(l, radius, center);
    };
    let r = (radius * scale).max(1e-6);
    let area = 4.0 * PI * r * r;
    let round = Photometric {
        area: Some(area),
        flux_per_nit: Some(PI * area),
        intensity_per_nit: Some(PI * r * r),
    };
    let (shaping, g) = shaped(l, round, |_| PI * r * r)?;
    Ok(Light::Sphere(SphereLight {
        prim_path: l.prim_path.clone(),
        center,
        radius: r,
        radiance: emission::radiance(&l.emission, g)?,
        shaping,
        ellipsoid: None,
    }))
}

/// A SphereLight under a non-uniform scale or a shear: the unit sphere mapped by the
/// transform's linear part times the radius.
fn ellipsoid(l: &LightDesc, radius: f32, center: Vec3) -> Reason<Light> {
    let linear = Mat3::from_mat4(l.to_world) * radius.max(1e-6);
    let e = Ellipsoid::new(linear)
        .ok_or_else(|| "the transform makes this SphereLight degenerate".to_string())?;
    let shape = Photometric {
        area: Some(e.area),
        flux_per_nit: Some(PI * e.area),
        intensity_per_nit: Some(e.peak_projected_area()),
    };
    let (shaping, g) = shaped(l, shape, |w| e.projected_area(w))?;
    Ok(Light::Sphere(SphereLight {
        prim_path: l.prim_path.clone(),
        center,
        radius: e.bounding_radius(),
        radiance: emission::radiance(&l.emission, g)?,
        shaping,
        ellipsoid: Some(Box::new(e)),
    }))
}

/// `treatAsPoint`: the sphere (or ellipsoid) becomes a point light with its far field.
fn as_point(light: Light, point: bool) -> Light {
    match light {
        Light::Sphere(sphere) if point => Light::Point(PointLight { sphere }),
        other => other,
    }
}

/// `treatAsLine`: the cylinder becomes a line light along its axis with its far field.
fn as_line(light: Light, line: bool) -> Light {
    match light {
        Light::Cylinder(cylinder) if line => Light::Line(LineLight { cylinder }),
        other => other,
    }
}

/// CylinderLight along local X: the length scales with the X axis, the radius with the
/// geometric mean of the Y and Z scales (exact for transforms that keep the cross-section
/// round). Φ = π · 2πrℓ · L; projected area 2rℓ sin β at angle β from the axis.
fn cylinder(l: &LightDesc, radius: f32, length: f32) -> Reason<Light> {
    let m = &l.to_world;
    let axis = m.transform_vector3(Vec3::X);
    let len = length * axis.length();
    let r = (radius * round_scale(m, &[1, 2], "CylinderLight's cross-section")?).max(1e-6);
    let light = CylinderLight {
        prim_path: l.prim_path.clone(),
        center: m.transform_point3(Vec3::ZERO),
        frame: Frame::from_normal(axis.normalize()),
        radius: r,
        length: len,
        radiance: Spectrum::Constant(0.0),
        shaping: None,
    };
    let area = light.area();
    let tube = Photometric {
        area: Some(area),
        flux_per_nit: Some(PI * area),
        intensity_per_nit: Some(2.0 * r * len),
    };
    let (shaping, g) = shaped(l, tube, |w| light.projected_area(w))?;
    Ok(Light::Cylinder(CylinderLight {
        radiance: emission::radiance(&l.emission, g)?,
        shaping,
        ..light
    }))
}

/// The light's ShapingAPI (if any) and its photometric factors with it: flux and peak
/// intensity per nit integrated over directions with `projected_area(ω)` (m², world ω).
fn shaped(
    l: &LightDesc,
    unshaped: Photometric,
    projected_area: impl Fn(Vec3) -> f32,
) -> Reason<(Option<Shaping>, Photometric)> {
    let Some(desc) = &l.shaping else {
        return Ok((None, unshaped));
    };
    let ies = match &desc.ies {
        Some(i) => Some(Arc::new(IesProfile::read(&i.file)?)),
        None => None,
    };
    let base = emission::unit_shape(&l.emission)?;
    let mut shaping = Shaping::new(desc, &l.to_world, &base, ies)?;
    shaping.photometry = shaping.integrate(projected_area);
    let d = shaping.photometry;
    let dark = |x: f32| x.is_nan() || x <= 0.0;
    if (l.emission.luminous_flux.is_some() && dark(d.flux_per_nit))
        || (l.emission.luminous_intensity.is_some() && dark(d.peak_per_nit))
    {
        return Err("the shaping emits no light, so it cannot reach the given spectral:luminousFlux / spectral:luminousIntensity".into());
    }
    let g = Photometric {
        area: unshaped.area,
        flux_per_nit: Some(d.flux_per_nit),
        intensity_per_nit: Some(d.peak_per_nit),
    };
    Ok((Some(shaping), g))
}

/// DistantLight with the UsdLux sizeFactor: normalize divides by π sin²θmax (θmax ≤ π/2) or
/// (2 − sin²θmax) π beyond; θmax = 0 is a delta light whose luminance is the illuminance.
fn distant(l: &LightDesc, angle_deg: f32) -> Reason<Light> {
    let theta_max = (0.5 * angle_deg).to_radians().clamp(0.0, PI);
    let s2 = theta_max.sin().powi(2);
    let size = if theta_max == 0.0 {
        1.0
    } else if theta_max <= 0.5 * PI {
        PI * s2
    } else {
        (2.0 - s2) * PI
    };
    let g = Photometric {
        area: Some(size),
        flux_per_nit: None,
        intensity_per_nit: None,
    };
    let mut radiance = emission::radiance(&l.emission, g)?;
    let one_minus_cos = 2.0 * (0.5 * theta_max).sin().powi(2);
    if theta_max > 0.0 && one_minus_cos == 0.0 {
        // A cone too narrow for f32 (θmax below ~1e-19 rad) is sampled as a delta light,
        // whose radiance is its illuminance: L · π sin²θmax, not L.
        let e = f64::from(PI) * f64::from(theta_max).sin().powi(2);
        radiance = radiance.scaled(e as f32);
    }
    let to_light = l.to_world.transform_vector3(Vec3::Z).normalize();
    Ok(Light::Distant(DistantLight {
        prim_path: l.prim_path.clone(),
        to_light,
        cos_theta_max: theta_max.cos(),
        one_minus_cos,
        radiance,
    }))
}

fn dome(l: &LightDesc, texture: Option<&std::path::Path>) -> Reason<Light> {
    let world_to_local = Mat3::from_mat4(l.to_world).inverse();
    let g = Photometric {
        area: None,
        flux_per_nit: None,
        intensity_per_nit: None,
    };
    let e = &l.emission;
    let Some(path) = texture else {
        return Ok(Light::Dome(DomeLight {
            prim_path: l.prim_path.clone(),
            world_to_local,
            radiance: emission::radiance(e, g)?,
            map: None,
            portals: Vec::new(),
        }));
    };
    if e.spd.is_some() {
        return Err("spectral:emission cannot be combined with a dome texture".into());
    }
    let img = imageio::read_rgb_linear(path).map_err(|e| e.to_string())?;
    let tint = e.color;
    let scale = e.intensity * e.exposure.exp2();
    check_dome_texels(path, &img.pixels, tint, scale)?;
    let texels: Vec<RgbIlluminantSpectrum> = img
        .pixels
        .iter()
        .map(|p| {
            RgbIlluminantSpectrum::new_lookup([p[0] * tint[0], p[1] * tint[1], p[2] * tint[2]])
        })
        .collect();
    let luminance: Vec<f32> = img
        .pixels
        .iter()
        .map(|p| {
            (0.2126 * p[0] * tint[0] + 0.7152 * p[1] * tint[1] + 0.0722 * p[2] * tint[2]).max(0.0)
        })
        .collect();
    let weights: Vec<f32> = (0..img.height)
        .flat_map(|y| {
            let sin_theta = ((y as f32 + 0.5) / img.height as f32 * PI).sin();
            luminance[y * img.width..(y + 1) * img.width]
                .iter()
                .map(move |&v| v * sin_theta)
                .collect::<Vec<_>>()
        })
        .collect();
    let distribution = Distribution2D::new(&weights, img.width, img.height);
    let map = LatLong {
        width: img.width,
        height: img.height,
        texels,
        luminance,
        distribution,
    };
    Ok(Light::Dome(DomeLight {
        prim_path: l.prim_path.clone(),
        world_to_local,
        radiance: Spectrum::Constant(scale),
        map: Some(map),
        portals: Vec::new(),
    }))
}

/// Dome texels must be finite (as surface texels are), and the brightest, tinted and
/// scaled, within [`limits::MAX_LUMINANCE`] (its largest channel bounds its luminance).
fn check_dome_texels(
    path: &std::path::Path,
    pixels: &[[f32; 3]],
    tint: [f32; 3],
    scale: f32,
) -> Reason<()> {
    let mut peak = 0.0f64;
    for p in pixels {
        if p.iter().any(|v| !v.is_finite()) {
            return Err(format!(
                "dome texture {} has non-finite texels",
                path.display()
            ));
        }
        for c in 0..3 {
            peak = peak.max(f64::from(p[c]) * f64::from(tint[c]) * f64::from(scale));
        }
    }
    limits::check_luminance(peak).map_err(|e| format!("dome texture {}: {e}", path.display()))
}

/// The RenderSettings camera, else the first camera, else one framing the scene from +Z.
fn camera(
    desc: &SceneDescription,
    resolution: Option<(u32, u32)>,
    center: Vec3,
    radius: f32,
) -> Result<Camera> {
    let chosen = match &desc.render.camera {
        Some(path) => Some(
            desc.cameras
                .iter()
                .find(|c| &c.prim_path == path)
                .ok_or_else(|| {
                    Error::prim(
                        &desc.source,
                        path,
                        "RenderSettings names a camera that is not in the stage",
                    )
                })?,
        ),
        None => desc.cameras.first(),
    };
    let cam = chosen
        .cloned()
        .unwrap_or_else(|| default_camera(center, radius));
    let (w, h) = resolution.or(desc.render.resolution).unwrap_or_else(|| {
        let aspect = cam.horizontal_aperture / cam.vertical_aperture;
        (
            DEFAULT_WIDTH,
            ((DEFAULT_WIDTH as f32 / aspect).round() as u32).max(1),
        )
    });
    if w == 0 || h == 0 {
        return Err(Error::scene(
            &desc.source,
            format!("resolution {w}x{h} must be positive"),
        ));
    }
    limits::check_transform(&cam.to_world, 1.0)
        .and_then(|()| limits::check_exposure(cam.exposure))
        .map_err(|r| Error::prim(&desc.source, &cam.prim_path, r))?;
    if !(cam.focal_length > 0.0 && cam.horizontal_aperture > 0.0 && cam.vertical_aperture > 0.0) {
        return Err(Error::prim(
            &desc.source,
            &cam.prim_path,
            "focalLength and apertures must be positive",
        ));
    }
    Ok(Camera::new(&cam, w, h))
}

/// A 40° camera on +Z looking at the scene's bounding sphere.
fn default_camera(center: Vec3, radius: f32) -> CameraDesc {
    let dist = radius / (20.0f32).to_radians().sin();
    CameraDesc {
        prim_path: "(default camera)".into(),
        to_world: Mat4::from_translation(center + Vec3::Z * dist),
        focal_length: 50.0,
        horizontal_aperture: 2.0 * 50.0 * (20.0f32).to_radians().tan(),
        vertical_aperture: 2.0 * 50.0 * (20.0f32).to_radians().tan(),
        clip_near: 1e-3 * dist,
        clip_far: 10.0 * dist + 2.0 * radius,
        f_stop: 0.0,
        focus_distance: 0.0,
        lens_radius: 0.0,
        exposure: 0.0,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_clamped_colour_temperature_is_named_in_the_summary() {
        let bulb = |name: &str, k: f32| LightDesc {
            prim_path: name.into(),
            kind: LightKind::Sphere {
                radius: 0.05,
                point: false,
            },
            to_world: Mat4::IDENTITY,
            emission: EmissionDesc {
                intensity: 10.0,
                color_temperature: Some(k),
                ..Default::default()
            },
            shaping: None,
            shadows: true,
        };
        let desc = SceneDescription {
            lights: vec![bulb("/Warm", 2700.0), bulb("/Blue", 20000.0)],
            ..Default::default()
        };
        let w = build(&desc, Some((1, 1))).unwrap().summary.warnings;
        assert_eq!(w.len(), 1, "{w:?}");
        assert!(
            w[0].starts_with("/Blue: inputs:colorTemperature 20000 K"),
            "{w:?}"
        );
    }
}
