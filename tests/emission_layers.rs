//! Emission-weighted layers (`--illuminants`, `--light-groups`): each illuminant layer is the
//! render of the scene with every light's spectrum replaced (bit for bit, same seed and light
//! selection; within noise of a stage edited by hand), the light groups sum to the image, and
//! the metamerism scene's patches match under D65 and part under A.

mod common;

use common::*;
use spectral_render::integrator::roulette::RrStart;
use spectral_render::output::exr;
use spectral_render::scene::{self, Scene};
use spectral_render::session::{self, RenderOptions, RenderOutput};
use spectral_render::spectral::{data, difference, xyz};
use std::path::{Path, PathBuf};

fn scene_path(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenes")
        .join(name)
}

fn load(name: &str, res: (u32, u32)) -> Scene {
    scene::load(&scene_path(name), Some(res)).unwrap_or_else(|e| panic!("{e}"))
}

/// A render at seed 11 with roulette from bounce 2: a given start, since `auto`'s pilot sees
/// the lights' spectra and so may start the replaced scenes' roulette elsewhere than the
/// layers' (which follow the image's paths).
fn render(scene: &Scene, spp: u32) -> RenderOutput {
    let opts = RenderOptions {
        spp: Some(spp),
        seed: 11,
        rr_depth: RrStart::At(2),
        ..Default::default()
    };
    let out = session::render(scene, &opts).unwrap_or_else(|e| panic!("{e}"));
    assert_finite(&out);
    out
}

/// Every illuminant layer equals, bit for bit, the render of the scene whose lights were
/// replaced by that illuminant (same seed, same light selection): on the metamers (one dome)
/// and on the room (five lights, a light table, an IES profile).
#[test]
fn each_illuminant_layer_is_the_replaced_scenes_render_bit_for_bit() {
    let names = ["D65", "A", "F11", "LED-B3"];
    for (stage, res, spp) in [("metamers.usda", (40, 20), 4), ("room.usda", (24, 18), 4)] {
        let mut scene = load(stage, res);
        scene
            .add_illuminant_layers(&names.map(String::from))
            .unwrap();
        let one_pass = render(&scene, spp);
        assert_eq!(one_pass.layers.emission.len(), names.len());
        for (layer, name) in one_pass.layers.emission.iter().zip(names) {
            let mut replaced = load(stage, res);
            replaced.replace_emission(name).unwrap();
            let separate = render(&replaced, spp);
            assert!(
                layer.xyz == separate.xyz,
                "{stage}: layer {} differs",
                layer.name
            );
            assert!(layer.rgb == separate.rgb, "{stage}: layer {}", layer.name);
        }
    }
}

/// The CIE-A layer of the metamers agrees with the stage whose dome names CIE-A itself:
/// per patch, the mean XYZ within 4 standard errors (the pixels of a uniform patch are
/// independent estimates of the same value; the standard error of their mean is their
/// sample standard deviation / √n, and the two renders' errors add in quadrature).
#[test]
fn an_illuminant_layer_matches_a_stage_edited_by_hand_within_its_noise() {
    let res = (80, 40);
    let mut scene = load("metamers.usda", res);
    scene.add_illuminant_layers(&["A".into()]).unwrap();
    let layer = render(&scene, 16).layers.emission.remove(0);
    let text = std::fs::read_to_string(scene_path("metamers.usda")).unwrap();
    let edited = text.replace(
        "token spectral:emission = \"CIE-D65\"",
        "token spectral:emission = \"CIE-A\"",
    );
    assert_ne!(edited, text);
    let separate = render(&load_text("metamers_a", &edited, res), 16);
    for patch in PATCHES {
        let (a, b) = (
            patch_stats(&layer.xyz, res, patch),
            patch_stats(&separate.xyz, res, patch),
        );
        for c in 0..3 {
            let tol = 4.0 * (a.1[c].powi(2) + b.1[c].powi(2)).sqrt();
            assert!(
                (a.0[c] - b.0[c]).abs() <= tol,
                "{patch:?} channel {c}: {} vs {} (tolerance {tol})",
                a.0[c],
                b.0[c]
            );
        }
    }
}

/// The light groups' layers sum to the image within float round-off (each layer and the
/// image are rounded to f32 once: a relative 1e-5 covers five of them).
#[test]
fn light_groups_sum_to_the_image() {
    let mut scene = load("room.usda", (24, 18));
    scene.add_light_group_layers().unwrap();
    let out = render(&scene, 4);
    let names: Vec<&str> = out
        .layers
        .emission
        .iter()
        .map(|l| l.name.as_str())
        .collect();
    assert_eq!(names, ["Panel0", "Panel1", "Panel2", "Panel3", "Downlight"]);
    for (i, px) in out.xyz.iter().enumerate() {
        for (c, &v) in px.iter().enumerate() {
            let sum: f64 = out
                .layers
                .emission
                .iter()
                .map(|l| f64::from(l.xyz[i][c]))
                .sum();
            let v = f64::from(v);
            assert!(
                (sum - v).abs() <= 1e-5 * v.abs() + 1e-9,
                "pixel {i} channel {c}: groups sum to {sum}, image {v}"
            );
        }
    }
    assert!(out
        .layers
        .emission
        .iter()
        .all(|l| l.xyz.iter().any(|p| p[1] > 0.0)));
}

/// The patches of `metamers.usda`: pixel rectangles at 80 × 40 (0.005 m per pixel, x from
/// −0.2 m, y from 0.1 m down), 0.015 m inside the 0.12 m squares.
const PATCHES: [(usize, usize, usize, usize); 2] = [(17, 11, 35, 29), (45, 11, 63, 29)];

/// Mean and standard error of the mean per channel over a patch rectangle at 80 × 40 (or a
/// multiple of it).
fn patch_stats(
    xyz: &[[f32; 3]],
    (w, _): (u32, u32),
    (x0, y0, x1, y1): (usize, usize, usize, usize),
) -> ([f64; 3], [f64; 3]) {
    let k = w as usize / 80;
    let mut vals: Vec<[f64; 3]> = Vec::new();
    for y in y0 * k..y1 * k {
        for x in x0 * k..x1 * k {
            vals.push(xyz[y * w as usize + x].map(f64::from));
        }
    }
    let n = vals.len() as f64;
    let mean: [f64; 3] = std::array::from_fn(|c| vals.iter().map(|v| v[c]).sum::<f64>() / n);
    let se = std::array::from_fn(|c| {
        let var = vals.iter().map(|v| (v[c] - mean[c]).powi(2)).sum::<f64>() / (n - 1.0);
        (var / n).sqrt()
    });
    (mean, se)
}

/// The metamers match under D65 (ΔE00 < 0.5) and part under A (ΔE00 > 3), measured on the
/// render's own layers; the white of each layer is the illuminant's at the dome's 100 cd/m².
/// Prints the ΔE per illuminant (the figures of scenes/README.md).
#[test]
fn the_metamers_match_under_d65_and_differ_under_a() {
    let res = (80, 40);
    let mut scene = load("metamers.usda", res);
    let names = ["D65", "A", "F11", "LED-B3"];
    scene
        .add_illuminant_layers(&names.map(String::from))
        .unwrap();
    let out = render(&scene, 64);
    for layer in &out.layers.emission {
        let spd = data::illuminant(&layer.name).unwrap();
        let w = xyz::dense_to_xyz(spd);
        let white = w.map(|c| 100.0 * c / w[1]);
        let [grey, metamer] = PATCHES.map(|p| {
            let m = patch_stats(&layer.xyz, res, p).0;
            difference::xyz_to_lab(m, white)
        });
        let de = difference::delta_e2000(grey, metamer);
        println!(
            "{}: ΔE00 {de:.2} (grey Lab {grey:.2?}, metamer {metamer:.2?})",
            layer.name
        );
        match layer.name.as_str() {
            "CIE-D65" => assert!(de < 0.5, "D65: ΔE00 {de}"),
            "CIE-A" => assert!(de > 3.0, "A: ΔE00 {de}"),
            _ => {}
        }
    }
}

/// The command line: the layers' channels, and one-line refusals.
#[test]
fn the_command_writes_the_layers_and_refuses_what_it_cannot() {
    let dir = temp_dir("emission-layers-cli");
    let stage = scene_path("metamers.usda");
    let exr_path = dir.join("m.exr");
    let args = [
        stage.to_str().unwrap(),
        "--resolution",
        "16x8",
        "--spp",
        "2",
        "--illuminants",
        "A,F11",
        "--light-groups",
        "--spectral-bins",
        "4",
        "-o",
        exr_path.to_str().unwrap(),
    ];
    let o = spectral_render(&args, &dir);
    assert!(o.status.success(), "{}", stderr(&o));
    let image = exr::read(&exr_path).unwrap();
    for layer in ["CIE-A", "CIE-F11", "Dome"] {
        for c in ["R", "G", "B", "XYZ.X", "XYZ.Y", "XYZ.Z"] {
            let name = format!("{layer}.{c}");
            assert!(image.channels.contains_key(&name), "no channel {name}");
        }
        let spectral = image
            .channels
            .keys()
            .filter(|k| k.starts_with(&format!("{layer}.S0.")))
            .count();
        assert_eq!(spectral, 4, "{layer}");
    }
    // The one group is the whole image.
    assert_eq!(image.channels["Dome.XYZ.Y"], image.channels["XYZ.Y"]);
    for (extra, needle) in [
        (
            &["--illuminants", "A", "--integrator", "bdpt"][..],
            "--integrator path",
        ),
        (&["--illuminants", "Z9"][..], "unknown illuminant 'Z9'"),
        (&["--light-groups", "--crop", "0,0,4,4"][..], "--crop"),
        (&["--illuminants", "A", "--part", "1/2"][..], "--part"),
    ] {
        let mut a: Vec<&str> = vec![
            stage.to_str().unwrap(),
            "--resolution",
            "16x8",
            "--spp",
            "2",
        ];
        a.extend_from_slice(extra);
        let out = dir.join("refused.exr");
        a.extend_from_slice(&["-o", out.to_str().unwrap()]);
        let o = spectral_render(&a, &dir);
        let err = stderr(&o);
        assert!(!o.status.success(), "{extra:?} was accepted");
        assert!(err.contains(needle), "{extra:?}: {err}");
        // One error line (a note that auto renders with path may come before it).
        let errors: Vec<&str> = err.lines().filter(|l| !l.starts_with("note:")).collect();
        assert_eq!(errors.len(), 1, "{extra:?}: {err}");
    }
}

/// `spectral:lightGroup` gathers lights into one layer.
#[test]
fn light_group_tokens_gather_lights() {
    let text = std::fs::read_to_string(scene_path("room.usda")).unwrap();
    let grouped = text.replace(
        "token spectral:emission = \"LED-B3\"",
        "token spectral:emission = \"LED-B3\"\n            token spectral:lightGroup = \"panels\"",
    );
    // The stage beside a copy of its IES profile.
    let dir = temp_dir("room_groups");
    std::fs::create_dir_all(dir.join("ies")).unwrap();
    std::fs::copy(
        scene_path("ies/downlight.ies"),
        dir.join("ies/downlight.ies"),
    )
    .unwrap();
    let path = write(&dir, "room.usda", &grouped);
    let mut scene = scene::load(&path, Some((8, 6))).unwrap_or_else(|e| panic!("{e}"));
    scene.add_light_group_layers().unwrap();
    let names = scene.emission_layers.names();
    assert_eq!(names, ["panels", "Downlight"]);
}

/// `--illuminants` refuses a light whose emission is textured with one error line naming the
/// stage and the light's prim (its colour varies over the light: no illuminant replaces it).
#[test]
fn a_textured_emission_is_refused_naming_the_light() {
    let dir = temp_dir("textured-emission");
    let sky = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/textures/sky.exr");
    std::fs::copy(sky, dir.join("sky.exr")).unwrap();
    let text = std::fs::read_to_string(scene_path("metamers.usda")).unwrap();
    let textured = text.replace(
        "token spectral:emission = \"CIE-D65\"",
        "asset inputs:texture:file = @sky.exr@",
    );
    assert_ne!(textured, text);
    let stage = write(&dir, "textured.usda", &textured);
    let exr_path = dir.join("t.exr");
    for layers in [&["--illuminants", "A"][..], &["--illuminant", "F11"]] {
        let mut args = vec![stage.to_str().unwrap(), "--resolution", "8x4", "--spp", "1"];
        args.extend_from_slice(layers);
        args.extend_from_slice(&["-o", exr_path.to_str().unwrap()]);
        let o = spectral_render(&args, &dir);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{layers:?}: {err}");
        let lines: Vec<&str> = err.lines().filter(|l| !l.starts_with("note:")).collect();
        assert_eq!(lines.len(), 1, "{layers:?}: {err}");
        assert!(
            lines[0].contains("textured.usda")
                && lines[0].contains("/World/Dome")
                && lines[0].contains("emission is textured"),
            "{err}"
        );
        assert!(!exr_path.exists());
    }
}

/// A stage's RenderSettings `dataWindowNDC` renders only its window, and the illuminant and
/// light-group layers are cut to it like the image: every channel of the windowed EXR is the
/// whole render's, bit for bit (same seed; the sampler is keyed by the pixel).
#[test]
fn emission_layers_are_cut_to_a_stage_data_window_like_the_image() {
    let dir = temp_dir("emission-layers-window");
    let text = std::fs::read_to_string(scene_path("metamers.usda")).unwrap();
    // NDC (0.25, 0.25)–(0.75, 0.75), y up: on 16 × 8, columns 4..12 and rows 2..6.
    let windowed = text.replace(
        "uniform int2 resolution = (160, 80)",
        "uniform int2 resolution = (160, 80)\n        float4 dataWindowNDC = (0.25, 0.25, 0.75, 0.75)",
    );
    assert_ne!(windowed, text);
    let stages = [
        ("whole", scene_path("metamers.usda")),
        ("window", write(&dir, "windowed.usda", &windowed)),
    ];
    let mut images = Vec::new();
    for (name, stage) in &stages {
        let out = dir.join(format!("{name}.exr"));
        let args = [
            stage.to_str().unwrap(),
            "--resolution",
            "16x8",
            "--spp",
            "3",
            "--seed",
            "9",
            "--integrator",
            "path",
            "--illuminants",
            "A,F11",
            "--light-groups",
            "--spectral-bins",
            "2",
            "-o",
            out.to_str().unwrap(),
        ];
        let o = spectral_render(&args, &dir);
        assert!(o.status.success(), "{name}: {}", stderr(&o));
        images.push(exr::read(&out).unwrap());
    }
    let (whole, window) = (&images[0], &images[1]);
    assert_eq!((whole.width, whole.height), (16, 8));
    assert_eq!((window.width, window.height), (8, 4));
    assert_eq!(
        whole.channels.keys().collect::<Vec<_>>(),
        window.channels.keys().collect::<Vec<_>>()
    );
    for layer in [
        "CIE-A.XYZ.Y",
        "CIE-F11.R",
        "Dome.B",
        "XYZ.Y",
        "CIE-A.S0.477,500000nm",
    ] {
        assert!(window.channels.contains_key(layer), "no {layer}");
    }
    for (name, c) in &window.channels {
        let w = &whole.channels[name];
        for row in 0..4 {
            for col in 0..8 {
                let v = w[(row + 2) * 16 + col + 4];
                assert_eq!(
                    c[row * 8 + col].to_bits(),
                    v.to_bits(),
                    "{name} ({col}, {row})"
                );
            }
        }
        assert!(c.iter().any(|v| *v > 0.0), "{name} is black");
    }
}
