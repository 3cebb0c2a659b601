//! The numerically hard corpus `scenes/hard/` (grazing light and view, total internal
//! reflection, IOR 1.0001, roughness 1e-4, 0.1 mm and 200 km scales, degenerate triangles,
//! a 1e9-nit bulb, cameras inside a mesh and inside glass, extreme shaping) through every
//! integrator, as images and as illuminance meters, from the library and from the command
//! line: not one sample may be dropped as non-finite. Each stage names its meter in its
//! `customLayerData` (`string meter = "x,y,z nx,ny,nz"`, stage coordinates).

mod common;

use common::{spectral_render, stderr, temp_dir};
use glam::DVec3;
use spectral_render::scene::{self, Scene};
use spectral_render::sensor::meter::{stage_normal, stage_point};
use spectral_render::session::{self, MeterOptions, RenderOptions, Stop};
use spectral_render::{Integrator, Meter};
use std::path::{Path, PathBuf};

fn corpus() -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/hard");
    let mut stages: Vec<PathBuf> = std::fs::read_dir(dir)
        .unwrap()
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.extension().is_some_and(|e| e == "usda"))
        .collect();
    stages.sort();
    assert!(stages.len() >= 10, "{stages:?}");
    stages
}

/// The stage's meter: (point, normal) as written, in stage coordinates.
fn meter_of(stage: &Path) -> (String, String) {
    let text = std::fs::read_to_string(stage).unwrap();
    let line = text
        .lines()
        .find_map(|l| l.trim().strip_prefix("string meter = \""))
        .unwrap_or_else(|| panic!("{} names no meter", stage.display()));
    let (at, normal) = line.trim_end_matches('"').split_once(' ').unwrap();
    (at.to_string(), normal.to_string())
}

fn parse(v: &str) -> DVec3 {
    let c: Vec<f64> = v.split(',').map(|x| x.parse().unwrap()).collect();
    DVec3::new(c[0], c[1], c[2])
}

fn meter(scene: &Scene, stage: &Path) -> Meter {
    let (at, normal) = meter_of(stage);
    let m = &scene.stage_to_world;
    Meter::illuminance(stage_point(m, parse(&at)), stage_normal(m, parse(&normal))).unwrap()
}

#[test]
fn every_integrator_keeps_every_sample_finite() {
    for stage in corpus() {
        let scene = scene::load(&stage, Some((32, 32))).unwrap_or_else(|e| panic!("{e}"));
        for integrator in Integrator::ALL {
            let opts = RenderOptions {
                spp: Some(16),
                seed: 3,
                integrator,
                ..Default::default()
            };
            let out = session::render(&scene, &opts).unwrap();
            let what = format!("{} with {}", stage.display(), integrator.name());
            assert_eq!(out.dropped_samples, 0, "{what}: non-finite samples");
            let finite = out
                .xyz
                .iter()
                .chain(&out.rgb)
                .flatten()
                .all(|v| v.is_finite());
            assert!(finite, "{what}: a non-finite pixel");
            if !integrator.capabilities().illuminance_meters {
                continue;
            }
            let opts = MeterOptions {
                stop: Stop::Samples(4096),
                seed: 3,
                integrator,
                ..Default::default()
            };
            let run = session::measure(&scene, &[meter(&scene, &stage)], &opts).unwrap();
            assert_eq!(run.dropped, 0, "{what}: non-finite meter samples");
            let r = run.readings[0];
            assert!(
                r.value.is_finite() && r.value >= 0.0 && r.ci95.is_finite(),
                "{what}: {r:?}"
            );
        }
    }
}

#[test]
fn the_command_line_reports_no_dropped_samples() {
    let dir = temp_dir("hard");
    for stage in corpus() {
        let path = stage.to_str().unwrap();
        let (at, normal) = meter_of(&stage);
        for integrator in Integrator::ALL {
            let name = integrator.name();
            let out_exr = dir.join("out.exr");
            let image = [
                path,
                "--integrator",
                name,
                "--resolution",
                "8x8",
                "--spp",
                "4",
                "-o",
            ];
            let mut args: Vec<&str> = image.to_vec();
            args.push(out_exr.to_str().unwrap());
            let meter = [
                "meter",
                path,
                "--at",
                &at,
                "--normal",
                &normal,
                "--spp",
                "1024",
                "--integrator",
                name,
            ];
            let meters = integrator.capabilities().illuminance_meters;
            for args in [&args[..], &meter[..]]
                .into_iter()
                .take(if meters { 2 } else { 1 })
            {
                let out = spectral_render(args, &dir);
                let err = stderr(&out);
                assert!(out.status.success(), "{args:?}: {err}");
                assert!(!err.contains("non-finite"), "{args:?}: {err}");
            }
        }
    }
}
