//! The ColorChecker under a uniform D65 dome, checked against colour-science: each patch's
//! rendered XYZ must be within ΔE2000 < 1 of `sd_to_XYZ(reflectance × D65 at luminance L)`.
//! The reference side is `tools/check_colorchecker.py`, run in the venv `tools/venv.sh` makes.

mod common;
use common::*;
use std::path::Path;

/// colour-science's patch order, row by row from the top left (scenes/colorchecker.usda).
const PATCHES: [&str; 24] = [
    "dark_skin",
    "light_skin",
    "blue_sky",
    "foliage",
    "blue_flower",
    "bluish_green",
    "orange",
    "purplish_blue",
    "moderate_red",
    "purple",
    "yellow_green",
    "orange_yellow",
    "blue",
    "green",
    "red",
    "yellow",
    "magenta",
    "cyan",
    "white_9_5",
    "neutral_8",
    "neutral_6_5",
    "neutral_5",
    "neutral_3_5",
    "black_2",
];
/// Dome luminance authored in the scene (cd/m²).
const DOME_NITS: f64 = 100.0;
const WIDTH: usize = 240;
const HEIGHT: usize = 160;

/// Mean XYZ over the central 20 × 20 pixels of patch `i` (layout in the scene file: patches
/// 0.05 m wide on a 0.06 m pitch, the camera's half-width is 0.2 m at 1 m).
fn patch_xyz(xyz: &[[f32; 3]], i: usize) -> [f64; 3] {
    let (row, col) = (i / 6, i % 6);
    let x = (col as f64 - 2.5) * 0.06;
    let y = (1.5 - row as f64) * 0.06;
    let half_h = 0.2 * HEIGHT as f64 / WIDTH as f64;
    let cx = ((x / 0.2 + 1.0) * 0.5 * WIDTH as f64) as usize;
    let cy = ((1.0 - y / half_h) * 0.5 * HEIGHT as f64) as usize;
    let mut sum = [0.0f64; 3];
    for py in cy - 10..cy + 10 {
        for px in cx - 10..cx + 10 {
            for c in 0..3 {
                sum[c] += xyz[py * WIDTH + px][c] as f64;
            }
        }
    }
    sum.map(|s| s / 400.0)
}

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
            let [x, y, z] = patch_xyz(&out.xyz, i);
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
