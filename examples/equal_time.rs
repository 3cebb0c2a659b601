//! Equal-time image error of several integrators against a long reference.
//!
//! ```text
//! cargo run --release --example equal_time -- STAGE [--time S | --spp N] [--seeds N]
//!     [--reference-time S | --reference-spp N] [--resolution WxH] [--max-depth N|unlimited]
//!     [--reference REF.exr] [--threads N] [--integrators path,bdpt,vcm,vcm:caustic,vcm:bins=B,auto,…]
//!     [--reference-integrator bdpt|vcm|path] [--region NAME=X0,Y0,X1,Y1]...
//!     [--exclude X0,Y0,X1,Y1]... [--seed N] [--keep DIR] [--metric mse|relmse]
//! ```
//!
//! 1. Reference: `--reference-integrator` (default BDPT; VCM where only merging samples the
//!    light, a consistent rather than unbiased reference) for `--reference-time` seconds
//!    (default 600; or `--reference-spp` samples per pixel) as two independent halves
//!    A and B; the reference is (A + B)/2 and its own noise variance per pixel is estimated as
//!    (A − B)²/4, which is subtracted from every MSE below. With `--reference PATH` the
//!    reference is read from (or, if absent, written to) PATH; its noise estimate travels in
//!    the `XYZ.X` channel of a second file `PATH.noise.exr`.
//! 2. Each of `--integrators` (default path,bdpt) renders for `--time` seconds (default 30;
//!    the render loop sizes its passes to end near the budget), or `--spp` samples per pixel.
//! 3. For each: RMSE of luminance (XYZ.Y, cd/m²) against the reference, relative RMSE, the
//!    time actually spent, and the ratio of its MSE and of its MSE × time (the inverse
//!    efficiency, fair even if the times differ a little) to the first integrator's and to
//!    the best one's. The process's CPU time of each render (user + system, from
//!    `/proc/self/stat`) is printed too, with the ratios of MSE × CPU time: on a machine
//!    shared with other work, the wall budget buys an integrator fewer samples when the load
//!    rises, and its CPU time says how much computing it actually got. `auto` runs its pilot
//!    within its time.
//! 4. Each `--region` (pixels X0 ≤ x < X1, Y0 ≤ y < Y1) gets the same figures over its
//!    pixels alone: where in the image an integrator wins or loses. With `--exclude`
//!    rectangles, the figures are also given for the image without them: for a few pixels
//!    that carry nearly all of every integrator's error with the same technique in all (a
//!    light seen through specular surfaces, which only the camera path hitting it samples),
//!    where the ratio is then only the ratio of the costs.
//!
//! 5. With `--seeds N` (N > 1) each integrator renders at seeds `--seed` … `--seed` + N − 1 (in
//!    turn per seed) and, per region, the table gives the mean MSE over the seeds with its
//!    standard error, the mean CPU time, and the inverse efficiency mean MSE × mean CPU time
//!    (PBR 3ed §13.7's 1/(V·T) with the MSE for V) over the best fixed integrator's, with a
//!    95 % interval from a paired bootstrap over the seeds. Where single renders' errors swing
//!    with rare fireflies (`scenes/caustic.usda`: 2–5× from seed to seed), only such means
//!    compare integrators. With `auto` among the integrators it prints auto's choices, whether
//!    under `--spp` its image was its choice's at every seed, and issue 11's criterion: auto's
//!    ratio at most 1.1 × (1 + the CPU time its losing candidates' pilots took, over the rest
//!    of its render's; each loser's pilot costed at that integrator's CPU time per sample here).
//!    Use `--threads 1` and `--spp` on a shared machine: CPU time is then what each render
//!    cost, whatever the load.
//!
//! `--metric` chooses the error every figure is of. `mse` (the default): the mean squared
//! error of luminance in (cd/m²)². `relmse`: the error the `converge` report judges by
//! (`converge::metrics`), pbrt-v4's relMSE, (y − r)² / (r² + 0.01) per pixel, less the
//! reference's noise per pixel on the same scale, over the pixels that do not see an emitter
//! directly (`converge::mask`), here on luminance (the references keep Y alone). Absolute MSE
//! lets the brightest few pixels decide (on `scenes/caustic.usda` the lamp's glints through
//! the ball); relMSE weighs every pixel by its own brightness.
//!
//! `--keep DIR` also writes each timed render to DIR/NAME.exr (colour included; two runs with
//! different `--seed`s give each integrator's colour noise without a reference).
//!
//! An integrator's name may end in `@independent` or `@zsobol`: its samples' numbers
//! (`--sampler`; default zsobol, the reference's too), e.g. `bdpt,bdpt@independent` for the
//! variance the low-discrepancy sequence saves BDPT at the same sample count.
//!
//! `path:rrN` is the path tracer with Russian roulette from bounce N (`--rr-depth N`; `path`
//! alone takes the default, `auto`: the roulette pilot's choice per seed), e.g.
//! `path,path:rr2,path:rr5,path@independent,path:rr5@independent`.
//!
//! `vcm:bins=B` is VCM with per-sample wavelength tuples and merges within B hero bins
//! (`VcmWavelengths::PerSample`), the measured alternative to one tuple per iteration.
//! `vcm:all` and `vcm:caustic` are VCM with that merge rule (`--vcm-merge`).

use spectral_render::converge::mask::emitter_mask;
use spectral_render::converge::metrics::REL_MSE_OFFSET;
use spectral_render::integrator::bidir::MergeRule;
use spectral_render::integrator::roulette::RrStart;
use spectral_render::integrator::vcm::{VcmParams, VcmWavelengths};
use spectral_render::output::exr;
use spectral_render::sampling::SamplerKind;
use spectral_render::session::{self, RenderOptions};
use spectral_render::{Integrator, MisHeuristic};
use std::path::PathBuf;

struct Args {
    stage: PathBuf,
    time: f64,
    reference_time: f64,
    resolution: Option<(u32, u32)>,
    max_depth: Option<u32>,
    spp: Option<u32>,
    reference_spp: Option<u32>,
    seeds: u64,
    reference: Option<PathBuf>,
    threads: Option<usize>,
    integrators: Vec<(String, Config)>,
    reference_integrator: Integrator,
    regions: Vec<(String, [usize; 4])>,
    exclude: Vec<[usize; 4]>,
    seed: u64,
    keep: Option<PathBuf>,
    metric: Metric,
}

/// The error the figures are of (`--metric`).
#[derive(Clone, Copy, PartialEq)]
enum Metric {
    /// Squared error of luminance, (cd/m²)².
    Mse,
    /// pbrt-v4's relative squared error, (y − r)² / (r² + 0.01), emitters seen directly left
    /// out: the `converge` report's measure.
    RelMse,
}

/// An integrator, the sampler its samples draw from and the path tracer's first bounce of
/// Russian roulette (`--rr-depth`).
type Config = (Integrator, SamplerKind, RrStart);

/// `NAME[@SAMPLER]`: the integrator `NAME` ([`integrator`]) on `SAMPLER` (default zsobol);
/// `path:rrN` is the path tracer with roulette from bounce N (`--rr-depth N`).
fn config(name: &str) -> Result<Config, String> {
    let (n, sampler) = match name.split_once('@') {
        Some((n, s)) => (
            n,
            SamplerKind::from_name(s).ok_or(format!("unknown sampler {s}"))?,
        ),
        None => (name, SamplerKind::default()),
    };
    if let Some(d) = n.strip_prefix("path:rr") {
        let rr: u32 = d.parse().map_err(|e| format!("{n}: {e}"))?;
        if rr == 0 {
            return Err(format!("{n}: the roulette's first bounce is at least 1"));
        }
        return Ok((Integrator::Path, sampler, RrStart::At(rr)));
    }
    Ok((integrator(n)?, sampler, RrStart::Auto))
}

fn integrator(name: &str) -> Result<Integrator, String> {
    if let Some(rule) = name.strip_prefix("vcm:") {
        if let Some(merges) = MergeRule::ALL.into_iter().find(|r| r.name() == rule) {
            return Ok(Integrator::Vcm(VcmParams {
                merges,
                ..VcmParams::default()
            }));
        }
    }
    if let Some(b) = name.strip_prefix("vcm:bins=") {
        let bins = b.parse().map_err(|e| format!("{name}: {e}"))?;
        return Ok(Integrator::Vcm(VcmParams {
            wavelengths: VcmWavelengths::PerSample { bins },
            ..VcmParams::default()
        }));
    }
    Integrator::from_name(name).ok_or(format!("unknown integrator {name}"))
}

/// `--max-depth N`, or `unlimited` (Russian roulette behind the safety cap, the default of
/// `render`).
fn depth(v: &str) -> Result<Option<u32>, String> {
    match v {
        "unlimited" => Ok(None),
        _ => v.parse().map(Some).map_err(|e| format!("--max-depth: {e}")),
    }
}

/// X0,Y0,X1,Y1 as a pixel rectangle.
fn rect(v: &str) -> Result<[usize; 4], String> {
    let n: Vec<usize> = v
        .split(',')
        .map(|x| x.trim().parse().map_err(|e| format!("{v}: {e}")))
        .collect::<Result<_, _>>()?;
    n.try_into().map_err(|_| format!("{v}: want X0,Y0,X1,Y1"))
}

fn parse() -> Result<Args, String> {
    let mut a = Args {
        stage: PathBuf::new(),
        time: 30.0,
        reference_time: 600.0,
        resolution: None,
        max_depth: Some(7),
        spp: None,
        reference_spp: None,
        seeds: 1,
        reference: None,
        threads: None,
        integrators: vec![
            (
                "path".into(),
                (Integrator::Path, SamplerKind::default(), RrStart::Auto),
            ),
            (
                "bdpt".into(),
                (
                    Integrator::Bdpt {
                        mis: MisHeuristic::Power,
                    },
                    SamplerKind::default(),
                    RrStart::Auto,
                ),
            ),
        ],
        reference_integrator: Integrator::Bdpt {
            mis: MisHeuristic::Power,
        },
        regions: Vec::new(),
        exclude: Vec::new(),
        seed: 7,
        keep: None,
        metric: Metric::Mse,
    };
    let mut it = std::env::args().skip(1);
    let mut stage = None;
    while let Some(arg) = it.next() {
        let mut value = || it.next().ok_or(format!("{arg} needs a value"));
        match arg.as_str() {
            "--time" => a.time = value()?.parse().map_err(|e| format!("--time: {e}"))?,
            "--reference-time" => {
                a.reference_time = value()?.parse().map_err(|e| format!("{e}"))?
            }
            "--max-depth" => a.max_depth = depth(&value()?)?,
            "--spp" => a.spp = Some(value()?.parse().map_err(|e| format!("--spp: {e}"))?),
            "--reference-spp" => {
                a.reference_spp = Some(value()?.parse().map_err(|e| format!("{e}"))?)
            }
            "--seeds" => a.seeds = value()?.parse().map_err(|e| format!("--seeds: {e}"))?,
            "--threads" => a.threads = Some(value()?.parse().map_err(|e| format!("{e}"))?),
            "--reference" => a.reference = Some(value()?.into()),
            "--integrators" => {
                a.integrators = value()?
                    .split(',')
                    .map(|n| Ok((n.to_string(), config(n)?)))
                    .collect::<Result<_, String>>()?
            }
            "--region" => {
                let v = value()?;
                let (name, r) = v.split_once('=').ok_or("--region NAME=X0,Y0,X1,Y1")?;
                a.regions.push((name.to_string(), rect(r)?));
            }
            "--exclude" => a.exclude.push(rect(&value()?)?),
            "--seed" => a.seed = value()?.parse().map_err(|e| format!("--seed: {e}"))?,
            "--keep" => a.keep = Some(value()?.into()),
            "--metric" => {
                a.metric = match value()?.as_str() {
                    "mse" => Metric::Mse,
                    "relmse" => Metric::RelMse,
                    m => return Err(format!("--metric {m}: want mse or relmse")),
                }
            }
            "--reference-integrator" => a.reference_integrator = integrator(&value()?)?,
            "--resolution" => {
                let v = value()?;
                let (w, h) = v.split_once('x').ok_or("--resolution WxH")?;
                a.resolution = Some((
                    w.parse().map_err(|e| format!("{e}"))?,
                    h.parse().map_err(|e| format!("{e}"))?,
                ));
            }
            _ if stage.is_none() && !arg.starts_with('-') => stage = Some(arg.into()),
            _ => return Err(format!("unknown argument {arg}")),
        }
    }
    a.stage = stage.ok_or("usage: equal_time STAGE [--time S] [--reference-time S] …")?;
    Ok(a)
}

/// CPU seconds (user + system) this process has used so far, from `/proc/self/stat` (fields
/// 14 and 15, in clock ticks of USER_HZ = 100 on Linux); 0 where it cannot be read.
fn cpu_seconds() -> f64 {
    let Ok(stat) = std::fs::read_to_string("/proc/self/stat") else {
        return 0.0;
    };
    // The command name (field 2) may hold spaces; the fields after it follow its ')'.
    let rest = stat.rsplit_once(')').map_or("", |(_, r)| r);
    let fields: Vec<&str> = rest.split_whitespace().collect();
    let ticks = |i: usize| {
        fields
            .get(i)
            .and_then(|f| f.parse::<f64>().ok())
            .unwrap_or(0.0)
    };
    // After ')': state is field 3, so utime (14) and stime (15) are at 11 and 12.
    (ticks(11) + ticks(12)) / 100.0
}

/// What one render gave: luminance per pixel, wall time, samples per pixel, CPU seconds and,
/// for `auto`, its choice and the share of the run its losing candidates' pilots took.
struct Render {
    y: Vec<f64>,
    wall: f64,
    spp: u64,
    cpu: f64,
    choice: Option<&'static str>,
    /// `auto`'s losing candidates and their pilots' samples per pixel.
    losers: Vec<(&'static str, u64)>,
}

/// One render of `seconds` (or of `spp` samples per pixel when given), written to `keep`
/// when given.
fn render_y(
    scene: &spectral_render::scene::Scene,
    args: &Args,
    (integrator, sampler, rr_depth): Config,
    (seconds, spp): (f64, Option<u32>),
    seed: u64,
    keep: Option<PathBuf>,
) -> Render {
    let cpu0 = cpu_seconds();
    let opts = RenderOptions {
        time_budget: if spp.is_some() { None } else { Some(seconds) },
        spp,
        seed,
        threads: args.threads,
        max_depth: args.max_depth,
        rr_depth,
        integrator,
        sampler,
        ..Default::default()
    };
    let out = session::render(scene, &opts).expect("render");
    let cpu = cpu_seconds() - cpu0;
    assert_eq!(out.dropped_samples, 0, "non-finite samples");
    if let Some(path) = keep {
        let meta = exr::ExrMetadata {
            spp: out.spp,
            integrator: integrator.name().into(),
            seed,
            wall_time_s: out.wall_time_s,
            version: env!("CARGO_PKG_VERSION").into(),
            scene: args.stage.display().to_string(),
            max_depth: args.max_depth,
            ..Default::default()
        };
        let white = spectral_render::spectral::color::white_xy().map(|c| c as f32);
        exr::write(
            &path, out.width, out.height, &out.rgb, &out.xyz, white, &meta,
        )
        .expect("write render");
    }
    let choice = out.auto.as_ref().map(|a| a.choice);
    let losers = out.auto.as_ref().map_or_else(Vec::new, |a| {
        a.pilot
            .iter()
            .filter(|p| Some(p.integrator) != choice)
            .map(|p| (p.integrator.name(), p.samples))
            .collect()
    });
    Render {
        y: out.xyz.iter().map(|p| p[1] as f64).collect(),
        wall: out.wall_time_s,
        spp: out.spp,
        cpu,
        choice: choice.map(|c| c.name()),
        losers,
    }
}

/// The reference luminance and the per-pixel variance of its noise.
fn reference(scene: &spectral_render::scene::Scene, args: &Args) -> (Vec<f64>, Vec<f64>) {
    if let Some(path) = &args.reference {
        if path.exists() {
            let read = |p: &PathBuf, ch: &str| -> Vec<f64> {
                let img = exr::read(p).expect("reference EXR");
                img.channels[ch].iter().map(|&v| v as f64).collect()
            };
            let noise = path.with_extension("noise.exr");
            eprintln!("reference: {}", path.display());
            return (read(path, "XYZ.Y"), read(&noise, "XYZ.X"));
        }
    }
    let half = (
        0.5 * args.reference_time,
        args.reference_spp.map(|n| n.div_ceil(2)),
    );
    let kind = args.reference_integrator;
    let config = (kind, SamplerKind::default(), RrStart::Auto);
    let a = render_y(scene, args, config, half, 1001, None);
    let b = render_y(scene, args, config, half, 1002, None);
    let (sa, sb, ta, tb) = (a.spp, b.spp, a.wall, b.wall);
    let (a, b) = (a.y, b.y);
    eprintln!(
        "reference: {} {} + {} spp in {:.0} + {:.0} s",
        kind.name(),
        sa,
        sb,
        ta,
        tb
    );
    let mean: Vec<f64> = a.iter().zip(&b).map(|(x, y)| 0.5 * (x + y)).collect();
    let noise: Vec<f64> = a
        .iter()
        .zip(&b)
        .map(|(x, y)| 0.25 * (x - y).powi(2))
        .collect();
    if let Some(path) = &args.reference {
        let (w, h) = (scene.camera.width as usize, scene.camera.height as usize);
        let meta = exr::ExrMetadata {
            spp: sa + sb,
            integrator: kind.name().into(),
            seed: 1001,
            wall_time_s: ta + tb,
            version: env!("CARGO_PKG_VERSION").into(),
            scene: args.stage.display().to_string(),
            ..Default::default()
        };
        let white = spectral_render::spectral::color::white_xy().map(|c| c as f32);
        let write = |p: &PathBuf, v: &[f64]| {
            let xyz: Vec<[f32; 3]> = v.iter().map(|&y| [y as f32, y as f32, y as f32]).collect();
            exr::write(p, w, h, &xyz, &xyz, white, &meta).expect("write reference");
        };
        write(path, &mean);
        write(&path.with_extension("noise.exr"), &noise);
    }
    (mean, noise)
}

fn main() {
    let args = match parse() {
        Ok(a) => a,
        Err(e) => {
            eprintln!("error: {e}");
            std::process::exit(2);
        }
    };
    let scene = spectral_render::scene::load(&args.stage, args.resolution).expect("stage");
    let (reference, noise) = reference(&scene, &args);
    let regions = regions(&scene, &args);
    let depth = args.max_depth.map_or("unlimited".into(), |d| d.to_string());
    println!(
        "{} ({}x{}), max depth {depth}",
        args.stage.display(),
        scene.camera.width,
        scene.camera.height
    );
    if args.seeds > 1 {
        many_seeds(&scene, &args, &regions, (&reference, &noise));
    } else {
        single_run(&scene, &args, &regions, (&reference, &noise));
    }
}

/// The pixel masks the figures are given over: the image, the image without `--exclude`,
/// each `--region`.
fn regions(scene: &spectral_render::scene::Scene, args: &Args) -> Vec<(String, Vec<bool>)> {
    let (w, h) = (scene.camera.width as usize, scene.camera.height as usize);
    let inside = |r: &[usize; 4], k: usize| {
        let (x, y) = (k % w, k / w);
        (r[0]..r[2]).contains(&x) && (r[1]..r[3]).contains(&y)
    };
    let kept: Vec<bool> = (0..w * h)
        .map(|k| !args.exclude.iter().any(|r| inside(r, k)))
        .collect();
    let left_out = kept.iter().filter(|k| !**k).count();
    let mut regions = vec![("image".to_string(), vec![true; w * h])];
    if left_out > 0 {
        regions.push((format!("image without {left_out} excluded pixels"), kept));
    }
    for (name, r) in &args.regions {
        let mask = (0..w * h).map(|k| inside(r, k)).collect();
        regions.push((format!("region {name} {r:?}"), mask));
    }
    if args.metric == Metric::RelMse {
        let lamps = emitter_mask(scene);
        let n = lamps.iter().filter(|l| **l).count();
        for (label, mask) in &mut regions {
            mask.iter_mut().zip(&lamps).for_each(|(m, l)| *m &= !l);
            if n > 0 {
                *label += &format!(" (relMSE; {n} pixels seeing an emitter left out)");
            }
        }
    }
    regions
}

/// The mean of `v` over the pixels of `mask`.
fn mean_over(v: &[f64], mask: &[bool]) -> f64 {
    let n = mask.iter().filter(|m| **m).count().max(1) as f64;
    v.iter()
        .zip(mask)
        .filter(|(_, m)| **m)
        .map(|(x, _)| x)
        .sum::<f64>()
        / n
}

/// The error of luminance `y` over `mask` against the reference (`metric`), less the
/// reference's own noise variance on the same scale.
fn region_mse(
    y: &[f64],
    (reference, noise): (&[f64], &[f64]),
    mask: &[bool],
    metric: Metric,
) -> f64 {
    let sq: Vec<f64> = y
        .iter()
        .zip(reference)
        .zip(noise)
        .map(|((a, b), n)| ((a - b).powi(2) - n) * metric.weight(*b))
        .collect();
    mean_over(&sq, mask)
}

impl Metric {
    /// The weight of a pixel's squared error where the reference is `r`.
    fn weight(self, r: f64) -> f64 {
        match self {
            Metric::Mse => 1.0,
            Metric::RelMse => 1.0 / (r * r + REL_MSE_OFFSET),
        }
    }

    /// The root of a mean error over pixels of reference mean `ref_mean`, relative.
    fn relative_root(self, err: f64, ref_mean: f64) -> f64 {
        match self {
            Metric::Mse => err.max(0.0).sqrt() / ref_mean,
            Metric::RelMse => err.max(0.0).sqrt(),
        }
    }

    fn name(self) -> &'static str {
        match self {
            Metric::Mse => "MSE",
            Metric::RelMse => "relMSE",
        }
    }
}

/// One render per integrator at `--seed`: the table, the ratios to the best and to the first.
fn single_run(
    scene: &spectral_render::scene::Scene,
    args: &Args,
    regions: &[(String, Vec<bool>)],
    reference: (&[f64], &[f64]),
) {
    let renders: Vec<(&str, Render)> = args
        .integrators
        .iter()
        .map(|(name, kind)| {
            let keep = args.keep.as_ref().map(|d| d.join(format!("{name}.exr")));
            let budget = (args.time, args.spp);
            let r = render_y(scene, args, *kind, budget, args.seed, keep);
            (name.as_str(), r)
        })
        .collect();
    for (label, mask) in regions {
        if !mask.iter().any(|m| *m) {
            continue;
        }
        let ref_mean = mean_over(reference.0, mask);
        println!(
            "{label}: reference mean Y {ref_mean:.5} cd/m², reference noise RMSE {:.3e}",
            mean_over(reference.1, mask).sqrt()
        );
        println!(
            "{:>10} {:>8} {:>8} {:>7} {:>12} {:>9}",
            "",
            "time s",
            "cpu s",
            "spp",
            format!("√{}", args.metric.name()),
            "relRMSE"
        );
        let mut rows = Vec::new();
        for (name, r) in &renders {
            let mse = region_mse(&r.y, reference, mask, args.metric);
            let rmse = mse.max(0.0).sqrt();
            println!(
                "{name:>10} {:8.1} {:8.1} {:7} {rmse:12.4e} {:9.4}",
                r.wall,
                r.cpu,
                r.spp,
                args.metric.relative_root(mse, ref_mean)
            );
            rows.push((*name, mse, r.wall, r.cpu));
        }
        ratios(&rows);
    }
}

/// The single run's ratios: MSE × time and MSE × CPU time over the best's, and each
/// integrator against the first.
fn ratios(rows: &[(&str, f64, f64, f64)]) {
    let over_best = |cost: &dyn Fn(f64, f64, f64) -> f64| {
        let best = rows
            .iter()
            .map(|&(_, m, t, c)| cost(m, t, c))
            .fold(f64::INFINITY, f64::min);
        let each: Vec<String> = rows
            .iter()
            .map(|&(n, m, t, c)| format!("{n} {:.2}", cost(m, t, c) / best))
            .collect();
        each.join(", ")
    };
    println!(
        "MSE × time over the best's: {}",
        over_best(&|m, t, _| m * t)
    );
    println!(
        "MSE × CPU time over the best's: {}",
        over_best(&|m, _, c| m * c)
    );
    let (first, mse0, t0, cpu0) = rows[0];
    for &(name, mse, t, cpu) in &rows[1..] {
        println!(
            "equal time: MSE({first})/MSE({name}) = {:.2} (RMSE ratio {:.2}); time-normalised (MSE × time) = {:.2}; CPU-normalised (MSE × CPU time) = {:.2}",
            mse0 / mse,
            (mse0 / mse).sqrt(),
            (mse0 * t0) / (mse * t),
            (mse0 * cpu0) / (mse * cpu)
        );
    }
}

/// One integrator's renders over the seeds.
struct Runs<'a> {
    name: &'a str,
    /// MSE per region, per seed (reference noise subtracted).
    mse: Vec<Vec<f64>>,
    cpu: Vec<f64>,
    spp: Vec<u64>,
    choices: Vec<&'static str>,
    losers: Vec<Vec<(&'static str, u64)>>,
}

/// `--seeds N`: every integrator renders at seeds S … S + N − 1 (in turn per seed, so that a
/// change of the machine's load falls on all alike); per region, the mean MSE over the seeds
/// with its standard error, the mean CPU time, and the inverse efficiency mean MSE × mean CPU
/// time over the best fixed integrator's with a 95 % interval from the seeds; for `auto`, its
/// choices and the criterion of issue 11.
fn many_seeds(
    scene: &spectral_render::scene::Scene,
    args: &Args,
    regions: &[(String, Vec<bool>)],
    reference: (&[f64], &[f64]),
) {
    let mut runs: Vec<Runs> = args
        .integrators
        .iter()
        .map(|(name, _)| Runs {
            name,
            mse: vec![Vec::new(); regions.len()],
            cpu: Vec::new(),
            spp: Vec::new(),
            choices: Vec::new(),
            losers: Vec::new(),
        })
        .collect();
    for seed in args.seed..args.seed + args.seeds {
        for ((_, kind), run) in args.integrators.iter().zip(&mut runs) {
            let r = render_y(scene, args, *kind, (args.time, args.spp), seed, None);
            let chose = r.choice.map_or(String::new(), |c| format!(" → {c}"));
            for (i, (_, mask)) in regions.iter().enumerate() {
                run.mse[i].push(region_mse(&r.y, reference, mask, args.metric));
            }
            eprintln!(
                "seed {seed} {}{chose}: {:.2} CPU-s, image MSE {:.4e}",
                run.name,
                r.cpu,
                run.mse[0].last().copied().unwrap_or(f64::NAN)
            );
            run.cpu.push(r.cpu);
            run.spp.push(r.spp);
            run.choices.extend(r.choice);
            run.losers.push(r.losers);
        }
    }
    let budget = args
        .spp
        .map_or(format!("{} s each", args.time), |n| format!("{n} spp"));
    for (i, (label, mask)) in regions.iter().enumerate() {
        let ref_mean = mean_over(reference.0, mask);
        println!(
            "{label}: {} seeds from {}, {budget}; reference mean Y {ref_mean:.5} cd/m², noise RMSE {:.3e}",
            args.seeds,
            args.seed,
            mean_over(reference.1, mask).sqrt()
        );
        seeds_table(&runs, i, ref_mean, args.metric);
        auto_criterion(&runs, i, args.spp.is_some());
    }
}

fn mean(v: &[f64]) -> f64 {
    v.iter().sum::<f64>() / v.len().max(1) as f64
}

/// Standard error of the mean of `v`.
fn std_error(v: &[f64]) -> f64 {
    let m = mean(v);
    let n = v.len() as f64;
    (v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0).max(1.0) / n).sqrt()
}

/// Mean MSE × mean CPU time of `r` in region `i` over the seeds `idx` (all when None).
fn inverse_efficiency(r: &Runs, i: usize, idx: Option<&[usize]>) -> f64 {
    match idx {
        None => mean(&r.mse[i]) * mean(&r.cpu),
        Some(idx) => {
            let pick = |v: &[f64]| mean(&idx.iter().map(|&k| v[k]).collect::<Vec<_>>());
            pick(&r.mse[i]) * pick(&r.cpu)
        }
    }
}

/// The fixed integrator (not `auto`) of lowest mean MSE × mean CPU time in region `i`.
fn best_fixed<'a>(runs: &'a [Runs<'a>], i: usize) -> Option<&'a Runs<'a>> {
    runs.iter()
        .filter(|r| r.name != "auto")
        .min_by(|a, b| inverse_efficiency(a, i, None).total_cmp(&inverse_efficiency(b, i, None)))
}

/// The 95 % interval of `a`'s inverse efficiency over `b`'s from the seeds: a percentile
/// bootstrap (Efron and Tibshirani 1993, §13.3) of 4000 resamplings of the seeds, paired (a
/// resampled seed takes both integrators' renders of it), from a fixed generator seed.
fn ratio_ci(a: &Runs, b: &Runs, i: usize) -> (f64, f64) {
    let n = a.cpu.len();
    let mut state = 0x9E37_79B9_7F4A_7C15_u64;
    let mut next = || {
        // xorshift64* (Vigna 2016)
        state ^= state >> 12;
        state ^= state << 25;
        state ^= state >> 27;
        (state.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as usize % n
    };
    let mut ratios: Vec<f64> = (0..4000)
        .map(|_| {
            let idx: Vec<usize> = (0..n).map(|_| next()).collect();
            inverse_efficiency(a, i, Some(&idx)) / inverse_efficiency(b, i, Some(&idx))
        })
        .collect();
    ratios.sort_by(f64::total_cmp);
    (ratios[100], ratios[3899])
}

/// Per integrator: mean CPU time, samples per pixel, mean MSE ± its standard error, relative
/// RMSE, and mean MSE × mean CPU time over the best fixed integrator's with its interval.
fn seeds_table(runs: &[Runs], i: usize, ref_mean: f64, metric: Metric) {
    let Some(best) = best_fixed(runs, i) else {
        return;
    };
    println!(
        "{:>10} {:>8} {:>7} {:>22} {:>8} {:>9} {:>16}",
        "",
        "cpu s",
        "spp",
        format!("{} (mean ± se)", metric.name()),
        "relRMSE",
        "err×cpu",
        "ci95"
    );
    for r in runs {
        let m = mean(&r.mse[i]);
        let ratio = inverse_efficiency(r, i, None) / inverse_efficiency(best, i, None);
        let (lo, hi) = ratio_ci(r, best, i);
        let spp = r.spp.iter().sum::<u64>() / r.spp.len().max(1) as u64;
        println!(
            "{:>10} {:8.2} {spp:7} {:>22} {:8.4} {ratio:9.3} {:>16}",
            r.name,
            mean(&r.cpu),
            format!("{m:.4e} ± {:.1e}", std_error(&r.mse[i])),
            metric.relative_root(m, ref_mean),
            format!("[{lo:.3}, {hi:.3}]"),
        );
    }
}

/// Issue 11's criterion: `auto`'s mean MSE × mean CPU time at most 1.1 × (1 + its losing
/// pilots' CPU time over the rest of its render's, [`pilot_shares`]) times the best fixed
/// integrator's; with `auto`'s choices, and,
/// under `--spp`, whether its image was its choice's at every seed.
fn auto_criterion(runs: &[Runs], i: usize, fixed_spp: bool) {
    let (Some(auto), Some(best)) = (runs.iter().find(|r| r.name == "auto"), best_fixed(runs, i))
    else {
        return;
    };
    let mut tally: Vec<(&str, usize)> = Vec::new();
    for c in &auto.choices {
        match tally.iter_mut().find(|(n, _)| n == c) {
            Some(t) => t.1 += 1,
            None => tally.push((c, 1)),
        }
    }
    let tally: Vec<String> = tally.iter().map(|(n, k)| format!("{n} {k}")).collect();
    let mut line = format!("auto chose: {}", tally.join(", "));
    if fixed_spp {
        let same = auto.choices.iter().enumerate().all(|(s, c)| {
            runs.iter()
                .find(|r| r.name == *c)
                .is_none_or(|r| r.mse[i][s] == auto.mse[i][s])
        });
        line += &format!("; its image = its choice's at every seed: {same}");
    }
    println!("{line}");
    let ratio = inverse_efficiency(auto, i, None) / inverse_efficiency(best, i, None);
    let (lo, hi) = ratio_ci(auto, best, i);
    let share = mean(&pilot_shares(runs, auto));
    let allowed = 1.1 * (1.0 + share);
    let verdict = if ratio <= allowed { "met" } else { "NOT met" };
    println!(
        "criterion: auto's MSE × CPU time {ratio:.3} × the best fixed ({}) [ci95 {lo:.3}, {hi:.3}] \
         <= 1.1 × (1 + {:.1} % pilot) = {allowed:.3}: {verdict} on the mean",
        best.name,
        100.0 * share
    );
}

/// Per seed, the CPU time `auto`'s losing pilots took as a share of its render's: each loser's
/// pilot samples per pixel times its CPU seconds per sample per pixel in its own renders here
/// (a loser not among the integrators counts at auto's own rate).
fn pilot_shares(runs: &[Runs], auto: &Runs) -> Vec<f64> {
    let rate = |r: &Runs| mean(&r.cpu) / mean(&r.spp.iter().map(|&n| n as f64).collect::<Vec<_>>());
    let auto_rate = rate(auto);
    auto.losers
        .iter()
        .zip(&auto.cpu)
        .map(|(losers, cpu)| {
            let spent: f64 = losers
                .iter()
                .map(|(name, samples)| {
                    let r = runs
                        .iter()
                        .find(|r| r.name == *name)
                        .map_or(auto_rate, rate);
                    *samples as f64 * r
                })
                .sum();
            spent / (cpu - spent).max(f64::MIN_POSITIVE)
        })
        .collect()
}
