//! UsdPreviewSurface textures end to end: decoding (sRGB / raw, PNG / EXR), the image cache,
//! rendered textured colour and cutouts under a uniform dome, and bad input through the CLI.

mod common;
use common::*;
use glam::{Vec2, Vec3};
use spectral_render::bxdf::TransportMode;
use spectral_render::desc::{ColorSpace, TextureChannel, TextureDesc, Wrap};
use spectral_render::geometry::Ray;
use spectral_render::imageio;
use spectral_render::output::exr;
use spectral_render::scene::{Hit, Scene, SurfaceHit};
use spectral_render::spectral::SampledWavelengths;
use spectral_render::texture::{ImageTexture, TextureCache};
use spectral_render::Integrator;
use std::path::{Path, PathBuf};
use std::process::Command;

/// A 16×16 RGBA8 PNG whose four 8×8 quadrants (top-left, top-right, bottom-left,
/// bottom-right) have the given texels.
fn quadrant_png(path: &Path, q: [[u8; 4]; 4]) {
    let mut bytes = Vec::new();
    for y in 0..16 {
        for x in 0..16 {
            bytes.extend_from_slice(&q[(y / 8) * 2 + x / 8]);
        }
    }
    imageio::write_png_rgba8(path, &bytes, 16, 16).unwrap();
}

fn desc(file: PathBuf, color_space: ColorSpace) -> TextureDesc {
    TextureDesc {
        shader_path: "/Looks/M/Tex".into(),
        file,
        st_primvar: "st".into(),
        st_transform: None,
        wrap_s: Wrap::Clamp,
        wrap_t: Wrap::Clamp,
        color_space,
        scale: [1.0; 4],
        bias: [0.0; 4],
        fallback: [0.0, 0.0, 0.0, 1.0],
        channel: TextureChannel::Rgb,
    }
}

#[test]
fn srgb_and_raw_decoding_scale_bias_and_the_cache() {
    let dir = temp_dir("tex-decode");
    let png = dir.join("grey.png");
    imageio::write_png_rgba8(&png, &[128, 128, 128, 128], 1, 1).unwrap();
    let mut cache = TextureCache::default();
    let uv = Vec2::splat(0.5).into();
    let srgb = cache.input(&desc(png.clone(), ColorSpace::Srgb)).unwrap();
    let auto = cache.input(&desc(png.clone(), ColorSpace::Auto)).unwrap();
    let raw = cache.input(&desc(png.clone(), ColorSpace::Raw)).unwrap();
    let again = cache.input(&desc(png.clone(), ColorSpace::Srgb)).unwrap();
    assert_eq!(cache.len(), 3, "one image per (file, colour space)");
    assert!(std::sync::Arc::ptr_eq(&srgb.image, &again.image));
    let v = 128.0f32 / 255.0;
    // 0.5 sRGB is 0.214 linear; byte 128 is 0.502, i.e. 0.2158.
    assert!(
        (srgb.rgb(uv)[0] - 0.2158).abs() < 1e-4,
        "{:?}",
        srgb.rgb(uv)
    );
    assert!((srgb.rgb(uv)[0] - 0.214).abs() < 3e-3);
    assert_eq!(auto.rgb(uv), srgb.rgb(uv), "auto is sRGB for an 8-bit file");
    assert!((raw.rgb(uv)[0] - v).abs() < 1e-6);
    // Alpha is never decoded.
    assert!((srgb.rgba(uv)[3] - v).abs() < 1e-6);
    let mut d = desc(png, ColorSpace::Raw);
    d.scale = [2.0, 1.0, 1.0, 1.0];
    d.bias = [-0.5, 0.25, 0.0, 0.0];
    let sb = cache.input(&d).unwrap();
    let t = sb.rgba(uv);
    assert!((t[0] - (2.0 * v - 0.5)).abs() < 1e-6 && (t[1] - (v + 0.25)).abs() < 1e-6);
}

#[test]
fn float_exr_textures_are_raw_under_auto() {
    let dir = temp_dir("tex-exr");
    let path = dir.join("hdr.exr");
    let rgb = [[2.5f32, 0.5, 0.25], [0.0, 1.0, 4.0]];
    exr::write(
        &path,
        2,
        1,
        &rgb,
        &rgb,
        [0.3127, 0.329],
        &Default::default(),
    )
    .unwrap();
    let img = ImageTexture::load(&path, ColorSpace::Auto).unwrap();
    let left = img.bilinear(Vec2::new(0.25, 0.5), [Wrap::Clamp; 2]);
    let right = img.bilinear(Vec2::new(0.75, 0.5), [Wrap::Clamp; 2]);
    assert_eq!(&left[..3], &rgb[0]);
    assert_eq!(&right[..3], &rgb[1]);
}

/// A quad filling the view of `camera(1, 0.2)` exactly with st ∈ [0, 1]², textured by
/// `Tex` (`tex_inputs`) on the shader inputs `connections`.
fn textured_stage(l: f32, file: &str, tex_inputs: &str, surface_inputs: &str) -> String {
    // The view spans x, y ∈ [−0.2, 0.2] on the plane: st = (x + 0.2) / 0.4 there.
    let st = "    texCoord2f[] primvars:st = [(-2, -2), (3, -2), (3, 3), (-2, 3)] (\n        interpolation = \"vertex\"\n    )\n";
    textured_stage_st(l, file, tex_inputs, surface_inputs, st)
}

/// [`textured_stage`] with the quad's st lines given (corners (−1, −1), (1, −1), (1, 1),
/// (−1, 1) in z = 0, facing +Z).
fn textured_stage_st(
    l: f32,
    file: &str,
    tex_inputs: &str,
    surface_inputs: &str,
    st: &str,
) -> String {
    let looks = format!(
        r#"def Scope "Looks"
{{
    def Material "Paint"
    {{
        token outputs:surface.connect = </Looks/Paint/S.outputs:surface>
        def Shader "S"
        {{
            uniform token info:id = "UsdPreviewSurface"
            float inputs:ior = 1
{surface_inputs}            token outputs:surface
        }}
        def Shader "Reader"
        {{
            uniform token info:id = "UsdPrimvarReader_float2"
            token inputs:varname = "st"
            float2 outputs:result
        }}
        def Shader "Tex"
        {{
            uniform token info:id = "UsdUVTexture"
            asset inputs:file = @{file}@
            float2 inputs:st.connect = </Looks/Paint/Reader.outputs:result>
{tex_inputs}            float3 outputs:rgb
            float outputs:a
        }}
    }}
}}

"#
    );
    dome_plane_stage(l, &looks, st)
}

/// Mean and SEM of channel `ch` over the pixels of a 32×32 image in quadrant `q`
/// (0 top-left, 1 top-right, 2 bottom-left, 3 bottom-right), away from the bilinear seam.
fn quadrant(out: &spectral_render::session::RenderOutput, q: usize, ch: usize) -> (f64, f64) {
    assert_eq!((out.width, out.height), (32, 32));
    let (qx, qy) = (q % 2, q / 2);
    let pixels = (0..32 * 32).filter(move |i| {
        let (x, y) = (i % 32, i / 32);
        x / 16 == qx && y / 16 == qy && !(14..18).contains(&x) && !(14..18).contains(&y)
    });
    mean_and_sem(pixels.map(|i| out.rgb[i][ch]))
}

/// The four texels of the round-trip checker (sRGB bytes read as raw).
const CHECKER: [[u8; 4]; 4] = [
    [204, 51, 25, 255],
    [25, 153, 76, 255],
    [13, 26, 230, 255],
    [128, 128, 128, 255],
];

/// UsdUVTexture input: texels are raw values.
const RAW: &str = "            token inputs:sourceColorSpace = \"raw\"\n";
/// UsdPreviewSurface input: diffuseColor from the texture.
const DIFFUSE_CONNECTED: &str =
    "            color3f inputs:diffuseColor.connect = </Looks/Paint/Tex.outputs:rgb>\n";

/// Renders `stage` (a textured plane filling the view under a uniform dome of radiance `l`,
/// textured with `q` by quadrant) at `spp` and checks that each quadrant reads L·texel within
/// 6e-3·L + 5 SEM.
fn assert_quadrants(dir: &Path, stage: &str, l: f32, q: [[u8; 4]; 4], spp: u32) {
    let out = render_file(
        &write(dir, "quadrants.usda", stage),
        (32, 32),
        spp,
        Some(7),
        None,
    );
    for (k, texel) in q.iter().enumerate() {
        for (ch, &byte) in texel[..3].iter().enumerate() {
            let (mean, sem) = quadrant(&out, k, ch);
            let expected = f64::from(l) * f64::from(byte) / 255.0;
            let tol = 6e-3 * f64::from(l) + 5.0 * sem;
            assert!(
                (mean - expected).abs() < tol,
                "quadrant {k} channel {ch}: {mean} vs {expected} (sem {sem})"
            );
        }
    }
}

#[test]
fn textured_diffuse_colour_round_trips_under_a_uniform_dome() {
    let l = 50.0f32;
    let dir = temp_dir("tex-render");
    quadrant_png(&dir.join("checker.png"), CHECKER);
    let stage = textured_stage(l, "checker.png", RAW, DIFFUSE_CONNECTED);
    assert_quadrants(&dir, &stage, l, CHECKER, 64);
}

#[test]
fn textured_opacity_cuts_out_with_a_threshold() {
    let l = 20.0f32;
    let dir = temp_dir("tex-cutout");
    // Left half opaque, right half transparent (alpha 0), read through outputs:a.
    let (on, off) = ([255, 255, 255, 255], [255, 255, 255, 0]);
    quadrant_png(&dir.join("mask.png"), [on, off, on, off]);
    let stage = textured_stage(
        l,
        "mask.png",
        "",
        "            color3f inputs:diffuseColor = (0.5, 0.5, 0.5)\n            float inputs:opacity.connect = </Looks/Paint/Tex.outputs:a>\n            float inputs:opacityThreshold = 0.5\n",
    );
    let out = render_file(
        &write(&dir, "cut.usda", &stage),
        (32, 32),
        32,
        Some(7),
        None,
    );
    for (k, expected) in [(0, 0.5 * l), (1, l), (2, 0.5 * l), (3, l)] {
        let (mean, sem) = quadrant(&out, k, 1);
        let tol = 6e-3 * f64::from(l) + 5.0 * sem;
        assert!(
            (mean - f64::from(expected)).abs() < tol,
            "quadrant {k}: {mean} vs {expected} (sem {sem})"
        );
    }
}

/// Runs the CLI on `stage` in `dir` and checks for one clean error line mentioning `parts`.
fn assert_cli_error(dir: &Path, stage: &str, parts: &[&str]) {
    write(dir, "bad.usda", stage);
    let o = Command::new(env!("CARGO_BIN_EXE_spectral-render"))
        .args(["bad.usda", "--spp", "1"])
        .current_dir(dir)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr).into_owned();
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(!err.contains("panicked"), "{err}");
    assert_eq!(err.lines().count(), 1, "{err}");
    for p in parts {
        assert!(err.contains(p), "'{p}' not in {err}");
    }
}

#[test]
fn a_missing_texture_is_one_error_line_naming_stage_shader_and_file() {
    let dir = temp_dir("tex-missing");
    let diffuse =
        "            color3f inputs:diffuseColor.connect = </Looks/Paint/Tex.outputs:rgb>\n";
    let stage = textured_stage(1.0, "nowhere/missing.png", "", diffuse);
    assert_cli_error(
        &dir,
        &stage,
        &["bad.usda", "/Looks/Paint/Tex", "nowhere/missing.png"],
    );
}

#[test]
fn an_unsupported_wrap_token_is_an_error() {
    let dir = temp_dir("tex-wrap");
    quadrant_png(&dir.join("checker.png"), [[0, 0, 0, 255]; 4]);
    let diffuse =
        "            color3f inputs:diffuseColor.connect = </Looks/Paint/Tex.outputs:rgb>\n";
    let wrap = "            token inputs:wrapT = \"wobble\"\n";
    let stage = textured_stage(1.0, "checker.png", wrap, diffuse);
    assert_cli_error(&dir, &stage, &["bad.usda", "/Looks/Paint/Tex", "wobble"]);
}

#[test]
fn textured_emission_and_clearcoat_roughness_are_read_and_ior_warns() {
    let dir = temp_dir("tex-warn");
    quadrant_png(&dir.join("checker.png"), [[255, 255, 255, 255]; 4]);
    let inputs = "            color3f inputs:emissiveColor.connect = </Looks/Paint/Tex.outputs:rgb>\n            float inputs:clearcoatRoughness.connect = </Looks/Paint/Tex.outputs:r>\n            float inputs:opacityThreshold.connect = </Looks/Paint/Tex.outputs:r>\n";
    let stage = textured_stage(1.0, "checker.png", "", inputs);
    let scene =
        spectral_render::scene::load(&write(&dir, "warn.usda", &stage), Some((4, 4))).unwrap();
    let warnings = &scene.summary.warnings;
    assert_eq!(warnings.len(), 1, "{warnings:?}");
    assert!(
        warnings[0].contains("inputs:opacityThreshold") && warnings[0].contains("texture"),
        "{warnings:?}"
    );
    assert_eq!(
        scene.lights.len(),
        3,
        "the dome and the quad's two triangles"
    );
    let spectral_render::material::Material::Preview(p) = &scene.materials[0] else {
        panic!("a UsdPreviewSurface")
    };
    assert!(p.textures.clearcoat_roughness.is_some() && p.textures.clearcoat_coats.is_some());
}

/// A `w`×4 RGBA8 PNG whose left half is `left` and right half `right`.
fn halves_png(path: &Path, w: usize, left: [u8; 4], right: [u8; 4]) {
    let mut bytes = Vec::new();
    for _ in 0..4 {
        for x in 0..w {
            bytes.extend_from_slice(if x < w / 2 { &left } else { &right });
        }
    }
    imageio::write_png_rgba8(path, &bytes, w as u32, 4).unwrap();
}

#[test]
fn textured_emission_is_seen_at_its_st() {
    let dir = temp_dir("tex-emit");
    let q = [
        [204, 51, 25, 255],
        [25, 153, 76, 255],
        [13, 26, 230, 255],
        [128, 128, 128, 255],
    ];
    quadrant_png(&dir.join("glow.png"), q);
    let inputs = "            color3f inputs:diffuseColor = (0, 0, 0)\n            color3f inputs:emissiveColor.connect = </Looks/Paint/Tex.outputs:rgb>\n";
    let raw = "            token inputs:sourceColorSpace = \"raw\"\n";
    let stage = textured_stage(0.0, "glow.png", raw, inputs);
    let out = render_file(
        &write(&dir, "glow.usda", &stage),
        (32, 32),
        16,
        Some(3),
        None,
    );
    for (k, texel) in q.iter().enumerate() {
        for (ch, &byte) in texel[..3].iter().enumerate() {
            let (mean, sem) = quadrant(&out, k, ch);
            let expected = f64::from(byte) / 255.0;
            assert!(
                (mean - expected).abs() < 6e-3 + 5.0 * sem,
                "quadrant {k} channel {ch}: {mean} vs {expected} (sem {sem})"
            );
        }
    }
}

/// A grey floor (z = 0) seen from above, lit by emitters beside the view at z = 0.6 facing
/// down: `emitters` are the Mesh prims, `looks` their materials.
fn lit_floor_stage(looks: &str, emitters: &str) -> String {
    let mut s = header();
    s += &camera(2.0, 0.1, 0.0);
    s += &format!(
        "def Scope \"Looks\"\n{{\n{looks}{}}}\n\n",
        material(
            "Floor",
            "UsdPreviewSurface",
            "            color3f inputs:diffuseColor = (0.5, 0.5, 0.5)\n"
        )
    );
    s += &quad(
        "Floor",
        0.0,
        1.0,
        &binding("Floor"),
        "\"MaterialBindingAPI\"",
    );
    s + emitters
}

/// A downward-facing rectangle x ∈ [x0, x1], y ∈ [−0.5, 0.5] at z = 0.6 with st over it.
fn ceiling_panel(name: &str, x0: f32, x1: f32, look: &str) -> String {
    format!(
        "def Mesh \"{name}\" (\n    prepend apiSchemas = [\"MaterialBindingAPI\"]\n)\n{{\n    int[] faceVertexCounts = [4]\n    int[] faceVertexIndices = [0, 1, 2, 3]\n    point3f[] points = [({x0}, -0.5, 0.6), ({x0}, 0.5, 0.6), ({x1}, 0.5, 0.6), ({x1}, -0.5, 0.6)]\n    texCoord2f[] primvars:st = [(0, 0), (0, 1), (1, 1), (1, 0)] (\n        interpolation = \"vertex\"\n    )\n{}}}\n\n",
        binding(look)
    )
}

/// Mean and SEM of the per-pixel difference of two images in channel `ch`.
fn difference(
    a: &spectral_render::session::RenderOutput,
    b: &spectral_render::session::RenderOutput,
    ch: usize,
) -> (f64, f64) {
    mean_and_sem(a.rgb.iter().zip(&b.rgb).map(|(x, y)| x[ch] - y[ch]))
}

#[test]
fn a_textured_emitter_lights_like_the_constant_emitters_it_is_made_of() {
    let dir = temp_dir("tex-emit-nee");
    halves_png(
        &dir.join("halves.png"),
        64,
        [255, 40, 20, 255],
        [20, 60, 255, 255],
    );
    let emissive = |rgb: &str| {
        format!("            color3f inputs:diffuseColor = (0, 0, 0)\n            color3f inputs:emissiveColor = {rgb}\n")
    };
    let red = material(
        "Red",
        "UsdPreviewSurface",
        &emissive("(1, 0.156863, 0.078431)"),
    );
    let blue = material(
        "Blue",
        "UsdPreviewSurface",
        &emissive("(0.078431, 0.235294, 1)"),
    );
    let two = lit_floor_stage(
        &(red + &blue),
        &(ceiling_panel("Left", 0.3, 0.8, "Red") + &ceiling_panel("Right", 0.8, 1.3, "Blue")),
    );
    let textured = textured_stage(0.0, "halves.png", "            token inputs:sourceColorSpace = \"raw\"\n            token inputs:wrapS = \"clamp\"\n", "            color3f inputs:diffuseColor = (0, 0, 0)\n            color3f inputs:emissiveColor.connect = </Looks/Paint/Tex.outputs:rgb>\n");
    // Keep the textured stage's material, replace its geometry by the floor and one panel.
    let looks = &textured
        [textured.find("    def Material \"Paint\"").unwrap()..textured.find("def Mesh").unwrap()];
    let looks = &looks[..looks.rfind('}').unwrap()];
    let one = lit_floor_stage(looks, &ceiling_panel("Panel", 0.3, 1.3, "Paint"));
    let (path_two, path_one) = (write(&dir, "two.usda", &two), write(&dir, "one.usda", &one));
    let reference = render_file(&path_two, (24, 24), 256, Some(3), None);
    for integrator in [Integrator::Path, Integrator::Light] {
        let scene = spectral_render::scene::load(&path_one, Some((24, 24))).unwrap();
        let opts = spectral_render::session::RenderOptions {
            spp: Some(256),
            seed: 11,
            max_depth: Some(3),
            integrator,
            ..Default::default()
        };
        let out = spectral_render::session::render(&scene, &opts).unwrap();
        assert_finite(&out);
        for ch in 0..3 {
            let (d, sem) = difference(&out, &reference, ch);
            let level = mean_and_sem(reference.rgb.iter().map(|p| p[ch])).0;
            println!(
                "{integrator:?} channel {ch}: mean {level:.4}, difference {d:.2e} ± {sem:.1e}"
            );
            assert!(level > 1e-3, "the floor is lit");
            assert!(
                d.abs() < 4.0 * sem + 2e-3 * level,
                "{integrator:?} channel {ch}"
            );
        }
    }
}

// ---- Normal maps -------------------------------------------------------------------------

/// A 1×1 float EXR holding `rgb` (values exact in half precision), for raw texture tests.
fn texel_exr(dir: &Path, name: &str, rgb: [f32; 3]) {
    let texels = [rgb];
    exr::write(
        &dir.join(name),
        1,
        1,
        &texels,
        &texels,
        [0.3127, 0.329],
        &Default::default(),
    )
    .unwrap();
}

/// UsdUVTexture inputs of a tangent-space normal map (UsdPreviewSurface spec: raw, ×2 − 1).
const NORMAL_TEX: &str = "            token inputs:sourceColorSpace = \"raw\"\n            float4 inputs:scale = (2, 2, 2, 1)\n            float4 inputs:bias = (-1, -1, -1, 0)\n";
const NORMAL_CONNECTED: &str =
    "            normal3f inputs:normal.connect = </Looks/Paint/Tex.outputs:rgb>\n";
const GLOSSY: &str =
    "            float inputs:metallic = 0.5\n            float inputs:roughness = 0.3\n";

/// The surface hit by the ray from (x, y, 1) straight down.
fn surface_at(scene: &Scene, x: f32, y: f32) -> SurfaceHit {
    let ray = Ray::new(Vec3::new(x, y, 1.0), -Vec3::Z);
    match scene.intersect(&ray, f32::INFINITY) {
        Some(Hit::Surface(si)) => si,
        other => panic!("expected the quad at ({x}, {y}), got {other:?}"),
    }
}

fn load_scene(dir: &Path, name: &str, stage: &str) -> Scene {
    spectral_render::scene::load(&write(dir, name, stage), Some((16, 16)))
        .unwrap_or_else(|e| panic!("{e}"))
}

const POINTS: [(f32, f32); 4] = [(0.1, 0.05), (-0.15, 0.1), (0.12, -0.17), (-0.05, -0.08)];

#[test]
fn a_flat_normal_map_is_the_identity() {
    let dir = temp_dir("nmap-flat");
    texel_exr(&dir, "flat.exr", [0.5, 0.5, 1.0]);
    let mapped = textured_stage(
        10.0,
        "flat.exr",
        NORMAL_TEX,
        &format!("{GLOSSY}{NORMAL_CONNECTED}"),
    );
    let plain = textured_stage(10.0, "flat.exr", NORMAL_TEX, GLOSSY);
    let (a, b) = (
        load_scene(&dir, "mapped.usda", &mapped),
        load_scene(&dir, "plain.usda", &plain),
    );
    assert!(a.materials[0].perturbs_normal() && !b.materials[0].perturbs_normal());
    for (x, y) in POINTS {
        assert_eq!(surface_at(&a, x, y).ns, surface_at(&b, x, y).ns);
    }
    let opts = spectral_render::session::RenderOptions {
        spp: Some(8),
        seed: 7,
        max_depth: Some(5),
        ..Default::default()
    };
    let (ia, ib) = (
        spectral_render::session::render(&a, &opts).unwrap(),
        spectral_render::session::render(&b, &opts).unwrap(),
    );
    assert_finite(&ia);
    for (pa, pb) in ia.rgb.iter().zip(&ib.rgb) {
        for c in 0..3 {
            assert!(
                (pa[c] - pb[c]).abs() <= 1e-6 * pb[c].abs().max(1.0),
                "{pa:?} {pb:?}"
            );
        }
    }
}

/// BSDF values of two scenes' materials at the same hit, for a few direction pairs.
fn assert_same_bsdf(a: &Scene, b: &Scene, x: f32, y: f32) {
    let (sa, sb) = (surface_at(a, x, y), surface_at(b, x, y));
    assert!((sa.ns - sb.ns).length() < 1e-6, "{} vs {}", sa.ns, sb.ns);
    let lambda = SampledWavelengths::sample_visible(0.37);
    let fa = a.materials[0].bsdf(sa.uv.into(), sa.ns, &lambda);
    let fb = b.materials[0].bsdf(sb.uv.into(), sb.ns, &lambda);
    let wo = Vec3::new(0.2, -0.3, 0.9).normalize();
    for wi in [Vec3::new(-0.4, 0.1, 0.8), Vec3::new(0.6, 0.2, 0.3), Vec3::Z] {
        let wi = wi.normalize();
        let (va, vb) = (
            fa.f(wo, wi, TransportMode::Radiance),
            fb.f(wo, wi, TransportMode::Radiance),
        );
        for i in 0..4 {
            assert!(
                (va.0[i] - vb.0[i]).abs() <= 1e-6 * vb.0[i].max(1.0),
                "{va:?} {vb:?}"
            );
        }
    }
}

#[test]
fn a_tilted_constant_normal_map_equals_the_constant_normal_input() {
    let dir = temp_dir("nmap-tilt");
    // (0.75, 0.5, 1) × 2 − 1 = (0.5, 0, 1): tilted towards +u, i.e. +X on this quad.
    texel_exr(&dir, "tilt.exr", [0.75, 0.5, 1.0]);
    let mapped = textured_stage(
        1.0,
        "tilt.exr",
        NORMAL_TEX,
        &format!("{GLOSSY}{NORMAL_CONNECTED}"),
    );
    let constant = format!("{GLOSSY}            normal3f inputs:normal = (0.5, 0, 1)\n");
    let constant = textured_stage(1.0, "tilt.exr", NORMAL_TEX, &constant);
    let (a, b) = (
        load_scene(&dir, "mapped.usda", &mapped),
        load_scene(&dir, "constant.usda", &constant),
    );
    let expected = Vec3::new(0.5, 0.0, 1.0).normalize();
    for (x, y) in POINTS {
        assert!((surface_at(&a, x, y).ns - expected).length() < 1e-6);
        assert_same_bsdf(&a, &b, x, y);
    }
}

#[test]
fn the_tangent_frame_follows_st() {
    let dir = temp_dir("nmap-st");
    texel_exr(&dir, "u.exr", [0.75, 0.5, 1.0]);
    texel_exr(&dir, "v.exr", [0.5, 0.75, 1.0]);
    let st = |values: &str| {
        format!("    texCoord2f[] primvars:st = [{values}] (\n        interpolation = \"vertex\"\n    )\n")
    };
    // Corners (−1, −1), (1, −1), (1, 1), (−1, 1); (∂p/∂u, ∂p/∂v) per parameterisation.
    let cases = [
        (
            "plain",
            st("(0, 0), (1, 0), (1, 1), (0, 1)"),
            Vec3::X,
            Vec3::Y,
        ),
        (
            "rotated",
            st("(-1, 1), (-1, -1), (1, -1), (1, 1)"),
            Vec3::Y,
            -Vec3::X,
        ),
        (
            "mirrored",
            st("(0, 1), (1, 1), (1, 0), (0, 0)"),
            Vec3::X,
            -Vec3::Y,
        ),
    ];
    for (name, st, dpdu, dpdv) in cases {
        for (file, axis) in [("u.exr", dpdu), ("v.exr", dpdv)] {
            let stage = textured_stage_st(1.0, file, NORMAL_TEX, NORMAL_CONNECTED, &st);
            let scene = load_scene(&dir, &format!("{name}.usda"), &stage);
            let expected = (0.5 * axis + Vec3::Z).normalize();
            for (x, y) in POINTS {
                let ns = surface_at(&scene, x, y).ns;
                assert!(
                    (ns - expected).length() < 1e-5,
                    "{name} {file}: {ns} vs {expected}"
                );
            }
        }
    }
}

/// `stage` with its mesh replaced by one bound to the same material whose st is one point
/// for the whole mesh and which has a zero-area triangle.
fn with_degenerate_mesh(stage: &str) -> String {
    let mut s = stage[..stage.find("def Mesh").unwrap()].to_string();
    s += "def Mesh \"Bad\" (\n    prepend apiSchemas = [\"MaterialBindingAPI\"]\n)\n{\n    int[] faceVertexCounts = [3, 3, 3]\n    int[] faceVertexIndices = [0, 1, 2, 0, 2, 3, 1, 1, 1]\n    point3f[] points = [(-1, -1, 0), (1, -1, 0), (1, 1, 0), (-1, 1, 0)]\n    texCoord2f[] primvars:st = [(0.5, 0.5)] (\n        interpolation = \"constant\"\n    )\n    rel material:binding = </Looks/Paint>\n}\n";
    s
}

#[test]
fn degenerate_st_and_zero_area_triangles_give_no_nan() {
    let dir = temp_dir("nmap-degenerate");
    texel_exr(&dir, "steep.exr", [1.0, 0.25, 0.5]);
    let stage = textured_stage_st(5.0, "steep.exr", NORMAL_TEX, NORMAL_CONNECTED, "");
    // The same material on a mesh whose st is one point and which has a zero-area triangle.
    let s = with_degenerate_mesh(&stage);
    let path = write(&dir, "bad.usda", &s);
    let scene = spectral_render::scene::load(&path, Some((16, 16))).unwrap();
    for (x, y) in POINTS {
        let ns = surface_at(&scene, x, y).ns;
        assert!(
            ns.is_finite() && (ns.length() - 1.0).abs() < 1e-5 && ns.z > 0.0,
            "{ns}"
        );
    }
    render_file(&path, (16, 16), 8, Some(5), None);
}

// ---- Textures on spectral:* shaders ------------------------------------------------------

/// [`textured_stage`] with the surface shader replaced by `spectral:*` shader `id`.
fn spectral_stage(l: f32, file: &str, tex_inputs: &str, id: &str, inputs: &str) -> String {
    let preview =
        "uniform token info:id = \"UsdPreviewSurface\"\n            float inputs:ior = 1\n";
    let stage = textured_stage(l, file, tex_inputs, inputs);
    assert!(stage.contains(preview));
    stage.replace(preview, &format!("uniform token info:id = \"{id}\"\n"))
}

#[test]
fn textured_spectral_diffuse_reflectance_round_trips_under_a_uniform_dome() {
    let l = 50.0f32;
    let dir = temp_dir("tex-spectral-diffuse");
    quadrant_png(&dir.join("checker.png"), CHECKER);
    let stage = spectral_stage(
        l,
        "checker.png",
        RAW,
        "spectral:diffuse",
        "            color3f inputs:reflectance.connect = </Looks/Paint/Tex.outputs:rgb>\n",
    );
    assert_quadrants(&dir, &stage, l, CHECKER, 64);
}

#[test]
fn textured_spectral_roughness_equals_the_constant_it_holds() {
    let dir = temp_dir("tex-spectral-rough");
    // α = 0.25 lies on the plastic's coat levels (√α = 16/32); σ = 0.5 rad.
    texel_exr(&dir, "alpha.exr", [0.25, 0.5, 0.0]);
    let raw = "            token inputs:sourceColorSpace = \"raw\"\n";
    let rough = |channel: &str| {
        format!(
            "            float inputs:roughness.connect = </Looks/Paint/Tex.outputs:{channel}>\n"
        )
    };
    let cases = [
        (
            "spectral:conductor",
            "            token inputs:metal = \"Au\"\n",
            "r",
            "0.25",
        ),
        (
            "spectral:dielectric",
            "            float inputs:ior = 1.33\n",
            "r",
            "0.25",
        ),
        (
            "spectral:plastic",
            "            color3f inputs:reflectance = (0.2, 0.5, 0.3)\n",
            "r",
            "0.25",
        ),
        (
            "spectral:diffuse",
            "            color3f inputs:reflectance = (0.2, 0.5, 0.3)\n",
            "g",
            "0.5",
        ),
    ];
    for (id, inputs, channel, value) in cases {
        let textured = spectral_stage(
            1.0,
            "alpha.exr",
            raw,
            id,
            &format!("{inputs}{}", rough(channel)),
        );
        let constant = format!("{inputs}            float inputs:roughness = {value}\n");
        let constant = spectral_stage(1.0, "alpha.exr", raw, id, &constant);
        let (a, b) = (
            load_scene(&dir, "textured.usda", &textured),
            load_scene(&dir, "constant.usda", &constant),
        );
        println!("{id}");
        for (x, y) in POINTS {
            assert_same_bsdf(&a, &b, x, y);
        }
    }
}

#[test]
fn a_texture_on_a_spectral_input_that_takes_only_a_value_is_an_error() {
    let dir = temp_dir("tex-spectral-bad");
    quadrant_png(&dir.join("checker.png"), [[0, 0, 0, 255]; 4]);
    let ior = "            float inputs:ior.connect = </Looks/Paint/Tex.outputs:r>\n";
    let stage = spectral_stage(1.0, "checker.png", "", "spectral:plastic", ior);
    assert_cli_error(
        &dir,
        &stage,
        &[
            "bad.usda",
            "/Looks/Paint/S",
            "inputs:ior",
            "spectral:plastic",
        ],
    );
}

// ---- Texture-coordinate primvars and UsdTransform2d ---------------------------------------

#[test]
fn a_texture_reads_the_primvar_its_reader_names() {
    let dir = temp_dir("tex-st1");
    quadrant_png(&dir.join("checker.png"), CHECKER);
    // primvars:st is mirrored; the texture must read the faceVarying, indexed primvars:st1.
    let st = "    texCoord2f[] primvars:st = [(3, -2), (-2, -2), (-2, 3), (3, 3)] (\n        interpolation = \"vertex\"\n    )\n    float2[] primvars:st1 = [(-2, -2), (3, -2), (3, 3), (-2, 3)] (\n        interpolation = \"faceVarying\"\n    )\n    int[] primvars:st1:indices = [0, 1, 2, 3]\n";
    let stage = textured_stage_st(20.0, "checker.png", RAW, DIFFUSE_CONNECTED, st).replace(
        "token inputs:varname = \"st\"",
        "token inputs:varname = \"st1\"",
    );
    assert_quadrants(&dir, &stage, 20.0, CHECKER, 32);
}

#[test]
fn usd_transform2d_nodes_transform_st_in_the_spec_order() {
    let dir = temp_dir("tex-transform2d");
    quadrant_png(&dir.join("checker.png"), CHECKER);
    // Reader → T1 → T2 → Tex. The quad's authored st is (T2 ∘ T1)⁻¹ of the plain mapping, so
    // the texture sees the plain mapping only if each node computes in·scale, rotated, plus
    // translation, and the nodes compose in order.
    let (s1, r1, t1) = (Vec2::new(2.0, 0.5), 30.0f32, Vec2::new(0.3, -0.2));
    let (s2, r2, t2) = (Vec2::new(-1.0, 3.0), -75.0f32, Vec2::new(1.5, 0.25));
    let affine = |s, r: f32, t| glam::Affine2::from_scale_angle_translation(s, r.to_radians(), t);
    let inverse = (affine(s2, r2, t2) * affine(s1, r1, t1)).inverse();
    let st: Vec<String> = [(-2.0, -2.0), (3.0, -2.0), (3.0, 3.0), (-2.0, 3.0)]
        .iter()
        .map(|&(x, y)| {
            let p = inverse.transform_point2(Vec2::new(x, y));
            format!("({:.9}, {:.9})", p.x, p.y)
        })
        .collect();
    let st = format!(
        "    texCoord2f[] primvars:st = [{}] (\n        interpolation = \"vertex\"\n    )\n",
        st.join(", ")
    );
    let node = |name: &str, input: &str, s: Vec2, r: f32, t: Vec2| {
        format!(
            "        def Shader \"{name}\"\n        {{\n            uniform token info:id = \"UsdTransform2d\"\n            float2 inputs:in.connect = </Looks/Paint/{input}.outputs:result>\n            float2 inputs:scale = ({}, {})\n            float inputs:rotation = {r}\n            float2 inputs:translation = ({}, {})\n            float2 outputs:result\n        }}\n",
            s.x, s.y, t.x, t.y
        )
    };
    let nodes = node("T1", "Reader", s1, r1, t1) + &node("T2", "T1", s2, r2, t2);
    let stage = textured_stage_st(20.0, "checker.png", RAW, DIFFUSE_CONNECTED, &st)
        .replace(
            "float2 inputs:st.connect = </Looks/Paint/Reader.outputs:result>",
            "float2 inputs:st.connect = </Looks/Paint/T2.outputs:result>",
        )
        .replace(
            "        def Shader \"Tex\"\n",
            &format!("{nodes}        def Shader \"Tex\"\n"),
        );
    assert!(stage.contains("T2.outputs:result") && stage.contains("def Shader \"T1\""));
    assert_quadrants(&dir, &stage, 20.0, CHECKER, 32);
}

#[test]
fn an_srgb_decoded_normal_map_warns() {
    let dir = temp_dir("nmap-srgb");
    quadrant_png(&dir.join("normal.png"), [[128, 128, 255, 255]; 4]);
    let stage = textured_stage(1.0, "normal.png", "", NORMAL_CONNECTED);
    let scene = load_scene(&dir, "srgb.usda", &stage);
    let warnings = &scene.summary.warnings;
    assert!(
        warnings
            .iter()
            .any(|w| w.contains("/Looks/Paint/Tex") && w.contains("normal map decoded as sRGB")),
        "{warnings:?}"
    );
}

// ---- MIP-mapped filtering over the camera footprint ---------------------------------------

/// A 64×64 RGBA8 PNG of 8×8-texel black and white checks.
fn checker_png(path: &Path) {
    let mut bytes = Vec::new();
    for y in 0..64 {
        for x in 0..64 {
            let v = if (x / 8 + y / 8) % 2 == 0 { 255 } else { 0 };
            bytes.extend_from_slice(&[v, v, v, 255]);
        }
    }
    imageio::write_png_rgba8(path, &bytes, 64, 64).unwrap();
}

/// A floor 0.1 below a camera looking along −Z (field ±0.2), reaching 500 m away, with the
/// checker texture repeated every 0.4 m (checks of 5 cm), diffuse under a dome of `l` nits:
/// its radiance is ρ·l, and near the horizon a pixel covers many checks.
fn grazing_floor_stage(l: f32, file: &str) -> String {
    let st = "    texCoord2f[] primvars:st = [(-1250, 0), (1250, 0), (1250, -1250), (-1250, -1250)] (\n        interpolation = \"vertex\"\n    )\n";
    let tex = "            token inputs:sourceColorSpace = \"raw\"\n            token inputs:wrapS = \"repeat\"\n            token inputs:wrapT = \"repeat\"\n";
    let stage = textured_stage_st(l, file, tex, DIFFUSE_CONNECTED, st);
    // The floor: y = −0.1 from z = 0.99 to z = −499, x ∈ [−500, 500], facing +Y.
    let floor = "point3f[] points = [(-500, -0.1, 1), (500, -0.1, 1), (500, -0.1, -499), (-500, -0.1, -499)]";
    let start = stage.find("point3f[] points").unwrap();
    let end = start + stage[start..].find('\n').unwrap();
    format!("{}{floor}{}", &stage[..start], &stage[end..])
}

/// Per-pixel mean and variance across seeds of the green channel over `pixels`, for `spp`.
fn per_pixel_stats(
    scene: &Scene,
    pixels: &[usize],
    spp: u32,
    seeds: u64,
    filter_textures: bool,
) -> (Vec<f64>, f64) {
    let images: Vec<_> = (0..seeds)
        .map(|seed| {
            let opts = spectral_render::session::RenderOptions {
                spp: Some(spp),
                seed,
                max_depth: Some(3),
                filter_textures,
                ..Default::default()
            };
            let out = spectral_render::session::render(scene, &opts).unwrap();
            assert_finite(&out);
            out
        })
        .collect();
    let mut means = Vec::new();
    let mut var = 0.0;
    for &i in pixels {
        let (m, v) = mean_and_var(images.iter().map(|o| o.rgb[i][1]));
        var += v;
        means.push(m);
    }
    (means, var / pixels.len() as f64)
}

/// The checker's E[ρ²] and ρ̄ under bilinear lookups at finest level (ramps between checks
/// included), from a dense grid over one period.
fn checker_moments(file: &Path) -> (f64, f64) {
    let img = spectral_render::texture::ImageTexture::load(file, ColorSpace::Raw).unwrap();
    let (mut m1, mut m2, n) = (0.0, 0.0, 512);
    for j in 0..n {
        for i in 0..n {
            let uv = Vec2::new((i as f32 + 0.5) / n as f32, (j as f32 + 0.5) / n as f32);
            let r = f64::from(img.bilinear(uv, [Wrap::Repeat; 2])[1]);
            m1 += r;
            m2 += r * r;
        }
    }
    let k = (n * n) as f64;
    (m1 / k, m2 / k)
}

/// A checkerboard seen at grazing angles: at 4 spp the unfiltered floor near the horizon is
/// noise (each sample picks a black or white check), the filtered one is grey up to the
/// lighting noise.
///
/// Expected ratio: a sample is ρ·Y with Y the lighting estimate (mean L, E[Y²] = c L²),
/// independent of ρ. Filtered near the horizon, ρ = ρ̄ (coarse levels hold the mean), so
/// Var_f = ρ̄² (c − 1) L² / n, which gives c. Unfiltered, ρ is the texture at a random point
/// of a footprint spanning many checks: Var_u = (E[ρ²] c − ρ̄²) L² / n, with E[ρ²], ρ̄ of
/// the bilinear checker. The measured Var_u / Var_f must be that ratio within the sampling
/// error of variances from a few seeds (and footprints that span a finite number of checks,
/// which can only lower Var_u): we require ≥ 0.7 × predicted and ≥ 3. The means agree:
/// filtering averages the texture over the footprint without changing its mean.
#[test]
fn a_grazing_checkerboard_is_smooth_when_filtered_and_keeps_its_mean() {
    let l = 10.0f32;
    let dir = temp_dir("tex-mip-grazing");
    let file = dir.join("checks.png");
    checker_png(&file);
    let path = write(&dir, "floor.usda", &grazing_floor_stage(l, "checks.png"));
    let scene = spectral_render::scene::load(&path, Some((64, 64))).unwrap();
    // Rows 32..40 see the floor 0.3 to 6 m away at slopes of 0.3° to 3°: a pixel covers
    // 4 to 500 checks along z.
    let pixels: Vec<usize> = (32 * 64..40 * 64).collect();
    let (spp, seeds) = (4, 6);
    let (mean_f, var_f) = per_pixel_stats(&scene, &pixels, spp, seeds, true);
    let (mean_u, var_u) = per_pixel_stats(&scene, &pixels, spp, seeds, false);
    let (rho, rho2) = checker_moments(&file);
    let c = 1.0 + var_f * f64::from(spp) / (rho * rho * f64::from(l * l));
    let predicted = (rho2 * c - rho * rho) / (rho * rho * (c - 1.0));
    let ratio = var_u / var_f;
    eprintln!(
        "grazing checker: Var_u {var_u:.4} Var_f {var_f:.4} ratio {ratio:.2} \
         (predicted {predicted:.2}, c = {c:.3}, rho {rho:.4}, E[rho²] {rho2:.4})"
    );
    assert!(
        ratio >= 0.7 * predicted && ratio >= 3.0,
        "{ratio} vs {predicted}"
    );
    // Means over the region: per-pixel means are independent across pixels.
    let stats = |m: &[f64]| mean_and_sem(m.iter().map(|&x| x as f32));
    let ((mf, sf), (mu, su)) = (stats(&mean_f), stats(&mean_u));
    let tol = 4.0 * (sf * sf + su * su).sqrt();
    eprintln!("means: filtered {mf:.4} ± {sf:.4}, unfiltered {mu:.4} ± {su:.4}");
    assert!((mf - mu).abs() < tol, "{mf} vs {mu} (tol {tol})");
    let expected = rho * f64::from(l);
    assert!(
        (mf - expected).abs() < 6e-3 * f64::from(l) + 4.0 * sf,
        "{mf} vs {expected}"
    );
}

/// Untextured materials get no footprint; textured ones a finite one, also on degenerate st,
/// and the footprint shrinks towards the camera and grows towards the horizon.
#[test]
fn footprints_are_finite_and_follow_distance() {
    use spectral_render::texture::TextureFilter;
    let dir = temp_dir("tex-mip-footprint");
    checker_png(&dir.join("checks.png"));
    let scene = load_scene(&dir, "floor.usda", &grazing_floor_stage(1.0, "checks.png"));
    let filter = TextureFilter::camera(Some(1));
    // Floor points straight below the given depth (the footprint depends on the point only).
    let hit = |z: f32| {
        let o = Vec3::new(0.0, 0.5, z);
        match scene.intersect(&Ray::new(o, Vec3::NEG_Y), f32::INFINITY) {
            Some(Hit::Surface(si)) => si,
            other => panic!("{other:?}"),
        }
    };
    // Seen from the camera (0, 0, 1) at a slope 0.1/d, the footprint along z grows as d².
    let near = scene.tex_coord(&hit(0.5), filter);
    let far = scene.tex_coord(&hit(-20.0), filter);
    assert!(near.filter_width() > 0.0 && near.filter_width().is_finite());
    assert!(
        far.filter_width() > 100.0 * near.filter_width(),
        "{near:?} {far:?}"
    );
    assert_eq!(
        scene.tex_coord(&hit(0.5), TextureFilter::Finest),
        spectral_render::texture::TexCoord::point(hit(0.5).uv)
    );
    // Degenerate st (one point for the whole mesh) and a zero-area triangle: zero
    // derivatives, no NaN, and a filtered render stays finite.
    let stage = textured_stage_st(5.0, "checks.png", RAW, DIFFUSE_CONNECTED, "");
    let s = with_degenerate_mesh(&stage);
    let path = write(&dir, "bad.usda", &s);
    let bad = spectral_render::scene::load(&path, Some((16, 16))).unwrap();
    assert!(bad.materials[0].is_textured());
    for (x, y) in POINTS {
        let tc = bad.tex_coord(&surface_at(&bad, x, y), filter);
        assert_eq!((tc.duvdx, tc.duvdy), (Vec2::ZERO, Vec2::ZERO), "{tc:?}");
    }
    render_file(&path, (16, 16), 2, Some(3), None);
}
