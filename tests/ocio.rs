//! The preview's OCIO display transforms (`output/ocio.rs`, the pure-Rust `ocio` crate)
//! against PyOpenColorIO (`tools/ocio_reference.py`, in the venv `tools/venv.sh` makes): every
//! display/view pair of the shipped config, from every working space, on a grid of
//! scene-linear values. Code values (clamped to 0–1, as the PNG stores them) must agree within
//! 1e-3.

mod common;
use common::*;
use spectral_render::output::ocio::OcioConfig;
use spectral_render::spectral::working_space::WorkingSpace;
use std::path::Path;
use std::process::Command;

/// Per channel: black, shadows, middle grey, white, highlights far above white, and a small
/// negative (a saturated colour outside the working space's gamut).
const LEVELS: [f32; 10] = [-0.02, 0.0, 0.002, 0.02, 0.09, 0.18, 0.5, 1.0, 4.0, 64.0];

const TOLERANCE: f32 = 1e-3;

fn grid() -> Vec<[f32; 3]> {
    let mut g = Vec::new();
    for r in LEVELS {
        for gr in LEVELS {
            for b in LEVELS {
                g.push([r, gr, b]);
            }
        }
    }
    g
}

#[test]
fn display_transforms_match_pyopencolorio_within_1e_3() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    colour_science_venv();
    let config = OcioConfig::shipped();
    let grid = grid();
    let mut transforms = Vec::new();
    for space in WorkingSpace::ALL {
        for display in config.displays() {
            for view in config.views(&display) {
                transforms.push((space.ocio_name(), display.clone(), view));
            }
        }
    }
    assert!(
        transforms.len() >= 4 * 30,
        "{} transforms",
        transforms.len()
    );

    let json_list = |v: &[String]| format!("[{}]", v.join(", "));
    let request = format!(
        "{{\"config\": {:?}, \"grid\": {}, \"transforms\": {}}}",
        root.join("assets/ocio/cg-config-v4.0.0_aces-v2.0_ocio-v2.5.ocio")
            .display()
            .to_string(),
        json_list(
            &grid
                .iter()
                .map(|p| format!("[{:?}, {:?}, {:?}]", p[0], p[1], p[2]))
                .collect::<Vec<_>>()
        ),
        json_list(
            &transforms
                .iter()
                .map(|(s, d, v)| format!("[{s:?}, {d:?}, {v:?}]"))
                .collect::<Vec<_>>()
        ),
    );
    let dir = temp_dir("ocio");
    let request_path = write(&dir, "request.json", &request);
    let answer_path = dir.join("answer.json");
    let run = Command::new(root.join(".venv/bin/python"))
        .arg(root.join("tools/ocio_reference.py"))
        .arg(&request_path)
        .arg(&answer_path)
        .output()
        .expect("run tools/ocio_reference.py");
    assert!(
        run.status.success(),
        "ocio_reference.py failed: {}",
        String::from_utf8_lossy(&run.stderr)
    );
    let answer: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&answer_path).unwrap()).unwrap();
    let results = answer["results"].as_array().unwrap();
    assert_eq!(results.len(), transforms.len());

    let code = |v: f32| if v.is_nan() { 0.0 } else { v.clamp(0.0, 1.0) };
    let mut worst = 0.0f32;
    let mut failures = Vec::new();
    for ((space, display, view), reference) in transforms.iter().zip(results) {
        let t = config
            .display_transform(space, Some(display), Some(view))
            .unwrap_or_else(|e| panic!("{space} → {display} / {view}: {e}"));
        let mut ours = grid.clone();
        t.apply(&mut ours);
        // The comparison is not vacuous: a tone-mapped view changes the values.
        if view.starts_with("ACES 2.0") {
            assert!(
                ours.iter().zip(&grid).any(|(o, g)| o != g),
                "{view} is the identity"
            );
        }
        let mut max = 0.0f32;
        let mut at = 0;
        for (i, (o, r)) in ours.iter().zip(reference.as_array().unwrap()).enumerate() {
            for c in 0..3 {
                let r = r[c].as_f64().unwrap() as f32;
                let e = (code(o[c]) - code(r)).abs();
                if e > max {
                    (max, at) = (e, i);
                }
            }
        }
        println!("{space} → {display} / {view}: max |Δ code value| {max:.2e}");
        worst = worst.max(max);
        if max > TOLERANCE {
            failures.push(format!(
                "{space} → {display} / {view}: {max:.2e} at {:?}",
                grid[at]
            ));
        }
    }
    println!(
        "{} transforms × {} values: max |Δ code value| {worst:.2e} (PyOpenColorIO {})",
        transforms.len(),
        grid.len(),
        answer["version"]
    );
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
