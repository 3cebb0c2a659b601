//! UsdLux gaps closed in issue 16.
//!
//! Non-uniformly scaled (or sheared) sphere, disk and cylinder lights are refused with an
//! error naming the scale, never rounded; light filters are named in the warning.
//!
//! A textured RectLight (`inputs:texture:file`) against closed forms, through next
//! event estimation (path), light subpaths (light tracing) and BDPT:
//! - a uniform texture of value v reads exactly v times the untextured light (same seed, same
//!   random numbers: only rounding differs);
//! - a texture black on its left half and white on its right half reads half the white
//!   light's illuminance straight below the centre (the bilinear, clamped lookup f satisfies
//!   f(a) + f(1 − a) = 1, and the set-up is symmetric under a ↔ 1 − a), and more under the
//!   white half (+X) than under the black one, and two mirrored points add up to the white
//!   light's reading.

mod common;
use common::*;
use spectral_render::output::exr;
use spectral_render::scene;
use spectral_render::session::{measure, MeterOptions, Stop};
use spectral_render::{Integrator, Meter};
use std::path::Path;

/// A 1 m square RectLight 1 m above the origin, facing down, with `texture` (or none).
fn stage(intensity: f32, texture: Option<&str>) -> String {
    let tex = texture.map_or(String::new(), |t| {
        format!("    asset inputs:texture:file = @{t}@\n")
    });
    format!(
        "{}def RectLight \"panel\" {{\n    float inputs:intensity = {intensity}\n{tex}    \
         double3 xformOp:translate = (0, 1, 0)\n    float xformOp:rotateX = -90\n    \
         uniform token[] xformOpOrder = [\"xformOp:translate\", \"xformOp:rotateX\"]\n}}\n",
        header()
    )
}

/// A float EXR of `w` × 1 texels.
fn texture(dir: &Path, name: &str, texels: &[[f32; 3]]) {
    exr::write(
        &dir.join(name),
        texels.len(),
        1,
        texels,
        texels,
        [0.3127, 0.329],
        &Default::default(),
    )
    .unwrap();
}

/// Illuminance readings (value, ci95) at `points` (facing up) with `integrator`.
fn lux(dir: &Path, text: &str, points: &[[f32; 3]], integrator: &str) -> Vec<(f64, f64)> {
    let path = write(dir, "stage.usda", text);
    let scene = scene::load(&path, Some((1, 1))).unwrap_or_else(|e| panic!("{e}"));
    assert!(
        scene.summary.warnings.is_empty(),
        "{:?}",
        scene.summary.warnings
    );
    let meters: Vec<Meter> = points
        .iter()
        .map(|p| Meter::illuminance((*p).into(), glam::Vec3::Y).unwrap())
        .collect();
    let opts = MeterOptions {
        stop: Stop::Samples(1 << 15),
        seed: 3,
        max_depth: Some(1),
        integrator: Integrator::from_name(integrator).unwrap(),
        ..MeterOptions::default()
    };
    let run = measure(&scene, &meters, &opts).unwrap_or_else(|e| panic!("{e}"));
    run.readings.iter().map(|r| (r.value, r.ci95)).collect()
}

const INTEGRATORS: [&str; 3] = ["path", "light", "bdpt"];

#[test]
fn a_uniform_texture_scales_the_light_by_its_value() {
    let dir = temp_dir("rect-texture-uniform");
    let v = 0.3f32;
    texture(&dir, "grey.exr", &[[v; 3]]);
    let points = [[0.0, 0.0, 0.0], [0.4, 0.0, -0.2]];
    for integrator in INTEGRATORS {
        let textured = lux(&dir, &stage(10.0, Some("grey.exr")), &points, integrator);
        let scaled = lux(&dir, &stage(10.0 * v, None), &points, integrator);
        for (t, s) in textured.iter().zip(&scaled) {
            assert!(t.0 > 0.0, "{integrator}: no light");
            assert!(
                (t.0 / s.0 - 1.0).abs() < 1e-5,
                "{integrator}: textured {} vs untextured × v {}",
                t.0,
                s.0
            );
        }
    }
}

#[test]
fn a_half_black_texture_halves_the_reading_below_the_centre() {
    let dir = temp_dir("rect-texture-half");
    texture(&dir, "white.exr", &[[1.0; 3]]);
    texture(&dir, "half.exr", &[[0.0; 3], [1.0; 3]]);
    let points = [[0.0, 0.0, 0.0], [0.3, 0.0, 0.0], [-0.3, 0.0, 0.0]];
    for integrator in INTEGRATORS {
        let white = lux(&dir, &stage(10.0, Some("white.exr")), &points, integrator);
        let half = lux(&dir, &stage(10.0, Some("half.exr")), &points, integrator);
        // The two readings share their random numbers, so the sum of their ci95 bounds
        // the ci95 of their difference; twice that is over 4 σ.
        let (w, h) = (white[0], half[0]);
        let bound = 2.0 * (h.1 + 0.5 * w.1);
        assert!(
            (h.0 - 0.5 * w.0).abs() < bound,
            "{integrator}: {} vs half of {} (bound {bound})",
            h.0,
            w.0
        );
        assert!(
            bound < 0.05 * h.0,
            "{integrator}: too noisy to tell ({bound})"
        );
        // st's u runs along the light's local +X (world +X here): brighter under the white
        // half, and the two mirrored points add up to the white light's reading at either
        // (f(a) + f(1 − a) = 1 again).
        assert!(half[1].0 > 1.3 * half[2].0, "{integrator}: {half:?}");
        let sides = half[1].0 + half[2].0;
        let bound = 2.0 * (half[1].1 + half[2].1 + white[1].1);
        assert!(
            (sides - white[1].0).abs() < bound,
            "{integrator}: {sides} vs {white:?}"
        );
    }
}

#[test]
fn an_empty_texture_path_is_no_texture_and_the_report_uses_the_mean() {
    let dir = temp_dir("rect-texture-report");
    texture(&dir, "half.exr", &[[0.0; 3], [1.0; 3]]);
    let plain = write(&dir, "plain.usda", &stage(10.0, Some("")));
    let scene = scene::load(&plain, Some((1, 1))).unwrap();
    assert!(
        scene.summary.warnings.is_empty(),
        "{:?}",
        scene.summary.warnings
    );
    let textured = write(&dir, "textured.usda", &stage(10.0, Some("half.exr")));
    let half = scene::load(&textured, Some((1, 1))).unwrap();
    let flux = |s: &scene::Scene| spectral_render::report::report(&s.lights)[0].luminous_flux;
    let (a, b) = (flux(&scene).unwrap(), flux(&half).unwrap());
    assert!((b / a - 0.5).abs() < 1e-3, "flux {b} vs half of {a}");
}

/// Loads `body` (after the header) and returns the error.
fn load_error(name: &str, body: &str) -> String {
    let dir = temp_dir(name);
    let path = write(&dir, "stage.usda", &format!("{}{body}", header()));
    match scene::load(&path, Some((1, 1))) {
        Ok(_) => panic!("{name}: loaded"),
        Err(e) => e.to_string(),
    }
}

#[test]
fn non_uniformly_scaled_round_lights_are_refused() {
    let scaled = |ty: &str, scale: &str| {
        format!(
            "def {ty} \"lamp\" {{\n    float3 xformOp:scale = ({scale})\n    \
             uniform token[] xformOpOrder = [\"xformOp:scale\"]\n}}\n"
        )
    };
    for (ty, scale, shape) in [
        ("SphereLight", "1, 2, 1", "an ellipsoid"),
        ("DiskLight", "1, 3, 1", "an ellipse"),
        ("CylinderLight", "1, 1, 2", "an ellipse"),
    ] {
        let e = load_error(ty, &scaled(ty, scale));
        assert!(
            e.contains("/lamp: the transform scales this") && e.contains(shape),
            "{ty}: {e}"
        );
    }
    // Scales that keep the shape round load: uniform, a disk's Z, a cylinder's length.
    for (ty, scale) in [
        ("SphereLight", "2, 2, 2"),
        ("DiskLight", "2, 2, 5"),
        ("CylinderLight", "3, 2, 2"),
    ] {
        let dir = temp_dir("round");
        let path = write(
            &dir,
            "stage.usda",
            &format!("{}{}", header(), scaled(ty, scale)),
        );
        scene::load(&path, Some((1, 1))).unwrap_or_else(|e| panic!("{ty} {scale}: {e}"));
    }
}

#[test]
fn light_filters_are_named_in_the_warning() {
    let dir = temp_dir("filters");
    let body = "def SphereLight \"lamp\" {\n    rel light:filters = [</f1>, </f2>]\n}\n\
                def LightFilter \"f1\" {}\ndef LightFilter \"f2\" {}\n";
    let path = write(&dir, "stage.usda", &format!("{}{body}", header()));
    let scene = scene::load(&path, Some((1, 1))).unwrap();
    let w = scene.summary.warnings.join("; ");
    assert!(
        w.contains("light filters are not supported; ignored: /f1, /f2"),
        "{w}"
    );
}
