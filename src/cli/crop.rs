//! The EXR and preview of a window (`--crop x0,y0,x1,y1` of the render command, or a stage's
//! `dataWindowNDC`: `session::crop`).

use super::color::ColorOutput;
use crate::error::Result;
use crate::output::exr;
use crate::session::crop::Crop;
use crate::session::RenderOutput;
use std::path::Path;

/// Writes the window `c` of `out` as an EXR whose data window is the crop and whose display
/// window is the full image, its RGB in `color`'s working space and its extra layers cut to
/// the window too, and the window's preview.
pub fn write_window(
    path: &Path,
    preview: Option<&Path>,
    color: &ColorOutput,
    out: &RenderOutput,
    c: Crop,
    white: [f32; 2],
    meta: exr::ExrMetadata,
) -> Result<exr::ExrMetadata> {
    let (rgb, xyz) = (
        c.cut(&color.rgb(out), out.width),
        c.cut(&out.xyz, out.width),
    );
    let mut layers = crate::output::layers::exr_layers(&out.layers, color.space);
    for (_, values) in &mut layers.channels {
        *values = c.cut(values, out.width);
    }
    let window = [c.x0, c.y0, c.width(), c.height()];
    exr::write_window(
        path,
        (out.width, out.height),
        window,
        &rgb,
        &xyz,
        &layers,
        white,
        &meta,
    )?;
    if let Some(preview) = preview {
        color.write_preview_of(preview, (c.width(), c.height()), &rgb, &xyz)?;
    }
    Ok(meta)
}
