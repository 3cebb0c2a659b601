//! `converge` (issue 12): the metrics against hand-computed and known-variance cases, the
//! −1/2 slope of the path tracer on an analytic scene, 1 against 4 wavelengths on the
//! ColorChecker under a spiky LED, meters' time to 1 % and ci95 coverage in an integrating
//! sphere, and the command's report: its files, its determinism (all but the times) and its
//! errors. Nothing here needs a peer renderer or any file outside the repository.

mod common;
use common::colorchecker::{patch_xyz, PATCHES};
use common::meters::integrating_sphere;
use common::*;
use spectral_render::converge::meters::{run_meters, ReferenceValue};
use spectral_render::converge::metrics::{image_errors, Reference, ReferenceVariance};
use spectral_render::converge::{fit, mask, run_image, Config, Row, RunOptions};
use spectral_render::output::exr;
use spectral_render::session::{ImageSession, RenderOptions};
use spectral_render::spectral::difference::{delta_e2000, xyz_to_lab};
use spectral_render::spectral::{data, xyz, DenseSpectrum};
use spectral_render::testing::rng::Rng;
use spectral_render::SamplerKind;
use spectral_render::{Integrator, MisHeuristic};
use std::path::Path;

/// A standard normal deviate (Box–Muller).
fn normal(rng: &mut Rng) -> f64 {
    let u1 = (f64::from(rng.f32()) + 1e-9).min(1.0);
    let u2 = f64::from(rng.f32());
    (-2.0 * u1.ln()).sqrt() * (2.0 * std::f64::consts::PI * u2).cos()
}

/// A synthetic truth t (grey, 5 to 15), an image x = t(1 + bias) + N(0, σx²) and a reference
/// r = t + N(0, σr²) per channel, with the reference's variance known exactly.
struct Synthetic {
    x: Vec<[f32; 3]>,
    x_y: Vec<f32>,
    reference: Reference,
    truth: Vec<f64>,
}

fn synthetic(n: usize, sx: f64, sr: f64, bias: f64, seed: u64) -> Synthetic {
    let mut rng = Rng::new(seed);
    let truth: Vec<f64> = (0..n).map(|_| 5.0 + 10.0 * f64::from(rng.f32())).collect();
    let mut draw = |t: f64, s: f64, b: f64| {
        let mut p = [0.0f32; 3];
        for c in &mut p {
            *c = (t * (1.0 + b) + s * normal(&mut rng)) as f32;
        }
        p
    };
    let x: Vec<[f32; 3]> = truth.iter().map(|&t| draw(t, sx, bias)).collect();
    let r: Vec<[f32; 3]> = truth.iter().map(|&t| draw(t, sr, 0.0)).collect();
    Synthetic {
        x_y: x.iter().map(|p| p[1]).collect(),
        x,
        reference: Reference {
            width: n,
            height: 1,
            y: r.iter().map(|p| p[1]).collect(),
            rgb: r,
            variance: Some(ReferenceVariance {
                rgb: vec![[(sr * sr) as f32; 3]; n],
                y: vec![(sr * sr) as f32; n],
            }),
        },
        truth,
    }
}

#[test]
fn noise_correction_recovers_the_true_error_within_its_standard_error() {
    let (n, sx, sr) = (100_000, 0.2, 0.2);
    let s = synthetic(n, sx, sr, 0.0, 11);
    let masked = vec![false; n];
    let own = vec![sx * sx; n];
    let e = image_errors(&s.x, &s.x_y, Some(&own), &s.reference, &masked);
    // The true relMSE against the truth: E[(x − t)²]/(t² + 0.01) = σx²/(t² + 0.01).
    let truth: f64 = s
        .truth
        .iter()
        .map(|t| sx * sx / (t * t + 0.01))
        .sum::<f64>()
        / n as f64;
    // Standard error of the corrected estimate from its per-value terms.
    let terms: Vec<f64> = (0..n)
        .flat_map(|i| {
            let r = s.reference.rgb[i];
            let x = s.x[i];
            (0..3).map(move |c| {
                let (x, r) = (f64::from(x[c]), f64::from(r[c]));
                ((x - r).powi(2) - sr * sr) / (r * r + 0.01)
            })
        })
        .collect();
    let (_, se) = mean_and_sem(terms.iter().copied());
    let corrected = e.rel_mse_corrected.unwrap();
    eprintln!(
        "true {truth:.6e}, corrected {corrected:.6e} ± {se:.1e}, uncorrected {:.6e}",
        e.rel_mse
    );
    assert!(
        (corrected - truth).abs() < 3.0 * se,
        "{corrected} vs {truth} ± {se}"
    );
    // Uncorrected, the reference's noise doubles the error: far outside the interval.
    assert!(e.rel_mse - truth > 50.0 * se);
    // No bias here: the estimate is within noise of 0.
    let bound = e.bias_masked_bound.unwrap();
    assert!(e.bias_masked.unwrap() <= bound && bound < 0.005, "{e:?}");
    // A 5 % bias is found.
    let b = synthetic(n, sx, sr, 0.05, 12);
    let eb = image_errors(&b.x, &b.x_y, Some(&own), &b.reference, &masked);
    let bias = eb.bias_masked.unwrap();
    assert!((bias - 0.05).abs() < 0.002, "{bias}");
}

#[test]
fn relmse_of_a_synthetic_pair_by_hand() {
    // Four pixels, reference (1, 2, 4) everywhere, errors 10 %, 0, −50 %, +0.1 absolute.
    let r = [1.0f32, 2.0, 4.0];
    let x = vec![
        r.map(|v| 1.1 * v),
        r,
        r.map(|v| 0.5 * v),
        r.map(|v| v + 0.1),
    ];
    let reference = Reference {
        width: 4,
        height: 1,
        rgb: vec![r; 4],
        y: vec![2.0; 4],
        variance: None,
    };
    let y: Vec<f32> = x.iter().map(|p| p[1]).collect();
    let e = image_errors(&x, &y, None, &reference, &[false, false, false, true]);
    let term = |d: f64, r: f64| d * d / (r * r + 0.01);
    let by_hand: f64 = [1.0f64, 2.0, 4.0]
        .iter()
        .map(|&v| term(0.1 * v, v) + term(0.5 * v, v) + term(0.1, v))
        .sum::<f64>()
        / 12.0;
    assert!(
        (e.rel_mse - by_hand).abs() < 1e-6,
        "{} vs {by_hand}",
        e.rel_mse
    );
    assert!((e.rel_rmse - by_hand.sqrt()).abs() < 1e-6);
    let masked: f64 = [1.0f64, 2.0, 4.0]
        .iter()
        .map(|&v| term(0.1 * v, v) + term(0.5 * v, v))
        .sum::<f64>()
        / 9.0;
    assert!((e.rel_rmse_masked.unwrap() - masked.sqrt()).abs() < 1e-6);
    assert_eq!(e.rel_mse_corrected, None);
}

/// A grey plane (ρ = 0.5) under a uniform D65 dome of 10 nits seen head-on: every pixel is
/// exactly ρ·L = 5 cd/m² of D65 white, RGB (5, 5, 5).
fn dome_plane(res: u32) -> spectral_render::scene::Scene {
    let looks = looks_scope(&flat_diffuse("Paint", 0.5));
    load_text(
        "dome-plane",
        &dome_plane_stage(10.0, &looks, ""),
        (res, res),
    )
}

fn exact_reference(w: usize, h: usize, v: f32) -> Reference {
    Reference {
        width: w,
        height: h,
        rgb: vec![[v; 3]; w * h],
        y: vec![v; w * h],
        variance: Some(ReferenceVariance {
            rgb: vec![[0.0; 3]; w * h],
            y: vec![0.0; w * h],
        }),
    }
}

fn no_keep(
) -> impl FnMut(&Config, &spectral_render::session::RenderOutput) -> spectral_render::Result<()> {
    |_, _| Ok(())
}

#[test]
fn path_tracer_relrmse_falls_with_slope_minus_one_half() {
    let scene = dome_plane(32);
    let masked = mask::emitter_mask(&scene);
    assert!(masked.iter().all(|m| !m), "the plane fills the image");
    // Monte Carlo's rate needs independent samples; the low-discrepancy sequence's is
    // steeper (below).
    let opts = RunOptions {
        time_s: 1e9,
        max_samples: Some(1024),
        seed: 3,
        sampler: SamplerKind::Independent,
        ..RunOptions::default()
    };
    let config = Config::new(Integrator::Path, 4, false);
    let rows = run_image(
        &scene,
        &config,
        &opts,
        &exact_reference(32, 32, 5.0),
        &masked,
        &mut no_keep(),
    )
    .unwrap();
    assert_eq!(rows.last().unwrap().samples, 1000);
    assert_eq!(rows.last().unwrap().dropped, Some(0));
    let pts: Vec<(f64, f64)> = rows
        .iter()
        .filter(|r| r.samples >= 4)
        .map(|r| (r.samples as f64, r.error.unwrap()))
        .collect();
    let f = fit::log_log_fit(&pts).unwrap();
    eprintln!(
        "slope against spp {:.4} ± {:.4} over {} snapshots",
        f.slope, f.stderr, f.points
    );
    assert!((f.slope + 0.5).abs() < 0.05, "{f:?}");
    // The unbiased path tracer leaves no bias beyond noise.
    let last = rows.last().unwrap();
    assert!(last.bias_masked.unwrap() <= last.bias_masked_bound.unwrap());
    assert!(
        last.bias_masked_bound.unwrap() < 0.5 * last.error.unwrap(),
        "{last:?}"
    );
    // The default sampler on the same smooth integrand: the error falls faster than 1/√spp.
    let sobol = RunOptions {
        sampler: SamplerKind::ZSobol,
        ..opts
    };
    let rows = run_image(
        &scene,
        &config,
        &sobol,
        &exact_reference(32, 32, 5.0),
        &masked,
        &mut no_keep(),
    )
    .unwrap();
    let pts: Vec<(f64, f64)> = rows
        .iter()
        .filter(|r| r.samples >= 4)
        .map(|r| (r.samples as f64, r.error.unwrap()))
        .collect();
    let g = fit::log_log_fit(&pts).unwrap();
    eprintln!(
        "zsobol: slope against spp {:.4} ± {:.4} over {} snapshots",
        g.slope, g.stderr, g.points
    );
    assert!(g.slope < f.slope - 0.1, "{g:?} against {f:?}");
}

#[test]
fn rows_are_reproducible_except_for_their_times() {
    let scene = dome_plane(16);
    let masked = mask::emitter_mask(&scene);
    let reference = exact_reference(16, 16, 5.0);
    let opts = RunOptions {
        time_s: 1e9,
        max_samples: Some(40),
        seed: 5,
        threads: Some(2),
        ..RunOptions::default()
    };
    let bdpt = Integrator::Bdpt {
        mis: MisHeuristic::Power,
    };
    for integrator in [Integrator::Path, bdpt] {
        let config = Config::new(integrator, 4, false);
        let run = |threads| {
            let o = RunOptions {
                threads,
                ..opts.clone()
            };
            run_image(&scene, &config, &o, &reference, &masked, &mut no_keep())
                .unwrap()
                .into_iter()
                .map(|r| Row {
                    time_s: 0.0,
                    elapsed_s: None,
                    ..r
                })
                .collect::<Vec<_>>()
        };
        let a = run(Some(2));
        assert_eq!(a.len(), 16, "1..=38 at 12 per decade");
        assert_eq!(a, run(Some(1)), "{}", integrator.name());
    }
}

/// The ColorChecker of scenes/colorchecker.usda under a uniform dome of LED-B3 (a blue pump
/// and a phosphor: spiky) at 100 cd/m²; 48 × 32 pixels, a patch spans 6.
const CC_W: usize = 48;
const CC_H: usize = 32;

#[test]
fn four_wavelengths_reach_delta_e_1_sooner_than_one_under_a_spiky_led() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(root.join("scenes/colorchecker.usda")).unwrap();
    let dome = "float inputs:intensity = 100";
    assert!(text.contains(dome));
    let text = text.replace(
        dome,
        &format!("{dome}\n        token spectral:emission = \"LED-B3\""),
    );
    let scene = load_text("colorchecker-led-b3", &text, (CC_W as u32, CC_H as u32));
    // Exact: radiance ρ(λ) · L(λ), L the LED-B3 shape at 100 cd/m².
    let led = data::illuminant("LED-B3").unwrap();
    let l = led.scaled((100.0 / xyz::luminance(led)) as f32);
    let white = xyz::dense_to_xyz(&l);
    let exact: Vec<[f64; 3]> = PATCHES
        .iter()
        .map(|name| {
            let rho = data::named(&format!("colorchecker/{name}")).unwrap();
            xyz::dense_to_xyz(&DenseSpectrum::from_fn(|w| rho.eval(w) * l.eval(w)))
        })
        .collect();
    let max_delta_e = |img: &[[f32; 3]]| {
        (0..24)
            .map(|i| {
                let lab = |p: [f64; 3]| xyz_to_lab(p, white);
                delta_e2000(lab(patch_xyz(img, CC_W, CC_H, i, 2)), lab(exact[i]))
            })
            .fold(0.0, f64::max)
    };
    // Samples per pixel from which on the worst patch stays below ΔE00 = 1 (checked at twice
    // that; None: not by 4096), over doubling counts.
    let spp_to_delta_e_1 = |wavelengths: usize| {
        let opts = RenderOptions {
            seed: 1,
            wavelengths,
            ..RenderOptions::default()
        };
        let mut session = ImageSession::new(&scene, &opts).unwrap();
        let (mut since, mut n) = (None, 1);
        while n <= 4096 {
            session.step_to(n);
            let de = max_delta_e(&session.output().xyz);
            eprintln!("{wavelengths} wavelengths, {n} spp: max ΔE00 {de:.3}");
            if de < 1.0 {
                since.get_or_insert(n);
                if n >= 2 * since.unwrap() {
                    break;
                }
            } else {
                since = None;
            }
            n *= 2;
        }
        since
    };
    let four = spp_to_delta_e_1(4).expect("4 wavelengths reach ΔE00 < 1");
    let one = spp_to_delta_e_1(1);
    eprintln!("ΔE00 < 1 from {four} spp with 4 wavelengths, {one:?} with 1");
    // Same cost per sample (the lanes are computed either way): fewer samples is sooner.
    assert!(one.is_none_or(|one| four < one), "{four} vs {one:?}");
}

#[test]
fn meters_reach_one_percent_and_their_ci95_covers_at_95_percent() {
    let case = integrating_sphere(0.7);
    let meters = [case.meters[2]];
    let reference = [ReferenceValue {
        value: case.exact[2],
        ci95: 0.0,
    }];
    let integrators = [
        Integrator::Path,
        Integrator::Light,
        Integrator::Bdpt {
            mis: MisHeuristic::Power,
        },
    ];
    for integrator in integrators {
        let config = Config::new(integrator, 4, false);
        // Time to 1 %: one long run.
        let opts = RunOptions {
            time_s: 1e9,
            max_samples: Some(1 << 17),
            seed: 1,
            max_depth: None,
            ..RunOptions::default()
        };
        let rows = run_meters(&case.scene, &meters, &config, &opts, &reference).unwrap();
        let s = &fit::summarize(&rows)[0];
        eprintln!(
            "{}: {} samples, error {:.3} %, time to 1 % {:?} s",
            integrator.name(),
            s.samples,
            100.0 * s.error,
            s.time_to[3]
        );
        assert!(
            s.time_to[3].is_some(),
            "{} does not reach 1 %",
            integrator.name()
        );
        // Coverage: the last snapshot (2048 samples) of independent seeds.
        let seeds = 100;
        let covered = (0..seeds)
            .filter(|&seed| {
                let o = RunOptions {
                    max_samples: Some(2048),
                    seed: 1000 + seed,
                    ..opts.clone()
                };
                let rows = run_meters(&case.scene, &meters, &config, &o, &reference).unwrap();
                rows.last().unwrap().covered.unwrap()
            })
            .count();
        // 95 % within 3 binomial standard deviations (σ = √(0.95 · 0.05 / 100) = 2.2 %).
        let rate = covered as f64 / seeds as f64;
        let sigma = (0.95 * 0.05 / seeds as f64).sqrt();
        eprintln!("{}: ci95 covers in {covered} of {seeds}", integrator.name());
        assert!(
            (rate - 0.95).abs() <= 3.0 * sigma,
            "{}: {rate}",
            integrator.name()
        );
    }
}

// ---------------------------------------------------------------------------------------
// The command
// ---------------------------------------------------------------------------------------

/// report.csv with the time columns emptied.
fn csv_without_times(dir: &Path) -> String {
    let text = std::fs::read_to_string(dir.join("report.csv")).unwrap();
    let mut lines = text.lines();
    let header: Vec<&str> = lines.next().unwrap().split(',').collect();
    let timed: Vec<usize> = ["time_s", "elapsed_s"]
        .iter()
        .map(|c| header.iter().position(|h| h == c).unwrap())
        .collect();
    lines
        .map(|l| {
            l.split(',')
                .enumerate()
                .map(|(i, v)| if timed.contains(&i) { "" } else { v })
                .collect::<Vec<_>>()
                .join(",")
        })
        .collect::<Vec<_>>()
        .join("\n")
}

#[test]
fn the_command_writes_a_reproducible_report() {
    let dir = temp_dir("converge-cli");
    let cbox = cbox_path();
    let cbox = cbox.to_str().unwrap();
    let first = dir.join("first");
    let args = |out: &Path, extra: &[&str]| {
        let mut a = vec![
            "converge",
            cbox,
            "-o",
            out.to_str().unwrap(),
            "--resolution",
            "24x24",
            "--integrators",
            "path,light",
            "--time",
            "100",
            "--max-spp",
            "12",
        ];
        a.extend_from_slice(extra);
        a.iter().map(|s| s.to_string()).collect::<Vec<_>>()
    };
    let run = |a: Vec<String>| {
        let refs: Vec<&str> = a.iter().map(String::as_str).collect();
        let o = spectral_render(&refs, &dir);
        assert!(o.status.success(), "{}", stderr(&o));
        o
    };
    // A rendered reference (written with its noise), then two runs against it.
    let o = run(args(
        &first,
        &["--reference-time", "1", "--wavelengths", "1,4"],
    ));
    for f in [
        "report.json",
        "report.csv",
        "report.md",
        "convergence.png",
        "reference.exr",
    ] {
        assert!(first.join(f).is_file(), "{f} missing");
    }
    let png = std::fs::read(first.join("convergence.png")).unwrap();
    assert_eq!(&png[..8], b"\x89PNG\r\n\x1a\n");
    let md = std::fs::read_to_string(first.join("report.md")).unwrap();
    assert!(
        md.contains("| path 4λ |") && md.contains("| light 1λ |"),
        "{md}"
    );
    assert!(md.contains("4 wavelengths cost"), "{md}");
    assert!(stdout(&o).contains("path 1λ [spectral-render]"));
    let reference = first.join("reference.exr");
    let runs: Vec<_> = ["a", "b"]
        .iter()
        .map(|name| {
            let out = dir.join(name);
            run(args(
                &out,
                &["--reference", reference.to_str().unwrap(), "--keep-images"],
            ));
            out
        })
        .collect();
    assert_eq!(csv_without_times(&runs[0]), csv_without_times(&runs[1]));
    assert!(runs[0].join("images/path_000012.exr").is_file());
    let json = std::fs::read_to_string(runs[0].join("report.json")).unwrap();
    assert!(json.contains("its noise (variance channels) is subtracted"));
    // The same rows read back as a peer's: the report accepts them (errors already there).
    let peers = run(args(
        &dir.join("c"),
        &[
            "--reference",
            reference.to_str().unwrap(),
            "--peers",
            runs[0].join("report.csv").to_str().unwrap(),
        ],
    ));
    assert!(peers.status.success());
}

#[test]
fn the_sampler_flag_reaches_the_path_tracer_and_the_exr_names_it() {
    let dir = temp_dir("converge-sampler");
    let cbox = cbox_path();
    let run = |name: &str, sampler: Option<&str>| {
        let out = dir.join(name);
        let mut a = vec![
            "converge".to_string(),
            cbox.display().to_string(),
            "-o".into(),
            out.display().to_string(),
            "--resolution".into(),
            "12x12".into(),
            "--integrators".into(),
            "path,light".into(),
            "--time".into(),
            "100".into(),
            "--max-spp".into(),
            "4".into(),
            "--reference-time".into(),
            "0.2".into(),
            "--reference-integrator".into(),
            "path".into(),
            "--keep-images".into(),
        ];
        if let Some(s) = sampler {
            a.extend(["--sampler".into(), s.into()]);
        }
        let refs: Vec<&str> = a.iter().map(String::as_str).collect();
        let o = spectral_render(&refs, &dir);
        assert!(o.status.success(), "{}", stderr(&o));
        out
    };
    let attr = |f: &Path| exr::read(f).unwrap().attributes[exr::SAMPLER_ATTRIBUTE].clone();
    let pixels = |f: &Path| exr::read(f).unwrap().channels["XYZ.Y"].clone();
    let zsobol = run("zsobol", None);
    let independent = run("independent", Some("independent"));
    let snapshot = "images/path_000004.exr";
    assert_eq!(attr(&zsobol.join(snapshot)), "zsobol");
    assert_eq!(attr(&independent.join(snapshot)), "independent");
    // The path tracer's reference draws from the same sampler.
    assert_eq!(attr(&independent.join("reference.exr")), "independent");
    // Light tracing ignores it.
    for out in [&zsobol, &independent] {
        assert_eq!(attr(&out.join("images/light_000004.exr")), "independent");
    }
    // The flag changes the path tracer's numbers, not the light tracer's.
    assert_ne!(
        pixels(&zsobol.join(snapshot)),
        pixels(&independent.join(snapshot))
    );
    assert_eq!(
        pixels(&zsobol.join("images/light_000004.exr")),
        pixels(&independent.join("images/light_000004.exr"))
    );
}

#[test]
fn the_command_refuses_bad_options_in_one_line() {
    let dir = temp_dir("converge-errors");
    let cbox = cbox_path();
    let cbox = cbox.to_str().unwrap();
    for (extra, says) in [
        (vec!["--integrators", "pathx"], "unknown integrator 'pathx'"),
        (vec!["--wavelengths", "2"], "--wavelengths 2"),
        (vec!["--sampler", "sobolx"], "sobolx"),
        (vec!["--time", "0"], "--time must be"),
        (
            vec!["--reference", "missing.exr", "--reference-time", "3"],
            "--reference takes",
        ),
        (
            vec![
                "--at",
                "0,1,0",
                "--normal",
                "0,1,0",
                "--reference-value",
                "1,2",
            ],
            "--reference-value",
        ),
    ] {
        let mut a = vec!["converge", cbox, "-o", "out"];
        a.extend(extra);
        let o = spectral_render(&a, &dir);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{err}");
        assert!(
            err.contains(says) && err.trim().lines().count() == 1,
            "{err}"
        );
        assert!(
            !dir.join("out").exists(),
            "nothing is written on an option error"
        );
    }
}
