//! Light-transport checks with closed-form answers: the white furnace, the reflectance round
//! trip under a uniform D65 dome, and determinism across thread counts.

mod common;
use common::*;

/// A closed cube (half-size 1) whose walls all emit `le` nits (double-sided, so winding does
/// not matter) and reflect a spectrally flat 0.8; the camera sits inside.
fn furnace_stage(le: f32) -> String {
    let flat = "        float2[] inputs:reflectance:samples = [(360, 0.8), (830, 0.8)]\n";
    let light = format!("    float inputs:intensity = {le}\n{}", binding("Wall"));
    // Six faces of the cube [-1, 1]³.
    let faces = [
        "(-1, -1, -1), (-1, 1, -1), (1, 1, -1), (1, -1, -1)",
        "(-1, -1, 1), (1, -1, 1), (1, 1, 1), (-1, 1, 1)",
        "(-1, -1, -1), (-1, -1, 1), (-1, 1, 1), (-1, 1, -1)",
        "(1, -1, -1), (1, 1, -1), (1, 1, 1), (1, -1, 1)",
        "(-1, -1, -1), (1, -1, -1), (1, -1, 1), (-1, -1, 1)",
        "(-1, 1, -1), (-1, 1, 1), (1, 1, 1), (1, 1, -1)",
    ];
    let mut s = header();
    s += &camera(0.5, 0.8, 0.0);
    s += "def Scope \"Looks\"\n{\n";
    s += &material("Wall", "spectral:diffuse", flat);
    s += "}\n\n";
    for (i, f) in faces.iter().enumerate() {
        s += &format!(
            "def Mesh \"Face{i}\" (\n    prepend apiSchemas = [\"MeshLightAPI\", \"MaterialBindingAPI\"]\n)\n{{\n    uniform bool doubleSided = 1\n    int[] faceVertexCounts = [4]\n    int[] faceVertexIndices = [0, 1, 2, 3]\n    point3f[] points = [{f}]\n{light}}}\n\n"
        );
    }
    s
}

#[test]
fn white_furnace_reads_le_over_one_minus_albedo() {
    let le = 2.0f32;
    let dir = temp_dir("furnace");
    let path = write(&dir, "furnace.usda", &furnace_stage(le));
    let out = render_file(&path, (16, 16), 1024, 10_000, None);
    let expected = le as f64 / (1.0 - 0.8);
    let (mean, sem) = mean_and_sem(out.xyz.iter().map(|p| p[1]));
    // The bound is 1 %; the statistical error of this mean must be far below it.
    assert!(sem / expected < 2e-3, "too noisy to judge: sem {sem}");
    assert!(
        (mean / expected - 1.0).abs() < 0.01,
        "furnace Y = {mean}, expected {expected}"
    );
}

/// A Lambertian plane with `inputs` under a constant dome of `l` nits, seen head-on.
fn dome_plane_stage(shader_id: &str, inputs: &str, l: f32) -> String {
    let mut s = header();
    s += &camera(1.0, 0.2, 0.0);
    s += &format!("def DomeLight \"Sky\"\n{{\n    float inputs:intensity = {l}\n}}\n\n");
    s += "def Scope \"Looks\"\n{\n";
    s += &material("Paint", shader_id, inputs);
    s += "}\n\n";
    s += &quad(
        "Plane",
        0.0,
        1.0,
        &binding("Paint"),
        "\"MaterialBindingAPI\"",
    );
    s
}

#[test]
fn preview_surface_colour_round_trips_under_d65() {
    let l = 50.0f32;
    let dir = temp_dir("roundtrip");
    for c in [
        [0.8f32, 0.2, 0.1],
        [0.1, 0.6, 0.3],
        [0.5, 0.5, 0.5],
        [0.05, 0.1, 0.9],
    ] {
        // IOR 1 turns off the specular coat of the (complete) UsdPreviewSurface mapping, so
        // the surface is exactly Lambertian with albedo diffuseColor.
        let inputs = format!(
            "        color3f inputs:diffuseColor = ({}, {}, {})\n        float inputs:ior = 1\n",
            c[0], c[1], c[2]
        );
        let path = write(
            &dir,
            "plane.usda",
            &dome_plane_stage("UsdPreviewSurface", &inputs, l),
        );
        let out = render_file(&path, (24, 24), 64, 7, None);
        for ch in 0..3 {
            let (mean, sem) = mean_and_sem(out.rgb.iter().map(|p| p[ch]));
            let expected = (l * c[ch]) as f64;
            let tol = 1e-3 * expected + 5.0 * sem;
            assert!(
                (mean - expected).abs() < tol,
                "colour {c:?} channel {ch}: {mean} vs {expected} (sem {sem})"
            );
        }
    }
}

#[test]
fn one_and_two_threads_give_bit_identical_images() {
    let cbox = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../shared/peers/cbox.usda");
    let scene = spectral_render::scene::load(&cbox, Some((32, 32))).unwrap();
    let run = |threads| {
        let opts = spectral_render::render::RenderOptions {
            spp: Some(8),
            seed: 3,
            threads: Some(threads),
            ..Default::default()
        };
        let out = spectral_render::render::render(&scene, &opts).unwrap();
        assert_finite(&out);
        out
    };
    let (a, b) = (run(1), run(2));
    let bits = |o: &spectral_render::render::RenderOutput| {
        o.xyz
            .iter()
            .flatten()
            .map(|v| v.to_bits())
            .collect::<Vec<_>>()
    };
    assert_eq!(bits(&a), bits(&b));
    assert!(a.xyz.iter().any(|p| p[1] > 0.0), "the image is black");
}
