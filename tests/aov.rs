//! `--aov variance`: the per-pixel variance of the mean luminance against the spread of
//! repeated renders with other seeds; the first-hit layers (position, normal, depth) on the
//! Cornell box; `--aov albedo`: a Lambertian's reflectance, 0 where the camera ray escapes,
//! and the layer read back with the `OpenEXR` Python module.

mod common;
use common::*;
use spectral_render::integrator::Integrator;
use spectral_render::scene::{self, Scene};
use spectral_render::session::{self, layers::LayerOptions, RenderOptions};
use spectral_render::spectral::color;
use std::path::{Path, PathBuf};
use std::process::Command;

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

fn metamers_path() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/metamers.usda")
}

/// `metamers.usda` with its backdrop shrunk to x ∈ ±0.15 m, y ∈ ±0.08 m: the image's borders
/// (±0.2 m × ±0.1 m at the patches) see the dome, so their camera rays escape.
fn metamers_with_a_small_backdrop() -> String {
    let text = std::fs::read_to_string(metamers_path()).unwrap();
    let small = text
        .replace("0.3000, -0.2000, -0.001", "0.1500, -0.0800, -0.001")
        .replace("0.3000, 0.2000, -0.001", "0.1500, 0.0800, -0.001");
    assert_eq!(
        small.matches("0.1500, ").count(),
        6,
        "the backdrop's points moved"
    );
    small
}

/// The grey patch of `metamers.usda` (flat reflectance 0.45) at 80 × 40: columns 17..35, rows
/// 11..29 (0.005 m per pixel, 0.015 m inside the patch); the metamer's columns 45..63.
const GREY: (usize, usize, usize, usize) = (17, 11, 35, 29);
const METAMER: (usize, usize, usize, usize) = (45, 11, 63, 29);

/// Per RGB channel, the mean and standard error of the mean of `rgb` over a rectangle.
fn rect_stats(
    rgb: &[[f64; 3]],
    w: usize,
    (x0, y0, x1, y1): (usize, usize, usize, usize),
) -> [(f64, f64); 3] {
    let vals: Vec<[f64; 3]> = (y0..y1)
        .flat_map(|y| (x0..x1).map(move |x| rgb[y * w + x]))
        .collect();
    let n = vals.len() as f64;
    std::array::from_fn(|c| {
        let m = vals.iter().map(|v| v[c]).sum::<f64>() / n;
        let var = vals.iter().map(|v| (v[c] - m).powi(2)).sum::<f64>() / (n - 1.0);
        (m, (var / n).sqrt())
    })
}

fn albedo_rgb(scene: &Scene, spp: u32) -> Vec<[f64; 3]> {
    let opts = RenderOptions {
        spp: Some(spp),
        seed: 5,
        max_depth: Some(1),
        integrator: Integrator::Path,
        layers: LayerOptions {
            albedo: true,
            ..Default::default()
        },
        ..Default::default()
    };
    let out = session::render(scene, &opts).unwrap();
    assert!(
        out.layers.first_hit.is_none(),
        "albedo alone writes no P, N, Z"
    );
    let albedo = out.layers.albedo.unwrap();
    albedo
        .iter()
        .map(|p| color::xyz_to_rgb(p.map(f64::from)))
        .collect()
}

#[test]
fn the_albedo_of_a_lambertian_is_its_reflectance_and_an_escaped_ray_gives_zero() {
    let scene = load_text("albedo", &metamers_with_a_small_backdrop(), (80, 40));
    let rgb = albedo_rgb(&scene, 64);
    // ρ_hd of a Lambertian is R exactly; only the sample's wavelengths (its RGB conversion)
    // are noisy, so the patch's mean is R within its standard error.
    let grey = rect_stats(&rgb, 80, GREY);
    println!("grey patch albedo {grey:?}");
    for (m, se) in grey {
        assert!((m - 0.45).abs() < 4.0 * se + 1e-4, "{grey:?}");
        // The test's power: an albedo off by 2 % would fail it.
        assert!(4.0 * se < 0.009, "too noisy: {se}");
    }
    // The metamer matches the grey under D65 (ΔE00 0.03, scenes/README.md), the white the
    // albedo is converted under: the same grey within the metamerism's residual.
    let metamer = rect_stats(&rgb, 80, METAMER);
    println!("metamer albedo {metamer:?}");
    for (m, se) in metamer {
        assert!((m - 0.45).abs() < 4.0 * se + 0.005, "{metamer:?}");
    }
    // The backdrop (reflectance 0.05, columns 10..70 and rows 4..36 now) left of the grey
    // patch, and the corners, which see the dome.
    let backdrop = rect_stats(&rgb, 80, (11, 6, 14, 34));
    for (m, se) in backdrop {
        // A colour3f reflectance, uplifted (Jakob and Hanika 2019): its RGB within 2 %.
        assert!((m - 0.05).abs() < 4.0 * se + 1e-3, "{backdrop:?}");
    }
    for i in [0, 79, 39 * 80, 40 * 80 - 1] {
        assert_eq!(rgb[i], [0.0; 3], "pixel {i}");
    }
}

#[test]
fn the_albedo_layer_reads_back_with_openexr() {
    colour_science_venv();
    let dir = temp_dir("albedo-exr");
    let stage = write(&dir, "m.usda", &metamers_with_a_small_backdrop());
    let exr = dir.join("m.exr");
    let out = spectral_render(
        &[
            stage.to_str().unwrap(),
            "--resolution",
            "80x40",
            "--spp",
            "8",
            "--aov",
            "albedo",
            "-o",
            exr.to_str().unwrap(),
        ],
        &dir,
    );
    assert!(out.status.success(), "{}", stderr(&out));
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let (x0, y0, x1, y1) = GREY;
    let check = Command::new(root.join(".venv/bin/python"))
        .arg(root.join("tools/check_albedo_exr.py"))
        .arg(&exr)
        .arg(format!("{x0},{y0},{x1},{y1}"))
        .arg("0,0")
        .output()
        .unwrap();
    let report = String::from_utf8_lossy(&check.stdout).into_owned();
    println!("{report}{}", String::from_utf8_lossy(&check.stderr));
    assert!(check.status.success(), "{report}");
    let lines: Vec<Vec<&str>> = report.lines().map(|l| l.split(' ').collect()).collect();
    assert_eq!(lines.len(), 3, "{report}");
    for (l, name) in lines.iter().zip(["albedo.R", "albedo.G", "albedo.B"]) {
        assert_eq!(l[..2], [name, "float32"], "{report}");
        let mean: f64 = l[2].parse().unwrap();
        let corner: f64 = l[3].parse().unwrap();
        // 8 spp over 18 × 18 pixels: the mean's standard error is below 0.002.
        assert!((mean - 0.45).abs() < 0.01, "{report}");
        assert_eq!(corner, 0.0, "{report}");
    }
}
