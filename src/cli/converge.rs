//! `spectral-render converge STAGE -o DIR`: error against wall time per integrator (and per
//! wavelength count), for the image or for light meters, as report.json, report.csv,
//! report.md and convergence.png in DIR (`converge` has the method, `output::report` and
//! `output::plot` the files).
//!
//! ```text
//! spectral-render converge STAGE -o DIR [--integrators path,light,bdpt,vcm] [--time S]
//!     [--reference ref.exr | --reference-time S] [--reference-integrator NAME]
//!     [--wavelengths 1,4] [--peers FILE.csv] [--keep-images] [--max-spp N]
//!     [--at X,Y,Z --normal NX,NY,NZ | --luminance --at X,Y,Z --dir DX,DY,DZ]
//!     [--reference-value V,…] [--seed N] [--threads N] [--resolution WxH] [--max-depth N]
//!     [--sampler zsobol|independent]
//! ```

use super::common::{clap_message, named, print_summary, Made};
use super::meter::{points, world_meter, PointArgs};
use super::render::parse_resolution;
use crate::converge::meters::{self, ReferenceValue};
use crate::converge::metrics::{image_errors, Reference};
use crate::converge::{self, fit, mask, reference, Config, Row, RunOptions};
use crate::error::{Error, Result};
use crate::integrator::{Integrator, MisHeuristic};
use crate::output::report::{self, Report};
use crate::output::{exr, plot, reference as reference_file};
use crate::sampling::SamplerKind;
use crate::scene::{self, Scene};
use crate::sensor::meter::{Meter, MeterKind};
use crate::session::image::WAVELENGTH_COUNTS;
use crate::session::RenderOutput;
use crate::spectral;
use clap::Parser;
use std::ffi::OsString;
use std::path::{Path, PathBuf};

/// Measure error against wall time for each integrator on a stage: images against a
/// reference EXR, or light meters against reference values.
#[derive(Parser, Debug)]
#[command(
    name = "spectral-render converge",
    bin_name = "spectral-render converge"
)]
struct ConvergeArgs {
    /// The stage (.usda, .usdc or .usdz).
    scene: PathBuf,
    /// Directory for report.json, report.csv, report.md and convergence.png (created).
    #[arg(short = 'o', long = "output")]
    output: PathBuf,
    /// Integrators to compare, comma-separated (default: those that render everything in
    /// the stage, or that can estimate the meters).
    #[arg(long, value_delimiter = ',')]
    integrators: Vec<String>,
    /// Integrator wall time per configuration, seconds.
    #[arg(long = "time", default_value_t = 60.0, allow_negative_numbers = true)]
    time: f64,
    /// Reference image: any absolute EXR of the render's resolution (ours, or another
    /// renderer's R, G, B).
    #[arg(long)]
    reference: Option<PathBuf>,
    /// Without --reference: render the reference (or, for meters, the reference readings)
    /// for this many seconds (default: 10 × --time); it is written to DIR/reference.exr.
    #[arg(long = "reference-time", allow_negative_numbers = true)]
    reference_time: Option<f64>,
    /// The integrator of the rendered reference (default: bdpt where it renders everything
    /// in the stage, else path; path for meters).
    #[arg(long = "reference-integrator")]
    reference_integrator: Option<String>,
    /// Wavelengths per sample to compare: 4 (hero + 3 rotations) and/or 1 (the hero alone).
    #[arg(long, value_delimiter = ',', default_value = "4")]
    wavelengths: Vec<usize>,
    /// CSV files of peer renders (tools/converge_peers.py) to add to the report and plot.
    #[arg(long)]
    peers: Vec<PathBuf>,
    /// Also write every snapshot as DIR/images/CONFIG_SPP.exr.
    #[arg(long = "keep-images")]
    keep_images: bool,
    /// Stop each configuration after the last snapshot at or below this many samples (per
    /// pixel, or per reading).
    #[arg(long = "max-spp")]
    max_spp: Option<u64>,
    /// Meters (as `meter` takes them): --at X,Y,Z with --normal, or --luminance with --dir;
    /// --at switches from the image to meters.
    #[command(flatten)]
    points: PointArgs,
    /// The meters' reference values (lx or cd/m²), one per --at, instead of a long run.
    #[arg(
        long = "reference-value",
        value_delimiter = ',',
        allow_negative_numbers = true
    )]
    reference_value: Vec<f64>,
    /// Seed of the deterministic sampler.
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Worker threads (default: all cores).
    #[arg(long)]
    threads: Option<usize>,
    /// Image size WxH, overriding RenderSettings.
    #[arg(long, value_parser = parse_resolution)]
    resolution: Option<(u32, u32)>,
    /// Maximum number of scattering events (default: unlimited, as for rendering).
    #[arg(long = "max-depth")]
    max_depth: Option<u32>,
    /// Sampler of the path tracer's, BDPT's and VCM's configurations and of their reference:
    /// zsobol (Owen-scrambled Sobol' in Morton order) or independent; light tracing always
    /// draws independent numbers.
    #[arg(long, default_value = "zsobol", value_parser = named::<SamplerKind>("sampler"))]
    sampler: SamplerKind,
    /// MIS heuristic of bdpt and vcm.
    #[arg(long, default_value = "power", value_parser = named::<MisHeuristic>("MIS heuristic"))]
    mis: MisHeuristic,
    /// Look textures up at full resolution (no MIP filtering).
    #[arg(long = "no-texture-filtering")]
    no_texture_filtering: bool,
}

/// Parses the arguments after `spectral-render` and runs.
pub fn main(argv: Vec<OsString>) -> Result<()> {
    let command = command_line(&argv);
    match ConvergeArgs::try_parse_from(argv) {
        Ok(args) => run(&args, command),
        Err(e) if !e.use_stderr() => e.exit(),
        Err(e) => Err(Error::option(clap_message(&e))),
    }
}

/// The command as typed (for the report), arguments with spaces quoted.
fn command_line(argv: &[OsString]) -> String {
    let words = argv.iter().map(|a| {
        let a = a.to_string_lossy();
        if a.contains(' ') {
            format!("'{a}'")
        } else {
            a.into_owned()
        }
    });
    std::iter::once("spectral-render".to_string())
        .chain(words)
        .collect::<Vec<_>>()
        .join(" ")
}

fn run(args: &ConvergeArgs, command: String) -> Result<()> {
    check(args)?;
    let named_integrators = integrators(&args.integrators, args.mis)?;
    let meters_asked = !args.points.at.is_empty();
    let points = if meters_asked {
        Some(points(&args.points)?)
    } else {
        None
    };
    std::fs::create_dir_all(&args.output)
        .map_err(|e| Error::io(&args.output, format!("cannot create the directory: {e}")))?;
    let scene = scene::load(&args.scene, args.resolution)?;
    print_summary(&scene);
    if let (Some(w), false) = (&scene.data_window, meters_asked) {
        eprintln!(
            "note: converge measures the whole image; <{}>'s dataWindowNDC is left out",
            w.prim_path
        );
    }
    let opts = RunOptions {
        time_s: args.time,
        max_samples: args.max_spp,
        seed: args.seed,
        threads: args.threads,
        max_depth: args.max_depth,
        filter_textures: !args.no_texture_filtering,
        sampler: args.sampler,
    };
    let mut report = Report {
        command,
        stage: args.scene.display().to_string(),
        kind: if meters_asked { "meters" } else { "image" }.into(),
        resolution: None,
        time_budget_s: args.time,
        seed: args.seed,
        max_depth: args.max_depth,
        reference: String::new(),
        masked_pixels: None,
        notes: Vec::new(),
        summaries: Vec::new(),
        rows: Vec::new(),
    };
    match points {
        Some((kind, pts)) => {
            let meters = pts
                .iter()
                .map(|&(p, d)| world_meter(&scene.stage_to_world, kind, p, d))
                .collect::<Result<Vec<_>>>()?;
            run_meters(
                args,
                &scene,
                &meters,
                kind,
                named_integrators,
                &opts,
                &mut report,
            )?;
        }
        None => run_images(args, &scene, named_integrators, &opts, &mut report)?,
    }
    report.summaries = fit::summarize(&report.rows);
    wavelength_notes(&mut report);
    report::write(&args.output, &report)?;
    let y_label = if meters_asked {
        "relative error of the reading"
    } else {
        "relRMSE (emitters masked)"
    };
    let stage = args.scene.file_name().unwrap_or_default().to_string_lossy();
    plot::write(
        &args.output.join("convergence.png"),
        &format!("{stage}: error against time"),
        y_label,
        &report.rows,
    )?;
    print_table(&report);
    eprintln!(
        "wrote {}/report.{{json,csv,md}} and convergence.png",
        args.output.display()
    );
    Ok(())
}

/// Option errors before any work.
fn check(args: &ConvergeArgs) -> Result<()> {
    let positive = |v: f64| v.is_finite() && v > 0.0;
    if !positive(args.time) {
        return Err(Error::option("--time must be a positive number of seconds"));
    }
    if args.reference_time.is_some_and(|t| !positive(t)) {
        return Err(Error::option(
            "--reference-time must be a positive number of seconds",
        ));
    }
    if args.reference.is_some()
        && (args.reference_time.is_some() || args.reference_integrator.is_some())
    {
        return Err(Error::option(
            "--reference takes an image; --reference-time and --reference-integrator render one instead",
        ));
    }
    if let Some(w) = args
        .wavelengths
        .iter()
        .find(|w| !WAVELENGTH_COUNTS.contains(w))
    {
        return Err(Error::option(format!(
            "--wavelengths {w}: a sample carries 4 wavelengths (hero sampling) or 1 (the hero alone)"
        )));
    }
    if args.threads == Some(0) {
        return Err(Error::option("--threads must be at least 1"));
    }
    if args.max_spp == Some(0) {
        return Err(Error::option("--max-spp must be at least 1"));
    }
    if args.points.at.is_empty() {
        if !args.reference_value.is_empty() {
            return Err(Error::option("--reference-value is for meters (--at …)"));
        }
    } else {
        if args.reference.is_some() || !args.peers.is_empty() || args.keep_images {
            return Err(Error::option(
                "--reference, --peers and --keep-images are for images, not meters",
            ));
        }
        if !args.reference_value.is_empty() && args.reference_value.len() != args.points.at.len() {
            return Err(Error::option(format!(
                "{} --reference-value for {} --at: give one per meter",
                args.reference_value.len(),
                args.points.at.len()
            )));
        }
        if let Some(v) = args.reference_value.iter().find(|v| !positive(v.abs())) {
            return Err(Error::option(format!(
                "--reference-value {v} must be a non-zero finite number (errors are relative to it)"
            )));
        }
    }
    Ok(())
}

/// The integrators named, with the MIS heuristic; empty when none were named.
fn integrators(names: &[String], mis: MisHeuristic) -> Result<Vec<Integrator>> {
    names
        .iter()
        .map(|n| {
            Integrator::from_name(n.trim())
                .map(|i| i.with_mis(mis))
                .ok_or_else(|| {
                    let all: Vec<&str> = Integrator::ALL.iter().map(|i| i.name()).collect();
                    Error::option(format!(
                        "unknown integrator '{n}' (available: {})",
                        all.join(", ")
                    ))
                })
        })
        .collect()
}

/// The configurations: the integrators (named, or every one that applies) × wavelengths;
/// notes on those left out.
fn configs(
    named: Vec<Integrator>,
    wavelengths: &[usize],
    applies: impl Fn(&Integrator) -> Option<String>,
    notes: &mut Vec<String>,
) -> Result<Vec<Config>> {
    let chosen = if named.is_empty() {
        let mut out = Vec::new();
        for i in Integrator::ALL {
            match applies(&i) {
                None => out.push(i),
                Some(why) => notes.push(format!("{} left out: {why}", i.name())),
            }
        }
        out
    } else {
        for i in &named {
            if let Some(why) = applies(i) {
                notes.push(format!("{}: {why}", i.name()));
            }
        }
        named
    };
    if chosen.is_empty() {
        return Err(Error::option(
            "no integrator applies; name them with --integrators",
        ));
    }
    let mut ws = wavelengths.to_vec();
    ws.dedup();
    let several = ws.len() > 1;
    Ok(chosen
        .iter()
        .flat_map(|&i| ws.iter().map(move |&w| Config::new(i, w, several)))
        .collect())
}

fn run_images(
    args: &ConvergeArgs,
    scene: &Scene,
    named: Vec<Integrator>,
    opts: &RunOptions,
    report: &mut Report,
) -> Result<()> {
    let (w, h) = (scene.camera.width as usize, scene.camera.height as usize);
    report.resolution = Some([w, h]);
    let configs = configs(
        named,
        &args.wavelengths,
        |i| {
            let warnings = i.warnings(scene, true);
            (!warnings.is_empty()).then(|| warnings.join("; "))
        },
        &mut report.notes,
    )?;
    let masked = mask::emitter_mask(scene);
    report.masked_pixels = Some(masked.iter().filter(|&&m| m).count());
    let reference = image_reference(args, scene, opts, report)?;
    let images = args.output.join("images");
    if args.keep_images {
        std::fs::create_dir_all(&images)
            .map_err(|e| Error::io(&images, format!("cannot create the directory: {e}")))?;
    }
    let mut keep = |c: &Config, out: &RenderOutput| -> Result<()> {
        if !args.keep_images {
            return Ok(());
        }
        let label = c.label.replace(' ', "_").replace('λ', "wl");
        let name = format!("{label}_{:06}.exr", out.spp);
        write_snapshot(&images.join(name), args, scene, c, out)
    };
    for c in &configs {
        eprintln!("converge: {} for {} s", c.label, args.time);
        let rows = converge::run_image(scene, c, opts, &reference, &masked, &mut keep)?;
        if let Some(d) = rows.last().and_then(|r| r.dropped).filter(|&d| d > 0) {
            report
                .notes
                .push(format!("{}: {d} samples dropped as non-finite", c.label));
        }
        report.rows.extend(rows);
    }
    for peers in &args.peers {
        report.rows.extend(peer_rows(peers, &reference, &masked)?);
    }
    Ok(())
}

/// The reference image: read (`--reference`) or rendered and written to DIR/reference.exr.
fn image_reference(
    args: &ConvergeArgs,
    scene: &Scene,
    opts: &RunOptions,
    report: &mut Report,
) -> Result<Reference> {
    if let Some(path) = &args.reference {
        let r = reference_file::read(path)?;
        check_size(path, &r, scene)?;
        let noise = if r.variance.is_some() {
            "its noise (variance channels) is subtracted"
        } else {
            "its noise is unknown and not subtracted"
        };
        report.reference = format!("{} ({noise}).", path.display());
        return Ok(r);
    }
    let time = args.reference_time.unwrap_or(10.0 * args.time);
    let (integrator, chosen) = match &args.reference_integrator {
        Some(n) => (integrators(std::slice::from_ref(n), args.mis)?[0], "named"),
        None => (
            reference::default_integrator(scene),
            "bdpt where it renders everything in the stage, else path",
        ),
    };
    eprintln!(
        "converge: rendering the reference with {} for {time} s",
        integrator.name()
    );
    let (r, info) = reference::render(scene, integrator, time, opts)?;
    let path = args.output.join("reference.exr");
    let meta = Made {
        stage: &args.scene,
        scene,
        integrator: &integrator,
        seed: opts.seed,
        max_depth: opts.max_depth,
        rr_depth: info.rr_depth,
        split: info.split,
        spp: 2 * info.spp_per_half,
        wall_time_s: info.time_s,
        sampler: info.sampler,
    }
    .metadata();
    reference_file::write(&path, &r, &meta)?;
    let bias = if integrator.capabilities().unbiased {
        "unbiased"
    } else {
        "consistent, not unbiased: its bias is not subtracted"
    };
    report.reference = format!(
        "rendered with {} ({chosen}; {bias}), 2 × {} spp in {:.1} s measured, written to \
         reference.exr with its noise (variance of the mean from the two halves' \
         difference), which is subtracted.",
        integrator.name(),
        info.spp_per_half,
        info.time_s
    );
    Ok(r)
}

fn check_size(path: &Path, r: &Reference, scene: &Scene) -> Result<()> {
    let (w, h) = (scene.camera.width as usize, scene.camera.height as usize);
    if (r.width, r.height) != (w, h) {
        return Err(Error::io(
            path,
            format!(
                "the image is {}x{}, the render {w}x{h} (use --resolution {}x{})",
                r.width, r.height, r.width, r.height
            ),
        ));
    }
    Ok(())
}

fn write_snapshot(
    path: &Path,
    args: &ConvergeArgs,
    scene: &Scene,
    c: &Config,
    out: &RenderOutput,
) -> Result<()> {
    let meta = Made {
        stage: &args.scene,
        scene,
        integrator: &c.integrator,
        seed: args.seed,
        max_depth: args.max_depth,
        rr_depth: out.rr_depth,
        split: out.split,
        spp: out.spp,
        wall_time_s: out.wall_time_s,
        sampler: out.sampler,
    }
    .metadata();
    let white = spectral::color::white_xy().map(|c| c as f32);
    exr::write(
        path, out.width, out.height, &out.rgb, &out.xyz, white, &meta,
    )
}

/// A peers CSV's rows; those naming an image and without errors get them computed here,
/// against the same reference and mask as ours.
fn peer_rows(csv: &Path, reference: &Reference, masked: &[bool]) -> Result<Vec<Row>> {
    let dir = csv.parent().unwrap_or(Path::new("."));
    let mut rows = report::read_csv(csv)?;
    for row in &mut rows {
        if row.source.is_empty() {
            row.source = "peer".into();
        }
        let Some(image) = row.image.clone().filter(|_| row.error.is_none()) else {
            continue;
        };
        let path = dir.join(&image);
        let img = reference_file::read(&path)?;
        if (img.width, img.height) != (reference.width, reference.height) {
            return Err(Error::io(
                &path,
                format!(
                    "the image is {}x{}, the reference {}x{}",
                    img.width, img.height, reference.width, reference.height
                ),
            ));
        }
        let e = image_errors(&img.rgb, &img.y, None, reference, masked);
        *row = std::mem::take(row).with_errors(&e);
    }
    Ok(rows)
}

fn run_meters(
    args: &ConvergeArgs,
    scene: &Scene,
    meters: &[Meter],
    kind: MeterKind,
    named: Vec<Integrator>,
    opts: &RunOptions,
    report: &mut Report,
) -> Result<()> {
    let configs = configs(
        named,
        &[4],
        |i| i.check_meter(kind).err().map(|e| e.to_string()),
        &mut report.notes,
    )?;
    for c in &configs {
        c.integrator.check_meter(kind)?;
    }
    if args.wavelengths != [4] {
        report
            .notes
            .push("meters carry 4 wavelengths; --wavelengths applies to images".into());
    }
    let references = if args.reference_value.is_empty() {
        let time = args.reference_time.unwrap_or(10.0 * args.time);
        let integrator = match &args.reference_integrator {
            Some(n) => integrators(std::slice::from_ref(n), args.mis)?[0],
            None => Integrator::Path,
        };
        integrator.check_meter(kind)?;
        eprintln!(
            "converge: reference readings with {} for {time} s",
            integrator.name()
        );
        let c = Config::new(integrator, 4, false);
        let r = meters::long_run(scene, meters, &c, time, opts)?;
        let vals: Vec<String> = r
            .iter()
            .map(|v| format!("{} ± {}", v.value, v.ci95))
            .collect();
        report.reference = format!(
            "a long run of {} ({time} s, seed-shifted): {} {} (95 % CI); a reading covers \
             it when |x − ref| ≤ √(ci95² + ci95_ref²).",
            integrator.name(),
            vals.join(", "),
            kind.unit()
        );
        r
    } else {
        report.reference = format!("given values {:?} {}", args.reference_value, kind.unit());
        args.reference_value
            .iter()
            .map(|&value| ReferenceValue { value, ci95: 0.0 })
            .collect()
    };
    for c in &configs {
        eprintln!("converge: {} for {} s", c.label, args.time);
        report
            .rows
            .extend(meters::run_meters(scene, meters, c, opts, &references)?);
    }
    Ok(())
}

/// The samples/s of 4 against 1 wavelength per integrator, as notes.
fn wavelength_notes(report: &mut Report) {
    for s4 in report
        .summaries
        .iter()
        .filter(|s| s.config.ends_with(" 4λ"))
    {
        let base = s4.config.trim_end_matches(" 4λ");
        let Some(s1) = report
            .summaries
            .iter()
            .find(|s| s.config == format!("{base} 1λ") && s.source == s4.source)
        else {
            continue;
        };
        let overhead = s1.samples_per_s / s4.samples_per_s - 1.0;
        report.notes.push(format!(
            "{base}: 4 wavelengths cost {:+.1} % in samples/s ({:.4} against {:.4} samples \
             per pixel per second with 1, measured over each run)",
            100.0 * overhead,
            s4.samples_per_s,
            s1.samples_per_s
        ));
    }
}

/// One line per configuration on stdout.
fn print_table(report: &Report) {
    for s in &report.summaries {
        let to: Vec<String> = fit::TARGETS
            .iter()
            .zip(&s.time_to)
            .map(|(t, v)| match v {
                Some(v) => format!("{:.0} % {v:.2} s", 100.0 * t),
                None => format!("{:.0} % —", 100.0 * t),
            })
            .collect();
        let meter = s.meter.map(|m| format!(" meter {m}")).unwrap_or_default();
        println!(
            "{}{meter} [{}]: {} samples, {:.2} s, error {:.3} %, slope {}, time to {}",
            s.config,
            s.source,
            s.samples,
            s.time_s,
            100.0 * s.error,
            s.slope.map_or("—".into(), |v| format!("{v:.2}")),
            to.join(", ")
        );
    }
}
