//! `spectral-render meter STAGE ...`: light-meter readings with 95% confidence intervals.
//!
//! ```text
//! spectral-render meter stage.usda --at X,Y,Z --normal NX,NY,NZ [--at … --normal …]
//!                                  [--spp N | --rel-error 0.005] [--seed N] [--json]
//!                                  [--integrator path|light|bdpt] [--mis power|balance]
//! spectral-render meter stage.usda --luminance --at X,Y,Z --dir DX,DY,DZ [--json]
//! spectral-render meter stage.usda --grid X,Y,Z --u UX,UY,UZ --v VX,VY,VZ --n NU,NV
//!                                  --normal NX,NY,NZ [-o map]
//! ```
//!
//! Points, normals and vectors are in the stage's coordinates and units and are converted to
//! world space like geometry (metersPerUnit, upAxis). `--json` prints
//! `{"meters":[{"kind":"illuminance","at":[…],"normal":[…],"value":E,"unit":"lx","ci95":h,
//! "samples":n}, …]}` (luminance entries have `"dir"` and `"unit":"cd/m2"`; under
//! `--rel-error` each entry also has `"converged"`). Option errors, clap's included, are one
//! line and exit 1; so is a luminance meter asked of light tracing, which cannot estimate it.

use super::common::{
    at_least, clap_message, max_memory, print_auto, print_report, print_summary, warn_depth_cut,
    warn_dropped, warn_limits, IntegratorArgs, MachineryArgs,
};
use super::frames::FrameArgs;
use super::interrupt;
use super::meter_parts::{self, MeterPartArgs};
use crate::error::{Error, Result};
use crate::output::json;
use crate::output::map::{self, IlluminanceMap};
use crate::output::rounding::{significant, with_confidence};
use crate::output::target::{self, Format, Target};
use crate::scene;
use crate::sensor::meter::{self, Meter, MeterKind};
use crate::session::meter::{DEFAULT_MAX_SAMPLES, DEFAULT_SAMPLES};
use crate::session::{Cap, MeterOptions, MeterRun, MeterSession, Progressive, Reading, Stop};
use clap::Parser;
use glam::{DMat4, DVec3};
use serde::Serialize;
use std::ffi::OsString;
use std::path::{Path, PathBuf};

/// Measure illuminance (lx) or luminance (cd/m²) in a USD stage, with 95% confidence
/// intervals, or write an illuminance map.
#[derive(Parser, Debug, Clone)]
#[command(name = "spectral-render meter", bin_name = "spectral-render meter")]
pub(super) struct MeterArgs {
    /// The stage (.usda, .usdc or .usdz).
    pub(super) scene: PathBuf,
    #[command(flatten)]
    pub(super) points: PointArgs,
    /// Origin (a corner) of an illuminance grid.
    #[arg(long, value_name = "X,Y,Z", allow_hyphen_values = true)]
    pub(super) grid: Option<String>,
    /// First edge vector of the grid.
    #[arg(long = "u", value_name = "UX,UY,UZ", allow_hyphen_values = true)]
    pub(super) u: Option<String>,
    /// Second edge vector of the grid.
    #[arg(long = "v", value_name = "VX,VY,VZ", allow_hyphen_values = true)]
    pub(super) v: Option<String>,
    /// Cells along u and v.
    #[arg(long = "n", value_name = "NU,NV", allow_hyphen_values = true)]
    pub(super) n: Option<String>,
    /// A fixed colour scale for the map's PNG, in lx (default: from the readings).
    #[arg(long, value_name = "MIN,MAX", value_parser = parse_range, allow_hyphen_values = true)]
    pub(super) range: Option<(f64, f64)>,
    /// Base name of the grid outputs: BASE.csv, BASE.json, BASE.png (default: map).
    #[arg(short = 'o', long = "output")]
    pub(super) output: Option<PathBuf>,
    /// Samples per reading (default 4096).
    #[arg(long, allow_negative_numbers = true, value_parser = at_least::<u64>(1))]
    pub(super) spp: Option<u64>,
    /// Sample until every reading's ci95/value is below this (or a cap is hit).
    #[arg(long = "rel-error", allow_negative_numbers = true)]
    pub(super) rel_error: Option<f64>,
    /// Cap on the samples of one reading under --rel-error (default 2^24).
    #[arg(long = "max-spp", allow_negative_numbers = true, value_parser = at_least::<u64>(1))]
    pub(super) max_spp: Option<u64>,
    /// Wall-clock cap in seconds.
    #[arg(long = "time", allow_negative_numbers = true)]
    pub(super) time: Option<f64>,
    /// Seed of the deterministic sampler.
    #[arg(long, default_value_t = 0, allow_negative_numbers = true, value_parser = at_least::<u64>(0))]
    pub(super) seed: u64,
    /// Worker threads (default: all cores).
    #[arg(long, allow_negative_numbers = true, value_parser = at_least::<usize>(1))]
    pub(super) threads: Option<usize>,
    /// Maximum number of scattering events (as for rendering; default unlimited).
    #[arg(long = "max-depth", allow_negative_numbers = true, value_parser = at_least::<u32>(0))]
    pub(super) max_depth: Option<u32>,
    /// Refuse to start a measurement estimated to need more memory than SIZE (e.g. 8G;
    /// default: the memory available).
    #[arg(long = "max-memory", value_name = "SIZE", value_parser = max_memory, allow_hyphen_values = true)]
    pub(super) max_memory: Option<u64>,
    /// Print the readings as JSON on stdout.
    #[arg(long)]
    pub(super) json: bool,
    #[command(flatten)]
    pub(super) integrator: IntegratorArgs,
    #[command(flatten)]
    pub(super) when: FrameArgs,
    #[command(flatten)]
    pub(super) machinery: MachineryArgs,
    #[command(flatten)]
    pub(super) part: MeterPartArgs,
}

/// Where meters are and what they measure (`meter` and `converge` take them alike).
#[derive(clap::Args, Debug, Clone)]
pub(super) struct PointArgs {
    /// Meter position in stage coordinates (repeat for several meters).
    #[arg(long = "at", value_name = "X,Y,Z", allow_hyphen_values = true)]
    pub at: Vec<String>,
    /// Normal of the receiving surface, one per --at (or one for --grid).
    #[arg(long, value_name = "NX,NY,NZ", allow_hyphen_values = true)]
    pub normal: Vec<String>,
    /// Measure luminance (cd/m²) looking along --dir instead of illuminance.
    #[arg(long)]
    pub luminance: bool,
    /// Viewing direction of a luminance meter, one per --at.
    #[arg(long, value_name = "DX,DY,DZ", allow_hyphen_values = true)]
    pub dir: Vec<String>,
}

/// The grid as given (stage coordinates).
#[derive(Clone, Copy, Debug)]
pub(super) struct GridSpec {
    origin: DVec3,
    u: DVec3,
    v: DVec3,
    n: (usize, usize),
    normal: DVec3,
}

/// What was asked for, validated, still in stage coordinates.
#[derive(Clone, Debug)]
pub(super) enum Request {
    /// (kind, position, normal or direction) per meter.
    Points(MeterKind, Vec<(DVec3, DVec3)>),
    Grid(GridSpec),
}

/// Cells a grid may have (a 2000 × 2000 map).
const MAX_CELLS: usize = 4_000_000;

/// Parses the arguments after `spectral-render` and measures. `--help` prints the usage; any
/// option error (clap's included) is one line and exit code 1.
pub fn main(argv: Vec<OsString>) -> Result<()> {
    match MeterArgs::try_parse_from(&argv) {
        Ok(args) if args.part.part.is_some() => meter_parts::run(&args, &argv),
        Ok(args) => run(&args),
        Err(e) if !e.use_stderr() => e.exit(),
        Err(e) => Err(Error::option(clap_message(&e))),
    }
}

fn run(args: &MeterArgs) -> Result<()> {
    let request = request(args)?;
    let opts = options(args)?;
    if let Request::Points(kind, _) = &request {
        opts.integrator.check_meter(*kind)?;
    }
    if let Request::Grid(_) = &request {
        check_map_targets(&output_base(args.output.as_deref()))?;
    }
    let Some(scene) = load(args, &opts)? else {
        return Ok(());
    };
    match request {
        Request::Points(kind, points) => run_points(args, &scene, &opts, kind, &points),
        Request::Grid(g) => run_grid(args, &scene, &opts, &g),
    }
}

/// Checks the map files of base name `base` as outputs, before the work.
pub(super) fn check_map_targets(base: &Path) -> Result<()> {
    let files = map::files(base);
    target::check(&[
        Target::new("-o", &files[0], Format::Any),
        Target::new("-o", &files[1], Format::Any),
        Target::new("-o", &files[2], Format::Png),
    ])
}

/// Installs the signal handlers and loads the stage to measure in; None when a signal
/// arrived meanwhile (nothing is measured or written).
pub(super) fn load(args: &MeterArgs, opts: &MeterOptions) -> Result<Option<scene::Scene>> {
    interrupt::install()?;
    let scene = scene::load_at(
        &args.scene,
        Some((1, 1)),
        args.machinery.machinery(),
        args.when.read_time(),
    )?;
    print_summary(&scene);
    if let Some(signal) = interrupt::received() {
        eprintln!("interrupted by {signal} before measuring; nothing written");
        return Ok(None);
    }
    warn_limits(&opts.integrator, &scene, false);
    Ok(Some(scene))
}

fn run_points(
    args: &MeterArgs,
    scene: &scene::Scene,
    opts: &MeterOptions,
    kind: MeterKind,
    points: &[(DVec3, DVec3)],
) -> Result<()> {
    let meters = point_meters(scene, kind, points)?;
    let run = measure(scene, &meters, opts)?;
    print!("{}", points_output(args.json, opts, kind, points, &run)?);
    Ok(())
}

/// The point meters in world space.
fn point_meters(
    scene: &scene::Scene,
    kind: MeterKind,
    points: &[(DVec3, DVec3)],
) -> Result<Vec<Meter>> {
    points
        .iter()
        .map(|&(p, d)| world_meter(&scene.stage_to_world, kind, p, d))
        .collect()
}

/// The warnings of a run of point meters, and what it prints: `--json`'s document or a line
/// per reading (also the merge of a study's parts, `meter_parts`).
pub(super) fn points_output(
    as_json: bool,
    opts: &MeterOptions,
    kind: MeterKind,
    points: &[(DVec3, DVec3)],
    run: &MeterRun,
) -> Result<String> {
    warn(run, opts);
    let rel = matches!(opts.stop, Stop::RelError(_)) || interrupt::received().is_some();
    if as_json {
        let meters = points
            .iter()
            .zip(&run.readings)
            .map(|(&(p, d), r)| json_entry(kind, p, d, r, rel))
            .collect();
        json::compact(&Readings { meters })
    } else {
        let lines: Vec<String> = points
            .iter()
            .zip(&run.readings)
            .map(|(&(p, d), r)| text_entry(kind, p, d, r) + "\n")
            .collect();
        Ok(lines.concat())
    }
}

/// The stage's metres per unit, for the map's axes.
pub(super) fn meters_per_unit(scene: &scene::Scene) -> f64 {
    scene.stage_to_world.x_axis.truncate().length()
}

fn run_grid(
    args: &MeterArgs,
    scene: &scene::Scene,
    opts: &MeterOptions,
    g: &GridSpec,
) -> Result<()> {
    let meters = grid_meters(scene, g)?;
    let run = measure(scene, &meters, opts)?;
    let base = output_base(args.output.as_deref());
    let scale = (args.range, meters_per_unit(scene));
    grid_output(args.json, opts, g, &run, &base, scale)
}

/// The grid's meters in world space, row by row.
fn grid_meters(scene: &scene::Scene, g: &GridSpec) -> Result<Vec<Meter>> {
    let (nu, nv) = g.n;
    let m = &scene.stage_to_world;
    let mut meters = Vec::with_capacity(nu * nv);
    for j in 0..nv {
        for i in 0..nu {
            let c = IlluminanceMap::cell_centre(
                g.origin.into(),
                g.u.into(),
                g.v.into(),
                (nu, nv),
                (i, j),
            );
            meters.push(world_meter(m, MeterKind::Illuminance, c.into(), g.normal)?);
        }
    }
    Ok(meters)
}

/// The meters a request asks for, in world space.
pub(super) fn request_meters(scene: &scene::Scene, request: &Request) -> Result<Vec<Meter>> {
    match request {
        Request::Points(kind, points) => point_meters(scene, *kind, points),
        Request::Grid(g) => grid_meters(scene, g),
    }
}

/// The warnings of a grid's run, its map files at `base` and its summary (also the merge of
/// a study's parts, `meter_parts`).
/// `scale`: the PNG's fixed colour range (`--range`) and the stage's metres per unit.
pub(super) fn grid_output(
    as_json: bool,
    opts: &MeterOptions,
    g: &GridSpec,
    run: &MeterRun,
    base: &Path,
    (range, meters_per_unit): (Option<(f64, f64)>, f64),
) -> Result<()> {
    warn(run, opts);
    let (nu, nv) = g.n;
    let map = IlluminanceMap {
        origin: g.origin.into(),
        u: g.u.into(),
        v: g.v.into(),
        nu,
        nv,
        normal: g.normal.into(),
        readings: run.readings.clone(),
        range,
        meters_per_unit,
    };
    let written = map.write(base)?;
    let line = summary_line(&map);
    if as_json {
        print!("{}", map.json()?);
        eprintln!("{line}");
    } else {
        println!("{line}");
    }
    let names: Vec<String> = written.iter().map(|p| p.display().to_string()).collect();
    eprintln!(
        "wrote {} ({} cells, {:.2} s)",
        names.join(", "),
        nu * nv,
        run.wall_time_s
    );
    Ok(())
}

/// EN 12464-1's figures rounded to their confidence: E_min and E_max with their cell's
/// 95 % half-width, E_avg with that of the mean of independent readings (√Σci² / n), U0 to
/// three significant digits.
fn summary_line(map: &IlluminanceMap) -> String {
    let s = map.summary();
    let r = &map.readings;
    let by_value = |a: &&Reading, b: &&Reading| a.value.total_cmp(&b.value);
    let (Some(lo), Some(hi)) = (r.iter().min_by(by_value), r.iter().max_by(by_value)) else {
        return "no readings".into();
    };
    let ci_avg = r.iter().map(|x| x.ci95 * x.ci95).sum::<f64>().sqrt() / r.len() as f64;
    format!(
        "E_min = {} lx, E_avg = {} lx, E_max = {} lx, U0 = {}",
        with_confidence(lo.value, lo.ci95),
        with_confidence(s.e_avg, ci_avg),
        with_confidence(hi.value, hi.ci95),
        significant(s.u0, 3)
    )
}

/// Measures to the end, or until a signal arrives: then the unfinished readings are marked
/// as interrupted and the readings so far are returned.
fn measure(scene: &scene::Scene, meters: &[Meter], opts: &MeterOptions) -> Result<MeterRun> {
    let mut session = MeterSession::new(scene, meters, opts)?;
    measure_session(&mut session)
}

/// Runs `session` to the end, or until a signal arrives (then the unfinished readings are
/// marked as interrupted).
pub(super) fn measure_session(session: &mut MeterSession) -> Result<MeterRun> {
    while session.step().is_some() {
        if let Some(signal) = interrupt::received() {
            session.interrupt();
            eprintln!("interrupted by {signal}; the readings so far follow");
            break;
        }
    }
    Ok(session.readings())
}

/// The meter in world space; a normal or direction that vanishes there is an error.
pub(super) fn world_meter(m: &DMat4, kind: MeterKind, p: DVec3, d: DVec3) -> Result<Meter> {
    let p_w = meter::stage_point(m, p);
    match kind {
        MeterKind::Illuminance => Meter::illuminance(p_w, meter::stage_normal(m, d)),
        MeterKind::Luminance => Meter::luminance(p_w, meter::stage_vector(m, d)),
    }
}

/// Warnings about dropped samples and readings a cap stopped.
fn warn(run: &MeterRun, opts: &MeterOptions) {
    print_auto(run.auto.as_ref());
    warn_dropped(run.dropped);
    warn_meter_depth_cut(&run.readings);
    print_report(&run.report);
    for (cap, what) in [
        (Cap::Samples, "the sample cap (--max-spp)"),
        (Cap::Time, "the time cap (--time)"),
        (Cap::Interrupted, "an interrupt"),
    ] {
        let k = run
            .readings
            .iter()
            .filter(|r| r.capped == Some(cap))
            .count();
        if k > 0 {
            let target = match opts.stop {
                Stop::RelError(r) => format!("before reaching ci95/value < {r}"),
                Stop::Samples(n) => format!("before {n} samples"),
            };
            eprintln!("warning: {k} readings were stopped by {what} {target}");
        }
    }
}

/// What the depth cap cut: of the one reading, or of the reading it cut most.
fn warn_meter_depth_cut(readings: &[Reading]) {
    let cut = readings
        .iter()
        .enumerate()
        .filter_map(|(i, r)| r.depth_cut.map(|c| (i, c)))
        .max_by(|a, b| a.1.fraction.total_cmp(&b.1.fraction));
    if let Some((i, c)) = cut {
        let what = match readings.len() {
            1 => "the reading".to_string(),
            n => format!("reading {} (the largest cut of the {n} readings)", i + 1),
        };
        warn_depth_cut(Some(&c), &what);
    }
}

/// `--json`: `{"meters": [...]}`, one entry per meter in the order given.
#[derive(Serialize)]
struct Readings {
    meters: Vec<ReadingJson>,
}

#[derive(Serialize)]
struct ReadingJson {
    kind: &'static str,
    at: [f64; 3],
    #[serde(skip_serializing_if = "Option::is_none")]
    normal: Option<[f64; 3]>,
    #[serde(skip_serializing_if = "Option::is_none")]
    dir: Option<[f64; 3]>,
    value: f64,
    unit: &'static str,
    ci95: f64,
    samples: u64,
    /// Under --rel-error: false when a cap stopped the reading.
    #[serde(skip_serializing_if = "Option::is_none")]
    converged: Option<bool>,
    /// What the depth cap cut of the reading, when a path reached it.
    #[serde(skip_serializing_if = "Option::is_none")]
    depth_cut: Option<DepthCutJson>,
}

/// `session::DepthCut` in the JSON: the cap, whether the user set it, the fraction of the
/// reading it cut with its ci95, the paths that reached it, and whether the fraction is a
/// lower bound.
#[derive(Serialize)]
struct DepthCutJson {
    max_depth: u32,
    user: bool,
    fraction: f64,
    ci95: f64,
    capped_paths: u64,
    lower_bound: bool,
}

fn json_entry(kind: MeterKind, p: DVec3, d: DVec3, r: &Reading, rel: bool) -> ReadingJson {
    let d = Some(d.to_array());
    let (normal, dir) = match kind {
        MeterKind::Illuminance => (d, None),
        MeterKind::Luminance => (None, d),
    };
    ReadingJson {
        kind: kind.name(),
        at: p.to_array(),
        normal,
        dir,
        value: r.value,
        unit: kind.unit(),
        ci95: r.ci95,
        samples: r.samples,
        converged: rel.then_some(r.capped.is_none()),
        depth_cut: r.depth_cut.map(|c| DepthCutJson {
            max_depth: c.max_depth,
            user: c.user,
            fraction: c.fraction,
            ci95: c.ci95,
            capped_paths: c.capped,
            lower_bound: c.lower_bound,
        }),
    }
}

fn text_entry(kind: MeterKind, p: DVec3, d: DVec3, r: &Reading) -> String {
    let what = match kind {
        MeterKind::Illuminance => "normal",
        MeterKind::Luminance => "looking along",
    };
    format!(
        "{} at ({}, {}, {}) {what} ({}, {}, {}): {} {} (95% CI, {} samples){}",
        kind.name(),
        p.x,
        p.y,
        p.z,
        d.x,
        d.y,
        d.z,
        with_confidence(r.value, r.ci95),
        kind.unit(),
        r.samples,
        match r.capped {
            Some(Cap::Interrupted) => " [interrupted]",
            Some(_) => " [capped]",
            None => "",
        }
    )
}

/// `-o`: a base name; a trailing .csv/.json/.png is dropped, a directory gets `map` inside.
pub(super) fn output_base(o: Option<&Path>) -> PathBuf {
    let Some(o) = o else {
        return PathBuf::from("map");
    };
    if o.is_dir() {
        return o.join("map");
    }
    match o.extension().and_then(|e| e.to_str()) {
        Some("csv" | "json" | "png") => o.with_extension(""),
        _ => o.to_path_buf(),
    }
}

/// Checks which meters were asked for and parses their vectors.
pub(super) fn request(a: &MeterArgs) -> Result<Request> {
    if a.grid.is_some() {
        return grid_request(a);
    }
    for (given, flag) in [
        (a.u.is_some(), "--u"),
        (a.v.is_some(), "--v"),
        (a.n.is_some(), "--n"),
        (a.output.is_some(), "-o"),
        (a.range.is_some(), "--range"),
    ] {
        if given {
            return Err(Error::option(format!(
                "{flag} belongs to --grid, which was not given"
            )));
        }
    }
    if a.points.at.is_empty() {
        return Err(Error::option(
            "nothing to measure: give --at X,Y,Z with --normal NX,NY,NZ \
                    (illuminance), --luminance --at X,Y,Z --dir DX,DY,DZ, or --grid",
        ));
    }
    let (kind, points) = points(&a.points)?;
    Ok(Request::Points(kind, points))
}

/// The meters of `--at` with `--normal` (illuminance) or, with `--luminance`, `--dir`: their
/// kind and (position, normal or direction) in stage coordinates (also `converge`'s).
pub(super) fn points(p: &PointArgs) -> Result<(MeterKind, Vec<(DVec3, DVec3)>)> {
    let PointArgs {
        at,
        normal,
        luminance,
        dir,
    } = p;
    let (kind, dirs, flag) = if *luminance {
        if !normal.is_empty() {
            return Err(Error::option("--luminance meters take --dir, not --normal"));
        }
        (MeterKind::Luminance, dir, "--dir")
    } else {
        if !dir.is_empty() {
            return Err(Error::option(
                "--dir is for --luminance meters; illuminance meters take --normal",
            ));
        }
        (MeterKind::Illuminance, normal, "--normal")
    };
    if dirs.len() != at.len() {
        return Err(Error::option(format!(
            "{} --at but {} {flag}: give one {flag} per --at, in the same order",
            at.len(),
            dirs.len()
        )));
    }
    let points = at
        .iter()
        .zip(dirs)
        .map(|(p, d)| Ok((vector("--at", p)?, direction(flag, d)?)))
        .collect::<Result<Vec<_>>>()?;
    Ok((kind, points))
}

fn grid_request(a: &MeterArgs) -> Result<Request> {
    if !a.points.at.is_empty() || a.points.luminance || !a.points.dir.is_empty() {
        return Err(Error::option(
            "--grid measures illuminance on its own: drop --at, --dir and --luminance",
        ));
    }
    let need = |v: &Option<String>, flag: &str| {
        v.clone().ok_or_else(|| {
            Error::option(format!(
                "--grid needs {flag} as well (origin, --u, --v, --n, --normal)"
            ))
        })
    };
    let (u, v, n) = (need(&a.u, "--u")?, need(&a.v, "--v")?, need(&a.n, "--n")?);
    let normal = match a.points.normal.as_slice() {
        [one] => direction("--normal", one)?,
        [] => return Err(Error::option("--grid needs --normal NX,NY,NZ")),
        _ => return Err(Error::option("--grid takes one --normal for all its cells")),
    };
    let g = GridSpec {
        origin: vector("--grid", a.grid.as_deref().unwrap_or_default())?,
        u: vector("--u", &u)?,
        v: vector("--v", &v)?,
        n: cells(&n)?,
        normal,
    };
    if g.u.cross(g.v).length() == 0.0 {
        return Err(Error::option(format!(
            "--u {u} and --v {v} do not span a rectangle (zero or parallel edges)"
        )));
    }
    Ok(Request::Grid(g))
}

/// Three comma-separated finite numbers.
/// `--range MIN,MAX`: finite, MIN < MAX.
fn parse_range(s: &str) -> std::result::Result<(f64, f64), String> {
    let bad = || format!("'{s}': expected MIN,MAX in lx with MIN < MAX, e.g. 0,500");
    let (a, b) = s.split_once(',').ok_or_else(bad)?;
    let (a, b) = (
        a.trim().parse::<f64>().map_err(|_| bad())?,
        b.trim().parse::<f64>().map_err(|_| bad())?,
    );
    if a.is_finite() && b.is_finite() && a < b {
        Ok((a, b))
    } else {
        Err(bad())
    }
}

fn vector(flag: &str, s: &str) -> Result<DVec3> {
    let parts: Vec<&str> = s.split(',').map(str::trim).collect();
    let bad = || {
        Error::option(format!(
            "{flag} '{s}': expected three comma-separated numbers, e.g. 1,0.8,-2"
        ))
    };
    if parts.len() != 3 {
        return Err(bad());
    }
    let mut v = [0.0; 3];
    for (x, p) in v.iter_mut().zip(&parts) {
        *x = p.parse::<f64>().map_err(|_| bad())?;
        if !x.is_finite() {
            return Err(bad());
        }
    }
    Ok(DVec3::from(v))
}

/// A vector that must not be zero.
fn direction(flag: &str, s: &str) -> Result<DVec3> {
    let v = vector(flag, s)?;
    if v.length() == 0.0 {
        return Err(Error::option(format!("{flag} '{s}' has zero length")));
    }
    Ok(v)
}

/// `NU,NV`: two positive integers.
fn cells(s: &str) -> Result<(usize, usize)> {
    let bad = || {
        Error::option(format!(
            "--n '{s}': expected two positive integers NU,NV, e.g. 20,10"
        ))
    };
    let (a, b) = s.split_once(',').ok_or_else(bad)?;
    let nu: usize = a.trim().parse().map_err(|_| bad())?;
    let nv: usize = b.trim().parse().map_err(|_| bad())?;
    if nu == 0 || nv == 0 {
        return Err(bad());
    }
    if nu.saturating_mul(nv) > MAX_CELLS {
        return Err(Error::option(format!(
            "--n '{s}': at most {MAX_CELLS} cells"
        )));
    }
    Ok((nu, nv))
}

/// Sampling options from the flags.
pub(super) fn options(a: &MeterArgs) -> Result<MeterOptions> {
    let stop = match (a.spp, a.rel_error) {
        (Some(_), Some(_)) => return Err(Error::option("give --spp or --rel-error, not both")),
        (Some(n), None) if n < 2 => {
            return Err(Error::option(
                "--spp must be at least 2 (a confidence interval needs two samples)",
            ))
        }
        (Some(n), None) => Stop::Samples(n),
        (None, Some(r)) if !(r.is_finite() && r > 0.0) => {
            return Err(Error::option(format!(
                "--rel-error {r} must be a positive number, e.g. 0.005"
            )))
        }
        (None, Some(r)) => Stop::RelError(r),
        (None, None) => Stop::Samples(DEFAULT_SAMPLES),
    };
    if a.max_spp.is_some() && a.rel_error.is_none() {
        return Err(Error::option(
            "--max-spp caps --rel-error; use --spp for a fixed count",
        ));
    }
    if a.max_spp.is_some_and(|n| n < 2) {
        return Err(Error::option("--max-spp must be at least 2"));
    }
    if let Some(t) = a.time {
        if !(t.is_finite() && t > 0.0) {
            return Err(Error::option("--time must be a positive number of seconds"));
        }
    }
    if a.threads == Some(0) {
        return Err(Error::option("--threads must be at least 1"));
    }
    Ok(MeterOptions {
        stop,
        max_samples: a.max_spp.unwrap_or(DEFAULT_MAX_SAMPLES),
        time_budget: a.time,
        seed: a.seed,
        max_depth: a.max_depth,
        rr_depth: a.integrator.rr_depth.or_default(),
        threads: a.threads,
        integrator: a.integrator.integrator(true)?,
        max_memory: a.max_memory,
    })
}
