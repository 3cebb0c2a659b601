//! The colour options of the commands that write an image: `--colorspace` (the EXR's RGB
//! working space) and the OCIO preview (`--preview`, `--preview-exposure`, `--ocio`,
//! `--display`, `--view`). The config and the transform are resolved before the work starts,
//! so a bad name fails at once.

use crate::error::{Error, Result};
use crate::output::ocio::{DisplayTransform, OcioConfig};
use crate::output::preview::{self, Exposure};
use crate::session::RenderOutput;
use crate::spectral::working_space::WorkingSpace;
use clap::Args;
use std::borrow::Cow;
use std::path::{Path, PathBuf};

/// `--colorspace` and the preview's options.
#[derive(Args, Debug, Clone)]
pub struct PreviewArgs {
    /// RGB working space of the EXR's R, G, B channels: lin_rec709, acescg, lin_p3d65 or
    /// xyz. The `chromaticities` attribute matches and `colorspace` holds its OCIO name;
    /// the XYZ.* channels are unchanged.
    #[arg(long, default_value = "lin_rec709", value_parser = parse_space)]
    pub colorspace: WorkingSpace,
    /// Also write an 8-bit PNG preview through an OCIO display transform (default: the
    /// shipped ACES 2.0 CG config, sRGB display, ACES 2.0 SDR view).
    #[arg(long)]
    pub preview: Option<PathBuf>,
    /// Exposure of the preview in stops, applied to the scene-linear RGB before the display
    /// transform (the EXR stays absolute), or `auto`: the log-average luminance to middle
    /// grey 0.18.
    #[arg(long = "preview-exposure", default_value = "0", value_parser = Exposure::parse, allow_hyphen_values = true)]
    pub preview_exposure: Exposure,
    /// The OCIO config of the preview (default: $OCIO, else the shipped ACES CG config).
    #[arg(long, value_name = "CONFIG")]
    pub ocio: Option<PathBuf>,
    /// The OCIO display of the preview (default: the config's).
    #[arg(long)]
    pub display: Option<String>,
    /// The OCIO view of the preview (default: the display's default view).
    #[arg(long)]
    pub view: Option<String>,
}

fn parse_space(s: &str) -> std::result::Result<WorkingSpace, String> {
    WorkingSpace::from_name(s).ok_or_else(|| {
        let names: Vec<_> = WorkingSpace::ALL.iter().map(|w| w.name()).collect();
        format!("'{s}' is not one of {}", names.join(", "))
    })
}

/// The colour side of an image's outputs, resolved before the work.
pub struct ColorOutput {
    pub space: WorkingSpace,
    preview: Option<(Exposure, DisplayTransform)>,
}

impl PreviewArgs {
    /// Loads the OCIO config and checks the display and view when a preview is asked for.
    pub fn resolve(&self) -> Result<ColorOutput> {
        let ocio_flags = self.ocio.is_some() || self.display.is_some() || self.view.is_some();
        if self.preview.is_none() && ocio_flags {
            return Err(Error::option("--ocio, --display and --view need --preview"));
        }
        let preview = match &self.preview {
            None => None,
            Some(_) => {
                let env = std::env::var_os("OCIO");
                let config = OcioConfig::select(self.ocio.as_deref(), env.as_deref())?;
                let transform = config.display_transform(
                    self.colorspace.ocio_name(),
                    self.display.as_deref(),
                    self.view.as_deref(),
                )?;
                Some((self.preview_exposure, transform))
            }
        };
        Ok(ColorOutput {
            space: self.colorspace,
            preview,
        })
    }
}

impl ColorOutput {
    /// The render's RGB in the working space (the render's own Rec.709 when it is that).
    pub fn rgb<'a>(&self, out: &'a RenderOutput) -> Cow<'a, [[f32; 3]]> {
        match self.space {
            WorkingSpace::LinRec709 => Cow::Borrowed(&out.rgb),
            space => Cow::Owned(space.convert(&out.xyz)),
        }
    }

    /// Writes the preview of `rgb` (working space) to `path`, if one was asked for.
    pub fn write_preview(&self, path: &Path, out: &RenderOutput, rgb: &[[f32; 3]]) -> Result<()> {
        self.write_preview_of(path, (out.width, out.height), rgb, &out.xyz)
    }

    /// Writes the preview of a `width` × `height` image, `rgb` in the working space and
    /// `xyz` its XYZ (for auto exposure), to `path`, if one was asked for.
    pub fn write_preview_of(
        &self,
        path: &Path,
        (width, height): (usize, usize),
        rgb: &[[f32; 3]],
        xyz: &[[f32; 3]],
    ) -> Result<()> {
        let Some((exposure, transform)) = &self.preview else {
            return Ok(());
        };
        let ev = exposure.stops(xyz.iter().map(|p| p[1]));
        preview::write(path, width, height, rgb, ev, transform)?;
        let how = match exposure {
            Exposure::Auto => " (auto)",
            Exposure::Stops(_) => "",
        };
        eprintln!(
            "wrote {} ({} / {}, exposure {ev:+.2} EV{how})",
            path.display(),
            transform.display,
            transform.view
        );
        Ok(())
    }
}
