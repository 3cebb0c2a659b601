//! The ColorChecker under a uniform D65 dome, checked against colour-science: each patch's
//! rendered XYZ must be within ΔE2000 < 1 of `sd_to_XYZ(reflectance × D65 at luminance L)`.
//! The reference side is `tools/check_colorchecker.py`, run in the venv `tools/venv.sh` makes.

mod common;
use common::colorchecker::{patch_xyz, PATCHES};
use common::*;
use std::path::Path;

/// Dome luminance authored in the scene (cd/m²).
const DOME_NITS: f64 = 100.0;
const WIDTH: usize = 240;
const HEIGHT: usize = 160;

#[test]
fn colorchecker_matches_colour_science_within_delta_e_1() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    colour_science_venv();

    let out = render_file(
        &root.join("scenes/colorchecker.usda"),
        (WIDTH as u32, HEIGHT as u32),
        64,
        Some(5),
        None,
    );
    let patches: Vec<String> = PATCHES
        .iter()
        .enumerate()
        .map(|(i, name)| {
            let [x, y, z] = patch_xyz(&out.xyz, WIDTH, HEIGHT, i, 10);
            format!("\"{name}\": [{x}, {y}, {z}]")
        })
        .collect();
    let json = format!(
        "{{\"luminance\": {DOME_NITS}, \"patches\": {{{}}}}}",
        patches.join(", ")
    );
    let dir = temp_dir("colorchecker");
    let json_path = write(&dir, "patches.json", &json);

    let (passed, report) = colour_science_check("check_colorchecker.py", &json_path);
    println!("{report}");
    assert!(passed, "ColorChecker check failed:\n{report}");
}
