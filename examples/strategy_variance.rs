//! Which BDPT strategies carry the variance: the path tracer's and BDPT's variance per sample,
//! and BDPT's per (s, t) strategy, from independent renders.
//!
//! ```text
//! cargo run --release --example strategy_variance -- STAGE [--resolution WxH]
//!     [--max-depth N] [--spp N] [--batches K] [--mis power|balance]
//! ```
//!
//! Renders the stage K times (seeds 1000 …) at N samples per pixel with the path tracer and
//! with BDPT recording its strategy images (`--strategies`), then prints, per integrator and per
//! strategy with a non-zero mean, the image's mean luminance and the mean over pixels of each
//! pixel's luminance variance per sample (the variance of a K-sample set of N-spp pixel
//! means, × N), weighted (the strategy's share of the BDPT image) and unweighted (the
//! technique alone). Weighted strategies covary, so their variances need not add up to BDPT's.

use spectral_render::session::{self, RenderOptions};
use spectral_render::{Integrator, MisHeuristic};
use std::collections::BTreeMap;
use std::path::PathBuf;

struct Args {
    stage: PathBuf,
    resolution: Option<(u32, u32)>,
    max_depth: u32,
    spp: u32,
    batches: u64,
    mis: MisHeuristic,
}

fn parse() -> Result<Args, String> {
    let mut a = Args {
        stage: PathBuf::new(),
        resolution: None,
        max_depth: 7,
        spp: 16,
        batches: 16,
        mis: MisHeuristic::Power,
    };
    let mut it = std::env::args().skip(1);
    let mut stage = None;
    while let Some(arg) = it.next() {
        let mut value = || it.next().ok_or(format!("{arg} needs a value"));
        let num = |v: String| v.parse::<u64>().map_err(|e| format!("{arg}: {e}"));
        match arg.as_str() {
            "--max-depth" => a.max_depth = num(value()?)? as u32,
            "--spp" => a.spp = num(value()?)? as u32,
            "--batches" => a.batches = num(value()?)?.max(2),
            "--mis" => {
                a.mis = match value()?.as_str() {
                    "power" => MisHeuristic::Power,
                    "balance" => MisHeuristic::Balance,
                    m => return Err(format!("--mis {m}: power or balance")),
                }
            }
            "--resolution" => {
                let v = value()?;
                let (w, h) = v.split_once('x').ok_or("--resolution WxH")?;
                let p = |s: &str| s.parse().map_err(|e| format!("--resolution: {e}"));
                a.resolution = Some((p(w)?, p(h)?));
            }
            _ if stage.is_none() && !arg.starts_with('-') => stage = Some(arg.into()),
            _ => return Err(format!("unknown argument {arg}")),
        }
    }
    a.stage = stage.ok_or("usage: strategy_variance STAGE [--spp N] [--batches K] …")?;
    Ok(a)
}

/// Per-pixel sums of luminance and its square over the batches.
#[derive(Clone, Default)]
struct Moments {
    sum: Vec<f64>,
    sum2: Vec<f64>,
}

impl Moments {
    fn add(&mut self, xyz: &[[f32; 3]]) {
        self.sum.resize(xyz.len(), 0.0);
        self.sum2.resize(xyz.len(), 0.0);
        for (i, p) in xyz.iter().enumerate() {
            let y = p[1] as f64;
            self.sum[i] += y;
            self.sum2[i] += y * y;
        }
    }

    /// (image mean, mean over pixels of the variance per sample) from `k` batches of `spp`.
    fn summary(&self, k: f64, spp: u32) -> (f64, f64) {
        let n = self.sum.len() as f64;
        let mean = self.sum.iter().sum::<f64>() / (k * n);
        let var = self
            .sum
            .iter()
            .zip(&self.sum2)
            .map(|(s, s2)| (s2 - s * s / k) / (k - 1.0))
            .sum::<f64>()
            / n;
        (mean, var * spp as f64)
    }
}

fn main() {
    let args = parse().unwrap_or_else(|e| {
        eprintln!("error: {e}");
        std::process::exit(2)
    });
    let scene = spectral_render::scene::load(&args.stage, args.resolution).unwrap_or_else(|e| {
        eprintln!("error: {e}");
        std::process::exit(1)
    });
    let k = args.batches as f64;
    println!(
        "{} ({}x{}), max depth {}, {} batches of {} spp, MIS {}",
        args.stage.display(),
        scene.camera.width,
        scene.camera.height,
        args.max_depth,
        args.batches,
        args.spp,
        args.mis.name()
    );
    for integrator in [Integrator::Path, Integrator::Bdpt { mis: args.mis }] {
        let strategies = integrator != Integrator::Path;
        let mut total = Moments::default();
        let mut per: BTreeMap<(u32, u32), (Moments, Moments)> = BTreeMap::new();
        let mut time = 0.0;
        for b in 0..args.batches {
            let opts = RenderOptions {
                spp: Some(args.spp),
                seed: 1000 + b,
                max_depth: Some(args.max_depth),
                integrator,
                strategies,
                ..Default::default()
            };
            let out = session::render(&scene, &opts).expect("render");
            time += out.wall_time_s;
            total.add(&out.xyz);
            for s in out.strategies.iter().flatten() {
                let e = per.entry((s.s, s.t)).or_default();
                e.0.add(&s.weighted);
                e.1.add(&s.unweighted);
            }
        }
        let (mean, var) = total.summary(k, args.spp);
        println!(
            "{}: mean Y {mean:.4e} cd/m², pixel variance per sample {var:.4e}, {time:.1} s",
            integrator.name()
        );
        for ((s, t), (w, u)) in &per {
            let ((mw, vw), (mu, vu)) = (w.summary(k, args.spp), u.summary(k, args.spp));
            if mw > 0.0 {
                println!(
                    "  ({s}, {t}): weighted mean {mw:.3e} variance {vw:.3e} | unweighted mean {mu:.3e} variance {vu:.3e}"
                );
            }
        }
    }
}
