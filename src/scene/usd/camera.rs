//! UsdGeomCamera and the UsdRender settings that name the camera and resolution.

use glam::{DMat4, DVec3};
use openusd::{sdf, usd};

use super::values::{self, Ctx};
use crate::desc::{CameraDesc, DataWindowDesc, RenderSettingsDesc};
use crate::error::Result;

/// Reads a camera. `local_to_world` is in stage space (units, up axis).
pub(super) fn read_camera(
    ctx: &mut Ctx,
    prim: &usd::Prim,
    local_to_world: DMat4,
) -> Result<CameraDesc> {
    let projection = ctx
        .token(prim, "projection")?
        .unwrap_or_else(|| "perspective".into());
    if projection != "perspective" {
        return Err(ctx.err(prim, format!("{projection} cameras are not supported")));
    }
    warn_aperture_offsets(ctx, prim)?;
    let mpu = ctx.meters_per_unit;
    let focal_length = positive(ctx, prim, "focalLength", 50.0)?;
    let f_stop = ctx.f32_or(prim, "fStop", 0.0)?;
    if f_stop < 0.0 {
        return Err(ctx.err(prim, "fStop is negative"));
    }
    let focus_distance = ctx.f32_or(prim, "focusDistance", 0.0)?;
    if f_stop > 0.0 && focus_distance <= 0.0 {
        let reason = format!(
            "fStop = {f_stop} makes a thin lens, which needs focusDistance > 0 (it is \
             {focus_distance}); use fStop = 0 for a pinhole camera"
        );
        return Err(ctx.err(prim, reason));
    }
    let (clip_near, clip_far) = clipping_range(ctx, prim)?;
    let lens_radius = if f_stop > 0.0 {
        f64::from(focal_length) * 0.1 * mpu / (2.0 * f64::from(f_stop))
    } else {
        0.0
    };
    Ok(CameraDesc {
        prim_path: prim.path().as_str().to_string(),
        to_world: rigid(ctx, prim, ctx.stage_to_world * local_to_world)?.as_mat4(),
        focal_length,
        horizontal_aperture: positive(ctx, prim, "horizontalAperture", 20.955)?,
        vertical_aperture: positive(ctx, prim, "verticalAperture", 15.2908)?,
        clip_near: (clip_near * mpu) as f32,
        clip_far: (clip_far * mpu) as f32,
        f_stop,
        focus_distance: (f64::from(focus_distance.max(0.0)) * mpu) as f32,
        lens_radius: lens_radius as f32,
        exposure: exposure(ctx, prim)?,
    })
}

/// The camera frame without scale (so that camera space is in metres, like the clipping
/// range): the viewing direction -Z and the up vector +Y of `to_world` are kept exactly.
fn rigid(ctx: &Ctx, prim: &usd::Prim, to_world: DMat4) -> Result<DMat4> {
    let up = to_world.y_axis.truncate().normalize_or_zero();
    let right = up.cross(to_world.z_axis.truncate()).normalize_or_zero();
    if up == DVec3::ZERO || right == DVec3::ZERO {
        return Err(ctx.err(prim, "degenerate camera transform (zero scale)"));
    }
    let back = right.cross(up);
    Ok(DMat4::from_cols(
        right.extend(0.0),
        up.extend(0.0),
        back.extend(0.0),
        to_world.w_axis,
    ))
}

/// A float attribute that must be positive.
fn positive(ctx: &Ctx, prim: &usd::Prim, name: &str, default: f32) -> Result<f32> {
    let value = ctx.f32_or(prim, name, default)?;
    if value <= 0.0 {
        return Err(ctx.err(prim, format!("{name} must be positive")));
    }
    Ok(value)
}

/// `clippingRange` in stage units (default (1, 1e6)), with 0 < near < far.
fn clipping_range(ctx: &Ctx, prim: &usd::Prim) -> Result<(f64, f64)> {
    let [near, far] = ctx.vec2(prim, "clippingRange")?.unwrap_or([1.0, 1e6]);
    if !(near > 0.0 && far > near && far.is_finite()) {
        return Err(ctx.err(
            prim,
            format!("clippingRange ({near}, {far}) must satisfy 0 < near < far"),
        ));
    }
    Ok((near, far))
}

/// `exposure` plus the photographic exposure controls (UsdGeomCamera
/// `ComputeLinearExposureScale`): log2(time * iso / 100 * responsivity / fStop^2).
fn exposure(ctx: &Ctx, prim: &usd::Prim) -> Result<f32> {
    let ev = ctx.f64(prim, "exposure")?.unwrap_or(0.0);
    let iso = ctx.f64(prim, "exposure:iso")?.unwrap_or(100.0);
    let time = ctx.f64(prim, "exposure:time")?.unwrap_or(1.0);
    let f_stop = ctx.f64(prim, "exposure:fStop")?.unwrap_or(1.0);
    let responsivity = ctx.f64(prim, "exposure:responsivity")?.unwrap_or(1.0);
    let scale = time * iso / 100.0 * responsivity / (f_stop * f_stop);
    if !(scale > 0.0 && scale.is_finite()) {
        return Err(ctx.err(
            prim,
            "exposure:iso/time/fStop/responsivity must be positive",
        ));
    }
    Ok((ev + scale.log2()) as f32)
}

/// Lens shift is not modelled: warn when it is authored.
fn warn_aperture_offsets(ctx: &mut Ctx, prim: &usd::Prim) -> Result<()> {
    for name in ["horizontalApertureOffset", "verticalApertureOffset"] {
        if ctx.f64(prim, name)?.is_some_and(|x| x != 0.0) {
            ctx.warn(
                prim,
                format!("{name} (lens shift) is not supported; ignored"),
            );
        }
    }
    Ok(())
}

/// The render settings: the prim named by the stage's `renderSettingsPrimPath`, else the
/// first RenderSettings prim. The first RenderProduct's resolution / camera override it.
pub(super) fn read_render_settings(
    ctx: &mut Ctx,
    settings: &[sdf::Path],
    cameras: &[CameraDesc],
) -> Result<RenderSettingsDesc> {
    let Some(path) = chosen_settings(ctx, settings)? else {
        return Ok(RenderSettingsDesc::default());
    };
    let prim = ctx.stage.prim(path);
    let mut desc = settings_of(ctx, &prim)?;
    if let Some(product) = ctx.targets(&prim, "products")?.into_iter().next() {
        let product_prim = ctx.stage.prim(product);
        let product = settings_of(ctx, &product_prim)?;
        desc.resolution = product.resolution.or(desc.resolution);
        desc.camera = product.camera.or(desc.camera);
        desc.data_window = product.data_window.or(desc.data_window);
    }
    desc.data_window = desc.data_window.filter(|w| w.ndc != WHOLE_IMAGE);
    if let Some(camera) = &desc.camera {
        if !cameras.iter().any(|c| &c.prim_path == camera) {
            return Err(ctx.err(
                &prim,
                format!("camera targets <{camera}>, which is not a Camera on the stage"),
            ));
        }
    }
    Ok(desc)
}

/// Which RenderSettings prim applies.
fn chosen_settings(ctx: &mut Ctx, settings: &[sdf::Path]) -> Result<Option<sdf::Path>> {
    let named = ctx
        .stage
        .stage_metadata("renderSettingsPrimPath")
        .map_err(|e| {
            crate::error::Error::usd(&ctx.file, format!("reading renderSettingsPrimPath: {e:#}"))
        })?;
    if let Some(named) = named
        .as_ref()
        .and_then(values::to_token)
        .filter(|s| !s.is_empty())
    {
        return match settings.iter().find(|p| p.as_str() == named) {
            Some(p) => Ok(Some(p.clone())),
            None => Err(crate::error::Error::usd(
                &ctx.file,
                format!("renderSettingsPrimPath <{named}> is not a RenderSettings prim"),
            )),
        };
    }
    if settings.len() > 1 {
        let prim = ctx.stage.prim(settings[0].clone());
        ctx.warn(
            &prim,
            "several RenderSettings prims and no renderSettingsPrimPath; using this one",
        );
    }
    Ok(settings.first().cloned())
}

/// The RenderSettings / RenderProduct properties that are read.
const HONOURED_SETTINGS: [&str; 4] = ["resolution", "camera", "products", "dataWindowNDC"];

/// `dataWindowNDC`'s schema fallback: the whole image.
const WHOLE_IMAGE: [f64; 4] = [0.0, 0.0, 1.0, 1.0];

/// Warns about every authored property of a RenderSettings or RenderProduct prim that is
/// not read, unless it holds its schema fallback or what the renderer does anyway.
fn warn_ignored_settings(ctx: &mut Ctx, prim: &usd::Prim) -> Result<()> {
    for name in ctx.property_names(prim)? {
        if HONOURED_SETTINGS.contains(&name.as_str()) {
            continue;
        }
        let value = ctx.raw(prim, &name)?;
        let harmless = match &value {
            None => ctx.targets(prim, &name)?.is_empty(),
            Some(v) => matches_behaviour(&name, v),
        };
        if !harmless {
            ctx.warn(prim, format!("{name} is not supported; ignored"));
        }
    }
    Ok(())
}

/// `true` when `value` of the render setting `name` is what the renderer does anyway (the
/// schema fallbacks of UsdRenderSettingsBase, RenderSettings and RenderProduct, and motion
/// blur, which is never rendered).
fn matches_behaviour(name: &str, value: &sdf::Value) -> bool {
    let tokens = |v: &sdf::Value| match v {
        sdf::Value::TokenVec(t) => {
            let mut t: Vec<String> = t.iter().map(|x| x.as_str().to_string()).collect();
            t.sort();
            Some(t)
        }
        _ => None,
    };
    match name {
        "pixelAspectRatio" => values::to_f64(value) == Some(1.0),
        "aspectRatioConformPolicy" => values::to_token(value).as_deref() == Some("expandAperture"),
        "disableMotionBlur" | "instantaneousShutter" => true,
        "disableDepthOfField" => values::to_bool(value) == Some(false),
        "includedPurposes" => tokens(value) == Some(vec!["default".into(), "render".into()]),
        "materialBindingPurposes" => tokens(value) == Some(vec!["".into(), "full".into()]),
        "productType" => values::to_token(value).as_deref() == Some("raster"),
        _ => false,
    }
}

/// `resolution` and `camera` of a RenderSettings or RenderProduct prim.
fn settings_of(ctx: &mut Ctx, prim: &usd::Prim) -> Result<RenderSettingsDesc> {
    warn_ignored_settings(ctx, prim)?;
    let resolution = match ctx.vec2(prim, "resolution")? {
        None => None,
        Some([w, h])
            if w >= 1.0 && h >= 1.0 && w.fract() == 0.0 && h.fract() == 0.0 && w.max(h) < 1e6 =>
        {
            Some((w as u32, h as u32))
        }
        Some([w, h]) => {
            return Err(ctx.err(
                prim,
                format!("resolution ({w}, {h}) must be positive integers"),
            ))
        }
    };
    let camera = ctx
        .targets(prim, "camera")?
        .into_iter()
        .next()
        .map(|p| p.as_str().to_string());
    Ok(RenderSettingsDesc {
        resolution,
        camera,
        data_window: data_window_of(ctx, prim)?,
    })
}

/// An authored `dataWindowNDC` (the whole image included, so that a product's whole window
/// overrides its settings' window). A window reaching outside [0, 1] (overscan: pixels
/// beyond the screen window) or an empty one is refused.
fn data_window_of(ctx: &mut Ctx, prim: &usd::Prim) -> Result<Option<DataWindowDesc>> {
    let Some(value) = ctx.raw(prim, "dataWindowNDC")? else {
        return Ok(None);
    };
    let Some(ndc) = values::to_vec4(&value, 1.0) else {
        return Err(ctx.err(prim, "dataWindowNDC is not a float4"));
    };
    let [x0, y0, x1, y1] = ndc;
    if !ndc.iter().all(|v| v.is_finite() && (0.0..=1.0).contains(v)) {
        return Err(ctx.err(
            prim,
            format!(
                "dataWindowNDC ({x0}, {y0}, {x1}, {y1}) reaches outside the screen window \
                 [0, 1]²; overscan is not supported"
            ),
        ));
    }
    if x0 >= x1 || y0 >= y1 {
        return Err(ctx.err(
            prim,
            format!("dataWindowNDC ({x0}, {y0}, {x1}, {y1}) is empty (xmin ≥ xmax or ymin ≥ ymax)"),
        ));
    }
    Ok(Some(DataWindowDesc {
        ndc,
        prim_path: prim.path().as_str().to_string(),
    }))
}
