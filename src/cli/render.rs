//! `spectral-render STAGE [options]`: render a stage to a calibrated EXR.

use crate::integrator::bidir::strategies::StrategyImage;
use crate::integrator::{IntegratorKind, MisHeuristic};
use crate::output::{exr, png};
use crate::render::{self, RenderOptions};
use crate::{scene, spectral};
use clap::Parser;
use std::ffi::OsString;
use std::path::{Path, PathBuf};

/// Render a USD stage spectrally into a linear, absolutely calibrated EXR
/// (1.0 = 1 cd/m² of D65 white).
#[derive(Parser, Debug)]
#[command(name = "spectral-render", version, about)]
struct RenderArgs {
    /// The stage to render (.usda, .usdc or .usdz).
    scene: PathBuf,
    /// Output EXR (default: the stage's name with .exr, in the current directory).
    #[arg(short = 'o', long = "output")]
    output: Option<PathBuf>,
    /// Samples per pixel (default 64, or unlimited with --time).
    #[arg(long)]
    spp: Option<u32>,
    /// Render until this many seconds have passed, then write the result.
    #[arg(long = "time")]
    time: Option<f64>,
    /// Seed of the deterministic sampler.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Worker threads (default: all cores).
    #[arg(long)]
    threads: Option<usize>,
    /// Image size WxH, overriding RenderSettings.
    #[arg(long, value_parser = parse_resolution)]
    resolution: Option<(u32, u32)>,
    /// Maximum number of scattering events (pbrt's maxdepth; Mitsuba's max_depth − 1).
    #[arg(long = "max-depth", default_value_t = 7)]
    max_depth: u32,
    /// Light-transport algorithm: path, light (light tracing) or bdpt.
    #[arg(long, default_value = "path", value_parser = parse_integrator)]
    integrator: IntegratorKind,
    /// MIS heuristic of BDPT: power (β = 2) or balance.
    #[arg(long, default_value = "power", value_parser = parse_mis)]
    mis: MisHeuristic,
    /// Also write one EXR per BDPT strategy (s, t), weighted and unweighted, into DIR.
    #[arg(long, value_name = "DIR")]
    strategies: Option<PathBuf>,
    /// Also write an 8-bit sRGB PNG preview.
    #[arg(long)]
    preview: Option<PathBuf>,
    /// Look textures up bilinearly at full resolution instead of filtering them over the
    /// pixel footprint (MIP-mapped, trilinear), as Mitsuba 3's bitmaps.
    #[arg(long = "no-texture-filtering")]
    no_texture_filtering: bool,
    /// Exposure of the preview in stops (the EXR stays absolute): the preview shows
    /// RGB × 2^EV, so −6.6 maps 100 cd/m² white to 1.
    #[arg(
        long = "preview-exposure",
        default_value_t = 0.0,
        allow_hyphen_values = true
    )]
    preview_exposure: f32,
}

fn parse_resolution(s: &str) -> Result<(u32, u32), String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or("expected WxH, e.g. 640x480")?;
    let w: u32 = w.trim().parse().map_err(|_| format!("bad width '{w}'"))?;
    let h: u32 = h.trim().parse().map_err(|_| format!("bad height '{h}'"))?;
    if w == 0 || h == 0 || w > 65536 || h > 65536 {
        return Err("width and height must be between 1 and 65536".into());
    }
    Ok((w, h))
}

pub(super) fn parse_integrator(s: &str) -> Result<IntegratorKind, String> {
    match s {
        "path" => Ok(IntegratorKind::Path),
        "light" => Ok(IntegratorKind::Light),
        "bdpt" => Ok(IntegratorKind::Bdpt),
        other => Err(format!(
            "unknown integrator '{other}' (available: path, light, bdpt)"
        )),
    }
}

pub(super) fn parse_mis(s: &str) -> Result<MisHeuristic, String> {
    match s {
        "power" => Ok(MisHeuristic::Power),
        "balance" => Ok(MisHeuristic::Balance),
        other => Err(format!(
            "unknown MIS heuristic '{other}' (available: power, balance)"
        )),
    }
}

/// Light tracing and BDPT treat partially opaque surfaces as opaque: say so.
pub(super) fn warn_opacity(scene: &scene::Scene, integrator: IntegratorKind) {
    if integrator != IntegratorKind::Path && !scene.all_opaque {
        eprintln!(
            "warning: --integrator {} treats partially opaque surfaces (UsdPreviewSurface opacity) as opaque; use --integrator path for cutouts",
            integrator.name()
        );
    }
}

/// Parses the arguments (clap exits with its usage message on bad ones) and renders.
pub fn main(argv: Vec<OsString>) -> Result<(), String> {
    run(&RenderArgs::parse_from(argv))
}

fn run(args: &RenderArgs) -> Result<(), String> {
    validate(args)?;
    let scene = scene::load(&args.scene, args.resolution).map_err(|e| e.to_string())?;
    print_summary(&scene);
    warn_opacity(&scene, args.integrator);
    let opts = RenderOptions {
        spp: args.spp,
        time_budget: args.time,
        seed: args.seed,
        threads: args.threads,
        max_depth: args.max_depth,
        integrator: args.integrator,
        mis: args.mis,
        strategies: args.strategies.is_some(),
        progress: true,
        filter_textures: !args.no_texture_filtering,
    };
    let out = render::render(&scene, &opts)?;
    if out.dropped_samples > 0 {
        eprintln!(
            "warning: {} samples had a non-finite value and were dropped",
            out.dropped_samples
        );
    }
    let path = args
        .output
        .clone()
        .unwrap_or_else(|| default_output(&args.scene));
    let meta = exr::ExrMetadata {
        spp: out.spp,
        integrator: opts.integrator.name().into(),
        seed: opts.seed,
        wall_time_s: out.wall_time_s,
        version: env!("CARGO_PKG_VERSION").into(),
        scene: args.scene.display().to_string(),
    };
    let white = spectral::color::white_xy().map(|c| c as f32);
    exr::write(
        &path, out.width, out.height, &out.rgb, &out.xyz, white, &meta,
    )?;
    if let Some(preview) = &args.preview {
        png::write_preview(
            preview,
            out.width,
            out.height,
            &out.rgb,
            args.preview_exposure,
        )?;
    }
    if let (Some(dir), Some(images)) = (&args.strategies, &out.strategies) {
        write_strategies(dir, &out, images, &meta, white)?;
    }
    let rate = (out.width * out.height) as f64 * out.spp as f64 / out.wall_time_s.max(1e-9);
    eprintln!(
        "wrote {} ({}x{}, {} spp, {:.2} s, {:.2} Msamples/s)",
        path.display(),
        out.width,
        out.height,
        out.spp,
        out.wall_time_s,
        rate * 1e-6
    );
    Ok(())
}

/// One EXR per strategy and kind: `DIR/d{depth}_s{s}_t{t}_{weighted,unweighted}.exr`.
fn write_strategies(
    dir: &Path,
    out: &render::RenderOutput,
    images: &[StrategyImage],
    meta: &exr::ExrMetadata,
    white: [f32; 2],
) -> Result<(), String> {
    std::fs::create_dir_all(dir).map_err(|e| format!("cannot create {}: {e}", dir.display()))?;
    for img in images {
        let depth = img.s + img.t - 2;
        for (kind, xyz) in [("weighted", &img.weighted), ("unweighted", &img.unweighted)] {
            let name = format!("d{depth:02}_s{:02}_t{:02}_{kind}.exr", img.s, img.t);
            let rgb: Vec<[f32; 3]> = xyz.iter().map(|p| render::xyz_to_rgb(*p)).collect();
            exr::write(
                &dir.join(name),
                out.width,
                out.height,
                &rgb,
                xyz,
                white,
                meta,
            )?;
        }
    }
    eprintln!(
        "wrote {} strategy images to {}",
        2 * images.len(),
        dir.display()
    );
    Ok(())
}

fn validate(args: &RenderArgs) -> Result<(), String> {
    if args.strategies.is_some() && args.integrator != IntegratorKind::Bdpt {
        return Err("--strategies needs --integrator bdpt".into());
    }
    if args.spp == Some(0) {
        return Err("--spp must be at least 1".into());
    }
    if let Some(t) = args.time {
        if !(t.is_finite() && t > 0.0) {
            return Err("--time must be a positive number of seconds".into());
        }
    }
    if args.threads == Some(0) {
        return Err("--threads must be at least 1".into());
    }
    Ok(())
}

/// `stage.usda` → `./stage.exr`.
fn default_output(scene: &Path) -> PathBuf {
    let stem = scene
        .file_stem()
        .map(|s| s.to_os_string())
        .unwrap_or_else(|| "render".into());
    PathBuf::from(stem).with_extension("exr")
}

/// The one-line summary every command that reads a scene prints.
pub fn print_summary(scene: &scene::Scene) {
    let s = &scene.summary;
    eprintln!(
        "loaded {}: {} meshes ({} triangles), {} materials, {} lights, camera {}, {}x{}{}",
        scene.source.display(),
        s.meshes,
        s.triangles,
        s.materials,
        s.lights,
        s.camera,
        scene.camera.width,
        scene.camera.height,
        if s.warnings.is_empty() {
            String::new()
        } else {
            format!("; ignored: {}", s.warnings.join("; "))
        }
    );
}
