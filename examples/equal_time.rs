//! Equal-time image error of several integrators against a long reference.
//!
//! ```text
//! cargo run --release --example equal_time -- STAGE [--time S] [--reference-time S]
//!     [--resolution WxH] [--max-depth N] [--reference REF.exr] [--threads N]
//!     [--integrators path,bdpt,vcm] [--reference-integrator bdpt|vcm|path]
//! ```
//!
//! 1. Reference: `--reference-integrator` (default BDPT; VCM where only merging samples the
//!    light, a consistent rather than unbiased reference) for `--reference-time` seconds
//!    (default 600) as two independent halves
//!    A and B; the reference is (A + B)/2 and its own noise variance per pixel is estimated as
//!    (A − B)²/4, which is subtracted from every MSE below. With `--reference PATH` the
//!    reference is read from (or, if absent, written to) PATH; its noise estimate travels in
//!    the `XYZ.X` channel of a second file `PATH.noise.exr`.
//! 2. Each of `--integrators` (default path,bdpt) renders for `--time` seconds (default 30;
//!    the render loop sizes its passes to end near the budget).
//! 3. For each: RMSE of luminance (XYZ.Y, cd/m²) against the reference, relative RMSE, the
//!    time actually spent, and the ratio of its MSE and of its MSE × time (the inverse
//!    efficiency, fair even if the times differ a little) to the first integrator's and to
//!    the best one's. The process's CPU time of each render (user + system, from
//!    `/proc/self/stat`) is printed too, with the ratios of MSE × CPU time: on a machine
//!    shared with other work, the wall budget buys an integrator fewer samples when the load
//!    rises, and its CPU time says how much computing it actually got. `auto` runs its pilot
//!    within its time.

use spectral_render::output::exr;
use spectral_render::session::{self, RenderOptions};
use spectral_render::{Integrator, MisHeuristic};
use std::path::PathBuf;

struct Args {
    stage: PathBuf,
    time: f64,
    reference_time: f64,
    resolution: Option<(u32, u32)>,
    max_depth: u32,
    reference: Option<PathBuf>,
    threads: Option<usize>,
    integrators: Vec<Integrator>,
    reference_integrator: Integrator,
}

fn integrator(name: &str) -> Result<Integrator, String> {
    Integrator::from_name(name).ok_or(format!("unknown integrator {name}"))
}

fn parse() -> Result<Args, String> {
    let mut a = Args {
        stage: PathBuf::new(),
        time: 30.0,
        reference_time: 600.0,
        resolution: None,
        max_depth: 7,
        reference: None,
        threads: None,
        integrators: vec![
            Integrator::Path,
            Integrator::Bdpt {
                mis: MisHeuristic::Power,
            },
        ],
        reference_integrator: Integrator::Bdpt {
            mis: MisHeuristic::Power,
        },
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
            "--max-depth" => a.max_depth = value()?.parse().map_err(|e| format!("{e}"))?,
            "--threads" => a.threads = Some(value()?.parse().map_err(|e| format!("{e}"))?),
            "--reference" => a.reference = Some(value()?.into()),
            "--integrators" => {
                a.integrators = value()?
                    .split(',')
                    .map(integrator)
                    .collect::<Result<_, _>>()?
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

/// One render: luminance per pixel, wall time, samples per pixel and CPU seconds.
fn render_y(
    scene: &spectral_render::scene::Scene,
    args: &Args,
    integrator: Integrator,
    seconds: f64,
    seed: u64,
) -> (Vec<f64>, f64, u64, f64) {
    let cpu0 = cpu_seconds();
    let opts = RenderOptions {
        time_budget: Some(seconds),
        seed,
        threads: args.threads,
        max_depth: Some(args.max_depth),
        integrator,
        ..Default::default()
    };
    let out = session::render(scene, &opts).expect("render");
    assert_eq!(out.dropped_samples, 0, "non-finite samples");
    let y = out.xyz.iter().map(|p| p[1] as f64).collect();
    (y, out.wall_time_s, out.spp, cpu_seconds() - cpu0)
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
    let half = 0.5 * args.reference_time;
    let kind = args.reference_integrator;
    let (a, ta, sa, _) = render_y(scene, args, kind, half, 1001);
    let (b, tb, sb, _) = render_y(scene, args, kind, half, 1002);
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
    let n = reference.len() as f64;
    let ref_mean = reference.iter().sum::<f64>() / n;
    let noise_floor = noise.iter().sum::<f64>() / n;
    println!(
        "{} ({}x{}), max depth {}: reference mean Y {:.5} cd/m², reference noise RMSE {:.3e}",
        args.stage.display(),
        scene.camera.width,
        scene.camera.height,
        args.max_depth,
        ref_mean,
        noise_floor.sqrt()
    );
    println!(
        "{:>6} {:>8} {:>8} {:>7} {:>12} {:>9}",
        "", "time s", "cpu s", "spp", "RMSE cd/m²", "relRMSE"
    );
    let mut rows = Vec::new();
    for &kind in &args.integrators {
        let name = kind.name();
        let (y, t, spp, cpu) = render_y(&scene, &args, kind, args.time, 7);
        let mse = y
            .iter()
            .zip(&reference)
            .map(|(a, b)| (a - b).powi(2))
            .sum::<f64>()
            / n
            - noise_floor;
        let rmse = mse.max(0.0).sqrt();
        println!(
            "{name:>6} {t:8.1} {cpu:8.1} {spp:7} {rmse:12.4e} {:9.4}",
            rmse / ref_mean
        );
        rows.push((name, mse, t, cpu));
    }
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
