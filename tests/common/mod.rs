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
    let out = session::render(&scene, &opts).unwrap();
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
