//! `--aov variance`: the per-pixel variance of the mean luminance against the spread of
//! repeated renders with other seeds.

mod common;
use common::*;
use spectral_render::integrator::Integrator;
use spectral_render::scene;
use spectral_render::session::{self, layers::LayerOptions, RenderOptions};

#[test]
fn variance_layer_matches_repeated_renders() {
    // The ColorChecker under its dome: noise without heavy tails, so the test has power.
    let stage = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/colorchecker.usda");
    let scene = scene::load(&stage, Some((48, 32))).unwrap();
    let seeds = 24;
    let (mut estimated, mut means) = (Vec::new(), Vec::new());
    for seed in 0..seeds {
        let opts = RenderOptions {
            spp: Some(4),
            seed,
            max_depth: Some(2),
            integrator: Integrator::Path,
            layers: LayerOptions {
                variance: true,
                ..Default::default()
            },
            ..Default::default()
        };
        let out = session::render(&scene, &opts).unwrap();
        assert_finite(&out);
        estimated.push(out.layers.variance.unwrap());
        means.push(out.xyz.iter().map(|p| f64::from(p[1])).collect::<Vec<_>>());
    }
    // Per pixel: the seeds' sample variance of Y (unbiased) minus the mean of the layer's
    // estimates (unbiased too): zero in expectation. Pixels are independent, so the mean
    // difference over pixels is z-tested against its standard error.
    let pixels = means[0].len();
    let n = seeds as f64;
    let diffs: Vec<f64> = (0..pixels)
        .map(|p| {
            let m = means.iter().map(|v| v[p]).sum::<f64>() / n;
            let spread = means.iter().map(|v| (v[p] - m).powi(2)).sum::<f64>() / (n - 1.0);
            let est = estimated.iter().map(|v| f64::from(v[p])).sum::<f64>() / n;
            spread - est
        })
        .collect();
    let (mean, se) = mean_and_standard_error(&diffs);
    let scale = estimated
        .iter()
        .flatten()
        .map(|&v| f64::from(v))
        .sum::<f64>()
        / (n * pixels as f64);
    println!("mean variance {scale:.4e}, spread − layer {mean:.3e} ± {se:.3e}");
    assert!(scale > 0.0);
    assert!(mean.abs() < 4.0 * se, "{mean} ± {se}");
    // The test's power: a layer off by half its value would fail it.
    assert!(0.5 * scale > 4.0 * se, "too noisy to test: {se}");
}

fn mean_and_standard_error(x: &[f64]) -> (f64, f64) {
    let n = x.len() as f64;
    let m = x.iter().sum::<f64>() / n;
    let v = x.iter().map(|v| (v - m).powi(2)).sum::<f64>() / (n - 1.0);
    (m, (v / n).sqrt())
}

#[test]
fn first_hit_layers_of_the_back_wall() {
    // The Cornell box's back wall is the plane z = −1 facing +z; the camera sits at z = 3.9
    // looking along −z: in OpenEXR's camera space the wall is at depth 4.9 with normal
    // (0, 0, −1), whatever the pixel it covers.
    let scene = scene::load(&cbox_path(), Some((33, 33))).unwrap();
    let opts = RenderOptions {
        spp: Some(4),
        max_depth: Some(1),
        integrator: Integrator::Path,
        layers: LayerOptions {
            first_hit: true,
            ..Default::default()
        },
        ..Default::default()
    };
    let out = session::render(&scene, &opts).unwrap();
    let fh = out.layers.first_hit.unwrap();
    // Pixel (16, 10): above the blocks, below the ceiling, on the back wall.
    let i = 10 * 33 + 16;
    let (p, n) = (fh.position[i], fh.normal[i]);
    assert!((p[2] - 4.9).abs() < 1e-4, "{p:?}");
    assert!(p[0].abs() < 0.1 && p[1] > 0.3, "{p:?}");
    assert!(
        (n[2] + 1.0).abs() < 1e-5 && n[0].abs() < 1e-5 && n[1].abs() < 1e-5,
        "{n:?}"
    );
    // The left wall (x = −1, normal +x) in the left column's middle.
    let j = 16 * 33;
    assert!(
        (fh.position[j][0] + 1.0).abs() < 1e-3,
        "{:?}",
        fh.position[j]
    );
    assert!((fh.normal[j][0] - 1.0).abs() < 1e-5, "{:?}", fh.normal[j]);
}
