//! `--crop x0,y0,x1,y1` of the render command: the window's EXR and preview
//! (`session::crop`).

use super::color::ColorOutput;
use crate::error::Result;
use crate::output::exr;
use crate::session::crop::Crop;
use crate::session::RenderOutput;
use std::path::Path;

/// Writes the window `c` of `out` as an EXR whose data window is the crop and whose display
/// window is the full image, its RGB in `color`'s working space, and the window's preview.
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
    let window = [c.x0, c.y0, c.width(), c.height()];
    exr::write_window(
        path,
        (out.width, out.height),
        window,
        &rgb,
        &xyz,
        white,
        &meta,
    )?;
    if let Some(preview) = preview {
        color.write_preview_of(preview, (c.width(), c.height()), &rgb, &xyz)?;
    }
    Ok(meta)
}
