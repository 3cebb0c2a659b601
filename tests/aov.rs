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
