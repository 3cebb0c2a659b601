//! `--part K/N` of the render command: render part K of N of every pixel's samples
//! (`session::part`) and write, beside the part's EXR (an image of its own samples), a
//! `.part` file holding its film's raw state under the render's identity, for
//! `spectral-render merge` (`cli/merge.rs`).
//!
//! The raw state is a sidecar rather than EXR channels or attributes: it is i128 sums on the
//! film's grid, counts and the depth cap's sums (about 120 B per pixel, more than the EXR's
//! own channels), and the checkpoint format already carries it with the run's identity, a
//! hash that catches damage and bounds-checked reading; the EXR stays an ordinary image.

use super::common::Made;
use crate::error::{Error, Result};
use crate::integrator::cut::depth_cap;
use crate::integrator::roulette::{RrStart, DEFAULT_RR_DEPTH};
use crate::integrator::split::Split;
use crate::integrator::Integrator;
use crate::output::atomic::write_atomically;
use crate::output::target::{Format, Target};
use crate::scene::Scene;
use crate::session::checkpoint::Checkpoint;
use crate::session::crop::{self, Crop, CropSpec};
use crate::session::part::{self, Part};
use crate::session::roulette;
use crate::session::{ImageSession, RenderOptions, RenderOutput, DEFAULT_SPP};
use std::io::Write;
use std::path::{Path, PathBuf};

/// The extension of a part's raw state beside its EXR.
pub const SIDECAR_EXTENSION: &str = "part";

/// The render command's part flag.
#[derive(clap::Args, Debug, Clone)]
pub struct PartArgs {
    /// Render only part K of N (samples [K·spp/N, (K+1)·spp/N) of every pixel) and write its
    /// raw film state beside the EXR (OUTPUT.part) for `spectral-render merge`.
    #[arg(long, value_name = "K/N", value_parser = Part::parse)]
    pub part: Option<Part>,
    /// Render only the pixels x0..x1 of rows y0..y1 (whole numbers: pixels; with decimal
    /// points: NDC, y down, as pbrt-v4's --cropwindow). The EXR's data window is the crop;
    /// OUTPUT.part is written for `merge`. Replaces the stage's dataWindowNDC.
    #[arg(long, value_name = "X0,Y0,X1,Y1", value_parser = CropSpec::parse)]
    pub crop: Option<CropSpec>,
}

/// The `.part` file beside `output`.
pub fn sidecar(output: &Path) -> PathBuf {
    output.with_extension(SIDECAR_EXTENSION)
}

impl PartArgs {
    /// Refuses what a part cannot be: a time budget (no fixed samples), auto (every part
    /// would run its own pilot), strategy images and checkpoints (not carried by parts).
    pub fn check(&self, opts: &RenderOptions, strategies: bool, checkpoints: bool) -> Result<()> {
        if !self.is_part() {
            return Ok(());
        }
        let flag = if self.part.is_some() {
            "--part"
        } else {
            "--crop"
        };
        let refuse = |why: &str| Err(Error::option(format!("{flag} {why}")));
        if opts.spp.is_none() && opts.time_budget.is_some() {
            return refuse("needs --spp: a time budget gives no fixed sample range");
        }
        if let Integrator::Auto { .. } = opts.integrator {
            return refuse(&format!(
                "needs a named --integrator ({}): auto would run its pilot in every part",
                Integrator::names_with(|_| true)
            ));
        }
        if strategies {
            return refuse("does not take --strategies");
        }
        if checkpoints {
            return refuse("does not take --checkpoint or --resume");
        }
        Ok(())
    }

    /// A part of a render: `--part`, `--crop`, or both.
    pub fn is_part(&self) -> bool {
        self.part.is_some() || self.crop.is_some()
    }

    /// The sample part (0/1: all samples, for a crop alone).
    fn sample_part(&self) -> Part {
        self.part.unwrap_or(Part { index: 0, count: 1 })
    }

    /// The sidecar as an output target, checked with the others before the work.
    pub fn target(&self, output: &Path) -> Option<Target> {
        self.is_part()
            .then(|| Target::new("--part", sidecar(output), Format::Any))
    }

    /// Restricts `session` to the part's samples (its window is `RenderOptions::crop`,
    /// from [`PartArgs::window`]).
    pub fn start(&self, session: &mut ImageSession, opts: &RenderOptions) -> Result<()> {
        if let Some(p) = self.part {
            let (first, end) = p.samples(u64::from(opts.spp.unwrap_or(DEFAULT_SPP)));
            session.start_part(first, end).map_err(Error::option)?;
            eprintln!("part {}: samples {first}..{end} of every pixel", p.label());
        }
        Ok(())
    }

    /// The window a render of `scene` renders: `--crop`'s, else the stage's
    /// `dataWindowNDC` (`session::crop`), else None (the whole image); said on the console.
    pub fn window(&self, scene: &Scene) -> Result<Option<Crop>> {
        let stage = crop::stage_window(scene)?;
        let Some(spec) = self.crop else {
            if let (Some(c), Some(dw)) = (stage, &scene.data_window) {
                eprintln!(
                    "data window {} ({}×{} pixels) from <{}>'s dataWindowNDC",
                    c.label(),
                    c.width(),
                    c.height(),
                    dw.prim_path
                );
            }
            return Ok(stage);
        };
        let (w, h) = (scene.camera.width as usize, scene.camera.height as usize);
        let c = spec
            .resolve(w, h)
            .map_err(|e| Error::option(format!("--crop {e}")))?;
        if let (Some(s), Some(dw)) = (stage, &scene.data_window) {
            eprintln!(
                "note: --crop replaces the data window {} of <{}>'s dataWindowNDC",
                s.label(),
                dw.prim_path
            );
        }
        eprintln!("crop {}: {}×{} pixels", c.label(), c.width(), c.height());
        Ok(Some(c))
    }

    /// Writes the part's raw state beside `output` (atomically).
    pub fn save(
        &self,
        made: &Made,
        opts: &RenderOptions,
        session: &ImageSession,
        output: &Path,
        out: &RenderOutput,
    ) -> Result<()> {
        if !self.is_part() {
            return Ok(());
        }
        let p = self.sample_part();
        let stage = made.stage.display().to_string();
        let state = Checkpoint {
            identity: part::identity(made.scene, opts, &stage, p, out.crop),
            samples: out.spp,
            dropped: out.dropped_samples,
            wall_time_s: out.wall_time_s,
            film: session.film_state(),
            strategies: None,
            depth_cut: session.depth_cut_sums(),
        };
        let path = sidecar(output);
        let bytes = state.encode();
        write_atomically(&path, |f| f.write_all(&bytes))
            .map_err(|e| Error::io(&path, format!("cannot write the part: {e}")))?;
        let crop = out
            .crop
            .map_or(String::new(), |c| format!(" (crop {})", c.label()));
        eprintln!("wrote part {}{crop} to {}", p.label(), path.display());
        Ok(())
    }
}

/// Reads a part: `path` is a `.part` file or the EXR beside which it lies.
pub fn read(path: &Path) -> Result<Checkpoint> {
    let file = if path.extension().is_some_and(|e| e == SIDECAR_EXTENSION) {
        path.to_path_buf()
    } else {
        sidecar(path)
    };
    let fail = |reason: String| Error::io(path, reason);
    let meta = std::fs::metadata(&file)
        .map_err(|e| fail(format!("cannot read its part {}: {e}", file.display())))?;
    if !meta.is_file() {
        return Err(fail(format!("{} is not a regular file", file.display())));
    }
    let bytes = std::fs::read(&file).map_err(|e| fail(e.to_string()))?;
    Checkpoint::decode(&bytes).map_err(|e| fail(e.replace("checkpoint", "part file")))
}

/// The scene a part was rendered from, for its merge's metadata.
pub fn made<'a>(
    stage: &'a Path,
    scene: &'a Scene,
    integrator: &'a Integrator,
    identity: &[(String, String)],
    out: &RenderOutput,
) -> Result<Made<'a>> {
    let bad = |key: &str| Error::option(format!("merge: the parts' {key} cannot be read"));
    let seed = part::value(identity, "seed")
        .and_then(|s| s.parse().ok())
        .ok_or_else(|| bad("seed"))?;
    let max_depth = match part::value(identity, "max depth") {
        Some("unlimited") => None,
        Some(d) => Some(d.parse().map_err(|_| bad("max depth"))?),
        None => return Err(bad("max depth")),
    };
    // Named in the identity unless 2, the default before `auto` (`session::checkpoint::
    // identity`); `auto` is resolved again, as every part resolved it (`session::roulette`).
    let rr = match part::value(identity, "rr depth") {
        Some(d) => d.parse().map_err(|_| bad("rr depth"))?,
        None => RrStart::At(DEFAULT_RR_DEPTH),
    };
    // The split likewise: named unless 1, the default before `auto`.
    let split = match part::value(identity, "split") {
        Some(n) => n.parse().map_err(|_| bad("split"))?,
        None => Split::At(1),
    };
    let resolved = roulette::resolve(scene, integrator, (rr, split), depth_cap(max_depth), seed);
    Ok(Made {
        stage,
        scene,
        integrator,
        seed,
        max_depth,
        rr_depth: resolved.as_ref().map(|r| r.start),
        split: resolved.as_ref().map(|r| r.split),
        spp: out.spp,
        wall_time_s: out.wall_time_s,
        sampler: out.sampler,
    })
}
