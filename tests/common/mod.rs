//! Shared helpers for the integration tests: small USD stages written to a temporary
//! directory, rendered through the library, and simple statistics on the result.
#![allow(dead_code)]

pub mod cli;
pub mod stages;
#[allow(unused_imports)]
pub use cli::*;
#[allow(unused_imports)]
pub use stages::*;

use spectral_render::scene;
use spectral_render::session::{self, RenderOptions, RenderOutput};
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};

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

/// Loads and renders a stage with the path tracer.
pub fn render_file(
    path: &Path,
    resolution: (u32, u32),
    spp: u32,
    max_depth: u32,
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

/// Mean and standard error of the mean of a channel over a set of pixels.
pub fn mean_and_sem(values: impl Iterator<Item = f32>) -> (f64, f64) {
    let v: Vec<f64> = values.map(f64::from).collect();
    let n = v.len() as f64;
    let mean = v.iter().sum::<f64>() / n;
    let var = v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0).max(1.0);
    (mean, (var / n).sqrt())
}

/// A USD stage header in metres, Y up.
pub fn header() -> String {
    "#usda 1.0\n(\n    metersPerUnit = 1\n    upAxis = \"Y\"\n)\n\n".to_string()
}

/// A camera at `z` on +Z looking down −Z with a square 2·half_tan field at distance 1.
pub fn camera(z: f32, half_tan: f32, exposure: f32) -> String {
    let focal = 10.0 / half_tan;
    format!(
        "def Camera \"Cam\"\n{{\n    float focalLength = {focal}\n    float horizontalAperture = 20\n    float verticalAperture = 20\n    float2 clippingRange = (0.001, 1000)\n    float exposure = {exposure}\n    double3 xformOp:translate = (0, 0, {z})\n    uniform token[] xformOpOrder = [\"xformOp:translate\"]\n}}\n\n"
    )
}

/// An axis-aligned quad mesh in the z = `z` plane facing +Z, half-size `h`.
pub fn quad(name: &str, z: f32, h: f32, extra: &str, api: &str) -> String {
    format!(
        "def Mesh \"{name}\" (\n    prepend apiSchemas = [{api}]\n)\n{{\n    int[] faceVertexCounts = [4]\n    int[] faceVertexIndices = [0, 1, 2, 3]\n    point3f[] points = [(-{h}, -{h}, {z}), ({h}, -{h}, {z}), ({h}, {h}, {z}), (-{h}, {h}, {z})]\n{extra}}}\n\n"
    )
}

/// A material with one shader; `inputs` are the shader's input lines.
pub fn material(name: &str, id: &str, inputs: &str) -> String {
    format!(
        "def Material \"{name}\"\n{{\n    token outputs:surface.connect = </Looks/{name}/S.outputs:surface>\n    def Shader \"S\"\n    {{\n        uniform token info:id = \"{id}\"\n{inputs}        token outputs:surface\n    }}\n}}\n"
    )
}

pub fn binding(name: &str) -> String {
    format!("    rel material:binding = </Looks/{name}>\n")
}
