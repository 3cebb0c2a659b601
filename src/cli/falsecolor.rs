//! `spectral-render falsecolor IN.exr -o OUT.png`: the luminance of a calibrated EXR as a
//! false-colour image with a legend in cd/m², after Radiance's `falsecolor` (`-s`, `-log`,
//! `-n`, `-cl`); the picture itself is `output/falsecolor.rs`.

use super::common::clap_message;
use crate::error::{Error, Result};
use crate::imageio::encode_png_rgb8;
use crate::output::atomic::write_atomically;
use crate::output::exr;
use crate::output::falsecolor::{default_scale, label, FalseColor, UNIT};
use crate::output::target::{self, Format, Target};
use clap::{CommandFactory, FromArgMatches, Parser};
use std::ffi::OsString;
use std::path::PathBuf;

/// False-colour luminance (cd/m²) of a calibrated EXR, with a legend (Radiance's falsecolor).
#[derive(Parser, Debug)]
#[command(name = "spectral-render falsecolor")]
struct FalseColorArgs {
    /// The EXR: its `XYZ.Y` channel, times `whiteLuminance` when the header has it.
    input: PathBuf,
    /// The PNG to write.
    #[arg(short = 'o', long = "output")]
    output: PathBuf,
    /// Top of the scale in cd/m² (Radiance's -s; default: the image's maximum rounded up
    /// to 1, 2 or 5 × 10^k).
    #[arg(long, value_name = "MAX", allow_negative_numbers = true)]
    scale: Option<f64>,
    /// A logarithmic scale over this many decades below MAX (Radiance's -log).
    #[arg(long = "log", value_name = "DECADES", allow_negative_numbers = true)]
    log: Option<f64>,
    /// Draw N − 1 isolines at the legend's divisions over the luminance in grey (Radiance's
    /// -cl with -n N).
    #[arg(long, value_name = "N", allow_negative_numbers = true)]
    contours: Option<usize>,
    /// The legend's divisions without --contours (Radiance's -n).
    #[arg(long, default_value_t = 8, allow_negative_numbers = true)]
    divisions: usize,
}

pub fn main(argv: Vec<OsString>) -> Result<()> {
    let parsed = FalseColorArgs::command()
        .try_get_matches_from(argv)
        .and_then(|m| FalseColorArgs::from_arg_matches(&m));
    match parsed {
        Ok(args) => run(&args),
        Err(e) if !e.use_stderr() => e.exit(),
        Err(e) => Err(Error::option(clap_message(&e))),
    }
}

fn run(args: &FalseColorArgs) -> Result<()> {
    check(args)?;
    target::check(&[Target::new("-o", &args.output, Format::Png)])?;
    let image = exr::read(&args.input)?;
    let mut y = image
        .channels
        .get("XYZ.Y")
        .cloned()
        .ok_or_else(|| Error::io(&args.input, "no XYZ.Y channel (luminance in cd/m²)"))?;
    let white = match image.attributes.get("whiteLuminance") {
        Some(w) => w
            .parse::<f32>()
            .ok()
            .filter(|w| w.is_finite() && *w > 0.0)
            .ok_or_else(|| Error::io(&args.input, format!("bad whiteLuminance '{w}'")))?,
        None => 1.0,
    };
    for v in &mut y {
        *v = if v.is_finite() { *v * white } else { 0.0 };
    }
    let max = y.iter().fold(0.0f32, |m, v| m.max(*v));
    let f = FalseColor {
        scale: args.scale.unwrap_or_else(|| default_scale(f64::from(max))),
        decades: args.log,
        divisions: args.contours.unwrap_or(args.divisions),
        contours: args.contours.is_some(),
    };
    let (canvas, _) = f.image(&y, image.width, image.height);
    let (w, h) = (canvas.width as u32, canvas.height as u32);
    write_atomically(&args.output, |file| {
        encode_png_rgb8(file, &canvas.bytes(), w, h)
    })
    .map_err(|e| Error::io(&args.output, format!("cannot write PNG: {e}")))?;
    let scale = match f.decades {
        Some(d) => format!("log, {d} decades below {} {UNIT}", label(f.scale)),
        None => format!("linear, 0 to {} {UNIT}", label(f.scale)),
    };
    eprintln!(
        "wrote {} ({scale}; image maximum {} {UNIT})",
        args.output.display(),
        label(f64::from(max))
    );
    Ok(())
}

fn check(args: &FalseColorArgs) -> Result<()> {
    if let Some(s) = args.scale {
        if !(s.is_finite() && s > 0.0) {
            return Err(Error::option(
                "--scale must be a positive luminance in cd/m²",
            ));
        }
    }
    if let Some(d) = args.log {
        if !(d.is_finite() && d > 0.0 && d <= 12.0) {
            return Err(Error::option("--log must be between 0 and 12 decades"));
        }
    }
    let n = args.contours.unwrap_or(args.divisions);
    if !(1..=64).contains(&n) {
        return Err(Error::option(
            "--contours and --divisions must be between 1 and 64",
        ));
    }
    Ok(())
}
