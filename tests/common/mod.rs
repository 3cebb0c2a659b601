//! Shared helpers for the integration tests: small USD stages written to a temporary
//! directory ([`stages`]), rendered through the library, the command line ([`process`]), and
//! simple statistics on the result ([`stats`]).
#![allow(dead_code)]

pub mod colorchecker;
pub mod meters;
pub mod process;
pub mod stages;
pub mod stats;

// Each test binary uses only part of these.
#[allow(unused_imports)]
pub use process::*;
#[allow(unused_imports)]
pub use stages::*;
#[allow(unused_imports)]
pub use stats::*;

use spectral_render::scene::{self, Scene};
use spectral_render::session::{self, RenderOptions, RenderOutput};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

/// The Cornell box committed with the tests (the scene the peer renderers are compared on).
pub fn cbox_path() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/usd/cbox.usda")
}

/// A fresh, empty directory under the system temp dir.
pub fn temp_dir(name: &str) -> PathBuf {
    static COUNTER: AtomicUsize = AtomicUsize::new(0);
    let n = COUNTER.fetch_add(1, Ordering::SeqCst);
    let dir = std::env::temp_dir().join(format!(
        "spectral-render-test-{}-{}-{}",
        std::process::id(),
        name,
        n
    ));
    let _ = std::fs::remove_dir_all(&dir);
    std::fs::create_dir_all(&dir).unwrap();
    dir
}

pub fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

/// Writes `text` as `<name>.usda` in a fresh directory and loads it at `res`.
pub fn load_text(name: &str, text: &str, res: (u32, u32)) -> Scene {
    let dir = temp_dir(name);
    let path = write(&dir, &format!("{name}.usda"), text);
    scene::load(&path, Some(res)).unwrap_or_else(|e| panic!("{e}"))
}

/// Loads and renders a stage with the path tracer.
pub fn render_file(
    path: &Path,
    resolution: (u32, u32),
    spp: u32,
    max_depth: Option<u32>,
    threads: Option<usize>,
) -> RenderOutput {
    let scene = scene::load(path, Some(resolution)).unwrap_or_else(|e| panic!("{e}"));
    let opts = RenderOptions {
        spp: Some(spp),
        seed: 7,
        threads,
        max_depth,
        ..Default::default()
    };
    render_checked(&scene, &opts)
}

/// Renders `scene` and checks the image ([`assert_finite`]); a render error fails the test
/// with its message.
pub fn render_checked(scene: &Scene, opts: &RenderOptions) -> RenderOutput {
    let out = session::render(scene, opts).unwrap_or_else(|e| panic!("{e}"));
    assert_finite(&out);
    out
}

/// Every test image must be free of NaN and Inf, with no sample dropped.
pub fn assert_finite(out: &RenderOutput) {
    assert_eq!(out.dropped_samples, 0, "non-finite samples were dropped");
    assert!(
        out.xyz
            .iter()
            .chain(&out.rgb)
            .flatten()
            .all(|v| v.is_finite()),
        "NaN or Inf in the image"
    );
}

/// (mean of Y over `pixels`, the variance of that mean from the per-pixel variance estimates
/// of the film's even and odd samples: `--aov variance`, which the render must have asked for).
pub fn mean_y(out: &RenderOutput, pixels: &[usize]) -> (f64, f64) {
    let v = out.layers.variance.as_ref().unwrap();
    let n = pixels.len() as f64;
    let mean = pixels
        .iter()
        .map(|&i| f64::from(out.xyz[i][1]))
        .sum::<f64>()
        / n;
    let var = pixels.iter().map(|&i| f64::from(v[i])).sum::<f64>() / (n * n);
    (mean, var)
}

/// z of the difference of `a`'s and `b`'s mean luminance over each quarter of the image and
/// over the whole, `a`'s scaled by `scale`.
pub fn z_scores(a: &RenderOutput, b: &RenderOutput, scale: f64) -> Vec<f64> {
    let (w, h) = (a.width, a.height);
    let quarter = |q: usize| -> Vec<usize> {
        (0..w * h)
            .filter(|i| usize::from(i % w >= w / 2) + 2 * usize::from(i / w >= h / 2) == q)
            .collect()
    };
    let regions = (0..4).map(quarter).chain([(0..w * h).collect()]);
    regions
        .map(|px| {
            let ((ma, va), (mb, vb)) = (mean_y(a, &px), mean_y(b, &px));
            (scale * ma - mb) / (scale * scale * va + vb).sqrt()
        })
        .collect()
}
