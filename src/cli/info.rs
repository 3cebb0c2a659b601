//! `spectral-render info STAGE [--json]`: what the stage calls for (`scene::analysis`), the
//! integrator `--integrator auto` picks and why (its candidates and, when there is more than
//! one, the pilot that chooses, `session::auto`), what a depth cap would cut, and the
//! expected cost of a render.
//!
//! `--json` prints one object:
//!
//! ```json
//! {
//!   "features": {
//!     "dispersion": {"on": false, "reason": "...", "prims": []},
//!     "caustics": {"on": true, "reason": "...", "prims": ["/Scene/Ball"]},
//!     ...
//!   },
//!   "integrator": {"choice": "vcm", "reasons": ["..."]},
//!   "max_depth": {"value": 7, "bound_cut": 0.5}
//! }
//! ```
//!
//! `bound_cut` is ρ_max^d / (1 − ρ_max) for the cap d (`SceneFeatures::bound_cut`): `null`
//! when a lossless material (glass) leaves no bound, 0 without a cap (`value` null).

use super::common::{clap_message, print_summary};
use crate::error::{Error, Result};
use crate::integrator::cut::SAFETY_DEPTH;
use crate::integrator::{Integrator, MisHeuristic};
use crate::output::json;
use crate::scene::{self, Scene, SceneFeatures};
use crate::session::{AutoReport, ImageSession, Progressive, RenderOptions, DEFAULT_SPP};
use clap::Parser;
use serde::Serialize;
use std::collections::BTreeMap;
use std::ffi::OsString;
use std::fmt::Write;
use std::path::PathBuf;
use std::time::Instant;

/// Report what a stage calls for: its features, the integrator `auto` picks and why, and the
/// expected cost of a render.
#[derive(Parser, Debug)]
#[command(name = "spectral-render info", bin_name = "spectral-render info")]
struct InfoArgs {
    /// The stage (.usda, .usdc or .usdz).
    scene: PathBuf,
    /// Print one JSON object instead of text.
    #[arg(long)]
    json: bool,
    /// Samples per pixel of the render the pilot and the cost are for (default 64).
    #[arg(long)]
    spp: Option<u32>,
    /// Seed of the pilot (as for rendering).
    #[arg(long, default_value_t = 0)]
    seed: u64,
    /// Worker threads of the pilot (default: all cores).
    #[arg(long)]
    threads: Option<usize>,
    /// Image size WxH, overriding RenderSettings.
    #[arg(long, value_parser = super::render::parse_resolution)]
    resolution: Option<(u32, u32)>,
    /// The depth cap to report on (default: the render's, unlimited).
    #[arg(long = "max-depth")]
    max_depth: Option<u32>,
    /// The path tracer's first bounce of Russian roulette in the pilot (as for rendering:
    /// `auto` or a whole number of at least 1).
    #[arg(
        long = "rr-depth",
        default_value = "auto",
        allow_negative_numbers = true
    )]
    rr_depth: crate::integrator::roulette::RrStart,
    /// The path tracer's split at the first vertex in the pilot (as for rendering: `auto`
    /// or a power of two from 1 to 16).
    #[arg(long = "split", default_value = "auto", allow_negative_numbers = true)]
    split: crate::integrator::split::Split,
}

/// Entry point: `argv[0]` is "info".
pub fn main(argv: Vec<OsString>) -> Result<()> {
    let args = match InfoArgs::try_parse_from(argv) {
        Ok(args) => args,
        Err(e) if !e.use_stderr() => e.exit(),
        Err(e) => return Err(Error::option(clap_message(&e))),
    };
    if args.spp == Some(0) {
        return Err(Error::option("--spp must be at least 1"));
    }
    if args.threads == Some(0) {
        return Err(Error::option("--threads must be at least 1"));
    }
    let scene = scene::load(&args.scene, args.resolution)?;
    print_summary(&scene);
    let depth = args.max_depth;
    let opts = RenderOptions {
        spp: Some(args.spp.unwrap_or(DEFAULT_SPP)),
        seed: args.seed,
        threads: args.threads,
        max_depth: depth,
        rr_depth: args.rr_depth,
        split: args.split,
        integrator: Integrator::Auto {
            mis: MisHeuristic::Power,
        },
        ..Default::default()
    };
    let (auto, cost) = choose(&scene, &opts)?;
    let out = if args.json {
        document(&scene.features, &auto, depth, &cost.roulette)?
    } else {
        text(&scene, &auto, depth, &cost)
    };
    print!("{out}");
    Ok(())
}

/// What a render of `opts` would cost: seconds per sample per pixel and ray queries per
/// sample of the chosen integrator, measured by its pilot (or one pass when it had none).
struct Cost {
    spp: u64,
    seconds_per_spp: f64,
    rays_per_sample: f64,
    /// What the roulette pilot chose for the path tracer (`session::roulette`).
    roulette: Option<String>,
}

/// Runs `auto`'s pilot for `opts` and measures the chosen integrator's cost.
fn choose(scene: &Scene, opts: &RenderOptions) -> Result<(AutoReport, Cost)> {
    let mut session = ImageSession::new(scene, opts)?;
    let auto = session
        .auto()
        .cloned()
        .ok_or_else(|| Error::option("auto made no choice"))?;
    let pixels = u64::from(scene.camera.width) * u64::from(scene.camera.height);
    let (seconds, samples) = match auto.pilot.iter().find(|p| p.integrator == auto.choice) {
        Some(p) => (p.seconds, p.samples),
        None => {
            let start = Instant::now();
            session.step();
            (start.elapsed().as_secs_f64(), session.samples())
        }
    };
    let samples = samples.max(1);
    let cost = Cost {
        spp: u64::from(opts.spp.unwrap_or(DEFAULT_SPP)),
        seconds_per_spp: seconds / samples as f64,
        rays_per_sample: session.ray_queries() as f64 / (samples * pixels.max(1)) as f64,
        roulette: session.roulette().and_then(|r| r.report.clone()),
    };
    Ok((auto, cost))
}

/// The reasons of the choice: the analysis's, each candidate's pilot, the summary line, and
/// where the chosen path tracer's roulette starts when its pilot chose (`--rr-depth auto`).
fn reasons(auto: &AutoReport, roulette: &Option<String>) -> Vec<String> {
    let mut out = auto.reasons.clone();
    for p in &auto.pilot {
        out.push(format!(
            "pilot {}: {} spp, {} ray queries, variance {:.4e}, efficiency {:.4e}",
            p.integrator.name(),
            p.samples,
            p.rays,
            p.variance,
            p.efficiency
        ));
    }
    out.push(auto.summary());
    out.extend(roulette.clone());
    out
}

#[derive(Serialize)]
struct Document<'a> {
    features: BTreeMap<&'static str, FeatureJson<'a>>,
    integrator: IntegratorJson,
    max_depth: MaxDepthJson,
}

#[derive(Serialize)]
struct FeatureJson<'a> {
    on: bool,
    reason: &'a str,
    prims: &'a [String],
}

#[derive(Serialize)]
struct IntegratorJson {
    choice: &'static str,
    reasons: Vec<String>,
}

#[derive(Serialize)]
struct MaxDepthJson {
    value: Option<u32>,
    bound_cut: Option<f64>,
}

/// What a cap of `depth` cuts at most (`None` without a bound); without a cap, what the
/// safety cap ([`SAFETY_DEPTH`]) cuts at most, which a render reports if it is ever reached.
fn bound_cut(f: &SceneFeatures, depth: Option<u32>) -> Option<f64> {
    f.bound_cut(depth.unwrap_or(SAFETY_DEPTH))
}

fn document(
    f: &SceneFeatures,
    auto: &AutoReport,
    depth: Option<u32>,
    roulette: &Option<String>,
) -> Result<String> {
    let features = f
        .all()
        .into_iter()
        .map(|(name, x)| {
            let x = FeatureJson {
                on: x.on,
                reason: &x.reason,
                prims: &x.prims,
            };
            (name, x)
        })
        .collect();
    json::pretty(&Document {
        features,
        integrator: IntegratorJson {
            choice: auto.choice.name(),
            reasons: reasons(auto, roulette),
        },
        max_depth: MaxDepthJson {
            value: depth,
            bound_cut: bound_cut(f, depth),
        },
    })
}

fn text(scene: &Scene, auto: &AutoReport, depth: Option<u32>, cost: &Cost) -> String {
    let f = &scene.features;
    let mut s = String::from("features:\n");
    for (name, x) in f.all() {
        let _ = writeln!(
            s,
            "  {name:<16} {:<3}  {}",
            if x.on { "on" } else { "off" },
            x.reason
        );
    }
    s.push_str("materials:\n");
    for m in &f.materials {
        let _ = writeln!(
            s,
            "  {}: albedo {:.3}, lobes {} ({})",
            m.prim,
            m.albedo,
            m.lobes.names(),
            m.meshes.join(", ")
        );
    }
    s.push_str("lights:\n");
    for l in &f.lights {
        let _ = writeln!(
            s,
            "  {}: {}, {:.3} % of the hemisphere from a scene radius away{}",
            l.prim,
            l.kind,
            100.0 * l.share,
            if l.point_like { " (point-like)" } else { "" }
        );
    }
    let _ = writeln!(s, "integrator: {}", auto.choice.name());
    for r in reasons(auto, &cost.roulette) {
        let _ = writeln!(s, "  {r}");
    }
    let _ = match (depth, bound_cut(f, depth)) {
        (None, Some(b)) => writeln!(
            s,
            "max depth: unlimited (Russian roulette; the safety cap of {SAFETY_DEPTH} cuts at \
             most {b:.3e}, and a render says so if it is reached)"
        ),
        (None, None) => writeln!(
            s,
            "max depth: unlimited (Russian roulette; a lossless material, ρ_max = 1: a render \
             says what the safety cap of {SAFETY_DEPTH} cut if it is reached)"
        ),
        (Some(d), Some(b)) => writeln!(
            s,
            "max depth {d}: cuts at most {:.3e} of the light arriving directly \
             (ρ_max^{d} / (1 − ρ_max), ρ_max = {:.3})",
            b, f.max_albedo
        ),
        (Some(d), None) => writeln!(
            s,
            "max depth {d}: no bound on what it cuts (a lossless material, ρ_max = 1)"
        ),
    };
    let _ = writeln!(
        s,
        "expected cost: ~{:.1} s for {} spp at {}x{} ({:.1} ray queries per sample), plus \
         the pilot",
        cost.seconds_per_spp * cost.spp as f64,
        cost.spp,
        scene.camera.width,
        scene.camera.height,
        cost.rays_per_sample
    );
    s
}
