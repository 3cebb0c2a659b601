//! Absolute calibration: an emitter of L nits seen directly reads L cd/m², with the light's
//! and the camera's exposure; a white emitter gives RGB (L, L, L).

mod common;
use common::*;

const L: f32 = 100.0;

/// Per-pixel luminance of a camera looking straight at a large white RectLight.
fn direct_view(
    light_exposure: f32,
    camera_exposure: f32,
) -> spectral_render::session::RenderOutput {
    let dir = temp_dir("direct");
    let text = format!(
        "{}{}def RectLight \"Panel\"\n{{\n    float inputs:width = 4\n    float inputs:height = 4\n    float inputs:intensity = {L}\n    float inputs:exposure = {light_exposure}\n}}\n",
        header(),
        camera(1.0, 0.5, camera_exposure)
    );
    // A RectLight emits along its local −Z; the camera at z = 1 looks down −Z, so rotate
    // the panel to face +Z.
    let text = text.replace(
        "    float inputs:exposure",
        "    float3 xformOp:rotateXYZ = (0, 180, 0)\n    uniform token[] xformOpOrder = [\"xformOp:rotateXYZ\"]\n    float inputs:exposure",
    );
    let path = write(&dir, "direct.usda", &text);
    render_file(&path, (8, 8), 4096, Some(5), None)
}

/// Each pixel's luminance is an average of 4096 × 4 wavelength samples of K_m L(λ)ȳ(λ)/p(λ)
/// (per-pixel standard deviation ≈ 0.08 %, measured from the spread over pixels), so every
/// pixel is held to the 0.5 % (> 5σ) and the mean to a bound from its standard error.
fn check_luminance(out: &spectral_render::session::RenderOutput, expected: f64) {
    let (mean, sem) = mean_and_sem(out.xyz.iter().map(|p| p[1]));
    assert!(
        (mean / expected - 1.0).abs() < 1e-3 + 5.0 * sem / expected,
        "mean Y {mean} vs {expected} (sem {sem})"
    );
    let sigma_pixel = sem * (out.xyz.len() as f64).sqrt();
    assert!(
        5.0 * sigma_pixel < 5e-3 * expected,
        "too noisy to judge pixels: sigma {sigma_pixel}"
    );
    for (i, p) in out.xyz.iter().enumerate() {
        let rel = (p[1] as f64 / expected - 1.0).abs();
        assert!(rel < 5e-3, "pixel {i}: Y = {} vs {expected}", p[1]);
    }
}

#[test]
fn directly_seen_emitter_reads_its_luminance() {
    let out = direct_view(0.0, 0.0);
    check_luminance(&out, L as f64);
    // White (1,1,1) is D65: equal RGB.
    let (r, _) = mean_and_sem(out.rgb.iter().map(|p| p[0]));
    let (b, _) = mean_and_sem(out.rgb.iter().map(|p| p[2]));
    assert!(
        (r / L as f64 - 1.0).abs() < 5e-3 && (b / L as f64 - 1.0).abs() < 5e-3,
        "rgb {r} {b}"
    );
}

#[test]
fn light_exposure_scales_by_powers_of_two() {
    check_luminance(&direct_view(1.5, 0.0), L as f64 * 2f64.powf(1.5));
}

#[test]
fn camera_exposure_scales_by_powers_of_two() {
    check_luminance(&direct_view(0.0, -2.0), L as f64 * 0.25);
}
