//! The ColorChecker of scenes/colorchecker.usda as the tests read it: its patches in
//! colour-science's order and the mean XYZ of a window at a patch's centre.

/// colour-science's patch order, row by row from the top left (scenes/colorchecker.usda).
pub const PATCHES: [&str; 24] = [
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

/// Mean XYZ over the central 2k × 2k pixels of patch `i` in a `width` × `height` render of
/// the scene's camera (layout in the scene file: patches 0.05 m wide on a 0.06 m pitch, the
/// camera's half-width is 0.2 m at 1 m).
pub fn patch_xyz(xyz: &[[f32; 3]], width: usize, height: usize, i: usize, k: usize) -> [f64; 3] {
    let (row, col) = (i / 6, i % 6);
    let x = (col as f64 - 2.5) * 0.06;
    let y = (1.5 - row as f64) * 0.06;
    let half_h = 0.2 * height as f64 / width as f64;
    let cx = ((x / 0.2 + 1.0) * 0.5 * width as f64) as usize;
    let cy = ((1.0 - y / half_h) * 0.5 * height as f64) as usize;
    let mut sum = [0.0f64; 3];
    for py in cy - k..cy + k {
        for px in cx - k..cx + k {
            for c in 0..3 {
                sum[c] += xyz[py * width + px][c] as f64;
            }
        }
    }
    sum.map(|s| s / (4 * k * k) as f64)
}
