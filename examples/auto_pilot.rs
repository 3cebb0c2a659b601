//! The figures behind `--integrator auto`'s cost model (`session::auto::cost_per_ray`): each
//! integrator renders a stage at a fixed sample count, and the table gives its wall time, ray
//! queries per sample, nanoseconds per ray query (and their ratio to the path tracer's, which
//! `cost_per_ray` rounds), and its efficiency measured both ways, 1/(variance × time) and
//! 1/(variance × ray queries × cost_per_ray), with what `auto`'s own pilot chooses.
//!
//! ```text
//! cargo run --release --example auto_pilot -- STAGE [--spp N] [--resolution WxH] [--threads N]
//!     [--integrators path,bdpt,vcm]
//! ```

use spectral_render::session::{auto::cost_per_ray, ImageSession, Progressive, RenderOptions};
use spectral_render::{scene, Integrator};
use std::time::Instant;

struct Args {
    stage: String,
    spp: u32,
    resolution: Option<(u32, u32)>,
    threads: Option<usize>,
    integrators: Vec<Integrator>,
}

fn parse() -> Result<Args, String> {
    let mut a = Args {
        stage: String::new(),
        spp: 8,
        resolution: None,
        threads: None,
        integrators: ["path", "bdpt", "vcm"]
            .iter()
            .filter_map(|n| Integrator::from_name(n))
            .collect(),
    };
    let mut it = std::env::args().skip(1);
    while let Some(arg) = it.next() {
        let mut value = || it.next().ok_or(format!("{arg} needs a value"));
        match arg.as_str() {
            "--spp" => a.spp = value()?.parse().map_err(|e| format!("--spp: {e}"))?,
            "--threads" => a.threads = Some(value()?.parse().map_err(|e| format!("{e}"))?),
            "--resolution" => {
                let v = value()?;
                let (w, h) = v.split_once('x').ok_or("--resolution WxH")?;
                let p = |s: &str| s.parse::<u32>().map_err(|e| format!("{e}"));
                a.resolution = Some((p(w)?, p(h)?));
            }
            "--integrators" => {
                a.integrators = value()?
                    .split(',')
                    .map(|n| Integrator::from_name(n).ok_or(format!("unknown integrator {n}")))
                    .collect::<Result<_, _>>()?
            }
            _ if a.stage.is_empty() && !arg.starts_with('-') => a.stage = arg,
            _ => return Err(format!("unknown argument {arg}")),
        }
    }
    if a.stage.is_empty() {
        return Err("usage: auto_pilot STAGE [--spp N] [--resolution WxH] …".into());
    }
    Ok(a)
}

fn main() {
    let args = parse().unwrap_or_else(|e| {
        eprintln!("error: {e}");
        std::process::exit(2)
    });
    let scene = scene::load(args.stage.as_ref(), args.resolution).expect("stage");
    let pixels = f64::from(scene.camera.width * scene.camera.height);
    println!(
        "{} ({}x{}), {} spp",
        args.stage, scene.camera.width, scene.camera.height, args.spp
    );
    println!(
        "{:>6} {:>8} {:>10} {:>8} {:>7} {:>12} {:>12}",
        "", "time s", "rays/smp", "ns/ray", "ratio", "eff (time)", "eff (rays)"
    );
    let mut path_ns = None;
    for &integrator in &args.integrators {
        let opts = RenderOptions {
            spp: Some(args.spp),
            threads: args.threads,
            integrator,
            ..Default::default()
        };
        let mut session = ImageSession::new(&scene, &opts).expect("session");
        let start = Instant::now();
        let mut last = None;
        while let Some(pass) = session.step() {
            last = Some(pass);
        }
        let seconds = start.elapsed().as_secs_f64();
        let variance: f64 = last.expect("a pass").variance.iter().sum();
        let rays = session.ray_queries() as f64;
        let ns = seconds * 1e9 / rays;
        let ratio = ns / *path_ns.get_or_insert(ns);
        println!(
            "{:>6} {seconds:8.2} {:10.2} {ns:8.1} {ratio:7.2} {:12.4e} {:12.4e}",
            integrator.name(),
            rays / (pixels * f64::from(args.spp)),
            1.0 / (variance * seconds),
            1.0 / (variance * rays * cost_per_ray(&integrator)),
        );
    }
    let opts = RenderOptions {
        spp: Some(args.spp),
        threads: args.threads,
        integrator: Integrator::from_name("auto").expect("auto"),
        ..Default::default()
    };
    let session = ImageSession::new(&scene, &opts).expect("auto");
    if let Some(report) = session.auto() {
        println!("{}", report.summary());
    }
}
