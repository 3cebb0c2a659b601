//! `spectral-render merge PART… -o out.exr`: the parts of a render (`--part K/N`) merged
//! into the render's calibrated EXR, bit for bit the single render's (`session::part`). The
//! parts must be of one render (same stage content and options), each complete, none missing
//! and none twice; otherwise one line names the part at fault. The stage is read again (from
//! the path the parts recorded, or `--stage`) for the EXR's camera metadata, and must still
//! have the content the parts were rendered from.

use super::color::PreviewArgs;
use super::common::{clap_message, print_summary, warn_clamped, warn_depth_cut, warn_dropped};
use super::parts;
use super::render::write_image;
use crate::error::{Error, Result};
use crate::output::target::{self, Format, Target};
use crate::sampling::SamplerKind;
use crate::scene::{self, Machinery};
use crate::session::checkpoint::Checkpoint;
use crate::session::image::xyz_to_rgb;
use crate::session::part::{self, STAGE_FILE_KEY};
use crate::session::{DepthCut, RenderOutput};
use clap::{CommandFactory, FromArgMatches, Parser};
use std::ffi::OsString;
use std::path::{Path, PathBuf};

/// Merge the parts of a render (`--part K/N`) into its calibrated EXR, bit for bit the
/// single render's.
#[derive(Parser, Debug)]
#[command(name = "spectral-render merge")]
struct MergeArgs {
    /// The parts: their EXRs (the .part file beside each is read) or the .part files; or a
    /// meter study's part files (PART.json, `meter --part`).
    #[arg(required = true)]
    parts: Vec<PathBuf>,
    /// The merged EXR; for meter parts, the points' JSON document or the grid's map base name.
    #[arg(short = 'o', long = "output")]
    output: PathBuf,
    /// The stage, when it is no longer at the path the parts recorded (its content must be
    /// the same).
    #[arg(long)]
    stage: Option<PathBuf>,
    #[command(flatten)]
    color: PreviewArgs,
}

pub fn main(argv: Vec<OsString>) -> Result<()> {
    let parsed = MergeArgs::command()
        .try_get_matches_from(argv)
        .and_then(|m| MergeArgs::from_arg_matches(&m));
    match parsed {
        Ok(args) => run(&args),
        Err(e) if !e.use_stderr() => e.exit(),
        Err(e) => Err(Error::option(clap_message(&e))),
    }
}

fn run(args: &MergeArgs) -> Result<()> {
    if super::meter_parts::are_meter_parts(&args.parts) {
        if args.color.preview.is_some() || args.stage.is_some() {
            return Err(Error::option(
                "merge: --preview and --stage are for a render's parts, not a meter study's",
            ));
        }
        return super::meter_parts::merge(&args.parts, &args.output);
    }
    let mut targets = vec![Target::new("-o", &args.output, Format::Exr)];
    let color = args.color.resolve()?;
    if let Some(p) = &args.color.preview {
        targets.push(Target::new("--preview", p, Format::Png));
    }
    target::check(&targets)?;
    // Each part's identity and counts first (its film's data dropped), then the films one
    // at a time in merge order: memory for two films, whatever the number of parts.
    let heads = args
        .parts
        .iter()
        .map(|p| parts::read(p).map(head))
        .collect::<Result<Vec<_>>>()?;
    let order = part::check(&heads).map_err(|(i, e)| match i {
        Some(i) => Error::io(&args.parts[i], e),
        None => Error::option(format!("merge: {e}")),
    })?;
    let mut merged = None;
    for &i in &order {
        let c = parts::read(&args.parts[i])?;
        let fail = |e: String| Error::io(&args.parts[i], e);
        if (&c.identity, c.samples) != (&heads[i].identity, heads[i].samples) {
            return Err(fail("the part changed while it was merged".into()));
        }
        part::add(&mut merged, &c).map_err(fail)?;
    }
    let merged = merged.expect("check refuses no parts");
    let states = heads;
    let id = &merged.identity;
    let recorded = part::value(&states[0].identity, STAGE_FILE_KEY).map(PathBuf::from);
    let stage = args
        .stage
        .clone()
        .or(recorded)
        .ok_or_else(|| Error::io(&args.parts[0], "the part names no stage"))?;
    let resolution = part::value(id, "resolution")
        .and_then(|r| super::render::parse_resolution(r).ok())
        .ok_or_else(|| Error::io(&args.parts[0], "the part's resolution cannot be read"))?;
    let scene = scene::load_with(&stage, Some(resolution), Machinery::default())?;
    print_summary(&scene);
    check_content(&stage, &scene, id)?;
    let integrator = part::integrator(id)
        .ok_or_else(|| Error::io(&args.parts[0], "the part's integrator cannot be read"))?;
    let out = output(&scene, &merged)?;
    warn_dropped(out.dropped_samples);
    warn_clamped(out.clamped);
    warn_depth_cut(out.depth_cut.as_ref(), "the image's mean luminance");
    let made = parts::made(&stage, &scene, &integrator, id, &out)?;
    let preview = args.color.preview.as_deref();
    write_image(
        &made,
        integrator.name().into(),
        &args.output,
        preview,
        &color,
        &out,
    )?;
    eprintln!(
        "merged {} parts into {} ({}x{}, {} spp, {:.2} s of rendering)",
        states.len(),
        args.output.display(),
        out.width,
        out.height,
        out.spp,
        out.wall_time_s
    );
    Ok(())
}

/// A part without its film's data (its size kept): what `part::check` reads.
fn head(mut c: Checkpoint) -> Checkpoint {
    let f = &mut c.film;
    (f.sums, f.samples, f.odd_y, f.splat, f.odd_splat_y) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new(), Vec::new());
    c.strategies = None;
    c
}

/// The stage must still be what the parts rendered.
fn check_content(stage: &Path, scene: &scene::Scene, id: &[(String, String)]) -> Result<()> {
    let now = format!("{:016x}", scene.content_hash);
    match part::value(id, "stage content") {
        Some(h) if h == now => Ok(()),
        h => Err(Error::io(
            stage,
            format!(
                "the stage's content ({now}) is not the parts' ({})",
                h.unwrap_or("unknown")
            ),
        )),
    }
}

/// The merged film as the render's output.
fn output(scene: &scene::Scene, m: &part::Merged) -> Result<RenderOutput> {
    let (w, h) = (scene.camera.width as usize, scene.camera.height as usize);
    if (m.film.width, m.film.height) != (w, h) {
        return Err(Error::option(format!(
            "merge: the parts' film is {}×{}, the stage's camera {w}×{h}",
            m.film.width, m.film.height
        )));
    }
    let xyz = m.film.xyz(scene.camera.exposure_scale as f64);
    let rgb = xyz.iter().map(|p| xyz_to_rgb(*p)).collect();
    let max_depth = match part::value(&m.identity, "max depth") {
        Some("unlimited") | None => None,
        Some(d) => d.parse().ok(),
    };
    let cut = &m.depth_cut;
    Ok(RenderOutput {
        width: w,
        height: h,
        xyz,
        rgb,
        spp: m.samples,
        wall_time_s: m.wall_time_s,
        dropped_samples: m.dropped,
        strategies: None,
        report: None,
        auto: None,
        // The metadata's start comes from the parts' identity (`parts::made`).
        rr_depth: None,
        split: None,
        depth_cut: DepthCut::new(max_depth, &cut.sums(), cut.capped, cut.limited),
        clamped: m.film.clamped(),
        crop: m.window,
        layers: Default::default(),
        sampler: part::value(&m.identity, "sampler").and_then(SamplerKind::from_name),
    })
}
