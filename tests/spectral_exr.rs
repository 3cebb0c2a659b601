//! `--spectral`: the bins integrate to the XYZ layer (the binning error), do not depend on
//! the threads, and the EXR follows the layout of Fichet, Pacanowski and Wilkie 2021 as the
//! `OpenEXR` Python module reads it (`tools/check_spectral_exr.py`).

mod common;
use common::*;
use spectral_render::integrator::Integrator;
use spectral_render::scene::{self, Scene};
use spectral_render::sensor::spectral_film::{SpectralBins, SpectralImage};
use spectral_render::session::{self, layers::LayerOptions, RenderOptions, RenderOutput};
use spectral_render::spectral::{data, K_M};
use std::path::Path;

fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

fn render(scene: &Scene, spp: u32, threads: usize, bins: SpectralBins) -> RenderOutput {
    let opts = RenderOptions {
        spp: Some(spp),
        seed: 3,
        threads: Some(threads),
        max_depth: Some(5),
        integrator: Integrator::Path,
        layers: LayerOptions {
            spectral: Some(bins),
            ..Default::default()
        },
        ..Default::default()
    };
    let out = session::render(scene, &opts).unwrap();
    assert_finite(&out);
    out
}

/// K_m ∫ over each bin of x̄, ȳ, z̄ (midpoint rule at 0.01 nm on the 1 nm tables).
fn bin_cmf(bins: &SpectralBins) -> Vec<[f64; 3]> {
    let cmf = data::cie_xyz();
    (0..bins.count)
        .map(|i| {
            let (a, b) = bins.edges(i);
            let n = ((b - a) / 0.01).ceil() as usize;
            let h = (b - a) / n as f64;
            let mut s = [0.0; 3];
            for k in 0..n {
                let l = (a + (k as f64 + 0.5) * h) as f32;
                for c in 0..3 {
                    s[c] += f64::from(cmf[c].eval(l)) * h * f64::from(K_M);
                }
            }
            s
        })
        .collect()
}

/// Per pixel, the bins integrated against the CIE curves.
fn integrate(s: &SpectralImage) -> Vec<[f64; 3]> {
    let w = bin_cmf(&s.bins);
    let pixels = s.images[0].len();
    (0..pixels)
        .map(|p| {
            let mut xyz = [0.0; 3];
            for (b, img) in s.images.iter().enumerate() {
                for c in 0..3 {
                    xyz[c] += f64::from(img[p]) * w[b][c];
                }
            }
            xyz
        })
        .collect()
}

/// The largest relative difference of the image means of X, Y, Z: bins against the layer.
fn binning_error(out: &RenderOutput) -> f64 {
    let spectral = out.layers.spectral.as_ref().expect("spectral layer");
    let from_bins = integrate(spectral);
    let n = out.xyz.len() as f64;
    (0..3)
        .map(|c| {
            let a: f64 = from_bins.iter().map(|p| p[c]).sum::<f64>() / n;
            let b: f64 = out.xyz.iter().map(|p| f64::from(p[c])).sum::<f64>() / n;
            println!("  {}: layer {b:.6e}, bins {a:.6e}", ["X", "Y", "Z"][c]);
            (a / b - 1.0).abs()
        })
        .fold(0.0, f64::max)
}

#[test]
fn bins_integrate_to_the_xyz_layer_within_one_percent() {
    let bins = SpectralBins::default();
    // Enough samples that the noise of the bins' difference from the layer (each sample's
    // x̄(λ) replaced by its bin's mean) stays well below 1 %: ~0.1 % here, ~0.8 % for the
    // box at 16 spp.
    for (name, res, spp) in [
        ("scenes/cornell-box.usda", (48, 48), 96),
        ("scenes/colorchecker.usda", (96, 64), 32),
    ] {
        let scene = scene::load(&root().join(name), Some(res)).unwrap();
        let out = render(&scene, spp, 2, bins);
        let err = binning_error(&out);
        println!("{name}: 32 bins, binning error {:.3} %", 100.0 * err);
        assert!(err < 0.01, "{name}: binning error {err}");
    }
}

#[test]
fn bins_do_not_depend_on_the_threads() {
    let scene = scene::load(&cbox_path(), Some((20, 12))).unwrap();
    let bins = SpectralBins::new(400.0, 700.0, 7).unwrap();
    let one = render(&scene, 5, 1, bins);
    let three = render(&scene, 5, 3, bins);
    let (a, b) = (one.layers.spectral.unwrap(), three.layers.spectral.unwrap());
    assert_eq!(a.images, b.images);
    assert!(a.images.iter().flatten().any(|v| *v > 0.0));
}

#[test]
fn spectral_exr_reads_back_in_the_papers_layout() {
    colour_science_venv();
    let dir = temp_dir("spectral-exr");
    let exr = dir.join("colorchecker.exr");
    let stage = root().join("scenes/colorchecker.usda");
    let out = spectral_render(
        &[
            stage.to_str().unwrap(),
            "--resolution",
            "48x32",
            "--spp",
            "32",
            "--spectral-bins",
            "16",
            "--spectral-range",
            "380,780",
            "-o",
            exr.to_str().unwrap(),
        ],
        &dir,
    );
    assert!(out.status.success(), "{}", stderr(&out));
    let (ok, report) = colour_science_check("check_spectral_exr.py", &exr);
    println!("{report}");
    assert!(ok, "{report}");
    assert!(report.contains("16 spectral channels"), "{report}");
}

#[test]
fn spectral_is_refused_where_its_bins_would_be_wrong_or_lost() {
    let dir = temp_dir("spectral-refused");
    let exr = dir.join("x.exr");
    let cbox = cbox_path();
    let base = [
        cbox.to_str().unwrap(),
        "--spp",
        "1",
        "-o",
        exr.to_str().unwrap(),
    ];
    for extra in [
        &["--spectral", "--integrator", "bdpt"][..],
        &["--spectral", "--part", "1/2"],
        &["--spectral", "--checkpoint", "x.ckpt"],
        &["--spectral-bins", "1000"],
        &["--spectral-range", "300,700"],
        &["--spectral-range", "700,400"],
    ] {
        let args: Vec<&str> = base.iter().chain(extra).copied().collect();
        let out = spectral_render(&args, &dir);
        assert_eq!(out.status.code(), Some(1), "{extra:?}: {}", stderr(&out));
        let err = stderr(&out);
        // One error line (a note may precede it).
        let errors = err.lines().filter(|l| l.starts_with("error: ")).count();
        assert!(
            errors == 1
                && err
                    .trim_end()
                    .lines()
                    .last()
                    .unwrap()
                    .starts_with("error: "),
            "{err}"
        );
        assert!(!exr.exists());
    }
}
