//! `spectral-render STAGE [options]`: render a stage to a calibrated EXR.

use super::checkpoints::{self, Checkpoints};
use super::color::{ColorOutput, PreviewArgs};
use super::common::{
    at_least, clap_message, max_memory, metadata_name, named, print_auto, print_report,
    print_summary, warn_clamped, warn_depth_cut, warn_dropped, warn_limits, IntegratorArgs,
    MachineryArgs, Made,
};
use super::frames::{frame_path, parse_frames, FrameArgs, FrameRange};
use super::interrupt;
use super::layers::LayerArgs;
use super::parts::PartArgs;
use super::progress::Progress;
use crate::error::{Error, Result};
use crate::integrator::bidir::strategies::StrategyImage;
use crate::integrator::Integrator;
use crate::output::target::{self, Format, Target};
use crate::output::{self, exr};
use crate::sampling::SamplerKind;
use crate::session::{self, ImageSession, Observer, Progressive, RenderOptions, RenderOutput};
use crate::{scene, spectral};
use clap::{CommandFactory, FromArgMatches, Parser};
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
    #[arg(long, allow_negative_numbers = true, value_parser = at_least::<u32>(1))]
    spp: Option<u32>,
    /// Render until this many seconds have passed, then write the result.
    #[arg(long = "time", allow_negative_numbers = true)]
    time: Option<f64>,
    /// Seed of the deterministic sampler.
    #[arg(long, default_value_t = 0, allow_negative_numbers = true, value_parser = at_least::<u64>(0))]
    seed: u64,
    /// Worker threads (default: all cores).
    #[arg(long, allow_negative_numbers = true, value_parser = at_least::<usize>(1))]
    threads: Option<usize>,
    /// Image size WxH, overriding RenderSettings.
    #[arg(long, value_parser = parse_resolution, allow_hyphen_values = true)]
    resolution: Option<(u32, u32)>,
    /// Maximum number of scattering events (pbrt's maxdepth; Mitsuba's max_depth − 1).
    /// Default: unlimited (Russian roulette ends paths); a cap that cuts light says how much.
    #[arg(long = "max-depth", allow_negative_numbers = true, value_parser = at_least::<u32>(0))]
    max_depth: Option<u32>,
    #[command(flatten)]
    integrator: IntegratorArgs,
    /// The numbers the path tracer's samples draw; the bidirectional integrators draw
    /// independent ones whatever this says.
    #[arg(long, default_value = "zsobol", value_parser = named::<SamplerKind>("sampler"))]
    sampler: SamplerKind,
    /// Give noisier pixels more samples, --spp being their mean: a pilot of an eighth of
    /// them, then each pixel's samples in proportion to the noise around it (unbiased; the
    /// path tracer only, which `auto` then means; the EXR's `samples` channel holds the
    /// counts).
    #[arg(long)]
    adaptive: bool,
    #[command(flatten)]
    machinery: MachineryArgs,
    #[command(flatten)]
    part: PartArgs,
    #[command(flatten)]
    layers: LayerArgs,
    /// Also write one EXR per BDPT strategy (s, t), weighted and unweighted, into DIR.
    #[arg(long, value_name = "DIR")]
    strategies: Option<PathBuf>,
    #[command(flatten)]
    color: PreviewArgs,
    /// Look textures up bilinearly at full resolution instead of filtering them over the
    /// pixel footprint (MIP-mapped, trilinear), as Mitsuba 3's bitmaps.
    #[arg(long = "no-texture-filtering")]
    no_texture_filtering: bool,
    /// Save the render's state to FILE every --checkpoint-interval seconds and when it is
    /// interrupted (SIGINT, SIGTERM), to continue it with --resume; removed once the image
    /// is written.
    #[arg(long, value_name = "FILE")]
    checkpoint: Option<PathBuf>,
    /// Seconds between checkpoints.
    #[arg(long = "checkpoint-interval", value_name = "SECONDS", default_value_t = checkpoints::DEFAULT_INTERVAL, allow_negative_numbers = true)]
    checkpoint_interval: f64,
    /// Continue the render saved in FILE by --checkpoint (same stage and options); the
    /// image equals the uninterrupted render's bit for bit.
    #[arg(long, value_name = "FILE")]
    resume: Option<PathBuf>,
    /// Refuse to start a render estimated to need more memory than SIZE (e.g. 8G, 512M;
    /// default: the memory available).
    #[arg(long = "max-memory", value_name = "SIZE", value_parser = max_memory, allow_hyphen_values = true)]
    max_memory: Option<u64>,
    #[command(flatten)]
    when: FrameArgs,
    /// Render the time codes A, A + STEP, ... up to B into a sequence: -o (default
    /// STAGE.####.exr) and --preview name each frame with a placeholder, #### or %04d.
    #[arg(long, value_name = "A..B[:STEP]", value_parser = parse_frames, allow_hyphen_values = true,
          conflicts_with_all = ["frame", "checkpoint", "resume", "strategies"])]
    frames: Option<FrameRange>,
}

pub(super) fn parse_resolution(s: &str) -> std::result::Result<(u32, u32), String> {
    let (w, h) = s
        .split_once(['x', 'X'])
        .ok_or("expected WxH, e.g. 640x480")?;
    let side = |v: &str, what: &str| {
        let v = v.trim();
        match v.parse::<i64>() {
            Ok(n) if n < 1 => Err(format!("the {what} {n} must be positive")),
            Ok(n) => u32::try_from(n).map_err(|_| format!("the {what} {n} is too large")),
            Err(_) => Err(format!("bad {what} '{v}'")),
        }
    };
    let (w, h) = (side(w, "width")?, side(h, "height")?);
    if w > 65536 || h > 65536 {
        return Err("width and height must be between 1 and 65536".into());
    }
    Ok((w, h))
}

/// Parses the arguments and renders. `--help` and `--version` print and exit; any option
/// error, clap's included, is one line and exit code 1.
pub fn main(argv: Vec<OsString>) -> Result<()> {
    let parsed = command()
        .try_get_matches_from(argv)
        .and_then(|m| RenderArgs::from_arg_matches(&m));
    match parsed {
        Ok(args) => run(&args),
        Err(e) if !e.use_stderr() => e.exit(),
        Err(e) => Err(Error::option(clap_message(&e))),
    }
}

/// The render command's clap command, its help listing the subcommands.
pub fn command() -> clap::Command {
    RenderArgs::command().after_help(super::commands_help())
}

fn run(args: &RenderArgs) -> Result<()> {
    let opts = options(args)?;
    args.layers.check_state(
        &opts.layers,
        args.part.is_part(),
        args.checkpoint.is_some() || args.resume.is_some(),
    )?;
    if args.part.crop.is_some()
        && (opts.layers.any() || opts.layers.variance || args.layers.emission_layers())
    {
        return Err(Error::option(
            "--crop writes the window's image only: it does not go with --spectral, --aov, \
             --illuminants or --light-groups",
        ));
    }
    let color = args.color.resolve()?;
    args.part.check(
        &opts,
        args.strategies.is_some(),
        args.checkpoint.is_some() || args.resume.is_some(),
    )?;
    if let Some(frames) = &args.frames {
        if args.part.is_part() {
            return Err(Error::option(
                "--part and --crop render one frame: they cannot go with --frames",
            ));
        }
        return run_sequence(args, &opts, frames, &color);
    }
    let path = args
        .output
        .clone()
        .unwrap_or_else(|| default_output(&args.scene));
    target::check(&targets(args, &path, args.color.preview.as_deref()))?;
    let resume = args.resume.as_deref().map(checkpoints::read).transpose()?;
    interrupt::install()?;
    let mut scene = scene::load_at(
        &args.scene,
        args.resolution,
        args.machinery.machinery(),
        args.when.read_time(),
    )?;
    args.layers.apply(&mut scene)?;
    print_summary(&scene);
    if let Some(signal) = interrupt::received() {
        eprintln!("interrupted by {signal} before rendering; nothing written");
        return Ok(());
    }
    let output = Output {
        exr: &path,
        preview: args.color.preview.as_deref(),
        color: &color,
    };
    render_frame(args, &opts, &scene, output, resume).map(|_| ())
}

/// `--frames`: every frame's outputs are checked first, the stage is opened once and read at
/// each time code in turn, each frame's scene built from the previous one's where the
/// description did not change (`scene::Rebuilder`); an interrupt ends the sequence after
/// writing the frame under way.
fn run_sequence(
    args: &RenderArgs,
    opts: &RenderOptions,
    frames: &FrameRange,
    color: &ColorOutput,
) -> Result<()> {
    let pattern = args
        .output
        .clone()
        .unwrap_or_else(|| default_output(&args.scene).with_extension("####.exr"));
    let mut outputs = Vec::new();
    let mut all_targets = Vec::new();
    for t in frames.times() {
        let exr = frame_path(&pattern, t)?;
        let preview = args
            .color
            .preview
            .as_deref()
            .map(|p| frame_path(p, t))
            .transpose()?;
        all_targets.extend(targets(args, &exr, preview.as_deref()));
        outputs.push((t, exr, preview));
    }
    target::check(&all_targets)?;
    interrupt::install()?;
    let stage = scene::open(&args.scene)?;
    let mut builder = scene::Rebuilder::new(args.resolution, args.machinery.machinery());
    let mut previous = None;
    for (t, exr, preview) in &outputs {
        let desc = stage.read(args.when.at(Some(*t)))?;
        let (mut scene, rebuilt) = builder.build(&desc, previous.take())?;
        args.layers.apply(&mut scene)?;
        eprintln!("frame {t}: {}", rebuilt.line());
        print_summary(&scene);
        if let Some(signal) = interrupt::received() {
            eprintln!("interrupted by {signal} before frame {t}; the sequence stops");
            return Ok(());
        }
        let output = Output {
            exr,
            preview: preview.as_deref(),
            color,
        };
        if render_frame(args, opts, &scene, output, None)?.is_some() {
            eprintln!("the sequence stops after frame {t}");
            return Ok(());
        }
        previous = Some(scene);
    }
    Ok(())
}

/// Where one frame is written.
#[derive(Clone, Copy)]
struct Output<'a> {
    exr: &'a Path,
    preview: Option<&'a Path>,
    color: &'a ColorOutput,
}

/// Renders `scene` and writes its outputs; the signal that interrupted it, if any.
fn render_frame(
    args: &RenderArgs,
    opts: &RenderOptions,
    scene: &scene::Scene,
    output: Output,
    resume: Option<crate::session::checkpoint::Checkpoint>,
) -> Result<Option<&'static str>> {
    warn_limits(&opts.integrator, scene, true);
    // auto continues with the integrator the checkpoint was rendered with, no pilot.
    let mut opts = match &resume {
        Some(c) => session::auto::for_checkpoint(scene, opts, c),
        None => opts.clone(),
    };
    opts.crop = args.part.window(scene)?;
    let opts = &opts;
    let mut session = ImageSession::new(scene, opts)?;
    print_auto(session.auto());
    if let (Some(c), Some(file)) = (resume, &args.resume) {
        let done = c.samples;
        session
            .resume(c)
            .map_err(|e| Error::io(file, format!("--resume: {e}")))?;
        eprintln!("resuming {} at {done} spp", file.display());
    }
    args.part.start(&mut session, opts)?;
    let pixels = match opts.crop {
        Some(c) => c.pixel_count() as u64,
        None => u64::from(scene.camera.width) * u64::from(scene.camera.height),
    };
    let target = opts.spp.map(u64::from).or(match opts.time_budget {
        Some(_) => None,
        None => Some(u64::from(session::DEFAULT_SPP)),
    });
    let mut progress = Progress::image(pixels, target);
    let mut saves = Checkpoints::new(args.checkpoint.clone(), args.checkpoint_interval);
    let interrupted = render_passes(&mut session, &mut progress, &mut saves)?;
    progress.finish();
    let out = session.output();
    warn_dropped(out.dropped_samples);
    warn_clamped(out.clamped);
    warn_depth_cut(out.depth_cut.as_ref(), "the image's mean luminance");
    print_report(&out.report);
    if let Some(a) = &out.layers.adaptive {
        eprintln!("adaptive sampling: {}", a.summary);
    }
    if let Some(signal) = interrupted {
        if let Some(file) = saves.write(&session)? {
            eprintln!("wrote checkpoint {} at {} spp", file.display(), out.spp);
        }
        eprintln!("interrupted by {signal} after {} spp", out.spp);
        if out.spp == 0 {
            eprintln!("nothing rendered; nothing written");
            return Ok(interrupted);
        }
    }
    write_outputs(args, opts, scene, output, &out)?;
    let chosen = opts.integrator;
    args.part.save(
        &made(args, opts, scene, &chosen, &out),
        opts,
        &session,
        output.exr,
        &out,
    )?;
    if interrupted.is_none() {
        saves.finished();
    }
    Ok(interrupted)
}

/// Runs passes until the session is finished or a signal arrives (its name), saving
/// checkpoints as asked.
fn render_passes(
    session: &mut ImageSession,
    progress: &mut Progress,
    saves: &mut Checkpoints,
) -> Result<Option<&'static str>> {
    while let Some(stats) = session.step() {
        progress.pass(&stats);
        if let Some(signal) = interrupt::received() {
            return Ok(Some(signal));
        }
        saves.after_pass(session)?;
    }
    Ok(interrupt::received())
}

/// Every file and directory the render will write, in the order given.
fn targets(args: &RenderArgs, output: &Path, preview: Option<&Path>) -> Vec<Target> {
    let mut t = vec![Target::new("-o", output, Format::Exr)];
    if let Some(p) = preview {
        t.push(Target::new("--preview", p, Format::Png));
    }
    if let Some(p) = &args.checkpoint {
        t.push(Target::new("--checkpoint", p, Format::Any));
    }
    if let Some(p) = &args.strategies {
        t.push(Target::new("--strategies", p, Format::Directory));
    }
    t.extend(args.part.target(output));
    t
}

/// What made the render's image (its EXR metadata).
fn made<'a>(
    args: &'a RenderArgs,
    opts: &RenderOptions,
    scene: &'a scene::Scene,
    integrator: &'a Integrator,
    out: &RenderOutput,
) -> Made<'a> {
    Made {
        stage: &args.scene,
        scene,
        integrator,
        seed: opts.seed,
        max_depth: opts.max_depth,
        rr_depth: out.rr_depth,
        split: out.split,
        spp: out.spp,
        wall_time_s: out.wall_time_s,
        sampler: out.sampler,
    }
}

/// Writes `out` as the calibrated EXR at `path` with `made`'s metadata (the integrator named
/// `integrator_name`), its RGB in `color`'s working space, and the preview when asked for;
/// returns the metadata.
pub(super) fn write_image(
    made: &Made,
    integrator_name: String,
    path: &Path,
    preview: Option<&Path>,
    color: &ColorOutput,
    out: &RenderOutput,
) -> Result<exr::ExrMetadata> {
    let mut meta = made.metadata();
    meta.integrator = integrator_name;
    meta.working_space = color.space;
    let white = spectral::color::white_xy().map(|c| c as f32);
    if let Some(c) = out.crop {
        return super::crop::write_window(path, preview, color, out, c, white, meta);
    }
    let rgb = color.rgb(out);
    exr::write_with_layers(
        path,
        out.width,
        out.height,
        &rgb,
        &out.xyz,
        &output::layers::exr_layers(&out.layers, color.space),
        white,
        &meta,
    )?;
    if let Some(preview) = preview {
        color.write_preview(preview, out, &rgb)?;
    }
    Ok(meta)
}

/// The EXR, the preview and the strategy images.
fn write_outputs(
    args: &RenderArgs,
    opts: &RenderOptions,
    scene: &scene::Scene,
    output: Output,
    out: &RenderOutput,
) -> Result<()> {
    let path = output.exr;
    let chosen = out.auto.as_ref().map_or(opts.integrator, |a| a.choice);
    let meta = write_image(
        &made(args, opts, scene, &chosen, out),
        metadata_name(&chosen, out.auto.as_ref()),
        path,
        output.preview,
        output.color,
        out,
    )?;
    let white = spectral::color::white_xy().map(|c| c as f32);
    if let (Some(dir), Some(images)) = (&args.strategies, &out.strategies) {
        write_strategies(dir, out, images, &meta, white)?;
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
    out: &RenderOutput,
    images: &[StrategyImage],
    meta: &exr::ExrMetadata,
    white: [f32; 2],
) -> Result<()> {
    std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, format!("cannot create: {e}")))?;
    for img in images {
        let depth = img.s + img.t - 2;
        for (kind, xyz) in [("weighted", &img.weighted), ("unweighted", &img.unweighted)] {
            let name = format!("d{depth:02}_s{:02}_t{:02}_{kind}.exr", img.s, img.t);
            let rgb = meta.working_space.convert(xyz);
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

/// The render's options, checked before the stage is read.
fn options(args: &RenderArgs) -> Result<RenderOptions> {
    let integrator = args.integrator.integrator(false)?;
    if args.strategies.is_some() {
        if !integrator.capabilities().strategy_images {
            return Err(Error::option(format!(
                "--strategies needs --integrator {}",
                Integrator::names_with(|c| c.strategy_images)
            )));
        }
        integrator.check_strategies(args.max_depth)?;
    }
    if args.spp == Some(0) {
        return Err(Error::option("--spp must be at least 1"));
    }
    if args
        .spp
        .is_some_and(|n| u64::from(n) > session::image::MAX_SPP)
    {
        return Err(Error::option(format!(
            "--spp must be at most {}",
            session::image::MAX_SPP
        )));
    }
    if let Some(t) = args.time {
        if !(t.is_finite() && t > 0.0) {
            return Err(Error::option("--time must be a positive number of seconds"));
        }
    }
    let interval = args.checkpoint_interval;
    if !(interval.is_finite() && interval > 0.0) {
        return Err(Error::option(
            "--checkpoint-interval must be a positive number of seconds",
        ));
    }
    if args.threads == Some(0) {
        return Err(Error::option("--threads must be at least 1"));
    }
    if args.adaptive {
        let whole = [
            (args.part.is_part(), "--part and --crop"),
            (
                args.checkpoint.is_some() || args.resume.is_some(),
                "--checkpoint and --resume",
            ),
        ];
        if let Some((_, flags)) = whole.iter().find(|(on, _)| *on) {
            return Err(Error::option(format!(
                "--adaptive allocates each pixel's samples from a pilot of the whole render \
                 in one run: it does not go with {flags}"
            )));
        }
    }
    let integrator = args.layers.integrator(integrator);
    // The path tracer is the one integrator whose samples are allocated per pixel: auto (the
    // default) means it under --adaptive.
    let integrator = match integrator {
        Integrator::Auto { .. } if args.adaptive => Integrator::Path,
        other => other,
    };
    let layers = args.layers.options(&integrator)?;
    let opts = RenderOptions {
        layers,
        spp: args.spp,
        time_budget: args.time,
        seed: args.seed,
        threads: args.threads,
        max_depth: args.max_depth,
        rr_depth: args.integrator.rr_depth,
        split: args.integrator.split,
        integrator,
        strategies: args.strategies.is_some(),
        filter_textures: !args.no_texture_filtering,
        max_memory: args.max_memory,
        sampler: args.sampler,
        adaptive: args.adaptive,
        ..RenderOptions::default()
    };
    session::image::check_adaptive(&opts, args.layers.emission_layers())?;
    Ok(opts)
}

/// `stage.usda` → `./stage.exr`.
fn default_output(scene: &Path) -> PathBuf {
    let stem = scene
        .file_stem()
        .map(|s| s.to_os_string())
        .unwrap_or_else(|| "render".into());
    PathBuf::from(stem).with_extension("exr")
}
