//! UsdLux: the concrete light prims, the shared `LightAPI` emission inputs (plus the `spectral:`
//! light vocabulary), the `ShapingAPI` inputs, and warnings for the light APIs that are not
//! implemented yet.
//!
//! ShapingAPI is read on rect, disk, sphere and cylinder lights when the prim applies
//! `ShapingAPI` or authors any `shaping:*` input. Unauthored inputs take the schema fallbacks
//! (focus 0, focusTint black, softness 0, angleScale 0, normalize off), except the cone angle:
//! its fallback of 90° applies when `ShapingAPI` is applied, as Hydra delegates see it; when a
//! prim only authors some `shaping:*` inputs without applying the API, the cone is off (180°),
//! so that e.g. a focused SphereLight still emits behind itself as the `shaping:focus` doc
//! describes. On distant, dome and mesh lights shaping is ignored with a warning.
//!
//! Every input is read as `inputs:<name>` and, when that is not authored, as the legacy
//! un-prefixed `<name>` (pre-21.05 UsdLux); defaults are the UsdLux schema fallbacks.

use glam::DMat4;
use openusd::usd;

use super::values::Ctx;
use super::vocab;
use crate::desc::{
    ColorSpace, EmissionDesc, IesDesc, LightDesc, LightKind, ShapingDesc, SpdDesc, TextureChannel,
    TextureDesc, Wrap,
};
use crate::error::Result;

/// The concrete UsdLux light types that become a [`LightDesc`].
const LIGHT_TYPES: [&str; 8] = [
    "RectLight",
    "DiskLight",
    "SphereLight",
    "CylinderLight",
    "DistantLight",
    "DomeLight",
    "DomeLight_1",
    "PortalLight",
];

/// UsdLux types that are recognised but not supported.
const UNSUPPORTED_LIGHT_TYPES: [&str; 4] = [
    "GeometryLight",
    "PluginLight",
    "LightFilter",
    "PluginLightFilter",
];

/// The light types ShapingAPI applies to.
const SHAPED_TYPES: [&str; 4] = ["RectLight", "DiskLight", "SphereLight", "CylinderLight"];

/// The radius used for point-like spheres and line-like cylinders, in metres.
const POINT_RADIUS_M: f64 = 1e-4;

/// `true` for a concrete UsdLux light type.
pub(super) fn is_light_type(type_name: &str) -> bool {
    LIGHT_TYPES.contains(&type_name)
}

/// `true` for a UsdLux type this reader recognises but does not support.
pub(super) fn is_unsupported_light_type(type_name: &str) -> bool {
    UNSUPPORTED_LIGHT_TYPES.contains(&type_name)
}

/// `true` when the applied schemas make a geometric prim emissive.
pub(super) fn has_light_api(apis: &[String]) -> bool {
    apis.iter().any(|a| a == "MeshLightAPI" || a == "LightAPI")
}

/// Reads a concrete light. `local_to_world` is in stage space (units, up axis).
pub(super) fn read_light(
    ctx: &mut Ctx,
    prim: &usd::Prim,
    type_name: &str,
    local_to_world: DMat4,
) -> Result<LightDesc> {
    let kind = match type_name {
        "RectLight" => rect(ctx, prim)?,
        "DiskLight" => LightKind::Disk {
            radius: size(ctx, prim, "radius", 0.5)?,
        },
        "SphereLight" => LightKind::Sphere {
            radius: round_radius(ctx, prim)?,
            point: ctx.bool_or(prim, "treatAsPoint", false)?,
        },
        "CylinderLight" => LightKind::Cylinder {
            radius: round_radius(ctx, prim)?,
            length: size(ctx, prim, "length", 1.0)?,
            line: ctx.bool_or(prim, "treatAsLine", false)?,
        },
        "DistantLight" => LightKind::Distant {
            angle_deg: angle(ctx, prim)?,
        },
        "PortalLight" => LightKind::Portal {
            width: size(ctx, prim, "width", 1.0)?,
            height: size(ctx, prim, "height", 1.0)?,
        },
        _ => LightKind::Dome {
            texture: dome_texture(ctx, prim)?,
        },
    };
    let mut to_world = ctx.stage_to_world * local_to_world;
    if type_name == "DomeLight_1" {
        to_world *= dome_pole(ctx, prim)?;
    }
    warn_unsupported_inputs(ctx, prim)?;
    let emission = read_emission(ctx, prim, default_intensity(type_name))?;
    let shaping = if SHAPED_TYPES.contains(&type_name) {
        read_shaping(ctx, prim)?
    } else {
        None
    };
    Ok(LightDesc {
        prim_path: prim.path().as_str().to_string(),
        kind,
        to_world: to_world.as_mat4(),
        emission,
        shaping,
        shadows: shadows(ctx, prim)?,
    })
}

/// `inputs:shadow:enable`: false makes this light's shadow rays pass through occluders, which
/// is not physical, so the load summary says so.
fn shadows(ctx: &mut Ctx, prim: &usd::Prim) -> Result<bool> {
    let enabled = ctx.bool_or(prim, &input_name(ctx, prim, "shadow:enable")?, true)?;
    if !enabled {
        ctx.warn(
            prim,
            "inputs:shadow:enable = 0: its next-event shadow rays pass through occluders (not \
             physical; honoured by --integrator path and meters only)",
        );
    }
    Ok(enabled)
}

/// The schema fallback of `inputs:intensity`: 50000 for a DistantLight (sunlight in lux),
/// 1 for every other light.
fn default_intensity(type_name: &str) -> f32 {
    if type_name == "DistantLight" {
        50_000.0
    } else {
        1.0
    }
}

/// The attribute name to read for input `base`: `inputs:<base>` unless only the legacy
/// `<base>` is authored.
fn input_name(ctx: &Ctx, prim: &usd::Prim, base: &str) -> Result<String> {
    let modern = format!("inputs:{base}");
    if ctx.raw(prim, &modern)?.is_none() && ctx.raw(prim, base)?.is_some() {
        return Ok(base.to_string());
    }
    Ok(modern)
}

/// A float input with its schema default.
fn input_f32(ctx: &Ctx, prim: &usd::Prim, base: &str, default: f32) -> Result<f32> {
    ctx.f32_or(prim, &input_name(ctx, prim, base)?, default)
}

/// A light dimension: finite and positive.
fn size(ctx: &Ctx, prim: &usd::Prim, base: &str, default: f32) -> Result<f32> {
    let value = input_f32(ctx, prim, base, default)?;
    if value < 0.0 {
        return Err(ctx.err(prim, format!("inputs:{base} is negative")));
    }
    if value == 0.0 {
        return Err(ctx.err(prim, format!("zero-size light (inputs:{base} = 0)")));
    }
    Ok(value)
}

/// A RectLight, with its `inputs:texture:file` (an empty asset path is no texture): read
/// like a UsdUVTexture with the schema's defaults (colour space auto, clamped at the edges),
/// st along the light's local +X and +Y.
fn rect(ctx: &mut Ctx, prim: &usd::Prim) -> Result<LightKind> {
    let width = size(ctx, prim, "width", 1.0)?;
    let height = size(ctx, prim, "height", 1.0)?;
    let file = ctx.asset(prim, &input_name(ctx, prim, "texture:file")?)?;
    let texture = file.map(|file| {
        Box::new(TextureDesc {
            shader_path: prim.path().as_str().to_string(),
            file,
            st_primvar: "st".into(),
            st_transform: None,
            wrap_s: Wrap::Clamp,
            wrap_t: Wrap::Clamp,
            color_space: ColorSpace::Auto,
            scale: [1.0; 4],
            bias: [0.0; 4],
            fallback: [1.0; 4],
            channel: TextureChannel::Rgb,
        })
    });
    Ok(LightKind::Rect {
        width,
        height,
        texture,
    })
}

/// The radius of a sphere or cylinder light (default 0.5). A zero radius gives a tiny radius
/// of 0.1 mm, with a warning (`treatAsPoint` / `treatAsLine` keep the radius: the point or
/// line light emits the far field of the shape of that radius).
fn round_radius(ctx: &mut Ctx, prim: &usd::Prim) -> Result<f32> {
    let radius = input_f32(ctx, prim, "radius", 0.5)?;
    if radius < 0.0 {
        return Err(ctx.err(prim, "inputs:radius is negative"));
    }
    if radius > 0.0 {
        return Ok(radius);
    }
    ctx.warn(
        prim,
        format!(
            "inputs:radius = 0: modelled with a radius of {} mm",
            POINT_RADIUS_M * 1e3
        ),
    );
    Ok((POINT_RADIUS_M / ctx.meters_per_unit) as f32)
}

/// A DistantLight's angular diameter in degrees (default 0.53).
fn angle(ctx: &Ctx, prim: &usd::Prim) -> Result<f32> {
    let angle = input_f32(ctx, prim, "angle", 0.53)?;
    if !(0.0..=360.0).contains(&angle) {
        return Err(ctx.err(
            prim,
            format!("inputs:angle = {angle} is outside [0, 360] degrees"),
        ));
    }
    Ok(angle)
}

/// A DomeLight's lat-long texture (absolute path), `None` for a constant dome.
fn dome_texture(ctx: &Ctx, prim: &usd::Prim) -> Result<Option<std::path::PathBuf>> {
    let format_name = input_name(ctx, prim, "texture:format")?;
    let format = ctx
        .token(prim, &format_name)?
        .unwrap_or_else(|| "automatic".into());
    if format != "automatic" && format != "latlong" {
        return Err(ctx.err(
            prim,
            format!("texture format '{format}' is not supported (only latlong)"),
        ));
    }
    ctx.asset(prim, &input_name(ctx, prim, "texture:file")?)
}

/// DomeLight_1's `poleAxis`: an extra rotation taking the dome's +Y pole to local +Z when
/// the pole is Z (explicitly, or "scene" on a Z-up stage).
fn dome_pole(ctx: &Ctx, prim: &usd::Prim) -> Result<DMat4> {
    let pole = ctx
        .token(prim, "poleAxis")?
        .unwrap_or_else(|| "scene".into());
    let z_pole = match pole.as_str() {
        "Y" => false,
        "Z" => true,
        "scene" => ctx.z_up,
        other => return Err(ctx.err(prim, format!("poleAxis '{other}' is not Y, Z or scene"))),
    };
    Ok(if z_pole {
        DMat4::from_rotation_x(std::f64::consts::FRAC_PI_2)
    } else {
        DMat4::IDENTITY
    })
}

/// The `inputs:` of UsdLux's LightAPI, ShadowAPI and ShapingAPI (every light has them).
const LIGHT_API_INPUTS: [&str; 20] = [
    "intensity",
    "exposure",
    "color",
    "enableColorTemperature",
    "colorTemperature",
    "normalize",
    "diffuse",
    "specular",
    "shadow:enable",
    "shadow:color",
    "shadow:distance",
    "shadow:falloff",
    "shadow:falloffGamma",
    "shaping:focus",
    "shaping:focusTint",
    "shaping:cone:angle",
    "shaping:cone:softness",
    "shaping:ies:file",
    "shaping:ies:angleScale",
    "shaping:ies:normalize",
];

/// The `inputs:` a light type adds to [`LIGHT_API_INPUTS`].
fn type_inputs(type_name: &str) -> &'static [&'static str] {
    match type_name {
        "RectLight" => &["width", "height", "texture:file"],
        "DiskLight" => &["radius"],
        "SphereLight" => &["radius"],
        "CylinderLight" => &["radius", "length"],
        "DistantLight" => &["angle"],
        "PortalLight" => &["width", "height"],
        "DomeLight" | "DomeLight_1" => &["texture:file", "texture:format", "guideRadius"],
        _ => &[],
    }
}

/// Warns about `inputs:*` that UsdLux does not define for this prim (a typo renders at the
/// schema default otherwise), with a "did you mean" one edit away.
fn warn_unknown_inputs(ctx: &mut Ctx, prim: &usd::Prim, type_name: &str) -> Result<()> {
    let mut known: Vec<&str> = LIGHT_API_INPUTS.to_vec();
    known.extend_from_slice(type_inputs(type_name));
    let what = if type_name.is_empty() {
        "a light"
    } else {
        type_name
    };
    vocab::warn_unknown_inputs(ctx, prim, &known, what)
}

/// Warns about light inputs that are authored but not implemented (shaping on lights it does
/// not apply to, shadows, non-physical diffuse/specular multipliers, light filters) or that
/// UsdLux does not define.
pub(super) fn warn_unsupported_inputs(ctx: &mut Ctx, prim: &usd::Prim) -> Result<()> {
    let type_name = ctx.type_name(prim)?;
    let light_type = if is_light_type(&type_name) {
        type_name.as_str()
    } else {
        ""
    };
    warn_unknown_inputs(ctx, prim, light_type)?;
    let names = ctx.property_names(prim)?;
    let has = |prefix: &str| {
        names
            .iter()
            .any(|n| n.starts_with(prefix) || n.starts_with(&format!("inputs:{prefix}")))
    };
    if has("shaping:") && !SHAPED_TYPES.contains(&type_name.as_str()) {
        ctx.warn(
            prim,
            format!(
                "ShapingAPI (shaping:*) applies to rect, disk, sphere and cylinder lights; \
                 ignored on this {}",
                if type_name.is_empty() {
                    "prim"
                } else {
                    &type_name
                }
            ),
        );
    }
    let tint = [
        "shadow:color",
        "shadow:distance",
        "shadow:falloff",
        "shadow:falloffGamma",
    ];
    if tint.iter().any(|t| has(t)) {
        ctx.warn(
            prim,
            "ShadowAPI shadow:color, shadow:distance, shadow:falloff and shadow:falloffGamma \
             are not physical; ignored",
        );
    }
    for base in ["diffuse", "specular"] {
        if input_f32(ctx, prim, base, 1.0)? != 1.0 {
            ctx.warn(
                prim,
                format!("inputs:{base} is a non-physical multiplier; ignored"),
            );
        }
    }
    let filters = ctx.targets(prim, "light:filters")?;
    if !filters.is_empty() {
        let names: Vec<&str> = filters.iter().map(|p| p.as_str()).collect();
        ctx.warn(
            prim,
            format!(
                "light filters are not supported; ignored: {}",
                names.join(", ")
            ),
        );
    }
    Ok(())
}

/// The ShapingAPI inputs of a light, or None when it has none (module docs: the defaults).
fn read_shaping(ctx: &mut Ctx, prim: &usd::Prim) -> Result<Option<ShapingDesc>> {
    let applied = ctx.api_schemas(prim)?.iter().any(|a| a == "ShapingAPI");
    let authored = ctx
        .property_names(prim)?
        .iter()
        .any(|n| n.starts_with("shaping:") || n.starts_with("inputs:shaping:"));
    if !applied && !authored {
        return Ok(None);
    }
    let cone_default = if applied { 90.0 } else { 180.0 };
    let cone_angle_deg = input_f32(ctx, prim, "shaping:cone:angle", cone_default)?;
    if cone_angle_deg.is_nan() || cone_angle_deg < 0.0 {
        return Err(ctx.err(
            prim,
            format!("inputs:shaping:cone:angle = {cone_angle_deg} must be a non-negative angle in degrees"),
        ));
    }
    let softness = input_f32(ctx, prim, "shaping:cone:softness", 0.0)?;
    let focus = input_f32(ctx, prim, "shaping:focus", 0.0)?;
    if !(softness.is_finite() && focus.is_finite()) {
        return Err(ctx.err(
            prim,
            "shaping:cone:softness and shaping:focus must be finite",
        ));
    }
    let focus_tint = ctx.rgb_or(prim, &input_name(ctx, prim, "shaping:focusTint")?, [0.0; 3])?;
    if focus_tint.iter().any(|&c| c.is_nan() || c < 0.0) {
        return Err(ctx.err(prim, "inputs:shaping:focusTint has a negative component"));
    }
    if focus_tint.iter().any(|&c| c > 1.0) {
        ctx.warn(
            prim,
            "inputs:shaping:focusTint above 1 is clamped to 1 (a tint only darkens)",
        );
    }
    Ok(Some(ShapingDesc {
        cone_angle_deg,
        cone_softness: softness.clamp(0.0, 1.0),
        focus: focus.max(0.0),
        focus_tint: focus_tint.map(|c| c.min(1.0)),
        ies: read_ies(ctx, prim)?,
    }))
}

/// `shaping:ies:file` (resolved like any asset), `angleScale` and `normalize`.
fn read_ies(ctx: &Ctx, prim: &usd::Prim) -> Result<Option<IesDesc>> {
    let Some(file) = ctx.asset(prim, &input_name(ctx, prim, "shaping:ies:file")?)? else {
        return Ok(None);
    };
    let angle_scale = input_f32(ctx, prim, "shaping:ies:angleScale", 0.0)?;
    if !angle_scale.is_finite() {
        return Err(ctx.err(prim, "inputs:shaping:ies:angleScale must be finite"));
    }
    Ok(Some(IesDesc {
        file,
        angle_scale,
        normalize: ctx.bool_or(
            prim,
            &input_name(ctx, prim, "shaping:ies:normalize")?,
            false,
        )?,
    }))
}

/// The LightAPI emission of a light or `MeshLightAPI` prim, with the `spectral:` vocabulary.
/// `default_intensity` is the schema's fallback for `inputs:intensity`.
pub(super) fn read_emission(
    ctx: &Ctx,
    prim: &usd::Prim,
    default_intensity: f32,
) -> Result<EmissionDesc> {
    let intensity = input_f32(ctx, prim, "intensity", default_intensity)?;
    if intensity < 0.0 {
        return Err(ctx.err(prim, "inputs:intensity is negative"));
    }
    let color = ctx.rgb_or(prim, &input_name(ctx, prim, "color")?, [1.0; 3])?;
    if color.iter().any(|&c| c < 0.0) {
        return Err(ctx.err(prim, "inputs:color has a negative component"));
    }
    let (luminous_flux, luminous_intensity) = photometric(ctx, prim)?;
    Ok(EmissionDesc {
        color,
        intensity,
        exposure: input_f32(ctx, prim, "exposure", 0.0)?,
        normalize: ctx.bool_or(prim, &input_name(ctx, prim, "normalize")?, false)?,
        color_temperature: color_temperature(ctx, prim)?,
        spd: spd(ctx, prim)?,
        luminous_flux,
        luminous_intensity,
        light_group: light_group(ctx, prim)?,
    })
}

/// `spectral:lightGroup`: a name usable as an EXR layer (letters, digits, `_`, `-`).
fn light_group(ctx: &Ctx, prim: &usd::Prim) -> Result<Option<String>> {
    let Some(g) = ctx.token(prim, vocab::LIGHT_GROUP)? else {
        return Ok(None);
    };
    let ok = |c: char| c.is_ascii_alphanumeric() || c == '_' || c == '-';
    if g.is_empty() || !g.chars().all(ok) {
        return Err(ctx.err(
            prim,
            format!(
                "spectral:lightGroup '{g}' must be letters, digits, '_' or '-' (an EXR layer name)"
            ),
        ));
    }
    Ok(Some(g))
}

/// `inputs:colorTemperature` (default 6500 K) when `inputs:enableColorTemperature` is on.
fn color_temperature(ctx: &Ctx, prim: &usd::Prim) -> Result<Option<f32>> {
    if !ctx.bool_or(
        prim,
        &input_name(ctx, prim, "enableColorTemperature")?,
        false,
    )? {
        return Ok(None);
    }
    let kelvin = input_f32(ctx, prim, "colorTemperature", 6500.0)?;
    if kelvin <= 0.0 {
        return Err(ctx.err(prim, "inputs:colorTemperature must be positive"));
    }
    Ok(Some(kelvin))
}

/// `spectral:emission` (named SPD or blackbody with `spectral:temperature`) or
/// `spectral:emission:samples`.
fn spd(ctx: &Ctx, prim: &usd::Prim) -> Result<Option<SpdDesc>> {
    let name = ctx.token(prim, vocab::EMISSION)?;
    let samples = ctx.samples(prim, vocab::EMISSION_SAMPLES)?;
    let temperature = ctx.f64(prim, vocab::TEMPERATURE)?;
    let blackbody = name.as_deref() == Some("blackbody");
    if temperature.is_some() && !blackbody {
        return Err(ctx.err(
            prim,
            "spectral:temperature needs spectral:emission = \"blackbody\"",
        ));
    }
    match (name, samples) {
        (Some(_), Some(_)) => Err(ctx.err(
            prim,
            "give only one of spectral:emission, spectral:emission:samples",
        )),
        (Some(_), None) if blackbody => match temperature {
            Some(t) if t > 0.0 => Ok(Some(SpdDesc::Blackbody(t as f32))),
            Some(_) => Err(ctx.err(prim, "spectral:temperature must be positive")),
            None => Err(ctx.err(
                prim,
                "spectral:emission = \"blackbody\" needs spectral:temperature",
            )),
        },
        (Some(name), None) => Ok(Some(SpdDesc::Named(name))),
        (None, Some(samples)) => Ok(Some(SpdDesc::Samples(samples))),
        (None, None) => Ok(None),
    }
}

/// `spectral:luminousFlux` (lm) and `spectral:luminousIntensity` (cd), at most one, non-negative.
fn photometric(ctx: &Ctx, prim: &usd::Prim) -> Result<(Option<f32>, Option<f32>)> {
    let flux = ctx.f64(prim, vocab::LUMINOUS_FLUX)?;
    let intensity = ctx.f64(prim, vocab::LUMINOUS_INTENSITY)?;
    if flux.is_some() && intensity.is_some() {
        return Err(ctx.err(
            prim,
            "give only one of spectral:luminousFlux, spectral:luminousIntensity",
        ));
    }
    if flux.or(intensity).is_some_and(|x| x < 0.0) {
        return Err(ctx.err(prim, "photometric quantity is negative"));
    }
    Ok((flux.map(|x| x as f32), intensity.map(|x| x as f32)))
}
