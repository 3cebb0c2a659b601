//! Noise of a dome light seen through a window, with and without the PortalLight over it, at
//! equal samples per pixel (the wall time of each render is printed beside it).
//!
//! ```text
//! cargo run --release --example portal_noise -- [STAGE] [--spp N] [--integrator NAME]
//! ```
//!
//! STAGE defaults to `scenes/portal-room.usda`; the variant without portals is the same text
//! with its `PortalLight` prims cut out. Each variant renders twice with different seeds, A
//! and B: (A − B)²/2 estimates a render's noise variance per pixel, and the mean luminance
//! checks that the portal leaves the image unchanged. Printed: mean luminance (cd/m²),
//! relative RMS noise of the luminance, wall time, and the ratio of variance × time.

use spectral_render::scene;
use spectral_render::session::{self, RenderOptions};
use spectral_render::Integrator;
use std::path::{Path, PathBuf};

/// `text` without its `def PortalLight` prims (each a block closed by a line holding only a
/// brace at the indentation of its `def`).
pub fn without_portals(text: &str) -> String {
    let mut out = String::new();
    let mut skip_until: Option<String> = None;
    for line in text.lines() {
        if let Some(end) = &skip_until {
            if line == end {
                skip_until = None;
            }
            continue;
        }
        if line.trim_start().starts_with("def PortalLight") {
            let indent = &line[..line.len() - line.trim_start().len()];
            skip_until = Some(format!("{indent}}}"));
            continue;
        }
        out.push_str(line);
        out.push('\n');
    }
    out
}

struct Run {
    mean: f64,
    rel_noise: f64,
    seconds: f64,
}

fn luminance(out: &session::RenderOutput) -> Vec<f64> {
    out.xyz.iter().map(|p| f64::from(p[1])).collect()
}

fn run(stage: &Path, spp: u32, integrator: Integrator) -> Run {
    let scene = scene::load(stage, None).unwrap_or_else(|e| panic!("{e}"));
    let render = |seed| {
        let opts = RenderOptions {
            spp: Some(spp),
            seed,
            integrator,
            ..RenderOptions::default()
        };
        session::render(&scene, &opts).unwrap_or_else(|e| panic!("{e}"))
    };
    let (a, b) = (render(1), render(2));
    let (ya, yb) = (luminance(&a), luminance(&b));
    let n = ya.len() as f64;
    let mean = ya.iter().chain(&yb).sum::<f64>() / (2.0 * n);
    let var = ya
        .iter()
        .zip(&yb)
        .map(|(x, y)| (x - y).powi(2) / 2.0)
        .sum::<f64>()
        / n;
    Run {
        mean,
        rel_noise: var.sqrt() / mean,
        seconds: 0.5 * (a.wall_time_s + b.wall_time_s),
    }
}

fn main() {
    let mut stage = PathBuf::from("scenes/portal-room.usda");
    let mut spp = 16u32;
    let mut integrator = Integrator::Path;
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        match a.as_str() {
            "--spp" => spp = args.next().and_then(|v| v.parse().ok()).expect("--spp N"),
            "--integrator" => {
                let name = args.next().expect("--integrator NAME");
                integrator = Integrator::from_name(&name).expect("an integrator name");
            }
            _ => stage = PathBuf::from(a),
        }
    }
    let text = std::fs::read_to_string(&stage).unwrap_or_else(|e| panic!("{stage:?}: {e}"));
    let plain = std::env::temp_dir().join(format!("portal-noise-{}.usda", std::process::id()));
    std::fs::write(&plain, without_portals(&text)).unwrap();
    // The variant is written beside nothing it references: the stage must be self-contained.
    let with = run(&stage, spp, integrator);
    let without = run(&plain, spp, integrator);
    let _ = std::fs::remove_file(&plain);
    println!("{spp} spp, --integrator {}", integrator.name());
    for (name, r) in [("portal", &with), ("no portal", &without)] {
        println!(
            "{name:>10}: mean {:.4} cd/m², relative RMS noise {:.4}, {:.2} s",
            r.mean, r.rel_noise, r.seconds
        );
    }
    let eff =
        (without.rel_noise.powi(2) * without.seconds) / (with.rel_noise.powi(2) * with.seconds);
    println!(
        "mean ratio {:.4}; noise variance ratio (no portal / portal) {:.2}; variance × time ratio {:.2}",
        with.mean / without.mean,
        (without.rel_noise / with.rel_noise).powi(2),
        eff
    );
}
