//! Light-transport checks with closed-form answers: the white furnace, the reflectance round
//! trip under a uniform D65 dome, and determinism across thread counts.

mod common;
use common::*;

#[test]
fn white_furnace_reads_le_over_one_minus_albedo() {
    let le = 2.0f32;
    let dir = temp_dir("furnace");
    let path = write(&dir, "furnace.usda", &furnace_stage(le, 0.8));
    let out = render_file(&path, (16, 16), 1024, None, None);
    let expected = le as f64 / (1.0 - 0.8);
    let (mean, sem) = mean_and_sem(out.xyz.iter().map(|p| p[1]));
    // The bound is 1 %; the statistical error of this mean must be far below it.
    assert!(sem / expected < 2e-3, "too noisy to judge: sem {sem}");
    assert!(
        (mean / expected - 1.0).abs() < 0.01,
        "furnace Y = {mean}, expected {expected}"
    );
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
            &dome_plane_stage(
                l,
                &looks_scope(&material("Paint", "UsdPreviewSurface", &inputs)),
                "",
            ),
        );
        let out = render_file(&path, (24, 24), 64, Some(7), None);
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
    let scene = spectral_render::scene::load(&cbox_path(), Some((32, 32))).unwrap();
    let run = |threads| {
        let opts = spectral_render::session::RenderOptions {
            spp: Some(8),
            seed: 3,
            threads: Some(threads),
            ..Default::default()
        };
        let out = spectral_render::session::render(&scene, &opts).unwrap();
        assert_finite(&out);
        out
    };
    let (a, b) = (run(1), run(2));
    let bits = |o: &spectral_render::session::RenderOutput| {
        o.xyz
            .iter()
            .flatten()
            .map(|v| v.to_bits())
            .collect::<Vec<_>>()
    };
    assert_eq!(bits(&a), bits(&b));
    assert!(a.xyz.iter().any(|p| p[1] > 0.0), "the image is black");
}
